"""Three-phase closure: the chain of :class:`radtree.annual.threephase.ThreePhase` against a
direct ``rcontrib`` of the *same* BSDF-crown scene (no crown representation in the
difference, only the matrices' own error), per grid, on two uniform light sources:

* ``sky`` — radiance 1 above the horizon (every Reinhart patch 1, the ``h=u`` ground column 0);
* ``ground`` — radiance 1 below the horizon (the ground column 1, the sky 0).

Each sensor's value is its irradiance per unit radiance (lux per lux/π, W m⁻² per W m⁻² sr⁻¹),
grey (the mean of the three channels). The chain is split into its by-pass (``V_sky``), the
light the crown transmits (Σ V·T·D) and the light it reflects back (Σ V·R·D').
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from radtree.annual.coefficients import CoefficientRunner, TraceParams
from radtree.annual.facets import FACETS
from radtree.annual.threephase import ThreePhase, _scene_with
from radtree.engines.radiance import threephase as rad3
from radtree.scene import Scene
from radtree.trees.model import TreeModel

LIGHTS = {"sky": slice(1, None), "ground": slice(0, 1)}
COLUMNS = ["grid", "state", "light", "reference", "chain", "ratio", "bypass", "transmitted",
           "reflected", "groups"]


@dataclass(frozen=True)
class ClosureSettings:
    """``trace``: the view matrix's and the reference's rcontrib settings; ``samples``: rays per
    Klems patch of a level-0 group's daylight matrix (``-c``); ``level``, ``material_up``:
    the facet grouping of :func:`radtree.annual.facets.facet_groups` (level None: the annual
    method's, :class:`radtree.annual.threephase.ThreePhase`; :data:`~radtree.annual.facets.FACETS`
    one group per facet plane); ``tile_m`` the wall cap's tile size (0:
    :data:`radtree.annual.threephase.GROUP_TILE_M`)."""

    trace: TraceParams
    samples: int = 100
    level: int | None = None
    material_up: bool = False
    tile_m: float = 0.0

    def __post_init__(self) -> None:
        if self.samples < 1 or (self.level is not None and self.level < FACETS):
            raise ValueError(f"closure: samples ≥ 1 and level ≥ {FACETS} or None, got "
                             f"{self.samples}, {self.level}")


def chain_parts(tp: ThreePhase, state: str) -> tuple[dict[str, np.ndarray], int]:
    """(sensors, patches) grey coefficients of the chain's by-pass, transmitted and reflected
    parts for ``state``, and the number of daylight-matrix groups."""
    views, v_sky = tp.view()
    groups = tp.d_groups(views, v_sky)
    files, vs = tp.view(groups, "d")
    days = tp.daylight(state, groups)
    back = tp.daylight(state, groups, room_side=True)
    n = vs.shape[:2]
    trans, refl = np.zeros(n), np.zeros(n)
    for v, t, d in zip(files, tp.transmission(state, groups), days):
        trans += rad3.multiply(v, t, d).mean(axis=2)
    for v, r, d in zip(files, tp.transmission(state, groups, reflection=True), back):
        refl += rad3.multiply(v, r, d).mean(axis=2)
    return {"bypass": vs.mean(axis=2), "transmitted": trans, "reflected": refl}, len(groups)


def closure_sensors(bare: Scene, *, models: dict[str, TreeModel], form: str,
                    grids: list[str], rho: float, folder: Path, settings: ClosureSettings,
                    state: str) -> tuple[np.ndarray, dict[str, np.ndarray], int]:
    """(sensors, patches) grey coefficients of the reference (rcontrib on the BSDF-crown
    scene, MF 1) and of the chain's parts (:func:`chain_parts`), the number of groups.
    Matrices are cached in ``folder`` by their inputs."""
    level = "default" if settings.level is None else settings.level
    tag = (f"l{level}_{'material' if settings.material_up else 'default'}"
           + (f"_t{settings.tile_m:g}" if settings.tile_m else ""))
    tp = ThreePhase(folder / f"chain_{tag}", bare=bare, models=models, form=form, grids=grids,
                    rho=rho, mf=1, trace=settings.trace, samples=settings.samples,
                    level=settings.level, material_up=settings.material_up,
                    tile_m=settings.tile_m)
    runner = CoefficientRunner(_scene_with(bare, models[state]), grids,
                               folder / f"reference_{state}", rho)
    ref = runner.sky(1, settings.trace).mean(axis=2)
    parts, n_groups = chain_parts(tp, state)
    return ref, parts, n_groups


def closure_table(bare: Scene, *, models: dict[str, TreeModel], form: str, grids: list[str],
                  rho: float, folder: Path, settings: ClosureSettings,
                  states: tuple[str, ...] = ("leaf_on",)) -> pd.DataFrame:
    """One row per grid × state × light (:data:`COLUMNS`): the grid's mean of the reference
    and of the chain (:func:`closure_sensors`), their ratio and the chain's parts."""
    sizes = [len(bare.grids[g]) for g in grids]
    cuts = np.cumsum([0, *sizes])
    rows = []
    for state in states:
        ref, parts, n_groups = closure_sensors(bare, models=models, form=form, grids=grids,
                                               rho=rho, folder=folder, settings=settings,
                                               state=state)
        for light, cols in LIGHTS.items():
            for k, g in enumerate(grids):
                rs = slice(cuts[k], cuts[k + 1])
                r = float(ref[rs, cols].sum(axis=1).mean())
                p = {n: float(v[rs, cols].sum(axis=1).mean()) for n, v in parts.items()}
                c = sum(p.values())
                rows.append({"grid": g, "state": state, "light": light, "reference": r,
                             "chain": c, "ratio": c / r if r > 0 else float("nan"), **p,
                             "groups": n_groups})
    return pd.DataFrame(rows, columns=COLUMNS)
