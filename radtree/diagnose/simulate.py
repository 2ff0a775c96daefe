"""Simulations for the diagnosis: façade grid only, fixed seed, cached per scenario.

:class:`Simulator` traces a scenario's façade sensor grid (no dense map) at the diagnosed hours
and returns a :class:`Run`: the hourly grid mean, its Monte Carlo standard error, the hourly
row means and the per-sensor values. With the NumPy engine every scenario is traced with the
same seed (common random numbers), so the difference between a base run and a switched run —
an effect's *signature* — carries much less noise than either run.

Caching inside a run: the traced part is keyed by everything that changes the tracing (the
project, model, form, sky, reflection mode and the switches other than ``reflection.*``), the
crown geometry by what changes the scene; the analytic ground terms (``reflection = calculated``
and the ``reflection.unfiltered`` switch, :mod:`radtree.light.ground`) are added afresh each time, so
fitting those costs no tracing (nor does the street's reflectance when reflection is calculated:
the traced hours then see no ground light). Any registered engine may trace (default: the seeded engine,
whose fixed seed gives common random numbers); tracing goes through
:func:`radtree.pipeline.trace.trace_hours`, exactly as ``simulate`` traces.
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario
from radtree.engines.base import Engine
from radtree.engines.registry import engine_named
from radtree.errors import RadtreeError
from radtree.light.ground import ground_terms
from radtree.light.hours import hour_states
from radtree.pipeline.assemble import make_scene
from radtree.pipeline.trace import trace_hours
from radtree.stats import mean_stderr

#: Rays per sensor for NumPy-engine diagnosis unless given (MC SE ≈ 8 lx on Mendoza's hourly
#: mean of 8 sensors; common random numbers make signatures less noisy still).
DEFAULT_RAYS = 1024
FACADE = "facade"
GROUND_RHO = "street.ground_reflectance"


@dataclass
class Run:
    """One scenario simulated at the diagnosed hours (façade grid).

    ``lux``/``stderr``: hourly grid mean and its MC standard error (lx, NaN SE for Radiance);
    ``rows``: DataFrame indexed by time, one column per sensor row (lx); ``sensors``:
    (hours × sensors) lx; ``seconds``: wall time spent tracing for this run (0 if cached).
    """

    times: tuple[str, ...]
    lux: np.ndarray
    stderr: np.ndarray
    rows: pd.DataFrame
    sensors: np.ndarray
    seconds: float = 0.0

    def row_daily(self) -> pd.Series:
        """Daily mean per row over the hours (lx)."""
        return self.rows.mean(axis=0)


@dataclass
class _Traced:
    lux: np.ndarray  # hours × sensors, traced part
    stderr: np.ndarray  # hours × sensors
    seconds: float
    grid: Any  # the façade SensorGrid


def _canonical(project: Project, sc: Scenario) -> Scenario:
    return Scenario(name="diagnose", model=sc.model, reflection=sc.reflection,
                    sky=sc.sky or project.light.sky, form=sc.form or project.tree.form,
                    description="", switches=dict(sorted(sc.switches.items())))


def scenario_key(project: Project, sc: Scenario) -> str:
    """Hash of everything that changes a scenario's numbers (name and description aside)."""
    return project.params_hash(_canonical(project, sc))


@dataclass
class Simulator:
    """Simulates scenarios of one project at fixed hours; caches runs inside one diagnosis."""

    project: Project
    hours: tuple[str, ...]
    engine: str | None = None   # None: the seeded engine (common random numbers)
    rays: int | None = None
    seed: int | None = None
    traced_runs: int = 0
    cache_hits: int = 0
    trace_seconds: float = 0.0
    _runs: dict[str, Run] = field(default_factory=dict, repr=False)
    _traced: dict[str, _Traced] = field(default_factory=dict, repr=False)
    _scenes: dict[str, Any] = field(default_factory=dict, repr=False)
    _grid: Any = field(default=None, repr=False)
    _engine: Engine = field(init=False, repr=False)
    #: traces scenarios ahead (e.g. :meth:`radtree.diagnose.parallel.TracePool.prefetch` in
    #: worker processes); None: every run is traced here when it is asked for
    ahead: Callable[[Simulator, list[Scenario]], int] | None = field(default=None,
                                                                    repr=False)

    def __post_init__(self) -> None:
        self._engine = engine_named(self.engine)
        self.engine = self._engine.name
        unknown = [h for h in self.hours if h not in self.project.site.hours]
        if unknown:
            raise RadtreeError(f"hour(s) {', '.join(unknown)} are not among the project's "
                               f"site.hours ({', '.join(self.project.site.hours)})")
        if not self.hours:
            raise RadtreeError("no hours to simulate")
        if self.rays is None:
            self.rays = DEFAULT_RAYS
        if self.seed is None:
            self.seed = int(self.project.engine.seed)
        # façade grid only
        self.project = replace(self.project,
                               sensors=replace(self.project.sensors, dense_grid=False))

    # ------------------------------------------------------------------ public
    @property
    def engine_name(self) -> str:
        """The registry name of the engine tracing the runs."""
        return self._engine.name

    @property
    def seeded(self) -> bool:
        """True when ``rays`` and ``seed`` set the engine's noise (e.g. the NumPy engine)."""
        return self._engine.seeded

    def key(self, sc: Scenario) -> str:
        return scenario_key(self.key_project(), sc)

    def key_project(self) -> Project:
        """The project the cache keys hash (the same in every process: :mod:`.parallel`)."""
        return self.project

    def grid(self, sc: Scenario | None = None):
        """The façade sensor grid (points, normals, row labels)."""
        if self._grid is None:
            sc = sc or Scenario("diagnose", "none")
            built = self._scene(replace(sc, model="none", switches={
                k: v for k, v in sc.switches.items() if k.startswith("sensors.")}))
            self._grid = built.scene.grids[FACADE]
        return self._grid

    def sensors_per_row(self) -> dict[str, int]:
        rows = pd.Series(self.grid().rows, dtype=str).str.lower()
        return {str(k): int(v) for k, v in rows.value_counts().items()}

    def run(self, sc: Scenario) -> Run:
        """The scenario's run (from the cache when the same numbers were simulated before)."""
        key = self.key(sc)
        if key in self._runs:
            self.cache_hits += 1
            hit = self._runs[key]
            return replace(hit, seconds=0.0)
        t0 = time.perf_counter()
        run = self._traced_run(sc)
        run.seconds = time.perf_counter() - t0
        self._runs[key] = run
        return run

    # ------------------------------------------------------------------ tracing
    def _scene_key(self, sc: Scenario) -> str:
        keep = {k: v for k, v in sc.switches.items()
                if not k.startswith(("reflection.", "light.", "engine."))}
        payload = {"model": sc.model, "form": sc.form or self.project.tree.form,
                   "switches": sorted(keep.items())}
        return hashlib.sha256(json.dumps(payload, default=str).encode()).hexdigest()

    def _scene(self, sc: Scenario):
        key = self._scene_key(sc)
        if key not in self._scenes:
            self._scenes[key] = make_scene(self.project, sc, dense_grid=False)
        return self._scenes[key]

    def _traced_key(self, sc: Scenario) -> str:
        keep = {k: v for k, v in sc.switches.items() if not k.startswith("reflection.")}
        if sc.reflection == "calculated":
            # the traced hours then see no ground light (radtree.light.hours: reflectance 0,
            # no ground glow): the street's reflectance enters the ground terms only
            keep.pop(GROUND_RHO, None)
        return scenario_key(self.key_project(), replace(sc, switches=keep))

    def spec(self) -> tuple[type, tuple[Any, ...], dict[str, Any]]:
        """How to make this simulator again in another process (:mod:`.parallel`): class,
        positional and keyword arguments (picklable)."""
        return type(self), (self.project, self.hours, self.engine, self.rays, self.seed), {}

    def traced_cache(self) -> dict[str, Any]:
        """The traced parts kept so far, by traced key (what :meth:`store_traced` fills)."""
        return self._traced

    def trace_ahead(self, scenarios: list[Scenario]) -> int:
        """Let :attr:`ahead` trace ``scenarios`` before they are run (same numbers); returns
        how many it traced (0 without :attr:`ahead`)."""
        return 0 if self.ahead is None else self.ahead(self, scenarios)

    def has_traced(self, sc: Scenario) -> bool:
        """True when the traced part of ``sc`` is cached (only ground terms left to add)."""
        return self._traced_key(sc) in self._traced

    def trace_payload(self, sc: Scenario) -> Any:
        """Trace ``sc`` (no cache): what :meth:`store_traced` keeps."""
        t0 = time.perf_counter()
        # as radtree simulate: the scene's -ab rule and engine switches (the scene is cached
        # without them; trace_hours takes -ab afresh from the switched project)
        out = trace_hours(self.project, sc, self._engine, hours=list(self.hours), grids=[FACADE],
                          rays=int(self.rays or 1), seed=int(self.seed or 0),
                          built=self._scene(sc))
        lux, se = [], []
        for res in out.results:
            g = res[FACADE]
            lux.append(g.lux)
            se.append(g.stderr if g.stderr is not None else np.full(len(g.lux), np.nan))
        return _Traced(np.array(lux), np.array(se), time.perf_counter() - t0,
                       out.built.scene.grids[FACADE])

    def store_traced(self, sc: Scenario, payload: Any, seconds: float) -> None:
        """Keep the traced part of ``sc`` (from :meth:`trace_payload`, here or elsewhere)."""
        self._traced[self._traced_key(sc)] = payload
        self.traced_runs += 1
        self.trace_seconds += seconds

    def _traced_run(self, sc: Scenario) -> Run:
        states = hour_states(self.project, sc, list(self.hours))
        tkey = self._traced_key(sc)
        traced = self._traced.get(tkey)
        if traced is not None:
            self.cache_hits += 1  # only the analytic ground terms differ
        else:
            traced = self.trace_payload(sc)
            self.store_traced(sc, traced, traced.seconds)
        grid = traced.grid
        extra = np.zeros_like(traced.lux)
        for i, st in enumerate(states):
            extra[i] = ground_terms(self.project, sc, st, grid)
        return self._make_run(traced.lux + extra, traced.stderr, list(grid.rows))

    def _make_run(self, sensors: np.ndarray, stderr: np.ndarray, rows: list[str]) -> Run:
        rows_l = pd.Series(rows, dtype=str).str.lower().to_numpy()
        names = sorted(set(rows_l))
        row_means = pd.DataFrame({r: sensors[:, rows_l == r].mean(axis=1) for r in names},
                                 index=pd.Index(self.hours, name="time"))
        lux = sensors.mean(axis=1)
        se = np.array([mean_stderr(s) for s in stderr])
        return Run(tuple(self.hours), lux, se, row_means, sensors)
