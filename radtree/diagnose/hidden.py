"""Hidden-effect self-test: can the loop find an effect we hid in synthetic measurements?

For each effect X of the catalogue (or of ``effects``) that applies to the scenario:

1. the *base* is the scenario with X off (switched off if the scenario has it);
2. the *truth* is the base with X on at its reference strength, simulated with a different seed
   (``seed + TRUTH_SEED_OFFSET``: the model never sees the truth's Monte Carlo noise), and the
   synthetic measurement is the truth's hourly grid mean × (1 + noise · N(0, 1)) (seeded; the
   per-row daily means likewise from the hourly row means) — written to
   ``PROJECT/diagnose/selftest/<X>.csv`` and read back through
   :func:`radtree.measurements.load_measured`;
3. **before any loop runs**, X is declared *distinguishable* when both hold:

   * **apart from every other explanation**: X's signature s lies at least ``SNR_MIN`` (3)
     noise units, counted over *all* the measured values, from the best fit of every other
     candidate — z = min_Y min_a ‖(s − p_Y(a)) / σ‖ ≥ 3 over the other candidates Y and the
     predictions p_Y(a) the loop's fit can make with them (an on/off effect its signature, a
     linear one its non-negative bounded amplitude, a searched one every strength it scans),
     and from no change (‖s/σ‖ ≥ 3) (:func:`~radtree.diagnose.identify.nearest_snr`). z² is
     the χ² by which fitting X beats fitting Y on noiseless data; the loop fits one effect at
     a time, so this is what naming X at the first step needs. It replaces a per-value SNR
     (many readings each below the noise add up) and a pairwise correlation cut (a
     correlation decides nothing without the signal's size). The table also gives the
     stricter joint number — the part of s outside the span of *all* the others' signatures
     together (:func:`~radtree.diagnose.identify.unique_snr`, the z-score of X's amplitude
     in a joint unconstrained fit, i.e. SNR·√(1 − R²), R² the squared multiple correlation);
   * **within the loop's reach**: fitting X is expected to lower the loop's RMSE by more than
     its margin — the signature's RMS over the values ≥ √((1 − margin)⁻² − 1) × the noise RMS
     (0.33 × for the default 5 %).

   σ_i = √((noise·E_i)² + noise_lux² + 2·se_i²), E_i the expected truth and se_i the Monte
   Carlo standard error (the truth's and the model's own noise); in a campaign the values
   are noise-weighted (:meth:`~.campaign_sim.CampaignSimulator.set_weights`);
4. the diagnosis loop runs from the base against the synthetic measurement.

The test passes when every distinguishable X is named by the first step; the table also shows
the effects named for the others, whether the gap shrank at each step, and the fitted strength.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario
from radtree.diagnose.attribution import (
    DEFAULT_MARGIN,
    Signature,
    compute_signatures,
    cosine,
    signature_scenarios,
)
from radtree.diagnose.campaign_sim import CampaignSimulator, campaign_synthetic
from radtree.diagnose.effects import EFFECTS, Effect, EffectContext, candidates
from radtree.diagnose.identify import DEFAULT_NOISE, nearest_snr, noise_sigma, unique_snr
from radtree.diagnose.measured import Measured, load_measurements
from radtree.diagnose.options import DEFAULT_OPTIONS, DiagnoseOptions
from radtree.diagnose.outcome import (
    SNR_MIN,
    HiddenCase,
    SelftestResult,
    pick_scenario,
    resolve_project,
)
from radtree.diagnose.parallel import TracePool
from radtree.diagnose.simulate import Run, Simulator
from radtree.errors import RadtreeError
from radtree.fileio import atomic_path, write_text

log = logging.getLogger(__name__)

TRUTH_SEED_OFFSET = 7919


def _base(ctx: EffectContext, effect: Effect, start: Scenario) -> Scenario:
    """The scenario ``effect`` is hidden in: ``start`` with it off."""
    base = effect.switch_off(ctx, start) if effect.is_on(ctx, start) else start
    if base is not start:
        base = Scenario(f"{start.name}-no-{effect.name}", base.model, base.reflection, base.sky,
                        base.form, f"{start.name} with {effect.name} off", base.switches)
    return base


def _ahead(ctx: EffectContext, start: Scenario, effects: Iterable[Effect]
           ) -> tuple[list[Scenario], list[Scenario]]:
    """What the decisions and the truths will simulate: every base with its candidates'
    switched scenarios, and every truth."""
    model, truths = [start], []
    for e in effects:
        if e.applies(ctx, start):
            continue
        base = _base(ctx, e, start)
        cands, _ = candidates(ctx, base)
        model += [base] + signature_scenarios(ctx, base, cands)
        truths.append(e.switch_on(ctx, base, e.reference(ctx, base)))
    return model, truths


def _decide(sim: Simulator, *, ctx: EffectContext, effect: Effect, start: Scenario,
            noise: float, noise_lux: float | np.ndarray = 0.0,
            margin: float = DEFAULT_MARGIN) -> HiddenCase:
    base = _base(ctx, effect, start)
    ref = effect.reference(ctx, base)
    truth = effect.switch_on(ctx, base, ref)
    base_run = sim.run(base)
    cands, _ = candidates(ctx, base)
    if effect not in cands:
        raise RadtreeError(f"self-test: {effect.name} is still on after switching it off "
                           "(catalogue bug)")
    sigs = compute_signatures(sim, ctx, base, base_run, cands)
    return _verdict(effect, ctx=ctx, base=base, truth=truth, ref=ref, sigs=sigs,
                    base_run=base_run, noise=noise, noise_lux=noise_lux, margin=margin)


def _verdict(effect: Effect, *, ctx: EffectContext, base: Scenario, truth: Scenario,
             ref: float | None, sigs: dict[str, Signature], base_run: Run, noise: float,
             noise_lux: float | np.ndarray, margin: float) -> HiddenCase:
    """The module doc's rule on the signatures of ``base``'s candidates."""
    sx = sigs[effect.name].reference_hourly()
    expected = base_run.lux + sx
    se = np.nan_to_num(base_run.stderr, nan=0.0)
    sigma = np.maximum(noise_sigma(expected, se, noise, noise_lux), 1e-9)
    noise_rms = float(np.sqrt(np.mean(sigma ** 2)))
    rms = float(np.sqrt(np.mean(sx ** 2)))
    others = {n: s for n, s in sigs.items() if n != effect.name}
    combined = unique_snr(sx, None, sigma)
    joint = unique_snr(sx, np.vstack([s.hourly for s in others.values()]).T
                       if others else None, sigma)
    near = {n: nearest_snr(sx, alternatives(s, sx, sigma), sigma) for n, s in others.items()}
    nearest = min(near, key=lambda k: near[k]) if near else ""
    z = min(combined, near[nearest]) if nearest else combined
    corr = {n: cosine(sx, s.reference_hourly()) for n, s in others.items()}
    corr = {k: v for k, v in corr.items() if math.isfinite(v)}
    most = max(corr, key=lambda k: corr[k]) if corr else ""
    cmax = corr[most] if most else math.nan
    need = margin_snr(margin)
    reasons = []
    if not z >= SNR_MIN:
        reasons.append(f"only {z:.1f} σ from " + (f"{nearest}'s best fit" if nearest and
                                                   near[nearest] <= combined else "no change")
                       + f" (< {SNR_MIN:g})")
    if not rms >= need * noise_rms:
        reasons.append(f"signature RMS {rms:.0f} lx < {need:.2f} × noise RMS {noise_rms:.0f} lx "
                       f"(the loop's {margin:.0%} margin)")
    st = effect.strength(ctx, base)
    stext = "on" if st is None or ref is None else st.text(ref)
    return HiddenCase(effect.name, base, truth, ref, stext, rms, noise_rms, cmax, most,
                      not reasons, "; ".join(reasons) or
                      f"{z:.1f} σ from the nearest other candidate's best fit ("
                      f"{nearest or 'none'}; {combined:.1f} σ from no change), signature RMS "
                      f"{rms / noise_rms:.2f} × noise; max correlation {cmax:.2f} "
                      f"({most or 'no other candidate'})", z, combined, joint, nearest)


def alternatives(sig: Signature, target: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """What the loop's fit of ``sig`` can predict for a residual ``target`` (k × values):
    an on/off effect its signature; a linear one the non-negative, bounded amplitude fitted
    (noise-weighted) to the target; a searched one every strength it scans."""
    if sig.kind == "binary" or sig.strength is None:
        return sig.hourly[:1]
    if sig.kind == "linear":
        x, w = sig.hourly[0], 1.0 / sigma ** 2
        den = float(np.sum(w * x * x))
        a = float(np.sum(w * x * target) / den) if den > 0 else 0.0
        a = float(np.clip(a, 0.0, sig.strength.hi / float(sig.strengths[0])))
        return (a * x)[None, :]
    return sig.choices()[1]


def margin_snr(margin: float) -> float:
    """The per-value signal-to-noise ratio (RMS over the values) at which fitting the effect is
    expected to lower the loop's RMSE by the relative ``margin``: 1 − 1/√(1 + q²) = margin."""
    return math.sqrt((1.0 - margin) ** -2 - 1.0)


def _synthetic(truth_sim: Simulator, case: HiddenCase, *, noise: float, seed: int, index: int,
               folder: Path | None, project: Project, noise_lux: float = 0.0) -> Measured:
    """The truth's run with seeded relative noise: the synthetic measurement of ``case``
    (written to ``folder/<effect>.csv`` and read back when ``folder`` is given)."""
    run = truth_sim.run(case.truth)
    rng = np.random.default_rng([int(seed), 4242, index])
    if isinstance(truth_sim, CampaignSimulator):
        return campaign_synthetic(truth_sim, case.truth, run, noise, noise_lux, rng,
                                  None if folder is None else folder / f"{case.effect}.csv",
                                  f"{case.base.name} + {case.effect} ({case.strength_text}), "
                                  f"seed {seed}")
    hourly = run.lux * (1.0 + noise * rng.standard_normal(len(run.lux)))
    rows_h = run.rows * (1.0 + noise * rng.standard_normal(run.rows.shape))
    counts = truth_sim.sensors_per_row()
    rows = pd.DataFrame({"row": list(rows_h.columns),
                         "sensors": [counts.get(r, 1) for r in rows_h.columns],
                         "measured_mean_lux": rows_h.mean(axis=0).to_numpy(float)})
    times = truth_sim.hours
    if folder is None:
        return Measured(tuple(times), hourly, f"synthetic ({case.effect})", "lux", "mean",
                        rows, None)
    folder.mkdir(parents=True, exist_ok=True)
    mpath = folder / f"{case.effect}.csv"
    rpath = folder / f"{case.effect}_rows.csv"
    head = (f"# Synthetic measurement: {case.base.name} + {case.effect} ({case.strength_text}),"
            f" seed {seed}, noise {noise:.1%}\n# Units: lux\n")
    write_text(mpath, head + "time,measured_lux\n"
               + "".join(f"{t},{v:.1f}\n" for t, v in zip(times, hourly)))
    write_text(rpath, head + "row,sensors,measured_mean_lux\n" + "".join(
        f"{r.row},{int(r.sensors)},{r.measured_mean_lux:.1f}\n" for r in rows.itertuples()))
    return load_measurements(project, mpath, None, counts, rows_path=rpath)



@dataclass
class _Plan:
    """What a self-test will do: the project and start, the effects to hide, the model's and
    the truth's simulators (different seeds), the noise and where it writes."""

    project: Project
    start: Scenario
    ctx: EffectContext
    effects: tuple[Effect, ...]
    sim: Simulator
    truth_sim: Simulator
    noise: float
    noise_lux: float
    out: Path
    options: DiagnoseOptions
    t0: float = field(default_factory=time.perf_counter)


def selftest(project: str | os.PathLike | Project, *, noise: float | None = None,
             noise_lux: float = 0.0, resimulate: bool = False,
             options: DiagnoseOptions = DEFAULT_OPTIONS) -> SelftestResult:
    """Hide each effect of ``options.effects`` (default: the catalogue) in synthetic
    measurements and check the loop names it.

    ``noise``: relative 1-σ noise of each synthetic value (default: the campaign's, else
    ``DEFAULT_NOISE``); ``noise_lux``: absolute floor (lux). ``resimulate``: re-simulate every
    candidate's signature at every step of each loop (default: after the first step the loop
    ranks with the first step's signatures, :class:`~radtree.diagnose.loop.LoopOptions`'s
    ``first_step_signatures`` — the first step, the one the test judges, is exact either way,
    and every winner is re-simulated). ``options.workers``: processes tracing ahead
    (:class:`~radtree.diagnose.parallel.TracePool`) — same numbers. ``options.campaign``:
    measure what the campaign measures (its days, hours, sensor groups; its noise unless
    ``noise`` is given); default the project's façade grid mean at its hours."""
    plan = _plan(project, noise, noise_lux, options)
    with TracePool(options.workers) as pool:
        cases, skipped = _decide_all(plan, pool)
        _diagnose_cases(plan, pool, cases, resimulate)
    return _publish(plan, cases, skipped)


def _plan(project: str | os.PathLike | Project, noise: float | None, noise_lux: float,
          options: DiagnoseOptions) -> _Plan:
    campaign = options.campaign
    if campaign is not None and noise is None:
        noise, noise_lux = campaign.noise, campaign.noise_lux
    noise = DEFAULT_NOISE if noise is None else noise
    if not 0 <= noise < 1:
        raise RadtreeError(f"noise must be a fraction in [0, 1), got {noise}")
    t0 = time.perf_counter()
    proj = resolve_project(project)
    hours = tuple(proj.site.hours)
    sim: Simulator
    truth_sim: Simulator
    if campaign is None:
        sim = Simulator(proj, hours, options.engine, options.rays, options.seed)
        truth_sim = Simulator(proj, hours, options.engine, sim.rays,
                              int(sim.seed or 0) + TRUTH_SEED_OFFSET)
    else:
        sim = CampaignSimulator(proj, hours, options.engine, options.rays, options.seed,
                                campaign=campaign)
        truth_sim = CampaignSimulator(proj, hours, options.engine, sim.rays,
                                      int(sim.seed or 0) + TRUTH_SEED_OFFSET, campaign=campaign)
    return _Plan(proj, pick_scenario(proj, options.scenario), EffectContext(proj),
                 options.effects if options.effects is not None else EFFECTS, sim, truth_sim,
                 noise, noise_lux, options.folder(proj.root), options, t0)


def _decide_all(plan: _Plan, pool: TracePool) -> tuple[list[HiddenCase], dict[str, str]]:
    """Before any loop runs: which hidden effects are distinguishable (module doc, 3)."""
    sim, truth_sim, start = plan.sim, plan.truth_sim, plan.start
    if pool.workers > 1:
        log.info("tracing ahead in %d processes: the bases, every candidate's signature "
                 "scenarios and the truths", pool.workers)
        model, truths = _ahead(plan.ctx, start, plan.effects)
        pool.prefetch(sim, model)
        pool.prefetch(truth_sim, truths)
    noise_lux: float | np.ndarray = plan.noise_lux
    if isinstance(sim, CampaignSimulator) and isinstance(truth_sim, CampaignSimulator):
        assert plan.options.campaign is not None
        truth_sim.weights = sim.set_weights(start, plan.noise, plan.noise_lux)
        log.info("campaign %s — %d observations, compared in noise-weighted lux (each value "
                 "÷ its noise)", plan.options.campaign.summary(), len(sim.labels))
        for note in sim.notes:
            log.info("  note: %s", note)
        if sim.weights is not None:
            noise_lux = plan.noise_lux * sim.weights
    log.info("self-test %s: scenario %s, noise %.1f%%, engine %s%s", plan.project.name,
             start.name, 100 * plan.noise, sim.engine_name,
             f", {sim.rays} rays/sensor, seed {sim.seed} (truth seed {truth_sim.seed})"
             if sim.seeded else "")
    log.info("  deciding which hidden effects are distinguishable (before any diagnosis runs):")
    skipped: dict[str, str] = {}
    cases: list[HiddenCase] = []
    for e in plan.effects:
        why = e.applies(plan.ctx, start)
        if why:
            skipped[e.name] = why
            log.info("  %s: skipped (%s)", e.name, why)
            continue
        case = _decide(sim, ctx=plan.ctx, effect=e, start=start, noise=plan.noise,
                       noise_lux=noise_lux, margin=plan.options.margin)
        cases.append(case)
        log.info("  %-26s %s: %s", e.name, "distinguishable" if case.distinguishable
                 else "not distinguishable", case.reason)
    return cases, skipped


def _diagnose_cases(plan: _Plan, pool: TracePool, cases: list[HiddenCase],
                    resimulate: bool) -> None:
    """Each case's synthetic measurement, then the loop from its base (in the workers)."""
    seed = int(plan.sim.seed or 0)
    for i, case in enumerate(cases):
        case.measured = _synthetic(
            plan.truth_sim, case, noise=plan.noise, seed=seed, index=i,
            folder=plan.out / "selftest" if plan.options.write else None,
            project=plan.project, noise_lux=plan.noise_lux)
    if pool.workers > 1:
        log.info("  diagnosing the %d synthetic measurements in %d processes", len(cases),
                 pool.workers)
    loops = pool.loops(plan.sim, plan.project,
                       [(c.base, c.measured) for c in cases if c.measured is not None],
                       plan.options.loop(catalogue=EFFECTS, first_step_signatures=not resimulate))
    for case, lp in zip(cases, loops):
        case.loop = lp
        log.info("  hidden %s (%s) in %s:", case.effect, case.strength_text, case.base.name)
        verdict = ("correct" if case.correct else
                   ("MISNAMED" if case.distinguishable else "not distinguishable"))
        tie = lp.steps[0].tie_with if lp.steps else []
        log.info("    named %s%s — %s; nRMSE %.3f → %.3f%s", case.named,
                 f" (tie: {', '.join(tie)})" if tie else "", verdict,
                 lp.start_map.stats["nrmse"], lp.final_map.stats["nrmse"],
                 f" via {' + '.join(s.effect for s in lp.steps)}" if lp.steps else "")


def _publish(plan: _Plan, cases: list[HiddenCase], skipped: dict[str, str]) -> SelftestResult:
    """The result; with ``options.write``: ``selftest.csv`` and the report."""
    sim, options = plan.sim, plan.options
    res = SelftestResult(plan.project, plan.start, plan.noise, cases, skipped,
                         time.perf_counter() - plan.t0,
                         sim.traced_runs + plan.truth_sim.traced_runs,
                         plan.out if options.write else None,
                         engine=sim.engine_name, rays=sim.rays if sim.seeded else None,
                         seed=sim.seed if sim.seeded else None,
                         campaign=options.campaign.summary() if options.campaign else "",
                         margin=options.margin)
    if options.write:
        from radtree.diagnose.report import write_selftest_report

        plan.out.mkdir(parents=True, exist_ok=True)
        path = plan.out / "selftest.csv"
        with atomic_path(path) as tmp:
            res.table().to_csv(tmp, index=False, float_format="%.6g")
        res.files = [path] + write_selftest_report(res, plan.out)
        res.seconds = time.perf_counter() - plan.t0
        log.info("  wrote %s", path)
    return res
