"""``diagnose``: the model–measurement discrepancy workflow on a project, with its outputs.

Writes into ``PROJECT/diagnose/``: ``steps.csv`` (one row per added effect), ``residuals.csv``
(residual by hour at every step), ``candidates.csv`` (every step's ranking), the step project
files ``radtree.step<k>.toml`` and ``index.html`` with its PNG figures.
"""

from __future__ import annotations

import logging
import math
import os
import time
from pathlib import Path

import pandas as pd

from radtree.config import Project, Scenario
from radtree.config.step_project import write_step_project
from radtree.diagnose.campaign import Campaign
from radtree.diagnose.campaign_sim import CampaignSimulator, campaign_readings
from radtree.diagnose.effects import EFFECTS, EffectContext, candidates
from radtree.diagnose.loop import LoopResult, OnStep, run_loop
from radtree.diagnose.measured import Measured, load_measurements
from radtree.diagnose.options import DEFAULT_OPTIONS, DiagnoseOptions
from radtree.diagnose.outcome import DiagnoseResult, pick_scenario, resolve_project
from radtree.diagnose.parallel import TracePool
from radtree.diagnose.simulate import Simulator
from radtree.errors import ConfigError
from radtree.fileio import atomic_path

log = logging.getLogger(__name__)


def diagnose(project: str | os.PathLike | Project, *, measured: str | os.PathLike | None = None,
             units: str | None = None, options: DiagnoseOptions = DEFAULT_OPTIONS
             ) -> DiagnoseResult:
    """Run the discrepancy loop from ``options.scenario`` (default: the project's first)
    against the measurements (default: ``[project] measured``; ``units`` when the file does
    not state them) and write ``PROJECT/diagnose/`` (:class:`DiagnoseOptions`).

    The engine defaults to the seeded engine (``rays`` per sensor, default 1024, fixed
    ``seed``, default the project's — so switched runs share random numbers).
    ``options.campaign``: diagnose against the campaign's readings (every day, hour and
    sensor group; values compared in noise-weighted lux) instead of the measured file.
    ``options.workers``: processes tracing each step's candidate signatures ahead — the same
    numbers either way.
    """
    t0 = time.perf_counter()
    proj = resolve_project(project)
    sc = pick_scenario(proj, options.scenario)
    if options.campaign is not None:
        if measured is not None:
            raise ConfigError("--measured does not go with --campaign (the campaign names its "
                              "measured files)")
        sim, meas = _campaign_side(proj, sc, options.campaign, options)
    else:
        sim, meas = _file_side(proj, measured, units, options)
    log.info("diagnose %s: scenario %s (%s, %s), engine %s%s, %d hours, measured mean %.0f lx",
             proj.name, sc.name, sc.model, sc.reflection, sim.engine_name,
             f", {sim.rays} rays/sensor, seed {sim.seed}" if sim.seeded else "",
             len(meas.times), meas.mean)
    loop = _execute(sim, proj, sc, meas, options)
    _, why = candidates(EffectContext(proj), sc, options.effects or EFFECTS)
    out = options.folder(proj.root)
    res = DiagnoseResult(proj, sc, sim.engine_name, sim.rays if sim.seeded else None,
                         sim.seed if sim.seeded else None, meas, loop,
                         out if options.write else None, 0.0, sim.traced_runs, sim.cache_hits,
                         why, margin=options.margin)
    log.info("  stop: %s", loop.stop_reason)
    res.seconds = time.perf_counter() - t0
    if options.write:
        res.files = write_outputs(res, out)
        log.info("  wrote %s and %s", out / "index.html", out / "steps.csv")
    return res


def _campaign_side(proj: Project, sc: Scenario, campaign: Campaign, options: DiagnoseOptions
                   ) -> tuple[Simulator, Measured]:
    """The campaign's simulator (noise-weighted) and its readings as the measured side."""
    csim = CampaignSimulator(proj, (), options.engine, options.rays, options.seed,
                             campaign=campaign)
    weights = csim.set_weights(sc, campaign.noise, campaign.noise_lux)
    meas = Measured(tuple(csim.labels), campaign_readings(csim) * weights,
                    str(campaign.source or campaign.name), "noise-weighted lux",
                    "campaign", sun=csim.sun_positions(sc), noise=campaign.noise,
                    noise_lux=campaign.noise_lux)
    log.info("campaign %s: %d observations", campaign.summary(), len(csim.labels))
    for note in csim.notes:
        log.info("  note: %s", note)
    return csim, meas


def _file_side(proj: Project, measured: str | os.PathLike | None, units: str | None,
               options: DiagnoseOptions) -> tuple[Simulator, Measured]:
    """The measured file matched to the project's hours, and a simulator of those hours."""
    sim = Simulator(proj, tuple(proj.site.hours), options.engine, options.rays, options.seed)
    meas = load_measurements(proj, measured, units, sim.sensors_per_row())
    for note in meas.notes():
        log.info("  note: %s", note)
    return Simulator(proj, meas.times, options.engine, sim.rays, sim.seed), meas


def _execute(sim: Simulator, proj: Project, sc: Scenario, meas: Measured,
             options: DiagnoseOptions) -> LoopResult:
    """The loop, with each step's project file written (when writing) and the candidates'
    signatures traced ahead in ``options.workers`` processes."""
    on_step = _step_writer(proj, options.folder(proj.root)) if options.write else None
    with TracePool(options.workers) as pool:
        if pool.workers > 1:
            sim.ahead = pool.prefetch
        try:
            return run_loop(sim, ctx=EffectContext(proj), start=sc, measured=meas,
                            options=options.loop(), on_step=on_step)
        finally:
            sim.ahead = None


def _step_writer(proj: Project, out: Path) -> OnStep:
    """Writes step ``k``'s scenario to ``out/radtree.step<k>.toml`` and reads it back."""
    def on_step(k: int, new: Scenario) -> tuple[Scenario, Path | None]:
        path = out / f"radtree.step{k}.toml"
        header = (f"Written by radtree diagnose, step {k}: the project {proj.source.name} with "
                  f"scenario {new.name}\n({new.description}).\nRun it with: radtree simulate "
                  f"{path} -s {new.name}")
        return write_step_project(proj, new, path, header), path

    return on_step


def write_outputs(res: DiagnoseResult, out: Path) -> list[Path]:
    from radtree.diagnose.report import write_diagnose_report

    out.mkdir(parents=True, exist_ok=True)
    files = []
    steps = res.loop.steps_table()
    files.append(_csv(steps, out / "steps.csv"))
    files.append(_csv(residual_table(res.loop), out / "residuals.csv"))
    files.append(_csv(candidates_table(res.loop), out / "candidates.csv"))
    # step files of an earlier, longer run would look current: remove them
    n = len(res.loop.steps)
    for p in out.glob("radtree.step*.toml"):
        try:
            k = int(p.stem.split("step")[-1])
        except ValueError:
            continue
        if k > n:
            p.unlink()
    files += [s.project_file for s in res.loop.steps if s.project_file is not None]
    files += write_diagnose_report(res, out)
    return files


def _csv(df: pd.DataFrame, path: Path) -> Path:
    with atomic_path(path) as tmp:
        df.to_csv(tmp, index=False, float_format="%.6g")
    return path


def residual_table(loop: LoopResult) -> pd.DataFrame:
    """Residual by hour at the start and after each step (long table)."""
    frames = []
    maps = [(0, "start", loop.start.name, loop.start_map)]
    maps += [(s.number, s.effect, s.scenario_after.name, s.map_after) for s in loop.steps]
    for k, eff, name, dm in maps:
        h = dm.hourly.copy()
        h.insert(0, "scenario", name)
        h.insert(0, "effect_added", eff)
        h.insert(0, "step", k)
        frames.append(h)
    return pd.concat(frames, ignore_index=True)


def candidates_table(loop: LoopResult) -> pd.DataFrame:
    frames = []
    atts = [(s.number, s.attribution) for s in loop.steps]
    if loop.last_attribution is not None:
        atts.append((len(loop.steps) + 1, loop.last_attribution))
    for k, att in atts:
        t = att.table()
        t.insert(0, "step", k)
        t["chosen"] = [att.winner is not None and e == att.winner.effect
                       and k <= len(loop.steps) for e in t["effect"]]
        frames.append(t)
    if not frames:
        return pd.DataFrame(columns=["step", "rank", "effect"])
    return pd.concat(frames, ignore_index=True)


def format_steps(res: LoopResult) -> list[str]:
    """Plain-text table of the steps (for the terminal)."""
    lines = [f"  start {res.start.name}: nRMSE {res.start_map.stats['nrmse']:.3f}, nMBE "
             f"{res.start_map.stats['nmbe']:+.3f}"]
    for s in res.steps:
        tie = f" (tie: {', '.join(s.tie_with)})" if s.tie_with else ""
        ef = s.explained_fraction
        lines.append(f"  step {s.number}: + {s.effect} [{s.strength_text}]{tie}: nRMSE "
                     f"{s.rmse_before:.3f} → {s.rmse_after:.3f}, CV nRMSE {s.cv_rmse_before:.3f}"
                     f" → {s.cv_rmse_after:.3f}, explained "
                     + (f"{ef:.0%}" if math.isfinite(ef) else "n/a"))
        if s.identify is not None and s.identify.partners(s.effect):
            lines.append(f"    {s.separability}")
    lines.append(f"  stop: {res.stop_reason}")
    return lines
