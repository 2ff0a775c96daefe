"""The one engine interface: what every estimator offers and what it returns.

An engine takes a :class:`radtree.scene.Scene` (plain data: meshes, materials, sensor grids),
the hours' :class:`SkyState` and the tracing parameters, *prepares* a plan (a Radiance build
folder, an in-memory tracer…) and *traces* one hour on named grids, returning illuminance per
sensor (lux) as :class:`GridResult`. The pipeline turns those into the one results table
(:mod:`radtree.pipeline.results`); nothing above ``engines/`` knows which engine ran.
Engines register by name in :mod:`radtree.engines.registry`.
"""

from __future__ import annotations

import tempfile
from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

if TYPE_CHECKING:
    from radtree.config import EngineParams
    from radtree.light.sky import SkyState
    from radtree.scene import Scene


@dataclass
class GridResult:
    """Illuminance (lux) per sensor of one grid for one hour; ``stderr`` the Monte Carlo
    standard error per sensor (None when the engine gives none)."""

    lux: np.ndarray
    stderr: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.lux = np.asarray(self.lux, float)
        if self.stderr is not None:
            self.stderr = np.asarray(self.stderr, float)
            if self.stderr.shape != self.lux.shape:
                raise ValueError("stderr must have the shape of lux")


@dataclass
class TreeAttribution:
    """The light each tree takes from the sensors of one grid for one hour, as an engine
    attributes it while tracing (:attr:`Engine.attributes_trees`).

    ``owners``: the trees (:attr:`radtree.scene.Mesh.owners`); ``removed`` (trees, sensors):
    the illuminance each tree takes (lux; positive = less light with the tree): what removing
    that tree alone gives back; ``stderr`` its Monte Carlo standard error; ``with_trees`` /
    ``without``: the sensors traced with every tree and without the attributed ones (the same
    paths); ``unattributed`` (sensors): change found on paths that meet no tree (0 for an
    exact attribution). ``without − with_trees − Σ removed`` is the light the trees take
    jointly (overlapping crowns). The engine's module states the method."""

    owners: list[str]
    removed: np.ndarray
    stderr: np.ndarray
    with_trees: GridResult
    without: GridResult
    unattributed: np.ndarray


class Engine(ABC):
    """An estimator of sensor illuminance behind one interface.

    ``name``: the registry name (``--engine NAME``). ``uses_build_folder``: the engine runs from
    the scenario's inspectable build folder (``PROJECT/build/<scenario>/``), which the pipeline
    (re)writes before preparing; other engines keep their plan in memory. ``seeded``: the
    engine's noise is set by ``engine.rays`` and ``engine.seed`` (a fixed seed gives common
    random numbers across scenarios)."""

    name: ClassVar[str]
    missing_hint: ClassVar[str] = "it is not available here"
    uses_build_folder: ClassVar[bool] = False
    seeded: ClassVar[bool] = False
    #: the engine places a scene's prototypes by reference (Radiance ``instance``); the others
    #: trace them expanded (:meth:`radtree.scene.Scene.solid_meshes`)
    instancing: ClassVar[bool] = False
    #: :meth:`trace_ab_ladder` traces the whole ``-ab`` ladder at once (bounce orders tallied
    #: from one set of paths) rather than one trace per ``-ab``
    ladder_in_one_trace: ClassVar[bool] = False
    #: :meth:`attribute_trees` attributes the light the trees remove to each tree while tracing
    attributes_trees: ClassVar[bool] = False
    #: the engine traces light from the sources to detectors (forward): its noise is set by
    #: ``engine.photons`` per hour, which the results of such an engine are labelled with
    #: (the backward engines' by ``engine.rays`` or Radiance's ``-ad``)
    photon_budget: ClassVar[bool] = False

    @classmethod
    @abstractmethod
    def available(cls) -> bool:
        """True when the engine can run on this machine."""

    @abstractmethod
    def version(self) -> str | None:
        """The engine's version text (None when unknown)."""

    @abstractmethod
    def describe(self) -> str:
        """One line for ``radtree doctor`` and reports."""

    def details(self) -> list[str]:
        """Further lines for ``radtree doctor`` (paths, search paths)."""
        return []

    def provenance(self) -> dict[str, str | None]:
        """What a results manifest records about this engine (``<name>_version``, …)."""
        return {f"{self.name}_version": self.version()}

    def sampling(self, params: EngineParams) -> str:
        """How the engine samples, for logs and reports (e.g. ``4096 rays/sensor, seed 1``)."""
        return ""

    @abstractmethod
    def prepare(self, scene: Scene, states: list[SkyState], params: EngineParams, ab: int,
                folder: Path | None = None) -> Any:
        """A plan to trace ``states`` (their ``label`` HHMM names an hour) of ``scene`` with
        ``ab`` diffuse bounces (``-ab``; every engine counts bounces like rtrace). ``folder``: the
        scenario's build folder when ``uses_build_folder`` (already written by the pipeline),
        else a work folder the engine may use, or None."""

    @abstractmethod
    def trace(self, plan: Any, label: str, grids: list[str] | None = None
              ) -> dict[str, GridResult]:
        """Trace hour ``label`` of a plan on ``grids`` (default every grid): lux per grid."""

    def trace_many(self, plan: Any, labels: list[str], grids: list[str] | None = None
                   ) -> list[dict[str, GridResult]]:
        """:meth:`trace` of each hour of ``labels``, in order. Here one after the other; an
        engine may trace them together (the NumPy engine: every hour's paths in one batch)."""
        return [self.trace(plan, label, grids) for label in labels]

    @abstractmethod
    def commands(self, plan: Any, label: str) -> list[str]:
        """What :meth:`trace` would run for hour ``label``, as lines to print (``--dry-run``)."""

    def write_folder(self, scene: Scene, states: list[SkyState], params: EngineParams, ab: int,
                     folder: Path, scenario: str, hour_grids: dict[str, list[str]]) -> None:
        """Write the scenario's inspectable build folder (engines with ``uses_build_folder``);
        ``hour_grids`` maps an hour label to the grids traced then."""
        raise NotImplementedError(f"engine {self.name!r} writes no build folder")

    def write_index(self, build_dir: Path, scenarios: list[str]) -> None:
        """Write what runs every scenario's folder at once (e.g. a top-level Makefile)."""
        raise NotImplementedError(f"engine {self.name!r} writes no build folder")

    def trace_ab_ladder(self, scene: Scene, state: SkyState, params: EngineParams,
                        ab_values: list[int], folder: Path | None = None,
                        grids: list[str] | None = None) -> dict[int, dict[str, GridResult]]:
        """Hour ``state`` of ``scene`` traced at every ``-ab`` of ``ab_values``: lux per grid per
        ``-ab``. Here one plan and one trace per value (in ``folder``, as :meth:`prepare`);
        an engine with ``ladder_in_one_trace`` tallies bounce orders from one set of paths."""
        out = {}
        for ab in ab_values:
            plan = self.prepare(scene, [state], params, ab, folder)
            out[ab] = self.trace(plan, state.label, grids)
        return out

    def attribute_trees(self, scene: Scene, state: SkyState, params: EngineParams, ab: int,
                        grids: list[str] | None = None, owners: set[str] | None = None,
                        seed: int | None = None) -> dict[str, TreeAttribution]:
        """Hour ``state`` of ``scene`` traced with and without the faces of ``owners`` (default
        every tree, :meth:`radtree.scene.Scene.without_owners`), the difference attributed to
        each tree, per grid (engines with ``attributes_trees``)."""
        raise NotImplementedError(f"engine {self.name!r} does not attribute light to trees")

    def trace_once(self, scene: Scene, state: SkyState, params: EngineParams, ab: int,
                   grids: list[str] | None = None) -> dict[str, GridResult]:
        """Prepare and trace one hour in a temporary work folder (nothing kept)."""
        with tempfile.TemporaryDirectory(prefix="radtree-") as tmp:
            plan = self.prepare(scene, [state], params, ab, Path(tmp))
            return self.trace(plan, state.label, grids)

