"""``diagnose``: the model–measurement discrepancy workflow on a project, with its outputs.

Writes into ``PROJECT/diagnose/``: ``steps.csv`` (one row per added effect), ``residuals.csv``
(residual by hour at every step), ``candidates.csv`` (every step's ranking), the step project
files ``radtree.step<k>.toml`` and ``index.html`` with its PNG figures.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Iterable
from pathlib import Path

import pandas as pd

from radtree.config import Project, Scenario
from radtree.diagnose.attribution import DEFAULT_MARGIN
from radtree.diagnose.campaign import Campaign
from radtree.diagnose.campaign_sim import CampaignSimulator, campaign_readings
from radtree.diagnose.effects import EFFECTS, Effect, EffectContext, candidates
from radtree.diagnose.loop import (
    DEFAULT_MAX_STEPS,
    LoopResult,
    Measured,
    load_measurements,
    run_loop,
    write_step_project,
)
from radtree.diagnose.outcome import DiagnoseResult, Echo, pick_scenario, resolve_project
from radtree.diagnose.parallel import TracePool
from radtree.diagnose.simulate import Simulator
from radtree.errors import ConfigError
from radtree.fileio import atomic_path


def diagnose(project: str | os.PathLike | Project, measured: str | os.PathLike | None = None,
             units: str | None = None, scenario: str | None = None, engine: str | None = None,
             rays: int | None = None, seed: int | None = None, margin: float = DEFAULT_MARGIN,
             max_steps: int = DEFAULT_MAX_STEPS, effects: Iterable[Effect] = EFFECTS,
             out_dir: str | os.PathLike | None = None, write: bool = True,
             echo: Echo | None = print, campaign: Campaign | None = None,
             workers: int | None = None) -> DiagnoseResult:
    """Run the discrepancy loop from ``scenario`` (default: the project's first) against the
    measurements (default: ``[project] measured``) and write ``PROJECT/diagnose/``.

    ``engine``: a registered engine name (default: the seeded engine — ``rays`` per sensor,
    default 1024, fixed ``seed``, default the project's — so switched runs share random numbers). ``margin``: relative CV improvement a step must bring.
    ``campaign``: diagnose against the campaign's readings (every day, hour and sensor group;
    values compared in noise-weighted lux) instead of the project's measured file.
    ``workers``: processes tracing each step's candidate signatures ahead (default: the usable
    cores, at most 4; 1 = all in this process) — the same numbers either way.
    """
    t0 = time.perf_counter()
    say = echo or (lambda s: None)
    proj = resolve_project(project)
    sc = pick_scenario(proj, scenario)
    out = Path(out_dir) if out_dir is not None else proj.root / "diagnose"
    ctx = EffectContext(proj)
    sim: Simulator
    if campaign is not None:
        if measured is not None:
            raise ConfigError("--measured does not go with --campaign (the campaign names its "
                              "measured files)")
        csim = CampaignSimulator(proj, (), engine, rays, seed, campaign=campaign)
        weights = csim.set_weights(sc, campaign.noise, campaign.noise_lux)
        sim = csim
        meas = Measured(tuple(csim.labels), campaign_readings(csim) * weights,
                        str(campaign.source or campaign.name), "noise-weighted lux",
                        "campaign", sun=csim.sun_positions(sc), noise=campaign.noise,
                        noise_lux=campaign.noise_lux)
        say(f"campaign {campaign.summary()}: {len(csim.labels)} observations")
        for note in csim.notes:
            say(f"  note: {note}")
    else:
        sim = Simulator(proj, tuple(proj.site.hours), engine, rays, seed)
        meas = load_measurements(proj, measured, units, sim.sensors_per_row())
        for note in meas.notes():
            say(f"  note: {note}")
        sim = Simulator(proj, meas.times, engine, sim.rays, sim.seed)
    say(f"diagnose {proj.name}: scenario {sc.name} ({sc.model}, {sc.reflection}), engine "
        f"{sim.engine_name}" + (f", {sim.rays} rays/sensor, seed {sim.seed}" if sim.seeded else "")
        + f", {len(meas.times)} hours, measured mean {meas.mean:.0f} lx")
    _, why = candidates(ctx, sc, effects)

    def on_step(k: int, new: Scenario) -> tuple[Scenario, Path | None]:
        if not write:
            return new, None
        path = out / f"radtree.step{k}.toml"
        header = (f"Written by radtree diagnose, step {k}: the project {proj.source.name} with "
                  f"scenario {new.name}\n({new.description}).\nRun it with: radtree simulate "
                  f"{path} -s {new.name}")
        return write_step_project(proj, new, path, header), path

    with TracePool(workers) as pool:   # the candidates' signatures traced ahead, in parallel
        if pool.workers > 1:
            sim.ahead = pool.prefetch
        try:
            loop = run_loop(sim, ctx, sc, meas, margin, max_steps, effects, echo=echo,
                            on_step=on_step)
        finally:
            sim.ahead = None
    res = DiagnoseResult(proj, sc, sim.engine_name, sim.rays if sim.seeded else None,
                         sim.seed if sim.seeded else None, meas, loop,
                         out if write else None, 0.0, sim.traced_runs, sim.cache_hits, why,
                         margin=margin)
    say(f"  stop: {loop.stop_reason}")
    res.seconds = time.perf_counter() - t0
    if write:
        res.files = write_outputs(res, out)
        say(f"  wrote {out / 'index.html'} and {out / 'steps.csv'}")
    return res


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
