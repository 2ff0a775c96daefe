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

import math
import os
import time
from collections.abc import Iterable
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
from radtree.diagnose.campaign import Campaign
from radtree.diagnose.campaign_sim import CampaignSimulator, campaign_synthetic
from radtree.diagnose.effects import EFFECTS, Effect, EffectContext, candidates
from radtree.diagnose.identify import DEFAULT_NOISE, nearest_snr, noise_sigma, unique_snr
from radtree.diagnose.loop import (
    DEFAULT_MAX_STEPS,
    Measured,
    load_measurements,
)
from radtree.diagnose.outcome import (
    SNR_MIN,
    Echo,
    HiddenCase,
    SelftestResult,
    pick_scenario,
    resolve_project,
)
from radtree.diagnose.parallel import TracePool
from radtree.diagnose.simulate import Run, Simulator
from radtree.errors import RadtreeError
from radtree.fileio import atomic_path, write_text

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


def _decide(sim: Simulator, ctx: EffectContext, effect: Effect, start: Scenario, noise: float,
            echo: Echo | None, noise_lux: float | np.ndarray = 0.0,
            margin: float = DEFAULT_MARGIN) -> HiddenCase:
    base = _base(ctx, effect, start)
    ref = effect.reference(ctx, base)
    truth = effect.switch_on(ctx, base, ref)
    base_run = sim.run(base)
    cands, _ = candidates(ctx, base)
    if effect not in cands:
        raise RadtreeError(f"self-test: {effect.name} is still on after switching it off "
                           "(catalogue bug)")
    sigs = compute_signatures(sim, ctx, base, base_run, cands, echo)
    return _verdict(effect, ctx, base, truth, ref, sigs, base_run, noise, noise_lux, margin)


def _verdict(effect: Effect, ctx: EffectContext, base: Scenario, truth: Scenario,
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


def _synthetic(truth_sim: Simulator, case: HiddenCase, noise: float, seed: int, index: int,
               folder: Path | None, project: Project, noise_lux: float = 0.0) -> Measured:
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


def selftest(project: str | os.PathLike | Project, scenario: str | None = None,
             effects: Iterable[Effect] | None = None, noise: float | None = None,
             engine: str | None = None, rays: int | None = None, seed: int | None = None,
             margin: float = DEFAULT_MARGIN, max_steps: int = DEFAULT_MAX_STEPS,
             out_dir: str | os.PathLike | None = None, write: bool = True,
             echo: Echo | None = print, campaign: Campaign | None = None,
             noise_lux: float = 0.0, resimulate: bool = False,
             workers: int | None = None) -> SelftestResult:
    """Hide each effect in synthetic measurements and check the loop names it.

    ``resimulate``: re-simulate every candidate's signature at every step of each loop
    (default: after the first step the loop ranks with the first step's signatures,
    :func:`~radtree.diagnose.loop.run_loop`'s ``first_step_signatures`` — the first step, the
    one the test judges, is exact either way, and every winner is re-simulated).
    ``workers``: processes tracing ahead (:class:`~radtree.diagnose.parallel.TracePool`;
    default the usable cores, at most 4; 1: everything in this process) — same numbers.

    ``campaign``: measure what the campaign measures (its days, hours, sensor groups; its
    noise unless ``noise`` is given); default the project's façade grid mean at its hours."""
    if campaign is not None and noise is None:
        noise, noise_lux = campaign.noise, campaign.noise_lux
    noise = DEFAULT_NOISE if noise is None else noise
    if not 0 <= noise < 1:
        raise RadtreeError(f"noise must be a fraction in [0, 1), got {noise}")
    t0 = time.perf_counter()
    say = echo or (lambda s: None)
    proj = resolve_project(project)
    start = pick_scenario(proj, scenario)
    ctx = EffectContext(proj)
    out = Path(out_dir) if out_dir is not None else proj.root / "diagnose"
    hours = tuple(proj.site.hours)
    chosen = tuple(effects) if effects is not None else EFFECTS
    sim: Simulator
    truth_sim: Simulator
    if campaign is None:
        sim = Simulator(proj, hours, engine, rays, seed)
        truth_sim = Simulator(proj, hours, engine, sim.rays,
                              int(sim.seed or 0) + TRUTH_SEED_OFFSET)
    else:
        sim = CampaignSimulator(proj, hours, engine, rays, seed, campaign=campaign)
        truth_sim = CampaignSimulator(proj, hours, engine, sim.rays,
                                      int(sim.seed or 0) + TRUTH_SEED_OFFSET, campaign=campaign)
    with TracePool(workers) as pool:
        if pool.workers > 1:
            say(f"tracing ahead in {pool.workers} processes: the bases, every candidate's "
                "signature scenarios and the truths")
            model, truths = _ahead(ctx, start, chosen)
            pool.prefetch(sim, model)
            pool.prefetch(truth_sim, truths)
        if isinstance(sim, CampaignSimulator) and isinstance(truth_sim, CampaignSimulator):
            assert campaign is not None
            truth_sim.weights = sim.set_weights(start, noise, noise_lux)
            say(f"campaign {campaign.summary()} — {len(sim.labels)} observations, compared in "
                "noise-weighted lux (each value ÷ its noise)")
            for note in sim.notes:
                say(f"  note: {note}")
        skipped: dict[str, str] = {}
        say(f"self-test {proj.name}: scenario {start.name}, noise {noise:.1%}, engine {sim.engine_name}"
            + (f", {sim.rays} rays/sensor, seed {sim.seed} (truth seed {truth_sim.seed})"
               if sim.seeded else ""))
        say("  deciding which hidden effects are distinguishable (before any diagnosis runs):")
        cases: list[HiddenCase] = []
        for e in chosen:
            why = e.applies(ctx, start)
            if why:
                skipped[e.name] = why
                say(f"  {e.name}: skipped ({why})")
                continue
            case = _decide(sim, ctx, e, start, noise, None,
                           noise_lux * sim.weights if isinstance(sim, CampaignSimulator)
                           and sim.weights is not None else noise_lux, margin)
            cases.append(case)
            say(f"  {e.name:26s} {'distinguishable' if case.distinguishable else 'not distinguishable'}"
                f": {case.reason}")
        for i, case in enumerate(cases):
            case.measured = _synthetic(truth_sim, case, noise, int(sim.seed or 0), i,
                                       out / "selftest" if write else None, proj, noise_lux)
        if pool.workers > 1:
            say(f"  diagnosing the {len(cases)} synthetic measurements in {pool.workers} "
                "processes")
        loops = pool.loops(sim, proj, [(c.base, c.measured) for c in cases
                                       if c.measured is not None],
                           margin, max_steps, not resimulate)
        for case, lp in zip(cases, loops):
            case.loop = lp
            say(f"  hidden {case.effect} ({case.strength_text}) in {case.base.name}:")
            verdict = ("correct" if case.correct else
                       ("MISNAMED" if case.distinguishable else "not distinguishable"))
            say(f"    named {case.named}"
                + (f" (tie: {', '.join(lp.steps[0].tie_with)})" if lp.steps and lp.steps[0].tie_with
                   else "")
                + f" — {verdict}; nRMSE {lp.start_map.stats['nrmse']:.3f} → "
                f"{lp.final_map.stats['nrmse']:.3f}"
                + (f" via {' + '.join(s.effect for s in lp.steps)}" if lp.steps else ""))
    res = SelftestResult(proj, start, noise, cases, skipped, time.perf_counter() - t0,
                         sim.traced_runs + truth_sim.traced_runs, out if write else None,
                         engine=sim.engine_name, rays=sim.rays if sim.seeded else None,
                         seed=sim.seed if sim.seeded else None,
                         campaign=campaign.summary() if campaign is not None else "",
                         margin=margin)
    if write:
        from radtree.diagnose.report import write_selftest_report

        out.mkdir(parents=True, exist_ok=True)
        path = out / "selftest.csv"
        with atomic_path(path) as tmp:
            res.table().to_csv(tmp, index=False, float_format="%.6g")
        res.files = [path] + write_selftest_report(res, out)
        res.seconds = time.perf_counter() - t0
        say(f"  wrote {path}")
    return res
