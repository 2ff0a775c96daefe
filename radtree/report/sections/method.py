"""The report section "what the study's numbers owe to its method" — from ``PROJECT/method/
*.csv`` (written by ``radtree method``, :mod:`radtree.verify.method`); absent without them.

For each finding of reference case §7 the section states a measurable test (below), evaluates it under
every variant and names the setting that makes it appear or vanish: the variants form a chain
in which each step changes one setting (study → threshold 0.005 → no threshold → whole-scene
sun → free crown), so the first step at which the test flips names the cause. Then the
dome-radius scan: hourly façade means and nRMSE per scenario and radius, the A–E ordering per
radius, and a figure.

Tests (lux are façade means of the 8 sensors, m = measured, s = simulated):

* ordering — the scenarios sorted by nRMSE equal the study's A < B ≈ C < E < D (B and C
  either way round);
* A close — mean |m − s| of A < 120 lx;
* B low at low sun — mean (m − s) of B at 10:30, 11:30, 15:30, 16:30 ≥ 300 lx and larger than
  at 12:30–14:30;
* C better than D — nRMSE(C) < nRMSE(D);
* perforated spikes — C or D exceeds the measured value by ≥ 30 % at some hour;
* E misses the reflection — E below half the measured value at every hour.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project
from radtree.engines.registry import photon_engines
from radtree.figures import new_figure, save_png
from radtree.measurements import hourly_grid_means
from radtree.stats import nrmse
from radtree.verify.method import STUDY, VARIANTS, read_method

LOW_SUN = ("10:30", "11:30", "15:30", "16:30")
MIDDAY = ("12:30", "13:30", "14:30")
STUDY_ORDER = ("A", "B", "C", "E", "D")
FIGURE = "method_radius.png"


def _order(fit: dict[str, float]) -> str:
    return " < ".join(k for k, _ in sorted(fit.items(), key=lambda kv: kv[1]))


def _ordering_holds(fit: dict[str, float]) -> bool:
    order = [k for k, _ in sorted(fit.items(), key=lambda kv: kv[1])]
    return order in (list(STUDY_ORDER), ["A", "C", "B", "E", "D"])


def _tests(h: dict[str, pd.Series], m: pd.Series) -> dict[str, bool | None]:
    def have(*names: str) -> bool:
        return all(n in h for n in names)

    fit = {k: nrmse(m.reindex(v.index).to_numpy(), v.to_numpy()) for k, v in h.items()}
    out: dict[str, bool | None] = {}
    out["ordering"] = _ordering_holds(fit) if have(*STUDY_ORDER) else None
    out["A close"] = bool((m - h["A"]).abs().mean() < 120.0) if have("A") else None
    if have("B"):
        d = m - h["B"]
        low, mid = d.reindex(LOW_SUN).mean(), d.reindex(MIDDAY).mean()
        out["B low at low sun"] = bool(low >= 300.0 and low > mid)
    else:
        out["B low at low sun"] = None
    out["C better than D"] = bool(fit["C"] < fit["D"]) if have("C", "D") else None
    out["perforated spikes"] = bool(max((h[k] / m).max() for k in ("C", "D")) >= 1.3) \
        if have("C", "D") else None
    out["E misses the reflection"] = bool((h["E"] < 0.5 * m).all()) if have("E") else None
    return out


FINDINGS = {
    "ordering": "Ordering by nRMSE: A (0.09) < B ≈ C < E < D",
    "A close": "A follows the measured day, differences below 120 lx",
    "B low at low sun": "B far below the measurements at the low-sun hours (≈ 500 lx)",
    "C better than D": "C (traced) fits better than D (calculated)",
    "perforated spikes": "Perforated models very high at some hours (direct sun through holes)",
    "E misses the reflection": "E (6 % shell) misses the reflected component at all hours",
}


def _cause(flags: list[tuple[str, bool | None]]) -> str:
    """The setting whose change first flips the test along the variant chain."""
    study = dict(flags).get(STUDY)
    if study is None:
        return "—"
    prev = study
    changes = {v.label: v.changes for v in VARIANTS}
    for label, value in flags[1:]:
        if value is not None and value != prev:
            return f"{'vanishes' if prev else 'appears'} with {changes[label]}"
        if value is not None:
            prev = value
    return "holds under every variant" if study else "fails under every variant"


def _hourly_frame(table: pd.DataFrame, variant: str, radius: float) -> dict[str, pd.Series]:
    t = table[(table["variant"] == variant) & np.isclose(table["radius_m"], radius)]
    return {str(k): g.set_index("time")["lux"] for k, g in t.groupby("scenario")}


def _radius_figure(table: pd.DataFrame, m: pd.Series, radii: list[float], path: Path) -> None:
    names = sorted(table["scenario"].unique())
    fig = new_figure(3.0 * (len(names) + 1), 3.0, 150)
    axes = fig.subplots(1, len(names) + 1)
    hours = list(m.index)
    x = np.arange(len(hours))
    colours = [f"C{i}" for i in range(len(radii))]
    for ax, name in zip(axes, names):
        ax.plot(x, m.to_numpy(), "k--", lw=1.5, label="measured")
        for r, c in zip(radii, colours):
            h = _hourly_frame(table, STUDY, r).get(name)
            if h is not None:
                ax.plot(x, h.reindex(hours).to_numpy(), color=c, lw=1, label=f"{r:g} m")
        ax.set_title(f"{name}: emulation by dome radius", fontsize=8)
        ax.set_xticks(x[::2], hours[::2], fontsize=6)
        ax.set_ylabel("façade mean (lx)", fontsize=7)
        ax.tick_params(labelsize=6)
    max(axes[:-1], key=lambda a: len(a.get_lines())).legend(fontsize=5)
    ax = axes[-1]
    for i, name in enumerate(names):
        vals = [nrmse(m.to_numpy(), h.reindex(hours).to_numpy()) if (h := _hourly_frame(
            table, STUDY, r).get(name)) is not None else np.nan for r in radii]
        ax.plot(radii, vals, "o-", color=f"C{i}", label=name, lw=1, ms=3)
    ax.set_xlabel("dome radius (m)", fontsize=7)
    ax.set_ylabel("nRMSE", fontsize=7)
    ax.set_title("nRMSE by dome radius", fontsize=8)
    ax.tick_params(labelsize=6)
    ax.legend(fontsize=6)
    save_png(fig, path, 150)


def method_section_data(project: Project, out: Path) -> dict[str, Any] | None:
    """The section's data (None without ``method/hourly.csv`` or measurements); writes the
    radius figure into the report folder ``out``."""
    table = read_method(project.root)
    if table is None or project.measured is None:
        return None
    measured = hourly_grid_means(project.measured)
    if measured is None:
        return None
    hours = [h for h in measured.index if h in set(table["time"])]
    m = measured.reindex(hours)
    base = float(project.tree.dome.radius_m)
    variants = [v for v in VARIANTS if v.label in set(table["variant"])]
    rows: list[list[str]] = []
    orders: list[list[str]] = []
    flags: dict[str, list[tuple[str, bool | None]]] = {k: [] for k in FINDINGS}
    for v in variants:
        h = _hourly_frame(table, v.label, base)
        if not h:
            continue
        fit = {k: nrmse(m.to_numpy(), s.reindex(hours).to_numpy()) for k, s in h.items()}
        for k in sorted(h):
            rows.append([v.label, k] + [f"{x:.0f}" for x in h[k].reindex(hours)]
                        + [f"{fit[k]:.3f}"])
        orders.append([v.label, v.changes, _order(fit)])
        for key, value in _tests({k: s.reindex(hours) for k, s in h.items()}, m).items():
            flags[key].append((v.label, value))
    mark = {True: "yes", False: "no", None: "—"}
    findings = [[FINDINGS[k], mark[dict(f).get(STUDY)],
                 ", ".join(f"{lab}: {mark[val]}" for lab, val in f), _cause(f)]
                for k, f in flags.items()]
    radii = sorted(float(r) for r in table.loc[table["variant"] == STUDY, "radius_m"].unique())
    scan, scan_orders = [], []
    for r in radii:
        h = _hourly_frame(table, STUDY, r)
        fit = {k: nrmse(m.to_numpy(), s.reindex(hours).to_numpy()) for k, s in h.items()}
        for k in sorted(h):
            scan.append([f"{r:g}", k] + [f"{x:.0f}" for x in h[k].reindex(hours)]
                        + [f"{fit[k]:.3f}"])
        scan_orders.append([f"{r:g}", _order(fit), ", ".join(sorted(set(STUDY_ORDER) - set(h)))
                            or "—"])
    figure = None
    if len(radii) > 1:
        (out / "figures").mkdir(parents=True, exist_ok=True)
        _radius_figure(table, m, radii, out / "figures" / FIGURE)
        figure = f"figures/{FIGURE}"
    photons = sorted(set(table.loc[table["engine"].isin(photon_engines()), "photons"].astype(int)))
    return {"hours": hours, "measured": [f"{x:.0f}" for x in m], "radius": f"{base:g}",
            "rows": rows, "orders": orders, "findings": findings, "scan": scan,
            "scan_orders": scan_orders, "figure": figure,
            "photons": ", ".join(f"{p:,}" for p in photons)}
