"""The identifiability and next-measurement parts of the diagnosis report: the correlation
heat map of the effects' signatures, the table of groups and strength intervals, and the
``next_measurement.html`` page (templates ``diagnose_identify.html.j2`` and
``diagnose_design.html.j2``, included by ``diagnose.html.j2``)."""

from __future__ import annotations

import math
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from jinja2 import Environment

from radtree import __version__
from radtree.diagnose.identify import CONFIDENCE, GROUP_CORR, Identifiability, Interval
from radtree.figures import new_figure, save_png
from radtree.fileio import write_text
from radtree.resources import template_environment

if TYPE_CHECKING:
    from radtree.diagnose.loop import Step

DPI = 120


def _env() -> Environment:
    env = template_environment(autoescape=True, trim_blocks=True, lstrip_blocks=True)
    env.filters["f3"] = lambda v: "–" if v is None or (isinstance(v, float) and
                                                      not math.isfinite(v)) else f"{v:.3f}"
    env.filters["f0"] = lambda v: "–" if v is None or (isinstance(v, float) and
                                                      not math.isfinite(v)) else f"{v:,.0f}"
    env.filters["pct"] = lambda v: "–" if v is None or (isinstance(v, float) and
                                                       not math.isfinite(v)) else f"{v:.0%}"
    env.filters["sgn"] = lambda v: "–" if v is None or (isinstance(v, float) and
                                                       not math.isfinite(v)) else f"{v:+,.0f}"
    return env


def fig_correlation(ident: Identifiability, title: str, path: Path) -> str:
    """Heat map of the whitened signature correlations, numbers in the cells."""
    n = len(ident.names)
    fig = new_figure(1.6 + 0.62 * n, 1.2 + 0.55 * n, DPI)
    ax = fig.add_subplot()
    im = ax.imshow(np.nan_to_num(ident.correlation, nan=0.0), cmap="RdBu_r", vmin=-1, vmax=1)
    for i in range(n):
        for j in range(n):
            v = ident.correlation[i, j]
            if math.isfinite(v):
                ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=7,
                        color="white" if abs(v) >= GROUP_CORR else "black",
                        fontweight="bold" if abs(v) >= GROUP_CORR and i != j else "normal")
    ax.set_xticks(range(n), ident.names, rotation=40, ha="right", fontsize=8)
    ax.set_yticks(range(n), ident.names, fontsize=8)
    ax.set_title(title, fontsize=9)
    fig.colorbar(im, ax=ax, shrink=0.8, label="correlation of whitened signatures")
    return save_png(fig, path, DPI).name


def interval_text(iv: Interval | None) -> str:
    if iv is None:
        return "on/off"
    return f"{iv.estimate:.4g} [{iv.lo:.4g}, {iv.hi:.4g}]"


def ident_context(step: Step, out: Path, next_csv: Path | None = None) -> dict[str, Any]:
    """Template data for the identifiability of a diagnosis step (the first)."""
    ident = step.identify
    assert ident is not None
    fig = fig_correlation(ident, f"Step {step.number}: which candidates the data can tell "
                          f"apart (|corr| ≥ {GROUP_CORR} → one group)",
                          out / "identifiability.png")
    table = ident.table()
    table["strength_ci"] = [interval_text(step.intervals.get(e)) for e in table["effect"]]
    nxt: list[dict[str, Any]] = []
    if next_csv is not None and next_csv.is_file():
        nxt = pd.read_csv(next_csv, keep_default_na=False).head(3).to_dict("records")
    return {"fig": fig, "table": table.to_dict("records"), "groups": ident.confounded,
            "condition": ident.condition, "n": len(step.attribution.residual),
            "threshold": GROUP_CORR, "level": CONFIDENCE, "sentence": step.separability,
            "named": step.effect, "next": nxt}


def write_design_report(design: Any, out: Path) -> list[Path]:
    """``next_measurement.html`` and its two heat maps for a :class:`~.design.Design`."""
    before = fig_correlation(design.before, f"{design.base.name}: correlations",
                             out / "next_before.png")
    after = fig_correlation(design.after_top, "with the top three next measurements",
                            out / "next_after.png")
    c = {"kind": "design", "project": None, "d": design, "before": before, "after": after,
         "table": design.table.to_dict("records"), "threshold": GROUP_CORR,
         "before_table": design.before.table().to_dict("records"),
         "after_table": design.after_top.table().to_dict("records"),
         "version": __version__,
         "created": datetime.now(timezone.utc).isoformat(timespec="seconds")}
    html = _env().get_template("diagnose.html.j2").render(c=c)
    return [write_text(out / "next_measurement.html", html), out / before, out / after]
