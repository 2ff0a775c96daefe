"""What each swept unknown does: per-case metrics, effect ranges, rank correlations, tornado.

Per case × scenario (``metrics.csv``):

* ``facade_mean_lux`` — the daily mean of the hourly ``facade`` grid mean (lux), and
  ``facade_lux_HH:MM`` — the hourly façade grid mean at each hour (lux);
* ``nrmse``, ``nmbe`` — against the project's measurements (reference case §3; over the measured hours that
  the sweep simulated) when the project has ``measured``.

Per scenario × parameter × metric (``sensitivity.csv``):

* ``effect_low``, ``effect_high``, ``effect_range`` — main effect: the metric averaged over all
  other parameters at each level of this one (full factorial: its values; Latin hypercube: its
  values for a list or integer range, else ``bins`` quantile bins), and the spread of those
  means; ``value_at_low``/``value_at_high`` are the levels giving them. For a full factorial
  this is the one-at-a-time range averaged over the other parameters.
* ``spearman_rho``, ``spearman_p`` — Spearman rank correlation of the parameter with the metric
  over the cases (numeric parameters, ≥ 3 cases, both not constant; NaN otherwise). It is the
  ranking statistic for Latin hypercube designs; for full factorials it is given as well.

``tornado.png`` draws the main-effect ranges (nRMSE when measured, and the daily façade mean),
largest on top, per scenario. :func:`sweep_section_data` gives the report section's data naming the
unknown that moves scenario A's nRMSE most.
"""

from __future__ import annotations

import base64
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.errors import RadtreeError
from radtree.fileio import atomic_path
from radtree.stats import FACADE_GRID, compare, hourly_means

SENSITIVITY_COLUMNS = ["scenario", "parameter", "metric", "method", "levels", "effect_low",
                       "effect_high", "effect_range", "value_at_low", "value_at_high",
                       "metric_min", "metric_max", "spearman_rho", "spearman_p", "n_cases"]
METRIC_LABELS = {"nrmse": "nRMSE", "nmbe": "nMBE", "facade_mean_lux": "daily mean façade lux"}


# ---------------------------------------------------------------- metrics per case
def _measured_frame(measured: pd.DataFrame | str | Path | None) -> pd.DataFrame | None:
    if measured is None:
        return None
    if isinstance(measured, pd.DataFrame):
        return measured
    from radtree.measurements import load_measured

    frame, _shape = load_measured(measured)
    return frame


def case_metrics(results: pd.DataFrame, parameters: list[str],
                 measured: pd.DataFrame | str | Path | None = None,
                 grid: str = FACADE_GRID) -> pd.DataFrame:
    """One row per case × scenario: parameters, façade means (daily, hourly), nRMSE, nMBE."""
    meas = _measured_frame(measured)
    rows: list[dict[str, Any]] = []
    for (cid, chash), group in results.groupby(["case_id", "case_hash"], sort=True):
        params = {p: group[p].iloc[0] for p in parameters}
        hourly = hourly_means(group, grid)
        stats = None
        if meas is not None:
            simulated = set(hourly["time"])
            m = meas[meas["time"].isin(simulated)]
            if len(m):
                stats = compare(group, m, grid=grid, n_boot=1).stats.set_index("scenario")
        for scenario, h in hourly.groupby("scenario", sort=True):
            row: dict[str, Any] = {"case_id": cid, "case_hash": chash, **params,
                                   "scenario": scenario, "model": h["model"].iloc[0],
                                   "facade_mean_lux": float(h["lux"].mean())}
            if stats is not None and scenario in stats.index:
                row["nrmse"] = float(stats.loc[scenario, "rmse"])
                row["nmbe"] = float(stats.loc[scenario, "mbe"])
                row["n_hours_compared"] = int(stats.loc[scenario, "n_hours"])
            for t, v in zip(h["time"], h["lux"], strict=True):
                row[f"facade_lux_{t}"] = float(v)
            rows.append(row)
    out = pd.DataFrame(rows)
    front = ["case_id", "case_hash", *parameters, "scenario", "model"]
    stat_cols = [c for c in ("nrmse", "nmbe", "n_hours_compared") if c in out.columns]
    hour_cols = sorted(c for c in out.columns if c.startswith("facade_lux_"))
    return out[[c for c in front if c in out.columns] + stat_cols + ["facade_mean_lux"]
               + hour_cols] if len(out) else out


def metric_names(metrics: pd.DataFrame) -> list[str]:
    names = [c for c in ("nrmse", "nmbe") if c in metrics.columns
             and metrics[c].notna().any()]
    names.append("facade_mean_lux")
    names += sorted(c for c in metrics.columns if c.startswith("facade_lux_"))
    return [n for n in names if n in metrics.columns]


# ---------------------------------------------------------------- effects
def _is_numeric(values: pd.Series) -> bool:
    return bool(all(isinstance(v, int | float | np.integer | np.floating)
                    and not isinstance(v, bool | np.bool_) for v in values))


def _levels(values: pd.Series, binned: bool, bins: int) -> tuple[pd.Series, str]:
    """Group labels for the main effect, and the method's name."""
    if not binned:
        return values, "main effect"
    k = int(min(bins, values.nunique()))
    codes = pd.qcut(values.astype(float).rank(method="first"), q=k, labels=False)
    mids = values.astype(float).groupby(codes).transform("mean")
    return mids, f"binned main effect ({k} quantile bins)"


def _spearman(x: pd.Series, y: pd.Series) -> tuple[float, float]:
    from scipy.stats import spearmanr

    ok = y.notna()
    xs, ys = x[ok].astype(float), y[ok].astype(float)
    if len(xs) < 3 or xs.nunique() < 2 or ys.nunique() < 2:
        return math.nan, math.nan
    res = spearmanr(xs, ys)
    return float(res.statistic), float(res.pvalue)


def sensitivity_table(metrics: pd.DataFrame, parameters: list[str], design: str = "full",
                      binned: dict[str, bool] | None = None, bins: int = 5) -> pd.DataFrame:
    """Per scenario × parameter × metric: main-effect range and Spearman rank correlation.

    ``binned[p]`` True bins a continuous Latin-hypercube parameter into ``bins`` quantile bins
    (default: binned when ``design == "lhs"`` and the parameter has more distinct values than
    ``bins``).
    """
    rows = []
    names = metric_names(metrics)
    for scenario, g in metrics.groupby("scenario", sort=True):
        for p in parameters:
            x = g[p]
            numeric = _is_numeric(x)
            is_binned = (binned or {}).get(
                p, design == "lhs" and numeric and x.nunique() > bins)
            labels, method = _levels(x, is_binned, bins)
            for metric in names:
                y = g[metric].astype(float)
                if y.notna().sum() == 0:
                    continue
                means = y.groupby(labels, sort=True).mean().dropna()
                if means.empty:
                    continue
                lo_at, hi_at = means.idxmin(), means.idxmax()
                rho, pval = _spearman(x, y) if numeric else (math.nan, math.nan)
                rows.append({
                    "scenario": scenario, "parameter": p, "metric": metric, "method": method,
                    "levels": int(len(means)), "effect_low": float(means.min()),
                    "effect_high": float(means.max()),
                    "effect_range": float(means.max() - means.min()),
                    "value_at_low": _plain(lo_at), "value_at_high": _plain(hi_at),
                    "metric_min": float(y.min()), "metric_max": float(y.max()),
                    "spearman_rho": rho, "spearman_p": pval, "n_cases": int(y.notna().sum()),
                })
    return pd.DataFrame(rows, columns=SENSITIVITY_COLUMNS)


def _plain(v: Any) -> Any:
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float):
        return float(f"{v:.6g}")
    return v


# ---------------------------------------------------------------- tornado
def tornado_plot(sens: pd.DataFrame, metrics: pd.DataFrame, path: Path,
                 scenarios: list[str] | None = None) -> Path:
    """Horizontal bars of each parameter's main-effect range about the overall mean."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    wanted = [m for m in ("nrmse", "facade_mean_lux") if m in set(sens["metric"])]
    scen = scenarios or sorted(sens["scenario"].unique())
    if not wanted or not scen:
        raise RadtreeError("nothing to plot in the sensitivity table")
    nparam = sens["parameter"].nunique()
    fig, axes = plt.subplots(len(scen), len(wanted), squeeze=False,
                             figsize=(5.2 * len(wanted), 0.9 + 0.45 * nparam * len(scen) + 0.6))
    for i, sc in enumerate(scen):
        for j, metric in enumerate(wanted):
            ax = axes[i][j]
            d = sens[(sens["scenario"] == sc) & (sens["metric"] == metric)]
            d = d.sort_values("effect_range")
            centre = float(metrics.loc[metrics["scenario"] == sc, metric].mean())
            y = np.arange(len(d))
            ax.barh(y, d["effect_high"] - d["effect_low"], left=d["effect_low"],
                    color="#4878a8" if metric == "nrmse" else "#d08c32", height=0.6)
            ax.axvline(centre, color="k", lw=0.8)
            ax.set_yticks(y, list(d["parameter"]), fontsize=8)
            for yy, (_, r) in zip(y, d.iterrows(), strict=True):
                ax.annotate(f"{r['value_at_low']}", (r["effect_low"], yy), fontsize=7,
                            ha="right", va="center", xytext=(-2, 0), textcoords="offset points")
                ax.annotate(f"{r['value_at_high']}", (r["effect_high"], yy), fontsize=7,
                            ha="left", va="center", xytext=(2, 0), textcoords="offset points")
            ax.set_title(f"scenario {sc}: {METRIC_LABELS.get(metric, metric)}", fontsize=9)
            if len(d):
                lo, hi = float(d["effect_low"].min()), float(d["effect_high"].max())
                span = (hi - lo) or (abs(hi) * 0.1) or 1.0
                ax.set_xlim(lo - 0.3 * span, hi + 0.3 * span)
            ax.tick_params(axis="x", labelsize=8)
    fig.suptitle("sweep: main-effect range of each parameter (labels: parameter value)",
                 fontsize=9)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return path


# ---------------------------------------------------------------- writing
def write_sensitivity(out_dir: Path, results: pd.DataFrame, design: Any,
                      measured: pd.DataFrame | str | Path | None = None) -> pd.DataFrame:
    """Write ``metrics.csv``, ``sensitivity.csv`` and ``tornado.png`` into ``out_dir``."""
    names = [p.name for p in design.parameters]
    metrics = case_metrics(results, names, measured)
    if metrics.empty:
        raise RadtreeError("no finished case has façade results")
    with atomic_path(out_dir / "metrics.csv") as tmp:
        metrics.to_csv(tmp, index=False)
    binned = {p.name: (design.kind == "lhs" and p.kind == "range" and not p.integer)
              for p in design.parameters}
    sens = sensitivity_table(metrics, names, design.kind, binned)
    with atomic_path(out_dir / "sensitivity.csv") as tmp:
        sens.to_csv(tmp, index=False)
    if len(sens):
        tornado_plot(sens, metrics, out_dir / "tornado.png")
    return sens


# ---------------------------------------------------------------- report
def _sweep_dir(project_root: str | Path) -> Path:
    root = Path(project_root)
    if root.is_file():
        root = root.parent
    out = root / "sweep"
    try:
        from radtree.sweep.settings import read_raw

        _, data = read_raw(root)
        custom = (data.get("sweep") or {}).get("out")
        if isinstance(custom, str) and custom:
            out = Path(custom) if Path(custom).is_absolute() else root / custom
    except RadtreeError:
        pass
    return out


def _fmt(v: float, metric: str) -> str:
    if metric in ("nrmse", "nmbe"):
        return f"{v:.3f}"
    return f"{v:,.0f} lx"


def sweep_section_data(project_root: str | Path, scenario: str = "A") -> dict[str, Any] | None:
    """The report section on the sweep of the project at ``project_root`` (None when none was
    run), as the data ``templates/sections/sweep.html.j2`` renders.

    Names the unknown that moves ``scenario``'s nRMSE most (or its daily façade mean when the
    project has no measurements; the first swept scenario when ``scenario`` was not swept),
    tabulates every parameter's effect (nRMSE/nMBE as fractions, illuminance in lux) and embeds
    the tornado plot (base64 PNG).
    """
    out = _sweep_dir(project_root)
    sens_path = out / "sensitivity.csv"
    if not sens_path.exists():
        return None
    sens = pd.read_csv(sens_path)
    if sens.empty:
        return None
    info: dict[str, Any] = {}
    if (out / "design.json").exists():
        info = json.loads((out / "design.json").read_text(encoding="utf-8"))
    swept = list(dict.fromkeys(sens["scenario"].astype(str)))
    sc = scenario if scenario in swept else swept[0]
    s = sens[sens["scenario"].astype(str) == sc]
    metric = "nrmse" if "nrmse" in set(s["metric"]) else "facade_mean_lux"
    s_m = s[s["metric"] == metric].sort_values("effect_range", ascending=False)
    top = s_m.iloc[0]
    head, rows = _effect_rows(s, ranked=s_m, metric=metric)
    png = out / "tornado.png"
    failures = out / "failures.csv"
    return {
        "cases": info.get("cases"),
        "design": {"full": "full factorial", "lhs": "Latin hypercube"}.get(
            info.get("design", ""), ""),
        "seed": info.get("seed"), "engine": str(info.get("engine", "")),
        "parameters": [{"name": str(p["name"]), "spec": str(p["spec"])}
                       for p in info.get("parameters", [])],
        "asked": scenario, "scenario": sc,
        "what": ("normalised RMSE against the measurements" if metric == "nrmse" else
                 "daily mean façade illuminance (the project has no measurements, so no nRMSE)"),
        "top": {"parameter": str(top["parameter"]),
                "low": _fmt(top["effect_low"], metric), "at_low": str(top["value_at_low"]),
                "high": _fmt(top["effect_high"], metric), "at_high": str(top["value_at_high"]),
                "method": str(top["method"]), "range": _fmt(top["effect_range"], metric)},
        "header": head, "rows": rows,
        "tornado": (base64.b64encode(png.read_bytes()).decode("ascii") if png.exists()
                    else None),
        "failures": len(pd.read_csv(failures)) if failures.exists() else 0,
        "failures_file": str(failures),
    }


def _effect_rows(s: pd.DataFrame, *, ranked: pd.DataFrame,
                 metric: str) -> tuple[list[str], list[dict[str, Any]]]:
    """The table's header and one row per parameter of ``ranked`` (``s``'s rows of ``metric``,
    largest effect first): its range, the values at the ends, Spearman ρ, and with nRMSE also
    the nMBE range (fraction) and the façade illuminance range (lux)."""
    lux = s[s["metric"] == "facade_mean_lux"].set_index("parameter")
    nmbe = s[s["metric"] == "nmbe"].set_index("parameter")
    head = ["parameter", f"{METRIC_LABELS.get(metric, metric)} range", "low → high at",
            "Spearman ρ"]
    if metric == "nrmse":
        head += ["nMBE range", "façade lux range"]
    rows = []
    for _, r in ranked.iterrows():
        cells = [f"{_fmt(r['effect_low'], metric)} – {_fmt(r['effect_high'], metric)}",
                 f"{r['value_at_low']} → {r['value_at_high']}",
                 "—" if pd.isna(r["spearman_rho"]) else f"{r['spearman_rho']:+.2f}"]
        if metric == "nrmse":
            p = r["parameter"]
            cells.append(f"{nmbe.loc[p, 'effect_low']:+.3f} – {nmbe.loc[p, 'effect_high']:+.3f}"
                         if p in nmbe.index else "—")
            cells.append(f"{lux.loc[p, 'effect_low']:,.0f} – {lux.loc[p, 'effect_high']:,.0f}"
                         if p in lux.index else "—")
        rows.append({"parameter": str(r["parameter"]), "cells": cells})
    return head, rows
