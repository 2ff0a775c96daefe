"""How to run a project's traces: :class:`RunOptions` (``simulate``, ``convergence``, ``sweep``).

One frozen value, checked on creation, instead of a row of keyword arguments::

    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project
    simulate_project(project, options=RunOptions(scenarios=("E",), hours=("12:30",),
                                                  workers=2))

Times are local ``HH:MM`` strings of the project's hours; lists given are kept as tuples.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from radtree.config.spec import TIME_RE
from radtree.engines.base import Engine
from radtree.errors import ConfigError
from radtree.pipeline.executor import Executor, ThreadExecutor, make_executor, scheduler_problem

__all__ = ["RunOptions"]


def _names(value: Any) -> tuple[str, ...] | None:
    """None or empty → None (all); a string or a list → a tuple of its names in order."""
    if value is None:
        return None
    items = (value,) if isinstance(value, str) else tuple(value)
    return tuple(dict.fromkeys(str(v) for v in items)) or None


@dataclass(frozen=True)
class RunOptions:
    """What to trace and how.

    ``engine``: a name of :data:`radtree.engines.registry.ENGINE_CHOICES`, an engine instance,
    or None (the project's ``engine.name``; ``auto`` → Radiance when found, else NumPy; a
    sweep: its ``[sweep]`` table's engine first). ``scenarios``/``hours``/``grids``: only these
    (None: all; the dense façade map only at ``sensors.dense_hours``). ``workers``: jobs at once
    (None: the project's ``engine.workers``; a sweep: one per core). ``scheduler``: None (a
    thread pool in this process), ``"sequential"``, ``"local"`` (a Dask LocalCluster) or a Dask
    scheduler address ``"tcp://HOST:PORT"`` (:mod:`radtree.pipeline.executor`). ``fresh``:
    recompute every finished part (``simulate``) or earlier ``-ab`` step (``convergence``)
    instead of resuming from it. ``tree_impact``: ``simulate`` attributes the light each tree
    takes (``results/tree_impact.csv``, when the project has a scenario without trees); False
    skips it — the NumPy engine's attribution traces each hour two to three times more."""

    engine: Any = None
    scenarios: tuple[str, ...] | None = None
    hours: tuple[str, ...] | None = None
    grids: tuple[str, ...] | None = None
    workers: int | None = None
    scheduler: str | None = None
    fresh: bool = False
    tree_impact: bool = True

    def __post_init__(self) -> None:
        for name in ("scenarios", "hours", "grids"):
            object.__setattr__(self, name, _names(getattr(self, name)))
        bad = [h for h in self.hours or () if not TIME_RE.match(h)]
        if bad:
            raise ConfigError(f"hour {bad[0]!r}: expected HH:MM, e.g. 13:30", field="hours")
        if self.workers is not None and (isinstance(self.workers, bool)
                                         or not isinstance(self.workers, int)
                                         or self.workers < 1):
            raise ConfigError(f"workers {self.workers!r}: expected a whole number ≥ 1",
                              field="workers")
        if self.scheduler is not None and scheduler_problem(self.scheduler):
            raise ConfigError(scheduler_problem(self.scheduler), field="scheduler")
        if self.engine is not None and not isinstance(self.engine, str | Engine):
            raise ConfigError(f"engine {self.engine!r}: expected an engine name or instance",
                              field="engine")

    @property
    def resume(self) -> bool:
        """Finished work is reused (not ``fresh``)."""
        return not self.fresh

    def executor(self, threads: int) -> Executor:
        """The executor of :attr:`scheduler`: without one a pool of :attr:`workers` threads
        (default ``threads``); a Dask LocalCluster has :attr:`workers` processes (default one
        per core)."""
        if self.scheduler is None:
            return ThreadExecutor(self.workers or threads)
        return make_executor(self.scheduler, self.workers)
