"""The diagnosis loop: find the disagreement, name the missing effect, add it, re-simulate.

Each step: simulate the current scenario; map the residual (:mod:`.residuals`); rank the
candidate effects by cross-validated error (:mod:`.attribution`); add the winner at its fitted
strength to the scenario (a new project file ``PROJECT/diagnose/radtree.step<k>.toml`` holding
the scenario ``<name>-diag<k>``, the user's file is never touched); re-simulate; repeat until no
candidate lowers the cross-validated RMSE by more than the margin (default 5 % relative), or
``max_steps``. A winner whose re-simulation at the fitted strength does not lower the RMSE is
rejected and the next improving candidate is tried (so the gap shrinks at every step).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import tomllib

from radtree.config import PATH_FIELDS, Project, Scenario, find_project_file, load_project
from radtree.diagnose.attribution import (
    DEFAULT_MARGIN,
    Attribution,
    CandidateFit,
    Signature,
    attribute,
    choose_winner,
)
from radtree.diagnose.effects import EFFECTS, Effect, EffectContext, get_effect
from radtree.diagnose.identify import (
    DEFAULT_NOISE,
    Identifiability,
    Interval,
    step_identifiability,
)
from radtree.diagnose.residuals import DisagreementMap, disagreement_map
from radtree.diagnose.simulate import Run, Simulator
from radtree.errors import RadtreeError
from radtree.fileio import write_text

DEFAULT_MAX_STEPS = 4
STEP_COLUMNS = ["step", "effect", "explained_fraction", "strength", "rmse_before", "rmse_after",
                "cv_rmse_before", "cv_rmse_after"]
Echo = Callable[[str], None]


# --------------------------------------------------------------------------- measurements
@dataclass
class Measured:
    """The measured side of a diagnosis, restricted to hours the project simulates.

    ``hourly``: grid mean per hour of ``times`` (lx). ``rows_daily``: ``row, sensors,
    measured_mean_lux`` or None; ``rows_hourly``: ``time, row, measured_lux`` or None.
    ``left_out``: measured hours without a simulation counterpart (not in ``site.hours``);
    ``unmeasured``: project hours without a measurement.
    """

    times: tuple[str, ...]
    hourly: np.ndarray
    source: str
    units: str
    shape: str
    rows_daily: pd.DataFrame | None = None
    rows_hourly: pd.DataFrame | None = None
    left_out: list[str] = field(default_factory=list)
    unmeasured: list[str] = field(default_factory=list)
    #: sun altitude and azimuth (degrees) per value when ``times`` are not clock times (a
    #: campaign's observations, :mod:`.campaign_sim`); None: from the project's hours
    sun: tuple[np.ndarray, np.ndarray] | None = None
    #: relative noise (1 σ) and floor (lux) of the values: the identifiability's weights
    noise: float = DEFAULT_NOISE
    noise_lux: float = 0.0

    @property
    def mean(self) -> float:
        return float(np.mean(self.hourly))

    def notes(self) -> list[str]:
        out = []
        if self.left_out:
            out.append("measured hour(s) without a simulation counterpart (not in the "
                       f"project's site.hours), left out of the diagnosis: "
                       f"{', '.join(self.left_out)}")
        if self.unmeasured:
            out.append(f"project hour(s) without a measurement, not simulated: "
                       f"{', '.join(self.unmeasured)}")
        if self.rows_daily is not None and (self.left_out or self.unmeasured):
            out.append("the per-row daily means were measured over the whole day; they are "
                       f"compared with simulated means over the {len(self.times)} matched hours")
        return out


def load_measurements(project: Project, path: str | os.PathLike | None = None,
                      units: str | None = None, sensors_per_row: dict[str, int] | None = None,
                      rows_path: str | os.PathLike | None = None) -> Measured:
    """Read the measured file (any shape of :func:`radtree.measurements.load_measured`) and the
    per-row daily means (``project.measured_rows``) and match them to the project's hours."""
    from radtree.measurements import grid_mean, load_measured, load_measured_rows

    if path is None:
        if project.measured is None:
            raise RadtreeError(f"no measurements: pass --measured FILE.csv or set [project] "
                               f"measured in {project.source}")
        path = project.measured
    frame, shape = load_measured(path, units)
    if shape.kind == "row" and sensors_per_row is None:
        raise RadtreeError("a per-row measured file needs the simulated sensors per row")
    gm = grid_mean(frame, sensors_per_row if shape.kind == "row" else None)
    hours = list(project.site.hours)
    have = dict(zip(gm["time"], gm["measured_lux"].astype(float)))
    times = tuple(h for h in hours if h in have)
    left_out = [t for t in gm["time"] if t not in hours]
    unmeasured = [h for h in hours if h not in have]
    if len(times) < 3:
        raise RadtreeError(
            f"{path}: only {len(times)} measured hour(s) match the project's site.hours "
            f"({', '.join(hours)}); the diagnosis needs at least 3 (measured: "
            f"{', '.join(gm['time'])})")
    rows_hourly = None
    if shape.kind == "row":
        rows_hourly = frame[["time", "row", "measured_lux"]].copy()
    elif shape.kind == "sensor" and "row" in frame.columns:
        rows_hourly = (frame.groupby(["time", "row"], sort=True)["measured_lux"].mean()
                       .reset_index())
    if rows_hourly is not None:
        rows_hourly = rows_hourly[rows_hourly["time"].isin(times)].reset_index(drop=True)
    rows_daily = None
    rp = rows_path if rows_path is not None else project.measured_rows
    if rp is not None:
        rows_daily = load_measured_rows(rp)
    return Measured(times, np.array([have[t] for t in times]), str(path), shape.units,
                    shape.kind, rows_daily, rows_hourly, left_out, unmeasured)


# --------------------------------------------------------------------------- loop data
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
    return disagreement_map(measured.times, measured.hourly, run.lux, run.stderr, alt, az,
                            run.rows, measured.rows_daily, measured.rows_hourly)


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


def run_loop(sim: Simulator, ctx: EffectContext, start: Scenario, measured: Measured,
             margin: float = DEFAULT_MARGIN, max_steps: int = DEFAULT_MAX_STEPS,
             catalogue: Iterable[Effect] = EFFECTS, echo: Echo | None = None,
             on_step: Callable[[int, Scenario], tuple[Scenario, Path | None]] | None = None,
             first_step_signatures: bool = False) -> LoopResult:
    """Diagnose ``start`` against ``measured`` (pure: files only through ``on_step``).

    ``first_step_signatures``: every step after the first ranks the candidates with the
    signatures simulated at the first step (to first order effects add; each effect is then
    simulated once per diagnosis, not once per step). The winner of every step is still
    re-simulated at its fitted strength and kept only if that lowers the RMSE, so the gap
    shrinking at every step is measured, not assumed. Default: re-simulated at every step.

    ``on_step(k, scenario)`` may write the step's project file and return the scenario as read
    back from it (which is then simulated) and the file's path.
    """
    if not 0 <= margin < 1:
        raise RadtreeError(f"margin must be in [0, 1), got {margin}")
    catalogue = tuple(catalogue)
    say = echo or (lambda s: None)
    alt, az = (measured.sun if measured.sun is not None
               else sun_positions(ctx.project, start, measured.times))
    mm = measured.mean
    current = start
    run = sim.run(current)
    dm = make_map(run, measured, alt, az)
    start_map = dm
    steps: list[Step] = []
    stop = ""
    att: Attribution | None = None
    kept: dict[str, Signature] | None = {} if first_step_signatures else None
    for k in range(1, max_steps + 1):
        say(f"  step {k}: {current.name} nRMSE {dm.stats['nrmse']:.3f}, "
            f"nMBE {dm.stats['nmbe']:+.3f}; simulating candidate signatures")
        att = attribute(sim, ctx, current, run, measured.hourly, _row_residual(run, measured),
                        catalogue, margin, echo=echo, reuse=kept)
        if not att.fits:
            stop = "no candidate effects are left (every effect is on or does not apply)"
            break
        rejected: list[str] = []
        chosen = None
        while att.winner is not None:
            w = att.winner
            eff = get_effect(w.effect)
            new = eff.switch_on(ctx, current, w.strength)
            new = replace(new, name=_step_name(start.name, k),
                          description=f"diagnose step {k}: {current.name} + {w.effect} "
                                      f"({w.strength_text})")
            path = None
            if on_step is not None:
                new, path = on_step(k, new)
            new_run = sim.run(new)
            after = make_map(new_run, measured, alt, az)
            if after.stats["rmse_lux"] < dm.stats["rmse_lux"]:
                chosen = (w, new, new_run, after, path)
                break
            say(f"    {w.effect} re-simulated at {w.strength_text} does not lower the RMSE "
                f"({after.stats['nrmse']:.3f} ≥ {dm.stats['nrmse']:.3f}): rejected")
            rejected.append(w.effect)
            choose_winner(att, skip=rejected)
        if chosen is None:
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
            break
        w, new, new_run, after, path = chosen
        ident, intervals = step_identifiability(att, run.lux, run.stderr, measured.noise,
                                                measured.noise_lux)
        step = Step(k, w.effect, w.title, w.strength, w.strength_text, w.change,
                    _why(att, w, dm) + " " + ident.sentence(w.effect) + ".",
                    w.explained_fraction, dm.stats["nrmse"],
                    after.stats["nrmse"], att.baseline_cv_lux / mm, w.cv_rmse_lux / mm,
                    dm.stats["nmbe"], after.stats["nmbe"], list(att.tie_with), att, current,
                    new, dm, after, rejected, path, ident, intervals)
        steps.append(step)
        say(f"    → add {w.effect} ({w.strength_text}): nRMSE {step.rmse_before:.3f} → "
            f"{step.rmse_after:.3f}, CV nRMSE {step.cv_rmse_before:.3f} → "
            f"{step.cv_rmse_after:.3f}" + (f"; tie with {', '.join(att.tie_with)}"
                                            if att.tie_with else ""))
        if ident.partners(w.effect):
            say(f"    {step.separability}")
        current, run, dm = new, new_run, after
        att = None
    else:
        stop = f"reached the maximum of {max_steps} step(s)"
    return LoopResult(start, start_map, steps, current, dm, stop, att)


# --------------------------------------------------------------------------- project files
def _relocate(value: Any, old: Path, new: Path) -> Any:
    """A relative data path of the project at ``old`` as seen from ``new``: relative when
    ``new`` lies inside the project folder, else absolute."""
    if isinstance(value, str) and value and not Path(value).is_absolute():
        target = old / value
        if target.exists():
            if new.resolve().is_relative_to(old.resolve()):
                return os.path.relpath(target.resolve(), new.resolve())
            return str(target.resolve())
    return value


def scenario_table(sc: Scenario) -> dict[str, Any]:
    d: dict[str, Any] = {"name": sc.name, "model": sc.model, "reflection": sc.reflection}
    if sc.sky is not None:
        d["sky"] = sc.sky
    if sc.form is not None:
        d["form"] = sc.form
    if sc.description:
        d["description"] = sc.description
    if sc.switches:
        d["switches"] = dict(sc.switches)
    return d


def write_step_project(project: Project, scenario: Scenario, path: Path,
                       header: str = "") -> Scenario:
    """Write the user's project file with ``scenario`` appended (or replacing one of the same
    name) to ``path``; relative data paths are rewritten for the new folder. Returns the
    scenario as loaded back from the written file (checked to equal ``scenario``)."""
    from radtree.tomlout import dumps

    src = find_project_file(project.source)
    data = tomllib.loads(src.read_text(encoding="utf-8"))
    old, new = src.parent, path.parent
    new.mkdir(parents=True, exist_ok=True)
    for name in PATH_FIELDS:
        parts = name.split(".")
        table: Any = data
        for p in parts[:-1]:
            table = table.get(p) if isinstance(table, dict) else None
        if isinstance(table, dict) and parts[-1] in table:
            table[parts[-1]] = _relocate(table[parts[-1]], old, new)
    for item in data.get("geometry", []) or []:
        if isinstance(item, dict) and "file" in item:
            item["file"] = _relocate(item["file"], old, new)
    scs = [s for s in data.get("scenario", []) if s.get("name") != scenario.name]
    for s in scs:
        sw = s.get("switches")
        if isinstance(sw, dict):
            s["switches"] = {k: _relocate(v, old, new) for k, v in sw.items()}
    table_new = scenario_table(scenario)
    if "switches" in table_new:
        table_new["switches"] = {k: _relocate(v, old, new)
                                 for k, v in table_new["switches"].items()}
    data["scenario"] = scs + [table_new]
    write_text(path, dumps(data, header=header))
    loaded = load_project(path).scenario(scenario.name)
    same = (loaded.model == scenario.model and loaded.reflection == scenario.reflection
            and loaded.sky == scenario.sky and loaded.form == scenario.form
            and _plain_switches(loaded.switches) == _plain_switches(table_new.get("switches",
                                                                                  {})))
    if not same:
        raise RadtreeError(f"{path}: the written scenario {scenario.name} does not read back "
                           f"as written ({loaded} vs {scenario})")
    return replace(loaded, switches=dict(scenario.switches))


def _plain_switches(sw: dict[str, Any]) -> dict[str, Any]:
    return {k: (float(v) if isinstance(v, int | float) and not isinstance(v, bool) else v)
            for k, v in sw.items()}
