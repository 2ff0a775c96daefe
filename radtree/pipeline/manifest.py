"""Provenance: what produced a build or a result (versions, parameters, seeds, input hashes)."""

from __future__ import annotations

import platform
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import radtree
from radtree.fileio import file_sha256
from radtree.light.weather import weather_sources

__all__ = ["file_sha256", "input_files", "manifest", "weather_record"]


def input_files(project) -> dict[str, str]:
    """Every input file the project names, with its SHA-256."""
    paths = {"project": project.source}
    for key, p in (("measured", project.measured), ("measured_rows", project.measured_rows),
                   ("direct_normal", project.light.direct_normal_table),
                   ("epw", project.light.epw),
                   ("ground_reflectance", project.street.ground_reflectance_table),
                   ("photo", project.tree.perforated.photo), ("tree_photo", project.tree.photo),
                   ("tree_points", project.tree.points), ("tree_voxels", project.tree.voxels),
                   ("tree_points_scans", project.tree.points_scans)):
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
    })
    from radtree.trees.turbid_voxels import voxel_record

    voxels = voxel_record(project.tree, str(project.source))
    if voxels is not None:   # a turbid voxel crown: its file, voxel size, leaf area, profile
        d["crown_voxels"] = voxels
    if extra:
        d.update(extra)
    return d


def _light_sources(light: Any, sky: str) -> tuple[str, str]:
    """Where an hour's direct normal and diffuse horizontal illuminance came from
    (:func:`radtree.light.weather.weather_sources`); no sky: no diffuse light."""
    dni, dhi = weather_sources(light)
    return dni, (dhi if sky == "perez" else "no sky (sun only)")


def weather_record(project: Any, states: dict[str, list[Any]]) -> dict[str, list[dict[str, Any]]]:
    """The light each scenario was traced under, per hour, from its hour states
    (``radtree.light.sky.SkyState``): ``{scenario: [{time, source, direct_normal_lux,
    diffuse_horizontal_lux, sky}]}``, illuminances in lux as traced (the report describes the
    light from this, issue 38)."""
    from radtree.config import effective_project

    out: dict[str, list[dict[str, Any]]] = {}
    for name, sts in states.items():
        sc = next((s for s in project.scenarios if s.name == name), None)
        light = (effective_project(project, sc) if sc is not None else project).light
        out[name] = []
        for st in sts:
            dni, dhi = _light_sources(light, st.sky_model)
            source = (f"direct normal and diffuse horizontal: {dni}" if dni == dhi else
                      f"direct normal: {dni}; diffuse horizontal: {dhi}")
            out[name].append({"time": st.time, "source": source, "direct_normal_lux": round(
                                  float(st.direct_normal_lux), 1),
                              "diffuse_horizontal_lux": round(float(st.diffuse_horizontal_lux), 1),
                              "sky": st.sky_model})
    return out
