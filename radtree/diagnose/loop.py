"""The diagnosis loop: find the disagreement, name the missing effect, add it, re-simulate.

Each step: simulate the current scenario; map the residual (:mod:`.residuals`); rank the
candidate effects by cross-validated error (:mod:`.attribution`); add the winner at its fitted
strength to the scenario (through ``on_step``, e.g. a new project file
``PROJECT/diagnose/radtree.step<k>.toml`` holding the scenario ``<name>-diag<k>``, written by
:func:`radtree.config.step_project.write_step_project`; the user's file is never touched);
re-simulate; repeat until no candidate lowers the cross-validated RMSE by more than the margin
(default 5 % relative), or ``max_steps``. A winner whose re-simulation at the fitted strength
does not lower the RMSE is rejected and the next improving candidate is tried (so the gap
shrinks at every step). The measured side is :mod:`.measured`. RMSE and MBE are normalised by
the mean measured value (nRMSE, nMBE); illuminances in lux.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario
from radtree.diagnose.attribution import (
    DEFAULT_MARGIN,
    Attribution,
    CandidateFit,
    Signature,
    attribute,
    choose_winner,
)
from radtree.diagnose.effects import EFFECTS, Effect, EffectContext, get_effect
from radtree.diagnose.identify import Identifiability, Interval, step_identifiability
from radtree.diagnose.measured import Measured
from radtree.diagnose.residuals import DisagreementMap, disagreement_map
from radtree.diagnose.simulate import Run, Simulator
from radtree.errors import RadtreeError

log = logging.getLogger(__name__)

DEFAULT_MAX_STEPS = 4
STEP_COLUMNS = ["step", "effect", "explained_fraction", "strength", "rmse_before", "rmse_after",
                "cv_rmse_before", "cv_rmse_after"]
#: ``on_step(k, scenario)`` → the scenario as read back from the step's file, and the file
OnStep = Callable[[int, Scenario], tuple[Scenario, Path | None]]


@dataclass(frozen=True)
class LoopOptions:
    """How the loop decides: ``margin`` (relative CV-RMSE improvement a step must bring, in
    [0, 1)), ``max_steps`` (≥ 1), the ``catalogue`` of candidate effects, and
    ``first_step_signatures`` (rank every later step with the first step's signatures)."""

    margin: float = DEFAULT_MARGIN
    max_steps: int = DEFAULT_MAX_STEPS
    catalogue: tuple[Effect, ...] = EFFECTS
    first_step_signatures: bool = False

    def __post_init__(self) -> None:
        if not 0 <= self.margin < 1:
            raise RadtreeError(f"margin must be in [0, 1), got {self.margin}")
        if self.max_steps < 1:
            raise RadtreeError(f"max_steps must be at least 1, got {self.max_steps}")
        object.__setattr__(self, "catalogue", tuple(self.catalogue))


@dataclass
class Step:
    """One added effect."""

    number: int
    effect: str
    title: str
    strength: float | None
    strength_text: str
    change: str
    why: str
    explained_fraction: float
    rmse_before: float  # normalised (÷ mean measured)
    rmse_after: float
    cv_rmse_before: float
    cv_rmse_after: float
    mbe_before: float
    mbe_after: float
    tie_with: list[str]
    attribution: Attribution
    scenario_before: Scenario
    scenario_after: Scenario
    map_before: DisagreementMap
    map_after: DisagreementMap
    rejected: list[str] = field(default_factory=list)
    project_file: Path | None = None
    identify: Identifiability | None = None
    intervals: dict[str, Interval] = field(default_factory=dict)

    @property
    def separability(self) -> str:
        """"named X, but X and Y are not separable with these data" (or that X is)."""
        return self.identify.sentence(self.effect) if self.identify is not None else ""

    def record(self) -> dict[str, Any]:
        return {"step": self.number, "effect": self.effect,
                "explained_fraction": self.explained_fraction,
                "strength": self.strength if self.strength is not None else math.nan,
                "rmse_before": self.rmse_before, "rmse_after": self.rmse_after,
                "cv_rmse_before": self.cv_rmse_before, "cv_rmse_after": self.cv_rmse_after,
                "mbe_before": self.mbe_before, "mbe_after": self.mbe_after,
                "strength_text": self.strength_text, "change": self.change,
                "tie_with": ";".join(self.tie_with),
                "not_separable_from": ";".join(self.identify.partners(self.effect))
                if self.identify is not None else "",
                "strength_ci_lo": self.intervals[self.effect].lo
                if self.effect in self.intervals else math.nan,
                "strength_ci_hi": self.intervals[self.effect].hi
                if self.effect in self.intervals else math.nan,
                "scenario": self.scenario_after.name,
                "project_file": str(self.project_file) if self.project_file else ""}


@dataclass
class LoopResult:
    start: Scenario
    start_map: DisagreementMap
    steps: list[Step]
    final: Scenario
    final_map: DisagreementMap
    stop_reason: str
    last_attribution: Attribution | None
    runs: dict[str, Run] = field(default_factory=dict)

    def steps_table(self) -> pd.DataFrame:
        recs = [s.record() for s in self.steps]
        cols = STEP_COLUMNS + [c for c in (recs[0] if recs else {}) if c not in STEP_COLUMNS]
        return pd.DataFrame(recs, columns=cols if recs else STEP_COLUMNS)

    def named(self) -> str:
        """The first step's effect (``none`` when no step was taken)."""
        return self.steps[0].effect if self.steps else "none"


def sun_positions(project: Project, sc: Scenario, hours: Iterable[str]
                  ) -> tuple[np.ndarray, np.ndarray]:
    from radtree.light.hours import hour_states

    states = hour_states(project, sc, list(hours))
    return (np.array([s.sun.altitude_deg for s in states]),
            np.array([s.sun.azimuth_deg for s in states]))


def make_map(run: Run, measured: Measured, alt: np.ndarray, az: np.ndarray) -> DisagreementMap:
    return disagreement_map(measured.times, measured=measured.hourly, simulated=run.lux,
                            simulated_se=run.stderr, sun_altitude=alt, sun_azimuth=az,
                            simulated_rows=run.rows, measured_rows=measured.rows_daily,
                            measured_rows_hourly=measured.rows_hourly)


def _row_residual(run: Run, measured: Measured) -> np.ndarray | None:
    if measured.rows_daily is None:
        return None
    sim = run.row_daily()
    md = measured.rows_daily.assign(row=measured.rows_daily["row"].astype(str).str.lower())
    md = md.set_index("row")["measured_mean_lux"]
    if set(md.index) != set(sim.index):
        return None
    return md.reindex(sim.index).to_numpy(float) - sim.to_numpy(float)


def _step_name(base: str, k: int) -> str:
    root = base.split("-diag")[0]
    return f"{root}-diag{k}"


def _why(att: Attribution, w: CandidateFit, dm: DisagreementMap) -> str:
    others = [f for f in att.fits if f is not w]
    nxt = others[0] if others else None
    mm = att.mean_measured
    text = (f"{w.effect} lowers the cross-validated nRMSE from {att.baseline_cv_lux / mm:.3f} "
            f"to {w.cv_rmse_lux / mm:.3f} (leave-one-hour-out) and explains "
            f"{w.explained_fraction:.0%} of the residual's sum of squares"
            + (f" at {w.strength_text}" if w.strength is not None else "") + ".")
    if nxt is not None:
        text += (f" Next best: {nxt.effect} (CV nRMSE {nxt.cv_rmse_lux / mm:.3f}"
                 + (f", signature correlation {nxt.corr_with_winner:.2f}"
                    if math.isfinite(nxt.corr_with_winner) else "") + ").")
    if att.tie_with:
        text += (f" Tie with {', '.join(att.tie_with)}: their signatures correlate above 0.9 "
                 "with the winner's, so the hourly data cannot tell them apart; chosen by the "
                 "lower CV error.")
        if math.isfinite(w.row_rms_after_lux):
            better = [f for f in att.fits if f.effect in att.tie_with
                      and f.row_rms_after_lux < 0.8 * w.row_rms_after_lux]
            if better:
                text += (" The per-row daily means lean towards " + ", ".join(
                    f"{f.effect} (row RMS {f.row_rms_after_lux:.0f} lx against "
                    f"{w.row_rms_after_lux:.0f} lx)" for f in better)
                    + " — a hint only: three daily values, not used in the ranking.")
    return text




@dataclass
class _State:
    """Where the loop stands: a scenario, its run and its disagreement map."""

    scenario: Scenario
    run: Run
    map: DisagreementMap


@dataclass
class _Trial:
    """A winner switched on and re-simulated."""

    fit: CandidateFit
    after: _State
    project_file: Path | None


def run_loop(sim: Simulator, *, ctx: EffectContext, start: Scenario, measured: Measured,
             options: LoopOptions = LoopOptions(), on_step: OnStep | None = None
             ) -> LoopResult:
    """Diagnose ``start`` against ``measured`` (pure: files only through ``on_step``).

    ``options.first_step_signatures``: every step after the first ranks the candidates with
    the signatures simulated at the first step (to first order effects add; each effect is
    then simulated once per diagnosis, not once per step). The winner of every step is still
    re-simulated at its fitted strength and kept only if that lowers the RMSE, so the gap
    shrinking at every step is measured, not assumed. Default: re-simulated at every step.

    ``on_step(k, scenario)`` may write the step's project file and return the scenario as read
    back from it (which is then simulated) and the file's path.
    """
    alt, az = (measured.sun if measured.sun is not None
               else sun_positions(ctx.project, start, measured.times))

    def simulate(sc: Scenario) -> _State:
        run = sim.run(sc)
        return _State(sc, run, make_map(run, measured, alt, az))

    state = simulate(start)
    start_map = state.map
    steps: list[Step] = []
    att: Attribution | None = None
    kept: dict[str, Signature] | None = {} if options.first_step_signatures else None
    stop = f"reached the maximum of {options.max_steps} step(s)"
    for k in range(1, options.max_steps + 1):
        log.info("  step %d: %s nRMSE %.3f, nMBE %+.3f; simulating candidate signatures", k,
                 state.scenario.name, state.map.stats["nrmse"], state.map.stats["nmbe"])
        att = attribute(sim, ctx=ctx, base=state.scenario, base_run=state.run,
                        measured=measured.hourly, row_residual=_row_residual(state.run, measured),
                        catalogue=options.catalogue, margin=options.margin, reuse=kept)
        if not att.fits:
            stop = "no candidate effects are left (every effect is on or does not apply)"
            break
        trial, rejected = _try_winners(att, k, state, start.name, simulate, ctx, on_step)
        if trial is None:
            stop = _stop_reason(att, options.margin, rejected)
            break
        steps.append(_record_step(k, att, state, trial, rejected, measured))
        state, att = trial.after, None
    return LoopResult(start, start_map, steps, state.scenario, state.map, stop, att)


def _try_winners(att: Attribution, k: int, state: _State, root: str,
                 simulate: Callable[[Scenario], _State], ctx: EffectContext,
                 on_step: OnStep | None) -> tuple[_Trial | None, list[str]]:
    """Switch on the winner, re-simulate it; while that does not lower the RMSE, reject it and
    try the next improving candidate. Returns the kept trial (None: none) and the rejected."""
    rejected: list[str] = []
    while att.winner is not None:
        w = att.winner
        new = get_effect(w.effect).switch_on(ctx, state.scenario, w.strength)
        new = replace(new, name=_step_name(root, k),
                      description=f"diagnose step {k}: {state.scenario.name} + {w.effect} "
                                  f"({w.strength_text})")
        path = None
        if on_step is not None:
            new, path = on_step(k, new)
        after = simulate(new)
        if after.map.stats["rmse_lux"] < state.map.stats["rmse_lux"]:
            return _Trial(w, after, path), rejected
        log.info("    %s re-simulated at %s does not lower the RMSE (%.3f ≥ %.3f): rejected",
                 w.effect, w.strength_text, after.map.stats["nrmse"], state.map.stats["nrmse"])
        rejected.append(w.effect)
        choose_winner(att, skip=rejected)
    return None, rejected


def _stop_reason(att: Attribution, margin: float, rejected: list[str]) -> str:
    mm = att.mean_measured
    moving = [f for f in att.fits if f.strength is None or f.strength > 0]
    stop = (f"no candidate lowers the cross-validated nRMSE by more than {margin:.0%} "
            f"of its current {att.baseline_cv_lux / mm:.3f}")
    if moving:
        best = moving[0]
        stop += (f" (best: {best.effect} at {best.strength_text}, CV nRMSE "
                 f"{best.cv_rmse_lux / mm:.3f})")
    else:
        stop += " (every candidate's fit chose strength 0, i.e. leave it off)"
    if rejected:
        stop += f"; rejected after re-simulation: {', '.join(rejected)}"
    return stop


def _record_step(k: int, att: Attribution, before: _State, trial: _Trial,
                 rejected: list[str], measured: Measured) -> Step:
    """The step that adds ``trial``'s effect, with its identifiability; logged."""
    w, dm, after = trial.fit, before.map, trial.after.map
    mm = att.mean_measured
    ident, intervals = step_identifiability(att, before.run.lux, before.run.stderr,
                                            measured.noise, measured.noise_lux)
    step = Step(number=k, effect=w.effect, title=w.title, strength=w.strength,
                strength_text=w.strength_text, change=w.change,
                why=_why(att, w, dm) + " " + ident.sentence(w.effect) + ".",
                explained_fraction=w.explained_fraction,
                rmse_before=dm.stats["nrmse"], rmse_after=after.stats["nrmse"],
                cv_rmse_before=att.baseline_cv_lux / mm, cv_rmse_after=w.cv_rmse_lux / mm,
                mbe_before=dm.stats["nmbe"], mbe_after=after.stats["nmbe"],
                tie_with=list(att.tie_with), attribution=att,
                scenario_before=before.scenario, scenario_after=trial.after.scenario,
                map_before=dm, map_after=after, rejected=rejected,
                project_file=trial.project_file, identify=ident, intervals=intervals)
    log.info("    → add %s (%s): nRMSE %.3f → %.3f, CV nRMSE %.3f → %.3f%s", w.effect,
             w.strength_text, step.rmse_before, step.rmse_after, step.cv_rmse_before,
             step.cv_rmse_after, f"; tie with {', '.join(att.tie_with)}" if att.tie_with else "")
    if ident.partners(w.effect):
        log.info("    %s", step.separability)
    return step
