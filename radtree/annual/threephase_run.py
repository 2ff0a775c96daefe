"""``radtree annual --method 3phase``: the run, step by step (the method: :mod:`.threephase`).

:func:`compute_annual_3phase` plans as the default method does
(:func:`radtree.annual.run.plan_annual`: scenarios, scenes, ``rcontrib`` settings), computes
the crown BSDFs and their BSDF crowns (:func:`_crowns`), reads the year, traces the view
matrix once and, per leaf state, the sun runs and the chain's coefficients
(:func:`_state_lux`), and returns the same :class:`radtree.annual.run.AnnualResult`: variants
``leaf_on``/``leaf_off`` from the crown BSDFs, ``without`` as the default method.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from radtree.annual.coefficients import CoefficientRunner
from radtree.annual.fivephase import five_phase_sun
from radtree.annual.run import (
    AnnualOptions,
    AnnualPlan,
    AnnualResult,
    by_grid,
    finish_annual,
    plan_annual,
    plan_year,
    scene_year_lux,
    with_season,
)
from radtree.annual.threephase import (
    GROUP_MATERIAL_UP,
    STATES,
    ThreePhase,
    _scene_with,
    crown_models,
    sky_lux,
    state_xmls,
)
from radtree.annual.weather_year import YearInputs
from radtree.config import Project, Scenario
from radtree.errors import ConfigError
from radtree.scene import Scene
from radtree.trees.model import TreeModel

log = logging.getLogger(__name__)

SUN_NOTES = {
    "explicit": "both on the explicit crown (slats, bare branches) of each leaf state",
    "bsdf": "both on the BSDF-crown scene of each leaf state",
    "fivephase": ("by the five-phase idea: the sun on the BSDF-crown scene minus the same "
                  "with the surroundings black, plus the sun through the explicit crown "
                  "(slats, bare branches) with the surroundings black"),
}


def _louvers_only(project: Project) -> Callable[[Scenario], None]:
    """The check of :func:`plan_annual`: the BSDF is computed from a louvers crown's slats."""
    def check(sc: Scenario) -> None:
        if sc.model != "louvers":
            raise ConfigError(f"--method 3phase needs a louvers crown (the BSDF is computed "
                              f"from its slats); scenario '{sc.name}' is {sc.model!r}",
                              source=str(project.source))
    return check


def _crowns(project: Project, plan: AnnualPlan
            ) -> tuple[dict[str, list[tuple[float, float, Path]]], dict[str, TreeModel], str,
                       Scene]:
    """The crown BSDFs of each leaf state (XML bands), their BSDF crowns, the crown's form and
    the scene without a crown."""
    from radtree.pipeline.assemble import make_scene

    xmls = state_xmls(project, plan.with_sc)
    models, form = crown_models(project, plan.with_sc, xmls)
    bare = make_scene(project, replace(plan.with_sc, model="none"), dense_grid=False).scene
    return xmls, models, form, bare


def _scene_lux(plan: AnnualPlan, year: YearInputs, scene: Scene, folder: Path,
               with_sky: bool) -> tuple[np.ndarray, np.ndarray]:
    """(total, direct) lux of ``scene`` by the default method's coefficients (in ``folder``)."""
    runner = CoefficientRunner(scene, plan.grids, folder, plan.rho)
    o = plan.options
    return scene_year_lux(runner, year, o.mf, o.sun_mf, plan.trace, plan.sun_trace, with_sky)


def _state_lux(plan: AnnualPlan, year: YearInputs, *, state: str, tp: ThreePhase,
               crown: Scene, views: tuple[list[Path], np.ndarray], work: Path,
               timing: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """(total, direct) lux of one leaf state: the sun runs (on the explicit scene, the
    BSDF-crown scene ``crown``, or both by the five-phase idea, as ``sun_crown`` says) plus
    the chain's sky light."""
    tv = time.perf_counter()
    if plan.options.sun_crown == "explicit":   # the default method's sun runs and cache
        sun_tot, sun_dir = _scene_lux(plan, year, plan.scenes[state],
                                      work / "coefficients" / state, False)
    elif plan.options.sun_crown == "fivephase":
        o = plan.options
        folder = work / "threephase"
        sun_tot, sun_dir = five_phase_sun(
            lambda r: scene_year_lux(r, year, o.mf, o.sun_mf, plan.trace, plan.sun_trace,
                                     False),
            bsdf_crown=crown, explicit=plan.scenes[state], surroundings=tp.bare,
            grids=plan.grids, rho=plan.rho,
            folders=(folder / f"sun_{state}", folder / f"sun_{state}_black",
                     folder / f"sun_{state}_explicit_black"))
    else:
        sun_tot, sun_dir = _scene_lux(plan, year, crown, work / "threephase" / f"sun_{state}",
                                      False)
    timing[f"{state}_sun_s"] = time.perf_counter() - tv
    td = time.perf_counter()
    dc = tp.coefficients(state, *views)
    timing[f"{state}_matrices_s"] = time.perf_counter() - td
    ts = time.perf_counter()
    sky_tot = sky_lux(dc, year[2])
    timing[f"{state}_sky_product_s"] = time.perf_counter() - ts
    timing[f"{state}_s"] = time.perf_counter() - tv
    return (sun_tot + sky_tot).astype(np.float32), sun_dir


def compute_annual_3phase(project: Project, *, options: AnnualOptions) -> AnnualResult:
    """The annual run of :func:`radtree.annual.run.compute_annual` by the three-phase method
    (:mod:`radtree.annual.threephase`); the same :class:`AnnualResult`, variants
    ``leaf_on``/``leaf_off`` from the crown BSDFs, ``without`` as the default method."""
    options = with_season(project, options)
    timing: dict[str, float] = {}
    t0 = time.perf_counter()
    plan = plan_annual(project, options, check=_louvers_only(project), crown_notes=False)
    t1 = time.perf_counter()
    xmls, models, form, bare = _crowns(project, plan)
    timing["bsdf_s"] = time.perf_counter() - t1
    timing["scenes_s"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    year = plan_year(project, plan)
    timing["weather_s"] = time.perf_counter() - t1
    work = project.results_dir / "annual"
    names = sorted({Path(b[2]).name for s in STATES for b in xmls[s]})
    log.info(f"  3-phase: {form} crown, BSDFs {', '.join(names)}")
    tp = ThreePhase(work / "threephase", bare=bare, models=models, form=form, grids=plan.grids,
                    rho=plan.rho, mf=options.mf, trace=plan.trace,
                    samples=options.daylight_samples, material_up=GROUP_MATERIAL_UP)
    t1 = time.perf_counter()
    views = tp.view()
    timing["view_s"] = time.perf_counter() - t1
    tv = time.perf_counter()
    per = {"without": _scene_lux(plan, year, plan.scenes["without"],
                                 work / "coefficients" / "without", True)}
    timing["without_s"] = time.perf_counter() - tv
    for state in STATES:
        per[state] = _state_lux(plan, year, state=state, tp=tp,
                                crown=_scene_with(bare, models[state]), views=views,
                                work=work, timing=timing)
    timing.update({f"3phase_{k}": v for k, v in tp.timing.items()})
    split = {variant: by_grid(lux, plan.grids, bare) for variant, lux in per.items()}
    lux = ({v: t for v, (t, _) in split.items()}, {v: d for v, (_, d) in split.items()})
    note = (f"Method: three-phase (V·T·D·s with dctimestep; {len(tp.groups)} shell facet "
            "groups; the crown BSDFs leaf-on and leaf-off); direct and reflected sun as "
            f"the default method, {SUN_NOTES[options.sun_crown]}.")
    return finish_annual(project, plan, year, lux, grid_scene=bare, timing=timing, t0=t0,
                         method_note=note, sunlight=False)
