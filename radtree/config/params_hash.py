"""A scenario's parameter hash: everything that changes its numbers, short and stable.

Input files count by their path relative to the project folder and their content, so a moved
project keeps its hashes and an edited input file changes them. Settings at their defaults
that were added after a hash was first written (species, photo, BSDF, forward and photon-map
keys, Radiance mist keys) are left out, so older build folders and results keep their hashes.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import fields, is_dataclass
from pathlib import Path
from typing import Any

from radtree.config.photo import drop_photo_defaults
from radtree.fileio import file_sha256_cached

#: the ``EngineParams`` fields only the Radiance photon map reads
PMAP_KEYS = ("pmap_photons", "pmap_caustic_photons", "pmap_bandwidth")
#: the ``EngineParams`` fields only Radiance's mist crowns read (turbid crowns)
MIST_KEYS = ("mist_extinction", "mist_sun")
#: the ``EngineParams`` fields only the forward engine reads
FORWARD_KEYS = ("photons", "forward_threshold", "forward_splitting", "beam_diameter_m",
                "patch_m", "forward_batches", "forward_focus_m", "forward_split",
                "forward_split_radius_m", "forward_guide", "forward_guide_radius_m",
                "target_rel_se", "max_photons", "forward_direct_sun",
                "forward_window", "forward_direct_sky", "forward_stages")


def plain(obj: Any, path: Callable[[Path], Any] = str) -> Any:
    """Dataclasses as dicts, tuples as lists, paths through ``path`` (default ``str``)."""
    if is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: plain(getattr(obj, f.name), path) for f in fields(obj)}
    if isinstance(obj, dict):
        return {k: plain(v, path) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [plain(v, path) for v in obj]
    if isinstance(obj, Path):
        return path(obj)
    return obj


def params_hashes(project: Any, scenarios: list[Any]) -> dict[str, str]:
    """``{scenario name: 12-hex-digit hash}`` of a ``Project``'s scenarios; the project's part
    is read once for all (typed ``Any``: :mod:`.schema` imports this module)."""
    base = _project_payload(project)
    return {sc.name: hashlib.sha256(json.dumps({**base, "scenario": _scenario(sc)}, sort_keys=True,
                                               default=str).encode()).hexdigest()[:12]
            for sc in scenarios}


def _scenario(sc: Any) -> dict[str, Any]:
    """A scenario's part; ``baseline`` (what the report compares against) changes no number."""
    d = plain(sc)
    d.pop("baseline", None)
    return d


def _project_payload(project: Any) -> dict[str, Any]:
    """The project's part of the hash (every table that changes numbers)."""
    d = plain(project, lambda p: _file_key(p, project.root))
    payload = {k: d[k] for k in ("site", "street", "light", "tree", "sensors", "engine",
                                 "office", "extra_geometry")}
    if payload["tree"].get("species") is None:  # no species: hashes unchanged
        payload["tree"].pop("species", None)
    payload["engine"] = project.engine.flat()   # the file's flat table: hashes unchanged
    payload["engine"].pop("workers", None)
    defaults = type(project.engine)().flat()
    for key in FORWARD_KEYS + PMAP_KEYS + MIST_KEYS + ("dense_rays",):  # at defaults: unchanged
        if payload["engine"].get(key) == defaults[key]:
            payload["engine"].pop(key, None)
    if project.honeybee is not None:   # absent otherwise: other projects' hashes unchanged
        payload["honeybee"] = {**d["honeybee"], "sha256": project.honeybee.digest()}
    drop_photo_defaults(payload["tree"])  # photo fields at their defaults: hashes unchanged
    for key, default in (("representation", "explicit"), ("bsdf", plain(type(project.tree.bsdf)()))):
        if payload["tree"].get(key) == default:   # BSDF settings unused: hashes unchanged
            payload["tree"].pop(key, None)
    from radtree.config.timezone import fixed_name

    if payload["site"].get("time_zone") == fixed_name(project.site.utc_offset_hours):
        payload["site"].pop("time_zone", None)   # a fixed offset: as before time zones
    if payload["light"].get("weather") in ("table", "epw"):
        payload["light"].pop("weather", None)    # inferred from the file: as before
    for key in ("leaf_on", "leaf_off", "accept_poor_fit"):   # change no traced hour
        payload["tree"].pop(key, None)
    if payload["tree"].get("points_scans") is None:   # airborne points: hashes unchanged
        payload["tree"].pop("points_scans", None)
    if payload["tree"].get("points") is None or "points_scans" in payload["tree"]:
        payload["tree"].pop("points_beams", None)   # no airborne points: hashes unchanged
    if project.district is not None:   # inventory inputs: relative path + content (_file_key)
        payload["district"] = d["district"]
        if payload["district"].get("turbid_above") == 500:   # at its default: hashes unchanged
            payload["district"].pop("turbid_above")
    return payload


def _file_key(path: Path, root: Path) -> str:
    """``relative/path sha256:…`` of an input file (the path as given when it is missing)."""
    try:
        name = str(path.resolve().relative_to(root.resolve()))
    except ValueError:
        name = str(path)
    if not path.is_file():
        return name
    return f"{name} sha256:{file_sha256_cached(path)}"
