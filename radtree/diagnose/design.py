"""What to measure next: rank candidate additions to a campaign by how well they separate the
effects the present data confound (``radtree diagnose next PROJECT``).

1. The *superset* campaign — the present campaign merged with every candidate — is simulated
   once per effect (:class:`~radtree.diagnose.campaign_sim.CampaignSimulator`): the base
   scenario and each candidate effect switched on at its reference strength, same seed, so
   each effect's signature on every observation the candidates could add is known.
2. Every campaign is a subset of the superset's observations (a candidate *adds* some and, for
   "readings per sensor instead of means", *removes* the means it replaces); its
   identifiability (:mod:`.identify`) follows from the rows of the signature matrix.
3. Greedy design: at each rank the candidate whose addition leaves the fewest pairs of the
   present confounded groups above ``GROUP_CORR``, then the lowest largest |correlation|
   among those pairs (``min_correlation_after``: a minimum-correlation design), then the
   largest log-determinant of the whitened, normalised information matrix (D-optimal) wins.

Outputs (``PROJECT/diagnose/``): ``next_measurement.csv`` (``candidate, description,
separated_effects, min_correlation_after, rank`` + ``confounded_pairs_after, log_det``),
``next_measurement.html`` and ``campaign-next.toml`` — the present campaign plus the top three,
ready for ``radtree diagnose selftest PROJECT --campaign diagnose/campaign-next.toml``.
"""

from __future__ import annotations

import logging
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario
from radtree.diagnose.campaign import (
    Campaign,
    Layout,
    SensorGroup,
    campaign_table,
    load_campaign,
    merge,
    project_campaign,
)
from radtree.diagnose.campaign_sim import CampaignSimulator
from radtree.diagnose.effects import EFFECTS, Effect, EffectContext, candidates
from radtree.diagnose.identify import Identifiability, identifiability, noise_sigma
from radtree.diagnose.options import DEFAULT_OPTIONS, DiagnoseOptions
from radtree.diagnose.outcome import pick_scenario, resolve_project
from radtree.diagnose.simulate import Run
from radtree.errors import ConfigError
from radtree.fileio import atomic_path, write_text

log = logging.getLogger(__name__)

DESIGN_COLUMNS = ["candidate", "description", "separated_effects", "min_correlation_after",
                  "rank", "confounded_pairs_after", "log_det"]
TOP = 3
#: rays per sensor of a seeded engine for the design's signatures unless given: the superset
#: campaign is ~10 × the present one, and common random numbers keep signatures precise
DESIGN_RAYS = 256
#: suffix of the group that reports a mean group's sensors one by one (a candidate)
PER_SENSOR = "_sensors"


@dataclass(frozen=True)
class Candidate:
    """A possible addition to a campaign: ``addition`` holds its days, hours and groups;
    ``replaces_means``: the groups whose hourly means it replaces by per-sensor readings."""

    name: str
    description: str
    addition: Campaign
    replaces_means: tuple[str, ...] = ()


def default_candidates(project: Project, base: Campaign) -> list[Candidate]:
    """Sensors at other heights, horizontal street sensors under the crown and in the open, a
    vertical sensor facing the crown, readings per sensor instead of means, an hour before and
    after the measured ones, and another two days (equinox, winter solstice)."""
    h = project.sensors.height_m
    first = base.days[0]
    year = int(first[:4]) + (1 if first[5:] > "06-21" else 0)
    facade_means = tuple(g.name for g in base.groups if g.report == "mean")

    def add(name: str, groups: tuple[SensorGroup, ...] = (), days: tuple[str, ...] = (),
            hours: tuple[str, ...] = ()) -> Campaign:
        return Campaign(name, days or base.days, hours or base.hours, groups or base.groups,
                        base.noise, base.noise_lux, base.rays)

    out = [Candidate(f"facade_h{z:g}", f"the façade circle at {z:g} m instead of {h:g} m too "
                     "(hourly mean)", add("h", (SensorGroup(f"facade_h{z:g}", "mean",
                                                            grid="facade", height_m=z),)))
           for z in (h - 1.0, h + 1.0)]
    out += [
        Candidate("street_under", "a horizontal sensor under the crown (0.8 m out, 4.3 m up)",
                  add("u", (SensorGroup("street_under", "sensor", orientation="horizontal",
                                        points=((0.0, 0.8, 4.3),)),))),
        Candidate("street_open", "a horizontal sensor in the open street (12 m out, 1 m up)",
                  add("o", (SensorGroup("street_open", "sensor", orientation="horizontal",
                                        points=((0.0, 12.0, 1.0),)),))),
        Candidate("facing_crown", "a vertical sensor 8 m out, 5 m up, facing the crown",
                  add("c", (SensorGroup("facing_crown", "sensor", orientation="facing_crown",
                                        points=((0.0, 8.0, 5.0),)),))),
    ]
    if facade_means:
        out.append(Candidate("per_sensor", "readings per sensor instead of the hourly means",
                             add("s", tuple(SensorGroup(f"{g.name}{PER_SENSOR}", "sensor",
                                                        g.grid, g.height_m, g.orientation,
                                                        g.points)
                                            for g in base.groups if g.name in facade_means)),
                             replaces_means=facade_means))
    hs = sorted(base.hours)
    for t in (_shift(hs[0], -60), _shift(hs[-1], 60)):
        if t not in base.hours:
            out.append(Candidate(f"hour_{t.replace(':', '')}", f"another hour, {t}",
                                 add("t", hours=(t,))))
    for d, what in ((f"{year}-03-20", "equinox"), (f"{year}-06-21", "winter solstice")):
        if d not in base.days:
            out.append(Candidate(f"day_{d}", f"another day, {d} ({what}), same hours",
                                 add("d", days=(d,))))
    return out


def _shift(t: str, minutes: int) -> str:
    h, m = map(int, t.split(":"))
    v = max(0, min(23 * 60 + 59, h * 60 + m + minutes))
    return f"{v // 60:02d}:{v % 60:02d}"


def file_candidates(path: str | os.PathLike, project: Project, base: Campaign
                    ) -> list[Candidate]:
    """Candidates from a campaign TOML: each group, each hour and each day not in ``base``."""
    c = load_campaign(path, project)
    out = [Candidate(g.name, g.description or f"sensor group {g.name} ({g.report})",
                     Campaign(g.name, base.days, base.hours, (g,), base.noise, base.noise_lux,
                              base.rays),
                     replaces_means=tuple(b.name for b in base.groups
                                          if b.name == g.name and b.report == "mean"
                                          and g.report == "sensor"))
           for g in c.groups]
    out += [Candidate(f"hour_{t.replace(':', '')}", f"another hour, {t}",
                      Campaign(t, base.days, (t,), base.groups, base.noise)) for t in c.hours
            if t not in base.hours]
    out += [Candidate(f"day_{d}", f"another day, {d}, same hours",
                      Campaign(d, (d,), base.hours, base.groups, base.noise)) for d in c.days
            if d not in base.days]
    if not out:
        raise ConfigError(f"{path}: no candidate (every group, hour and day is already measured)")
    return out


def _mask(layout: Layout, c: Campaign, drop_means: tuple[str, ...] = ()) -> np.ndarray:
    """The superset's observations that campaign ``c`` measures."""
    by = {g.name: g.report for g in c.groups}
    return np.array([o.day in c.days and o.time in c.hours and o.group in by
                     and (o.sensor is None) == (by[o.group] == "mean")
                     and not (o.sensor is None and o.group in drop_means)
                     for o in layout.observations])


@dataclass
class Design:
    """The ranked candidates and what they do to the identifiability."""

    base: Campaign
    scenario: Scenario
    names: list[str]
    before: Identifiability
    table: pd.DataFrame
    after_top: Identifiability
    next_campaign: Campaign
    seconds: float
    out_dir: Path | None = None
    files: list[Path] = field(default_factory=list)

    def lines(self) -> list[str]:
        out = [f"  confounded with {self.base.name}: "
               + ("; ".join(" ~ ".join(g) for g in self.before.confounded) or "none")]
        for r in self.table.head(TOP).itertuples():
            out.append(f"  {r.rank}. {r.candidate}: {r.description} — separates "
                       f"{r.separated_effects or 'nothing new'}; largest |corr| left "
                       f"{r.min_correlation_after:.3f}")
        out.append("  confounded after the top three: "
                   + ("; ".join(" ~ ".join(g) for g in self.after_top.confounded) or "none"))
        if self.files:
            out.append(f"  wrote {self.files[0]} ({self.seconds:.0f} s)")
        return out


def _pairs(groups: list[list[str]]) -> list[tuple[str, str]]:
    return [(a, b) for g in groups for i, a in enumerate(g) for b in g[i + 1:]]


def rank_candidates(names: list[str], signatures: np.ndarray, sigma: np.ndarray,
                    base: np.ndarray, moves: dict[str, tuple[np.ndarray, np.ndarray]],
                    labels: list[str] | None = None, top: int = TOP
                    ) -> tuple[list[dict[str, Any]], Identifiability, Identifiability]:
    """Greedy ranking (see the module doc) of candidate observation sets.

    ``signatures`` (observations × effects, lux) and ``sigma`` (lux) over every observation
    any campaign could hold; ``base``: the present campaign's observations (bool mask);
    ``moves[name] = (add, remove)`` masks of each candidate. Returns the ranked records
    (``candidate, separated_effects, min_correlation_after, rank, confounded_pairs_after,
    log_det``), the present identifiability and the one after the top ``top``."""
    obs = labels or [str(i) for i in range(len(base))]

    def ident(mask: np.ndarray) -> Identifiability:
        return identifiability(names, signatures[mask], sigma[mask],
                               observations=[x for x, m in zip(obs, mask) if m])

    before = ident(base)
    pairs = _pairs(before.confounded)
    ix = {n: i for i, n in enumerate(names)}

    def score(m: np.ndarray) -> tuple[int, float, float, Identifiability]:
        idn = ident(m)
        cors = [abs(idn.correlation[ix[a], ix[b]]) for a, b in pairs]
        left = sum(1 for a, b in pairs if not idn.separable(a, b))
        keep = [i for i, n in enumerate(names) if not idn.below_noise(n)]
        w = signatures[m][:, keep] / sigma[m][:, None]
        w = w / np.linalg.norm(w, axis=0)
        sign, logdet = np.linalg.slogdet(w.T @ w)
        return left, max(cors) if cors else 0.0, float(logdet) if sign > 0 else -math.inf, idn

    recs: list[dict[str, Any]] = []
    remaining = list(moves)
    current = base.copy()
    separated = {n for n in names if before.distinguishable(n)}
    after_top = before
    while remaining:
        trials = []
        for name in remaining:
            add, drop = moves[name]
            m = (current & ~drop) | add
            left, worst, logdet, idn = score(m)
            trials.append(((left, worst, -logdet, name), name, m, idn, left, worst, logdet))
        trials.sort(key=lambda x: x[0])
        _, name, m, idn, left, worst, logdet = trials[0]
        alone = {n for n in names if idn.distinguishable(n)}
        recs.append({"candidate": name, "description": "",
                     "separated_effects": ";".join(sorted(alone - separated)),
                     "min_correlation_after": worst, "rank": len(recs) + 1,
                     "confounded_pairs_after": left, "log_det": logdet})
        separated |= alone
        current = m
        remaining.remove(name)
        if len(recs) <= top:
            after_top = idn
    return recs, before, after_top


def next_measurement(project: str | os.PathLike | Project, *,
                     candidates_file: str | os.PathLike | None = None,
                     options: DiagnoseOptions = DEFAULT_OPTIONS) -> Design:
    """Rank candidate additions to ``options.campaign`` (default: the project's own
    measurement); ``candidates_file``: a campaign TOML whose groups, hours and days are the
    candidates (default: :func:`default_candidates`). Writes ``next_measurement.csv``,
    ``campaign-next.toml`` and ``next_measurement.html`` unless ``options.write`` is off."""
    t0 = time.perf_counter()
    proj = resolve_project(project)
    start = pick_scenario(proj, options.scenario)
    base = options.campaign or project_campaign(proj)
    cands = (file_candidates(candidates_file, proj, base) if candidates_file is not None
             else default_candidates(proj, base))
    union = merge(base, *[c.addition for c in cands], name="superset")
    sim = CampaignSimulator(proj, (), options.engine, options.rays or base.rays or DESIGN_RAYS,
                            options.seed, campaign=union)
    assert sim.layout is not None
    log.info("next measurement %s: scenario %s, %d candidates, superset %d day(s) × %d "
             "hour(s) × %d group(s) = %d observations, engine %s", proj.name, start.name,
             len(cands), len(union.days), len(union.hours), len(union.groups),
             len(sim.labels), sim.engine_name)
    for note in sim.notes:
        log.info("  note: %s", note)
    names, S, base_run = _signatures(sim, EffectContext(proj), start, options.effects or EFFECTS)
    sigma = noise_sigma(base_run.lux, base_run.stderr, base.noise, base.noise_lux)
    sigma = np.maximum(sigma, 1e-6)
    base_mask = _mask(sim.layout, base)
    recs, before, top_idn = rank_candidates(names, S, sigma, base_mask,
                                            _moves(sim.layout, base, cands, base_mask),
                                            sim.labels)
    text = {c.name: c.description for c in cands}
    for r in recs:
        r["description"] = text[r["candidate"]]
    chosen = [next(c for c in cands if c.name == r["candidate"]) for r in recs[:TOP]]
    table = pd.DataFrame(recs, columns=DESIGN_COLUMNS)
    design = Design(base, start, names, before, table, top_idn, _next_campaign(base, chosen),
                    0.0)
    if options.write:
        _publish(design, proj, chosen, options.folder(proj.root), t0)
    design.seconds = time.perf_counter() - t0
    return design


def _signatures(sim: CampaignSimulator, ctx: EffectContext, start: Scenario,
                effects: tuple[Effect, ...]) -> tuple[list[str], np.ndarray, Run]:
    """Each candidate effect's change (lux, observations × effects) at its reference
    strength, and the base run."""
    effs, _ = candidates(ctx, start, effects)
    base_run = sim.run(start)
    cols = []
    for e in effs:
        run = sim.run(e.switch_on(ctx, start, e.reference(ctx, start)))
        cols.append(run.lux - base_run.lux)
        log.info("  signature %s: %.1f s", e.name, run.seconds)
    return [e.name for e in effs], np.column_stack(cols), base_run


def _moves(layout: Layout, base: Campaign, cands: list[Candidate], base_mask: np.ndarray
           ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each candidate's (added, removed) observations of the superset."""
    moves = {}
    for c in cands:
        drop = (_mask(layout, Campaign("x", c.addition.days, c.addition.hours, base.groups),
                      c.replaces_means) if c.replaces_means else np.zeros(len(base_mask), bool))
        moves[c.name] = (_mask(layout, c.addition), drop)
    return moves


def _next_campaign(base: Campaign, chosen: list[Candidate]) -> Campaign:
    """The present campaign plus the chosen candidates (per-sensor readings replacing the
    means they replace)."""
    nxt = merge(base, *[c.addition for c in chosen], name=f"{base.name} + next {len(chosen)}")
    repl = {g for c in chosen for g in c.replaces_means}
    if not repl:
        return nxt
    return Campaign(nxt.name, nxt.days, nxt.hours, tuple(
        g if g.name not in repl else SensorGroup(g.name, "sensor", g.grid, g.height_m,
                                                 g.orientation, g.points)
        for g in nxt.groups if g.name.removesuffix(PER_SENSOR) not in repl
        or not g.name.endswith(PER_SENSOR)), nxt.noise, nxt.noise_lux, nxt.rays, False,
        "the present campaign plus the top three next measurements (no readings yet)",
        nxt.direct_normal)


def _publish(design: Design, proj: Project, chosen: list[Candidate], out: Path,
             t0: float) -> None:
    """``next_measurement.csv``, ``campaign-next.toml`` and the report in ``out``."""
    from radtree.diagnose.report_identify import write_design_report
    from radtree.tomlout import dumps

    out.mkdir(parents=True, exist_ok=True)
    design.out_dir = out
    path = out / "next_measurement.csv"
    with atomic_path(path) as tmp:
        design.table.to_csv(tmp, index=False, float_format="%.6g")
    camp = out / "campaign-next.toml"
    write_text(camp, dumps(campaign_table(design.next_campaign, out), header=(
        f"Written by radtree diagnose next: {design.base.name} plus the top "
        f"{len(chosen)} candidates\n({', '.join(c.name for c in chosen)}). Run: radtree "
        f"diagnose selftest {proj.root} --campaign {camp}")))
    design.files = [path, camp]
    design.seconds = time.perf_counter() - t0
    design.files += write_design_report(design, out)
