"""The forward light-tracing engine behind the engine interface (``--engine forward``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from radtree.engines.base import GridResult
from radtree.engines.common.inprocess import InProcessEngine
from radtree.engines.common.raycast import embree_available
from radtree.engines.forward.run import check_beam, trace_forward
from radtree.engines.forward.settings import ForwardSettings

if TYPE_CHECKING:
    from radtree.config import EngineParams
    from radtree.light.sky import SkyState
    from radtree.scene import Scene


@dataclass
class ForwardPlan:
    """A scene, its hours by label (HHMM) and the validated settings, traced in memory."""

    scene: Scene
    states: dict[str, SkyState]
    settings: ForwardSettings
    workers: int


class ForwardEngine(InProcessEngine):
    """Photons from the sun (collimated: whole scene or a beam) and the sky, ray splitting or
    Russian roulette, square patch detectors around the sensors (TracePro's method)."""

    name = "forward"
    photon_budget = True

    def describe(self) -> str:
        ray = "embree" if embree_available() else "numpy-bvh"
        return f"forward light tracing (photons → patch detectors), ray backend {ray}"

    def sampling(self, params: EngineParams) -> str:
        return ForwardSettings.from_params(params).describe()

    def prepare(self, scene: Scene, states: list[SkyState], params: EngineParams, ab: int,
                folder: Path | None = None) -> ForwardPlan:
        """The plan; a sun beam that misses the target grid at any hour is a ConfigError
        before anything is traced."""
        settings = ForwardSettings.from_params(params, ab)
        for st in states:
            check_beam(scene, st, settings)
        return ForwardPlan(scene, {s.label: s for s in states}, settings,
                           int(params.workers or 1))

    def trace(self, plan: ForwardPlan, label: str, grids: list[str] | None = None
              ) -> dict[str, GridResult]:
        return trace_forward(plan.scene, plan.states[label], plan.settings, grids,
                             workers=plan.workers).grids

    def commands(self, plan: ForwardPlan, label: str) -> list[str]:
        st = plan.states[label]
        return [f"forward engine: {st.time}, {plan.scene.n_triangles} triangles, "
                f"{plan.settings.describe()}, -ab {plan.settings.max_bounces}"]
