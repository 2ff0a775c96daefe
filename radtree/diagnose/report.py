"""The diagnosis report: PNG figures beside ``index.html`` (and ``selftest.html``).

Figures (matplotlib Agg, no pyplot state): residual by hour at every step (the gap shrinking),
measured against simulated by hour, residual against sun altitude, per-row residuals, nRMSE and
CV nRMSE per step, and per step the residual with every candidate's fitted signature.
"""

from __future__ import annotations

import math
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from radtree import __version__
from radtree.diagnose.attribution import TIE_CORR
from radtree.diagnose.effects import EFFECTS, EffectContext, candidates
from radtree.diagnose.report_identify import _env, ident_context
from radtree.diagnose.residuals import RULES, DisagreementMap
from radtree.figures import new_figure, save_png
from radtree.fileio import write_text

if TYPE_CHECKING:
    from radtree.diagnose.loop import LoopResult
    from radtree.diagnose.outcome import DiagnoseResult, SelftestResult

DPI = 120
LUX = "lx"


def _fig(w: float, h: float) -> Figure:
    return new_figure(w, h, DPI)


def _save(fig: Figure, path: Path) -> str:
    return save_png(fig, path, DPI).name


def _hour(t: str) -> float:
    h, m = str(t).split(":")
    return int(h) + int(m) / 60


def _xs(times: Any) -> list[float]:
    """x positions of the values: clock hours, or the index for a campaign's observations
    (labelled ``DAY HH:MM GROUP``)."""
    times = [str(t) for t in times]
    if all(len(t) == 5 and t[2] == ":" for t in times):
        return [_hour(t) for t in times]
    return [float(i) for i in range(len(times))]


def _maps(loop: LoopResult) -> list[tuple[str, DisagreementMap]]:
    out = [(f"start ({loop.start.name})", loop.start_map)]
    out += [(f"step {s.number}: + {s.effect}", s.map_after) for s in loop.steps]
    return out


def _step_colour(i: int, n: int, first: str) -> Any:
    """Colour of step ``i`` of ``n`` maps: ``first`` for the start, then viridis."""
    return first if i == 0 else colormaps["viridis"](0.15 + 0.7 * i / max(1, n - 1))


def fig_residual_steps(loop: LoopResult, path: Path) -> str:
    fig = _fig(7.5, 4.2)
    ax = fig.add_subplot()
    maps = _maps(loop)
    for i, (label, dm) in enumerate(maps):
        h = dm.hourly
        x = _xs(h["time"])
        c = _step_colour(i, len(maps), "black")
        ax.errorbar(x, h["residual_lux"], yerr=2 * h["simulated_se_lux"].fillna(0), marker="o",
                    color=c, lw=2.2 if i in (0, len(maps) - 1) else 1.2, capsize=3,
                    label=f"{label}: nRMSE {dm.stats['nrmse']:.3f}")
    ax.axhline(0, color="grey", lw=0.8)
    ax.set_xlabel("local clock time (h)")
    ax.set_ylabel("residual measured − simulated (lx)")
    ax.set_title("Residual by hour at each step (error bars: ±2 Monte Carlo SE)")
    ax.legend(fontsize=8)
    return _save(fig, path)


def fig_measured(loop: LoopResult, path: Path) -> str:
    fig = _fig(7.5, 4.2)
    ax = fig.add_subplot()
    maps = _maps(loop)
    h0 = maps[0][1].hourly
    x = _xs(h0["time"])
    ax.plot(x, h0["measured_lux"], "o-", color="black", lw=2.4, label="measured", zorder=5)
    for i, (label, dm) in enumerate(maps):
        c = _step_colour(i, len(maps), "tab:red")
        ax.plot(x, dm.hourly["simulated_lux"], "s--", color=c, label=label)
    ax.set_xlabel("local clock time (h)")
    ax.set_ylabel("vertical illuminance, façade grid mean (lx)")
    ax.set_title("Measured and simulated hourly means")
    ax.legend(fontsize=8)
    return _save(fig, path)


def fig_altitude(loop: LoopResult, path: Path) -> str:
    fig = _fig(6.5, 4.0)
    ax = fig.add_subplot()
    maps = _maps(loop)
    sel = [maps[0]] + ([maps[-1]] if len(maps) > 1 else [])
    for (label, dm), c in zip(sel, ("black", "tab:green")):
        h = dm.hourly
        for period, mk in (("morning", "o"), ("noon", "s"), ("afternoon", "^")):
            m = h["period"] == period
            if not m.any():
                continue
            ax.scatter(h.loc[m, "sun_altitude_deg"], h.loc[m, "residual_lux"], marker=mk,
                       color=c, label=f"{label}, {period}")
    ax.axhline(0, color="grey", lw=0.8)
    ax.set_xlabel("sun altitude (°)")
    ax.set_ylabel("residual measured − simulated (lx)")
    ax.set_title("Residual against sun altitude")
    ax.legend(fontsize=7)
    return _save(fig, path)


def fig_rows(loop: LoopResult, path: Path) -> str | None:
    maps = [(lab, dm) for lab, dm in _maps(loop) if dm.rows is not None]
    if not maps:
        return None
    fig = _fig(6.5, 3.8)
    ax = fig.add_subplot()
    rows = list(maps[0][1].rows["row"])  # type: ignore[index]
    width = 0.8 / len(maps)
    cmap = colormaps["viridis"]
    for i, (label, dm) in enumerate(maps):
        r = dm.rows.set_index("row").reindex(rows)  # type: ignore[union-attr]
        c = "black" if i == 0 else cmap(0.15 + 0.7 * i / max(1, len(maps) - 1))
        ax.bar(np.arange(len(rows)) + i * width, r["residual_lux"], width, color=c, label=label)
    ax.set_xticks(np.arange(len(rows)) + 0.4 - width / 2, rows)
    ax.axhline(0, color="grey", lw=0.8)
    ax.set_ylabel("daily-mean residual (lx)")
    ax.set_title("Residual of the per-row daily means")
    ax.legend(fontsize=7)
    return _save(fig, path)


def fig_rmse(loop: LoopResult, path: Path) -> str:
    fig = _fig(6.0, 3.6)
    ax = fig.add_subplot()
    labels = ["start"] + [f"{s.number}: {s.effect}" for s in loop.steps]
    rm = [loop.start_map.stats["nrmse"]] + [s.rmse_after for s in loop.steps]
    cv = [loop.steps[0].cv_rmse_before if loop.steps else loop.start_map.stats["nrmse"]]
    cv += [s.cv_rmse_after for s in loop.steps]
    x = np.arange(len(labels))
    ax.bar(x - 0.2, rm, 0.4, label="nRMSE after re-simulation", color="tab:blue")
    ax.bar(x + 0.2, cv, 0.4, label="CV nRMSE (leave-one-hour-out fit)", color="tab:orange")
    ax.set_xticks(x, labels, rotation=20, ha="right", fontsize=8)
    ax.set_ylabel("normalised RMSE (–)")
    ax.set_title("Gap at each step")
    ax.legend(fontsize=8)
    return _save(fig, path)


def fig_candidates(att: Any, times: list[str], title: str, path: Path) -> str:
    fig = _fig(7.5, 4.2)
    ax = fig.add_subplot()
    x = _xs(times)
    ax.plot(x, att.residual, "o-", color="black", lw=2.5, label="residual", zorder=5)
    cmap = colormaps["tab10"]
    for i, f in enumerate(att.fits):
        win = att.winner is not None and f.effect == att.winner.effect
        ax.plot(x, f.prediction, "-" if win else "--", color=cmap(i % 10), lw=2.2 if win else 1,
                label=f"{f.effect} [{f.strength_text}] CV {f.cv_rmse_lux / att.mean_measured:.3f}")
    ax.axhline(0, color="grey", lw=0.8)
    ax.set_xlabel("local clock time (h)")
    ax.set_ylabel("lx")
    ax.set_title(title)
    ax.legend(fontsize=7, ncol=2)
    return _save(fig, path)


# --------------------------------------------------------------------------- HTML
def _records(df: Any) -> list[dict[str, Any]]:
    return [] if df is None else df.to_dict("records")


def _map_ctx(dm: DisagreementMap) -> dict[str, Any]:
    return {"hourly": _records(dm.hourly), "rows": _records(dm.rows), "stats": dm.stats,
            "findings": dm.findings}


def _catalogue(ctx: EffectContext | None, sc: Any) -> list[dict[str, Any]]:
    status: dict[str, str] = {}
    if ctx is not None and sc is not None:
        cands, why = candidates(ctx, sc)
        status = {e.name: "candidate (off)" for e in cands} | why
    out = []
    for e in EFFECTS:
        st = e.strength(ctx, sc) if ctx is not None and sc is not None else None
        out.append({"name": e.name, "title": e.title, "physics": e.physics, "switch": e.switch,
                    "strength": "on/off" if st is None else
                    f"{st.label} ({st.mode}), [{st.text(st.lo)}, {st.text(st.hi)}], "
                    f"reference {st.text(st.reference)}",
                    "status": status.get(e.name, "")})
    return out


def write_diagnose_report(res: DiagnoseResult, out: Path) -> list[Path]:
    loop = res.loop
    files: list[Path] = []
    figs: dict[str, str] = {}
    figs["residual_steps"] = fig_residual_steps(loop, out / "residual_steps.png")
    figs["measured"] = fig_measured(loop, out / "measured_simulated.png")
    figs["altitude"] = fig_altitude(loop, out / "residual_altitude.png")
    rows = fig_rows(loop, out / "residual_rows.png")
    if rows:
        figs["rows"] = rows
    figs["rmse"] = fig_rmse(loop, out / "rmse_steps.png")
    times = list(res.measured.times)
    steps: list[dict[str, Any]] = []
    for s in loop.steps:
        name = fig_candidates(s.attribution, times, f"Step {s.number}: residual and each "
                              "candidate's fitted signature", out / f"candidates_step{s.number}.png")
        table = s.attribution.table()
        table["chosen"] = table["effect"] == s.effect
        steps.append({"s": s, "fig": name, "table": _records(table),
                      "map_before": _map_ctx(s.map_before),
                      "not_candidates": s.attribution.not_candidates,
                      "project_file": s.project_file.name if s.project_file else ""})
    last: dict[str, Any] | None = None
    if loop.last_attribution is not None and loop.last_attribution.fits:
        k = len(loop.steps) + 1
        name = fig_candidates(loop.last_attribution, times, f"Step {k} (not taken): residual "
                              "and each candidate's fitted signature", out / "candidates_last.png")
        last = {"fig": name, "table": _records(loop.last_attribution.table()),
                "not_candidates": loop.last_attribution.not_candidates}
    for stale in out.glob("candidates_step*.png"):
        try:
            if int(stale.stem.split("step")[-1]) > len(loop.steps):
                stale.unlink()
        except ValueError:
            continue
    ctx = EffectContext(res.project)
    c = {
        "kind": "diagnose", "project": res.project, "scenario": res.scenario, "res": res,
        "measured": res.measured, "figs": figs, "steps": steps, "last": last,
        "start": _map_ctx(loop.start_map), "final": _map_ctx(loop.final_map),
        "steps_table": _records(loop.steps_table()), "stop": loop.stop_reason,
        "rules": RULES, "catalogue": _catalogue(ctx, res.scenario), "tie_corr": TIE_CORR,
        "margin": res.margin, "version": __version__,
        "ident": ident_context(loop.steps[0], out, out / "next_measurement.csv")
        if loop.steps and loop.steps[0].identify is not None else None,
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
    }
    html = _env().get_template("diagnose.html.j2").render(c=c)
    files.append(write_text(out / "index.html", html))
    ident = c["ident"]
    if isinstance(ident, dict):
        files.append(out / str(ident["fig"]))
    files += [out / f for f in figs.values()] + [out / s["fig"] for s in steps]
    if last:
        files.append(out / last["fig"])
    return files


def fig_selftest(res: SelftestResult, path: Path) -> str:
    fig = _fig(7.5, 4.0)
    ax = fig.add_subplot()
    names = [c.effect for c in res.cases]
    x = np.arange(len(names))
    before = [c.loop.start_map.stats["nrmse"] if c.loop else math.nan for c in res.cases]
    after = [c.loop.final_map.stats["nrmse"] if c.loop else math.nan for c in res.cases]
    ax.bar(x - 0.2, before, 0.4, label="before (model without the effect)", color="tab:red")
    ax.bar(x + 0.2, after, 0.4, label="after the loop", color="tab:green")
    for i, c in enumerate(res.cases):
        ax.annotate("✓" if c.correct else ("✗" if c.distinguishable else "·"), (x[i], before[i]),
                    ha="center", va="bottom")
    ax.set_xticks(x, names, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("nRMSE against the synthetic measurement (–)")
    ax.set_title(f"Hidden-effect self-test (noise {res.noise:.0%})")
    ax.legend(fontsize=8)
    return _save(fig, path)


def write_selftest_report(res: SelftestResult, out: Path) -> list[Path]:
    from radtree.diagnose.outcome import SNR_MIN

    fig = fig_selftest(res, out / "selftest.png") if res.cases else None
    c = {
        "kind": "selftest", "project": res.project, "scenario": res.scenario, "res": res,
        "table": _records(res.table()), "fig": fig, "skipped": res.skipped,
        "snr_min": SNR_MIN, "tie_corr": TIE_CORR, "version": __version__,
        "campaign": res.campaign,
        "catalogue": _catalogue(EffectContext(res.project), res.scenario),
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
    }
    html = _env().get_template("diagnose.html.j2").render(c=c)
    files = [write_text(out / "selftest.html", html)]
    if fig:
        files.append(out / fig)
    return files
