"""The built-in NumPy Monte Carlo engine behind the engine interface."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from radtree.engines.base import GridResult, TreeAttribution
from radtree.engines.common.inprocess import InProcessEngine
from radtree.engines.common.kernel import name as kernel_name
from radtree.engines.numpy.engine import describe
from radtree.engines.numpy.tracing import trace_bounce_ladder, trace_hour, trace_states

if TYPE_CHECKING:
    from radtree.config import EngineParams
    from radtree.light.sky import SkyState
    from radtree.scene import Scene


@dataclass
class NumpyPlan:
    """A scene, its hours by label (HHMM) and the parameters, ready to trace in memory."""

    scene: Scene
    states: dict[str, SkyState]
    params: EngineParams


class NumpyEngine(InProcessEngine):
    """Vectorised backward path tracing (Embree first-hit queries when available). Like for
    like with Radiance: ``max_bounces`` = the scene's ``-ab``."""

    name = "numpy"
    seeded = True
    ladder_in_one_trace = True
    attributes_trees = True

    def describe(self) -> str:
        return f"available ({describe()})"

    def provenance(self) -> dict[str, str | None]:
        """The NumPy version (and Embree) and which shadow-ray kernel traced: ``c`` (the
        compiled one) or ``numpy`` — the same numbers either way."""
        return {**super().provenance(), "numpy_kernel": kernel_name()}

    def sampling(self, params: EngineParams) -> str:
        p = params.numpy
        dense = f" ({p.dense_rays} per dense-map point)" if p.dense_rays is not None else ""
        return f"{p.rays} rays/sensor{dense}, {p.sampling} sampling, seed {params.seed}"

    def prepare(self, scene: Scene, states: list[SkyState], params: EngineParams, ab: int,
                folder: Path | None = None) -> NumpyPlan:
        return NumpyPlan(scene, {s.label: s for s in states},
                         params.changed(ab=ab, max_bounces=ab))

    def trace(self, plan: NumpyPlan, label: str, grids: list[str] | None = None
              ) -> dict[str, GridResult]:
        return trace_hour(plan.scene, plan.states[label], plan.params, grids=grids)

    def trace_many(self, plan: NumpyPlan, labels: list[str], grids: list[str] | None = None
                   ) -> list[dict[str, GridResult]]:
        """Every hour's paths in the same batches (:func:`trace_states`)."""
        return trace_states(plan.scene, [plan.states[lb] for lb in labels], plan.params,
                            grids=grids)

    def trace_ab_ladder(self, scene: Scene, state: SkyState, params: EngineParams,
                        ab_values: list[int], folder: Path | None = None,
                        grids: list[str] | None = None) -> dict[int, dict[str, GridResult]]:
        """One trace to the largest ``-ab``, its contributions tallied by bounce order."""
        return trace_bounce_ladder(scene, state, params, ab_values, grids)

    def attribute_trees(self, scene: Scene, state: SkyState, params: EngineParams, ab: int,
                        grids: list[str] | None = None, owners: set[str] | None = None,
                        seed: int | None = None) -> dict[str, TreeAttribution]:
        """Paired paths, each difference given to the first crown it crossed
        (:mod:`radtree.engines.numpy.attribution`)."""
        from radtree.engines.numpy.attribution import attribute_hour

        return attribute_hour(scene, state, params.changed(ab=ab, max_bounces=ab), grids,
                              owners, seed)

    def commands(self, plan: NumpyPlan, label: str) -> list[str]:
        st = plan.states[label]
        return [f"numpy engine: {st.time}, {plan.scene.n_triangles} triangles, "
                f"{plan.params.numpy.rays} rays/sensor, -ab {plan.params.numpy.max_bounces}"]
