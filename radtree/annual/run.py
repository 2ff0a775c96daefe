"""The annual run: three scenes, their coefficients, 8760 hours of illuminance, the metrics.

Method (daylight coefficients with a separate direct-sun treatment)
-------------------------------------------------------------------
For every sensor and hour h, in lux (179 · (0.265 R + 0.670 G + 0.065 B) of the visible
irradiance):

    E(h) = Σ_p C_sky[p] · S_sky[p, h]                       sky (and ground glow), -ab N
         + C_dir[h] · L_sun(h)                               direct sun, -ab 0, exact sun
         + Σ_j w_j(h) · (C_N[v_j] − C_0[v_j]) · L_sun(h)     inter-reflected sun, -ab N

* ``S_sky`` — ``gendaymtx -s`` (the Perez sky *without* the sun, visible radiance,
  Reinhart MF patches, ground patch ρ·E_global/π) from the EPW via ``epw2wea``;
  ``C_sky`` — ``rcontrib`` sky-patch coefficients (``reinhartb.cal``), all bounces.
* ``L_sun(h)`` and the sun direction — ``gendaymtx -D`` (the same solar position and Perez
  luminous efficacy gendaymtx uses for the sky); ``C_dir`` — a unit 0.533° sun exactly at
  each hour's position, ``-ab 0``: the direct sunlight of IES LM-83 (ASE uses this term
  alone).
* inter-reflected sun — unit suns at the Reinhart patch centres (``sun_mf``, default
  :data:`DEFAULT_SUN_MF` = 1; the office example's year needs 80 of the 145) around the
  sun's path, ``-ab N`` minus ``-ab 0`` (the direct part is deterministic, so the
  difference is exactly the reflected part); each hour interpolates between the three
  centres around its sun with weights that reproduce every sunlit plane's n·d exactly
  (:func:`radtree.annual.skymatrix.sun_patch_weights`). Each of these unit suns is a light
  source every ambient hit must test (a shadow ray per sun and hit), so this run is traced
  with coarser sampling than the sky (default ``-ad`` ÷ 4, ``-lw`` ≥ 1e-3): reflected
  sunlight is a smaller, smoother share than the direct sun, and its sampling noise is
  spread over the many hours each patch serves. Measured against point-in-time ``rtrace``
  under ``gendaylit`` (``radtree verify --full --group annual``, docs/validation.md): on an
  open ground plane every sensor within −3.1 … +0.8 % at six hours. Behind one louvers crown
  (:func:`radtree.verify.annual.crown_annual_checks`) the reflected sun, ≈ 55 % of the
  shaded façade's light at low sun, interpolated from the centres of MF 1 / 2 / 3 / 4 / 6
  reads 0.93–1.11 / 0.94–1.03 / 0.99–1.04 / 0.97–1.03 / 0.98–1.03 × the exact sun's (8
  sensors, 22 Dec 9:30 and 17:30, 21 Jun 10:30; all traced at -ad 2048 -lw 1e-5, 4 passes,
  ``-u+``): MF 1 missed the 5 %
  claim at three hours, MF 2 at one (21 Jun 10:30, +6.7 %: gendaymtx's sky +2 % over
  gendaylit's, the MF 2 interpolation +1 %, this run's sampling noise, ± 2–7 % per sensor
  there, and the fixed-seed sampling's +0 … +7 %: radtree.verify.annual). MF 2 stays an
  option (``--sun-mf 2``), not the default: its sun runs trace 266 unit suns instead of 80: behind the office example's leafed crowns (every
  ambient hit tests a shadow ray per sun through the slats) that run took 3.8 × as long
  (7 of its 70 sensors, 1 pass, -ab 6 -ad 512: 135 s against 35.5 s), and at MF 1 it was
  35 of the whole office annual's 37 min (``-j 1``, load 3–5 on 2 cores): ≈ 2.3 h at MF 2
  (projected from those two measurements, 7 Dec 2026) — a fourfold wait for a fix of
  low-sun hours behind crowns that still misses one of them. Its effect on a year's metrics,
  measured on the Honeybee office example without its crowns (8 Dec 2026, offices 1 and 2,
  one pass; that scene's sun runs take seconds): MF 1 against MF 4 sDA −2.1 / −3.1 pp (2–3
  of 96 sensors across the 50 % line; MF 2 equal to MF 4), DA ≤ 0.4 pp, UDI bands ≤ 0.3 pp;
  the reflected sun of single hours up to +36 % (14 Oct 8:30: 113 lx against 83 from the
  exact sun, which reads an unbiased rtrace's sun part to 0.3 %; MF 2 89, MF 4 85).

Why not ``gendaymtx -5 0.533 -d`` (the five-phase sun matrix)? The Radiance shipped in the
pyradiance wheel has no ``-5`` option; ``-D`` gives each hour's sun exactly, and with
``-ab 0`` 4 400 suns cost seconds, so the direct term needs no patch approximation at all.
The sky matrix ``gendaymtx -s`` has no sun, so nothing is counted twice.

Deciduous tree: three scenes are traced — without the tree, with the leafed crown (the
project's louvers scenario) and with the bare crown (:mod:`radtree.annual.branches`); the
"with tree" year takes each day from the leaf-on or the leaf-off coefficients by the
:class:`~radtree.annual.schedule.LeafSchedule`.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

import radtree.annual.standards as standards
from radtree.annual.branches import BranchParams, build_leaf_off
from radtree.annual.coefficients import CoefficientRunner, TraceParams
from radtree.annual.combine import combine
from radtree.annual.phenology import Phenology, crown_year, phenology_of
from radtree.annual.schedule import (
    DEFAULT_OCCUPANCY,
    LeafSchedule,
    leaf_season,
    occupied,
    parse_occupancy,
)
from radtree.annual.skymatrix import Wea, patch_count
from radtree.annual.weather_year import YearInputs, annual_ground_reflectance, annual_weather
from radtree.config import Project, Scenario, effective_project
from radtree.errors import ConfigError
from radtree.light.weather import WeatherSource
from radtree.log import progress
from radtree.scene import Scene

log = logging.getLogger(__name__)

VARIANTS = ("without", "leaf_on", "leaf_off")
SUN_LW_MIN = 1e-3
METHOD_NOTES = [
    "Sky model: gendaymtx's Perez sky patches do not blend the sky into the ground near the "
    "horizon as gendaylit's perezlum.cal does (the point-in-time runs); sensors that see "
    "mostly low sky get a few per cent (up to ≈ 8 % in a test box) more sky light here.",
    "Reflected sunlight is interpolated between unit suns at Reinhart patch centres (MF 1 by "
    "default): behind a louvers crown at low sun within −7 … +11 % of the exact sun's "
    "(--sun-mf 2: −6 … +3 %, at ≈ 4 × the reflected-sun run's time; radtree.verify.annual); "
    "the direct sun (ASE) is exact for every hour.",
]
#: Reinhart subdivision of the unit suns of the reflected sun (``radtree annual --sun-mf``):
#: MF 1. MF 2 halves the interpolation error behind a crown at low sun but takes 3.8 × the
#: reflected-sun run's time behind a crown (module docstring, measured 7 Dec 2026)
DEFAULT_SUN_MF = 1
METHODS = ("dc", "3phase")
#: replicates of a dc run (``radtree annual --replicates``): 4 passes of every Monte Carlo
#: trace, 4 × the time of one, report the metrics' standard errors and halve those of DA
#: and UDI; one pass at -ad 1024 moves sDA by ≈ 1.6 pp SE on the office's 96-sensor grids,
#: four by ≈ 1.1 pp (sDA's SE falls as R^-¼: benchmarks/annual_precision.py)
DEFAULT_REPLICATES = 4
#: ``AnnualOptions.sun_crown`` values (3phase)
SUN_CROWNS = ("explicit", "bsdf", "fivephase")


@dataclass(frozen=True)
class AnnualOptions:
    """Settings of an annual run (None = from the project)."""

    #: the leaf season; None: :func:`radtree.annual.schedule.leaf_season` of the project
    leaf: LeafSchedule | None = None
    mf: int = 1
    sun_mf: int = DEFAULT_SUN_MF
    occupancy: tuple[float, float] = DEFAULT_OCCUPANCY
    ab: int | None = None
    ad: int | None = None
    lw: float | None = None
    sun_ad: int | None = None
    sun_lw: float | None = None
    nproc: int = 2
    #: independent passes of every Monte Carlo trace (:class:`TraceParams`); above 1 the
    #: metrics' Monte Carlo standard errors are reported (:mod:`radtree.annual.uncertainty`).
    #: None: :data:`DEFAULT_REPLICATES` with the dc method, 1 with 3phase
    replicates: int | None = None
    with_scenario: str | None = None
    without_scenario: str | None = None
    epw: Path | None = None
    grids: tuple[str, ...] | None = None
    branches: BranchParams = field(default_factory=BranchParams)
    #: with ``[tree] species``: the crown of each hour from the species' phenology
    #: (:mod:`radtree.annual.phenology`) instead of the ``leaf`` dates (False: the dates)
    species_phenology: bool = True
    #: "dc" (daylight coefficients, the default) or "3phase" (:mod:`radtree.annual.threephase`)
    method: str = "dc"
    #: 3phase: rays per Klems patch of each daylight matrix (rfluxmtx -c)
    daylight_samples: int = 400
    #: 3phase: the crown the sun is traced through (:data:`SUN_CROWNS`): "explicit" (the
    #: default method's sun runs — hourly direct sun and reflected sun — on its leaf-on /
    #: bare-branch scenes), "bsdf" (both on the BSDF-crown scene) or "fivephase" (the sun
    #: reflected by the surroundings through the BSDF crown, the sun through the crown from
    #: the explicit crown with the surroundings black: :mod:`radtree.annual.fivephase`)
    sun_crown: str = "explicit"
    #: EN 17037 exposure to sunlight: the date (MM-DD, 1 February – 21 March)
    sunlight_date: str = standards.SUNLIGHT_DATE

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ConfigError(f"unknown annual method {self.method!r} (have: {', '.join(METHODS)})")
        if self.sun_crown not in SUN_CROWNS:
            raise ConfigError(f"unknown sun crown {self.sun_crown!r} for --method 3phase "
                              f"(have: {', '.join(SUN_CROWNS)})")
        if self.mf < 1 or self.sun_mf < 1:
            raise ConfigError(f"sky subdivision must be ≥ 1 (got --mf {self.mf}, "
                              f"sun MF {self.sun_mf})")
        parse_occupancy(self.occupancy)
        standards.check_sunlight_date(self.sunlight_date)
        if self.nproc < 1:
            raise ConfigError("processes must be ≥ 1")
        if self.replicates is not None and (
                self.replicates < 1 or (self.replicates > 1 and self.method != "dc")):
            raise ConfigError(f"replicates must be ≥ 1 (above 1 with --method dc only), got "
                              f"{self.replicates}")
        for name, value in (("--lw", self.lw), ("--sun-lw", self.sun_lw)):
            if value is not None and not 0 < value < 1:
                raise ConfigError(f"{name} must be between 0 and 1 (a ray weight), got {value:g}")


    @property
    def season(self) -> LeafSchedule:
        """The resolved leaf season (:func:`with_season`)."""
        if self.leaf is None:
            raise ValueError("the leaf season is not resolved: call with_season first")
        return self.leaf

@dataclass
class AnnualResult:
    """Hourly illuminance of the year and what produced it."""

    project: Project
    options: AnnualOptions
    weather: WeatherSource
    wea: Wea
    grids: dict[str, dict[str, np.ndarray]]  # grid → points, normals
    total: dict[str, dict[str, np.ndarray]]  # variant/tree → grid → (sensors, 8760) lux
    direct: dict[str, dict[str, np.ndarray]]
    in_leaf: np.ndarray  # (8760,) bool
    occupied: np.ndarray  # (8760,) bool
    scenarios: dict[str, str]
    trace: TraceParams
    sun_trace: TraceParams
    ground_reflectance: float
    notes: list[str]
    timing: dict[str, float]
    #: (8760,) leaf area fraction f and weight w of each hour (species phenology), else None
    leaf_fraction: np.ndarray | None = None
    leaf_weight: np.ndarray | None = None
    phenology: Phenology | None = None
    #: EN 17037 sunlight: "with"/"without" → grid → hours of sun per sensor (standards.py)
    sunlight: dict[str, dict[str, np.ndarray]] | None = None
    #: with replicates: grid, tree, metric, value, se (:func:`radtree.annual.uncertainty.table`)
    uncertainty: pd.DataFrame | None = None


# ---------------------------------------------------------------- scene choice
def choose_scenarios(project: Project, options: AnnualOptions
                     ) -> tuple[Scenario, Scenario, list[str]]:
    """The leafed-tree scenario and the no-tree scenario of the annual run."""
    notes = []
    if options.with_scenario:
        with_sc = project.scenario(options.with_scenario)
        if with_sc.model == "none":
            raise ConfigError(f"scenario {with_sc.name!r} has no crown (model 'none'): choose "
                              "a scenario with a tree for --with", source=str(project.source))
    else:
        trees = [s for s in project.scenarios if s.model != "none"]
        if not trees:
            raise ConfigError("the project has no scenario with a crown model: the annual "
                              "run compares a tree with no tree", source=str(project.source))

        def rank(s: Scenario) -> tuple[int, int, int]:
            return (s.model != "louvers", (s.form or project.tree.form) != "free",
                    s.reflection != "traced")

        with_sc = sorted(trees, key=rank)[0]
    if options.without_scenario:
        without_sc = project.scenario(options.without_scenario)
        if without_sc.model != "none":
            raise ConfigError(f"scenario {without_sc.name!r} has a crown ({without_sc.model}); "
                              "--without needs model 'none'", source=str(project.source))
    else:
        nones = [s for s in project.scenarios if s.model == "none"]
        if nones:
            without_sc = nones[0]
        else:
            without_sc = replace(with_sc, name=f"{with_sc.name}-no-tree", model="none",
                                 description="the leafed scenario without its crown")
            notes.append(f"No scenario without a tree in the project: the annual run uses "
                         f"'{with_sc.name}' with its crown removed.")
    from radtree.pipeline.realisations import realisations_of

    crowns = realisations_of(project, with_sc)
    if len(crowns) > 1:
        notes.append(f"Scenario '{with_sc.name}' averages {len(crowns)} random crowns in "
                     f"point-in-time runs; the annual run uses the first one "
                     f"(louvers.seed {crowns[0].switches['louvers.seed']}).")
    if with_sc.reflection == "calculated":
        notes.append(f"Scenario '{with_sc.name}' calculates the ground-reflected light "
                     "analytically for single hours; the annual run traces it (the street "
                     "is part of the coefficients).")
    notes.append("The annual sky comes from the weather file (Perez sky + sun every hour); "
                 "a scenario's own sky setting applies to the point-in-time runs only.")
    return with_sc, without_sc, notes


def annual_scenes(project: Project, with_sc: Scenario, without_sc: Scenario,
                  branches: BranchParams, grids: tuple[str, ...] | None
                  ) -> tuple[dict[str, Scene], list[str], int, list[str]]:
    """Scenes of the three variants, the grids to trace, the recommended -ab and notes."""
    from radtree.pipeline.assemble import facade_frame, make_scene

    b_on = make_scene(project, with_sc, dense_grid=False)
    b_none = make_scene(project, without_sc, dense_grid=False)
    bare = make_scene(project, replace(with_sc, model="none"), dense_grid=False)
    crown = build_leaf_off(effective_project(project, with_sc), with_sc,
                           facade_frame(effective_project(project, with_sc)), branches)
    materials = dict(bare.scene.materials)
    for k, v in crown.materials.items():
        materials.setdefault(k, v)
    off = Scene(bare.scene.meshes + crown.meshes, materials, bare.scene.grids,
                bare.scene.notes + crown.notes, bare.scene.ground_material)
    scenes = {"without": b_none.scene, "leaf_on": b_on.scene, "leaf_off": off}
    available = list(b_on.scene.grids)
    use = list(grids) if grids else available
    unknown = [g for g in use if g not in available]
    if unknown:
        raise ConfigError(f"unknown grid(s) {', '.join(unknown)} (have: {', '.join(available)})")
    for name, sc in scenes.items():
        for g in use:
            if g not in sc.grids or not np.allclose(sc.grids[g].points,
                                                    b_on.scene.grids[g].points):
                raise ConfigError(f"grid {g!r} differs between the annual scenes ({name})")
    ab = max(b_on.ab, b_none.ab)
    if project.office is not None:
        from radtree.site.office import RECOMMENDED_AB

        ab = max(ab, RECOMMENDED_AB)
    notes = list(crown.notes)
    return scenes, use, ab, notes


# ---------------------------------------------------------------- combination
# ---------------------------------------------------------------- the run


def scene_year_lux(runner: CoefficientRunner, year: YearInputs, mf: int, sun_mf: int,
                   trace: TraceParams, sun_trace: TraceParams, with_sky: bool = True
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(total, direct) lux, each (sensors, hours), of one scene over ``year``: sky coefficients
    (zero unless ``with_sky``), exact suns at ``-ab 0`` and the sun patches' reflected part."""
    _, wea, sky, suns, verts, weights, need, patch_dirs = year
    c_sky = runner.sky(mf, trace) if with_sky else np.zeros(
        (runner.n_sensors, patch_count(mf), 3), np.float32)
    c_dir = runner.suns("direct", suns.direction, 0, trace)
    c_n = runner.suns(f"patch{sun_mf}_ab{trace.ab}", patch_dirs[need], trace.ab, sun_trace)
    c_0 = runner.suns(f"patch{sun_mf}_ab0", patch_dirs[need], 0, sun_trace)
    c_ind = np.zeros((runner.n_sensors, len(patch_dirs), 3), np.float32)
    c_ind[:, need] = c_n - c_0
    return combine(c_sky, sky, c_dir, suns, c_ind, verts, weights, wea.n_hours)


def with_season(project: Project, options: AnnualOptions) -> AnnualOptions:
    """``options`` with its leaf season resolved (:func:`radtree.annual.schedule.leaf_season`)."""
    if options.leaf is not None:
        return options
    return replace(options, leaf=leaf_season(project))


@dataclass(frozen=True)
class AnnualPlan:
    """What an annual run traces: the options (leaf season resolved), the scenarios with and
    without the tree, the scenes of :data:`VARIANTS`, the grids, the ``rcontrib`` settings of
    the sky and of the reflected sun, the ground reflectance (0–1) and the notes so far."""

    options: AnnualOptions
    with_sc: Scenario
    without_sc: Scenario
    scenes: dict[str, Scene]
    grids: list[str]
    trace: TraceParams
    sun_trace: TraceParams
    rho: float
    notes: tuple[str, ...]


def plan_annual(project: Project, options: AnnualOptions, *,
                check: Callable[[Scenario], None] | None = None,
                crown_notes: bool = True) -> AnnualPlan:
    """The :class:`AnnualPlan` of ``options`` (season resolved): ``check`` refuses a leafed
    scenario before any scene is built; ``crown_notes``: keep the leaf-off crown's notes."""
    with_sc, without_sc, notes = choose_scenarios(project, options)
    if check is not None:
        check(with_sc)
    scenes, grids, rec_ab, more = annual_scenes(project, with_sc, without_sc,
                                                options.branches, options.grids)
    eng = effective_project(project, with_sc).engine
    reps = options.replicates or (DEFAULT_REPLICATES if options.method == "dc" else 1)
    ab = options.ab if options.ab is not None else (eng.ab if eng.ab is not None else rec_ab)
    trace = TraceParams(ab=ab, ad=options.ad or eng.radiance.ad,
                        lw=options.lw or eng.radiance.lw, nproc=options.nproc,
                        replicates=reps)
    sun_trace = TraceParams(ab=ab, ad=options.sun_ad or max(128, trace.ad // 4),
                            lw=options.sun_lw or max(trace.lw, SUN_LW_MIN), nproc=options.nproc,
                            replicates=reps)
    return AnnualPlan(options, with_sc, without_sc, scenes, grids, trace, sun_trace,
                      annual_ground_reflectance(project),
                      tuple(notes + (more if crown_notes else [])))


def plan_year(project: Project, plan: AnnualPlan) -> YearInputs:
    """The year of the plan (:func:`radtree.annual.weather_year.annual_weather`)."""
    o = plan.options
    return annual_weather(project, epw=o.epw, mf=o.mf, sun_mf=o.sun_mf, rho=plan.rho)


def by_grid(values: tuple[np.ndarray, np.ndarray], grids: list[str], scene: Scene
            ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """(total, direct) rows of all sensors (grid after grid) split into ``{grid: rows}``."""
    tot, dire = values
    total, direct = {}, {}
    start = 0
    for g in grids:
        n = len(scene.grids[g])
        total[g], direct[g] = tot[start:start + n], dire[start:start + n]
        start += n
    return total, direct


def _trace_variants(plan: AnnualPlan, year: YearInputs, folder: Path,
                    timing: dict[str, float], replicas: list | None = None) -> tuple[dict, dict]:
    """(total, direct) lux ``{variant: {grid: (sensors, hours)}}`` of the plan's scenes, their
    coefficients cached in ``folder/<variant>``; a progress bar over the variants. With
    replicates the year of each replicate is appended to ``replicas`` as (total, direct) of
    the same form, and the result is their mean."""
    from radtree.annual.uncertainty import year_replicates

    total: dict[str, dict[str, np.ndarray]] = {}
    direct: dict[str, dict[str, np.ndarray]] = {}
    o = plan.options
    reps = plan.trace.replicates
    if replicas is not None and reps > 1:
        replicas.extend(({}, {}) for _ in range(reps))
    for variant in progress(VARIANTS, desc="annual", unit="scene"):
        tv = time.perf_counter()
        scene = plan.scenes[variant]
        log.info(f"  {variant}: {scene.n_triangles} triangles, "
                 f"{sum(len(scene.grids[g]) for g in plan.grids)} sensors")
        runner = CoefficientRunner(scene, plan.grids, folder / variant, plan.rho)
        if replicas is not None and reps > 1:
            years = year_replicates(runner, year, o.mf, o.sun_mf, plan.trace, plan.sun_trace)
            for (tot_k, dir_k), year_k in zip(replicas, years):
                tot_k[variant], dir_k[variant] = by_grid(year_k, plan.grids, scene)
            values = (np.mean([y[0] for y in years], axis=0), years[0][1])
        else:
            values = scene_year_lux(runner, year, o.mf, o.sun_mf, plan.trace, plan.sun_trace)
        total[variant], direct[variant] = by_grid(values, plan.grids, scene)
        timing[f"{variant}_s"] = time.perf_counter() - tv
    return total, direct


def finish_annual(project: Project, plan: AnnualPlan, year: YearInputs,
                  lux: tuple[dict, dict], *, grid_scene: Scene, timing: dict[str, float],
                  t0: float, method_note: str | None = None, sunlight: bool = True,
                  replicas: list | None = None) -> AnnualResult:
    """The :class:`AnnualResult` of the variants' (total, direct) ``lux``: the crown of each
    hour (leaf season or phenology), occupancy, the sensors of ``grid_scene``, the notes
    (``method_note`` before :data:`METHOD_NOTES`), EN 17037 sunlight when ``sunlight``; the
    metrics' Monte Carlo standard errors from ``replicas`` (of :func:`_trace_variants`)."""
    weather, wea = year[0], year[1]
    total, direct = lux
    o = plan.options
    phen = phenology_of(project, o.species_phenology)
    in_leaf, fraction, weight = crown_year(total, direct, plan.grids, wea, o.season, phen)
    grid_geo = {g: {"points": grid_scene.grids[g].points,
                    "normals": grid_scene.grids[g].normals} for g in plan.grids}
    notes = [*plan.notes, f"Crown {o.season.describe() if phen is None else phen.describe()}.",
             *([method_note] if method_note else []), *METHOD_NOTES]
    sun = (standards.annual_sunlight(project, plan.scenes, plan.grids, o.sunlight_date,
                                     in_leaf, wea) if sunlight else None)
    occ = occupied(wea.hour, o.occupancy)
    spread = None
    if replicas:
        from radtree.annual.uncertainty import table

        for tot_k, dir_k in replicas:
            crown_year(tot_k, dir_k, plan.grids, wea, o.season, phen)
        spread = table([r[0] for r in replicas], plan.grids, occ)
    timing["total_s"] = time.perf_counter() - t0
    return AnnualResult(project=project, options=o, weather=weather, wea=wea, grids=grid_geo,
                        total=total, direct=direct, in_leaf=in_leaf, occupied=occ,
                        scenarios={"with": plan.with_sc.name, "without": plan.without_sc.name},
                        trace=plan.trace, sun_trace=plan.sun_trace,
                        ground_reflectance=plan.rho, notes=notes, timing=timing,
                        leaf_fraction=fraction, leaf_weight=weight, phenology=phen,
                        sunlight=sun, uncertainty=spread)


def compute_annual(project: Project, *, options: AnnualOptions | None = None
                   ) -> AnnualResult:
    """Trace the three scenes and assemble 8760 hours of illuminance per sensor (the default
    ``dc`` method): plan, the year, the scenes' coefficients, the result. Messages through
    :mod:`logging` (INFO), a progress bar over the scenes when the CLI turned bars on."""
    options = with_season(project, options or AnnualOptions())
    if options.method != "dc":
        raise ConfigError(f"compute_annual is the 'dc' method; for {options.method!r} use "
                          "radtree.annual.methods.compute")
    timing: dict[str, float] = {}
    t0 = time.perf_counter()
    plan = plan_annual(project, options)
    timing["scenes_s"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    year = plan_year(project, plan)
    timing["weather_s"] = time.perf_counter() - t1
    weather, wea, _, suns, _, _, need, _ = year
    trace, sun_trace = plan.trace, plan.sun_trace
    log.info(f"  weather: {weather.description}; {int((wea.dni + wea.dhi > 0).sum())} "
             f"daylight hours, {len(suns)} sun positions, {len(need)} sun patches "
             f"(MF {options.sun_mf})")
    log.info(f"  rcontrib: -ab {trace.ab} -ad {trace.ad} -lw {trace.lw:g} (sky, MF "
             f"{options.mf}); -ad {sun_trace.ad} -lw {sun_trace.lw:g} (reflected sun); "
             f"{trace.nproc} process(es); ground ρ {plan.rho:.3f}"
             + (f"; {trace.replicates} replicates" if trace.replicates > 1 else ""))
    replicas: list = []
    lux = _trace_variants(plan, year, project.results_dir / "annual" / "coefficients", timing,
                          replicas)
    return finish_annual(project, plan, year, lux, grid_scene=plan.scenes["leaf_on"],
                         timing=timing, t0=t0, replicas=replicas)
