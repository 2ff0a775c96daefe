"""Refuse a project up front when it is too big: triangles per scene and estimated memory.

The thresholds are ``[limits]`` of the project file (:mod:`radtree.config.limits`). Memory is
an estimate, not a measurement: every scene held in this process costs
:data:`BYTES_PER_TRIANGLE_HELD` per triangle (float64 vertices and faces, the in-process
engines' acceleration structure), and every worker tracing at once costs :data:`BASE_BYTES`
plus :data:`BYTES_PER_TRIANGLE_TRACED` per triangle of its scene (rtrace's octree and
objects: measured 54 MiB max RSS for 200 000 triangles, ≈ 270 B each, rounded up).
Available memory is ``MemAvailable`` of ``/proc/meminfo`` (or the physical memory from
``os.sysconf`` where there is no /proc).
"""

from __future__ import annotations

import os
from pathlib import Path

from radtree.config import Project, Scenario
from radtree.errors import ConfigError

BYTES_PER_TRIANGLE_HELD = 200
BYTES_PER_TRIANGLE_TRACED = 300
BASE_BYTES = 100 * 2**20
GIB = 2**30


def available_memory(meminfo: Path = Path("/proc/meminfo")) -> int | None:
    """Bytes of memory available to a new process, or None when unknown."""
    try:
        for line in meminfo.read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return None


def check_triangles(project: Project, scenario: Scenario, triangles: int) -> None:
    """ConfigError when a scenario's scene has more triangles than ``limits.max_triangles``."""
    limit = project.limits.max_triangles
    if triangles > limit:
        raise ConfigError(
            f"scenario {scenario.name} would build {triangles:,} triangles, more than the "
            f"limit of {limit:,}: use larger slats (tree.louvers.slat_size_m), fewer layers "
            "(tree.louvers.layers) or a lower tree.perforated.resolution, or raise "
            "max_triangles in [limits]", source=str(project.source), field="limits.max_triangles")


def memory_estimate(triangles: list[int], workers: int) -> int:
    """Bytes a run is estimated to need: ``triangles`` of every scene held, ``workers`` of the
    largest traced at once."""
    if not triangles:
        return 0
    held = BYTES_PER_TRIANGLE_HELD * sum(triangles)
    traced = min(workers, len(triangles)) * (BASE_BYTES + BYTES_PER_TRIANGLE_TRACED
                                            * max(triangles))
    return held + traced


def check_memory(project: Project, triangles: list[int], workers: int,
                 available: int | None = None) -> None:
    """ConfigError when :func:`memory_estimate` exceeds ``limits.max_memory_fraction`` of the
    available memory (nothing is checked when that is unknown)."""
    available = available_memory() if available is None else available
    if available is None:
        return
    need = memory_estimate(triangles, workers)
    share = project.limits.max_memory_fraction
    if need > share * available:
        raise ConfigError(
            f"this run would need about {need / GIB:.2f} GiB ({len(triangles)} scene(s), "
            f"{sum(triangles):,} triangles, {workers} worker(s)), more than {share * 100:g} % of the "
            f"{available / GIB:.2f} GiB available: use fewer --workers or scenarios at once "
            "(-s), a coarser crown model, or raise max_memory_fraction in [limits]",
            source=str(project.source), field="limits.max_memory_fraction")
