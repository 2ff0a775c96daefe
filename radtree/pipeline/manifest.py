"""Provenance: what produced a build or a result (versions, parameters, seeds, input hashes)."""

from __future__ import annotations

import platform
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import radtree
from radtree.fileio import file_sha256
from radtree.light.weather import weather_record

__all__ = ["file_sha256", "input_files", "manifest"]


def input_files(project) -> dict[str, str]:
    """Every input file the project names, with its SHA-256."""
    paths = {"project": project.source}
    for key, p in (("measured", project.measured), ("measured_rows", project.measured_rows),
                   ("direct_normal", project.light.direct_normal_table),
                   ("epw", project.light.epw),
                   ("ground_reflectance", project.street.ground_reflectance_table),
                   ("photo", project.tree.perforated.photo), ("tree_photo", project.tree.photo)):
        if p is not None:
            paths[key] = p
    return {k: f"{Path(v).name} sha256:{file_sha256(Path(v))}" for k, v in paths.items()
            if Path(v).exists()}


def manifest(project, extra: dict[str, Any] | None = None,
             engines: list[Any] | None = None) -> dict[str, Any]:
    """Versions, parameters, seeds and input hashes of ``project`` (plus ``extra``); the
    provenance of ``engines`` (default: every available engine)."""
    from radtree.engines.registry import available_engines

    d: dict[str, Any] = {"radtree_version": radtree.__version__}
    for engine in available_engines() if engines is None else engines:
        d.update(engine.provenance())
    d.update({
        "python": platform.python_version(),
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "project": project.name,
        "parameters": project.to_dict(),
        "seeds": {"engine": project.engine.seed, "louvers": project.tree.louvers.seed},
        "inputs": input_files(project),
        "params_hash": project.params_hashes(project.scenarios),
        "weather": weather_record(project),
    })
    if extra:
        d.update(extra)
    return d
