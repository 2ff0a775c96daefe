"""The trees of a segmented tile as an inventory GeoJSON that ``radtree new --trees`` reads.

One ``Point`` feature per tree at the crown's area centroid (the trunk position an airborne
scan can offer; the top is in ``top``), with the properties the inventory reader
(:func:`radtree.site.inventory.read_trees`) needs — ``id``, ``species``, ``height_m``,
``crown_diameter_m``, ``crown_base_m`` — and ``points`` (the crown's point count) and
``crown_outline`` (the crown's outline, a closed ring of [x, y] in the same coordinates).

Coordinates: longitude/latitude (WGS 84, the GeoJSON default of RFC 7946; pyproj) when the
tile's CRS is known — its own (WKT or GeoTIFF keys) or ``crs`` given by the user (``--crs``,
which wins) — so ``radtree new`` finds the site from them. ``crs = "local"`` (x, y already the
site's local frame, metres east and north of the site origin) keeps the metres and records
``"local"`` in the file's ``crs`` member. A tile without a CRS and no ``crs`` keeps its metres
and gets no ``crs`` member: ``radtree new`` / ``[site] crs`` must be told their CRS before they
can meet longitude/latitude data.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from radtree.errors import ConfigError
from radtree.fileio import write_text
from radtree.lidar.segment import Segmentation


def crs_name(wkt: str | None, given: str | None, source: str) -> str | None:
    """The CRS to record: ``given`` (checked) or the tile's as ``EPSG:code`` / WKT, or None."""
    from radtree.site.inventory import check_crs

    if given:
        check_crs(given, source)
        if given != "local":
            from pyproj import CRS

            if CRS.from_user_input(given).is_geographic:
                raise ConfigError(f"--crs {given} is geographic (degrees), but a tile's x, y "
                                  "are metres: give its projected CRS (e.g. EPSG:32633) or "
                                  "'local'", source=source, field="crs")
        return given
    if wkt is None:
        return None
    from pyproj import CRS

    crs = CRS.from_wkt(wkt)
    code = crs.to_epsg(min_confidence=70)
    return f"EPSG:{code}" if code else wkt


def inventory(seg: Segmentation, species: str, crs: str | None = None) -> dict[str, Any]:
    """The FeatureCollection (module text); ``species`` for every tree."""
    if not species.strip():
        raise ConfigError("an airborne scan cannot tell species: give one (--species NAME; "
                          "edit the file per tree afterwards)", field="species")
    name = crs_name(seg.tile.crs, crs, seg.tile.source)
    if name is None or name == "local":
        def to_out(x: np.ndarray, y: np.ndarray) -> np.ndarray:
            return np.round(np.column_stack([x, y]), 3)
    else:
        from pyproj import Transformer

        t = Transformer.from_crs(name, "EPSG:4326", always_xy=True)

        def to_out(x: np.ndarray, y: np.ndarray) -> np.ndarray:
            lon, lat = t.transform(np.asarray(x, float), np.asarray(y, float))
            return np.round(np.column_stack([lon, lat]), 8)

    feats = []
    for t_ in seg.trees:
        pos = to_out(np.array([t_.x, t_.top_x]), np.array([t_.y, t_.top_y]))
        ring = to_out(t_.outline[:, 0], t_.outline[:, 1])
        feats.append({"type": "Feature", "id": t_.id,
                      "geometry": {"type": "Point", "coordinates": pos[0].tolist()},
                      "properties": {
                          "id": t_.id, "species": species.strip(),
                          "height_m": round(t_.height_m, 2),
                          "crown_diameter_m": round(t_.crown_diameter_m, 2),
                          "crown_base_m": round(t_.crown_base_m, 2), "points": t_.points,
                          "top": pos[1].tolist(), "crown_outline": ring.tolist()}})
    doc: dict[str, Any] = {"type": "FeatureCollection", "features": feats}
    if name == "local":
        doc = {"type": "FeatureCollection",
               "crs": {"type": "name", "properties": {"name": "local"}}, "features": feats}
    return doc


def write_inventory(seg: Segmentation, out: str | Path, species: str,
                    crs: str | None = None) -> Path:
    """Write :func:`inventory` to ``out`` (atomically)."""
    if not seg.trees:
        raise ConfigError(f"no tree of at least {seg.config.min_height_m:g} m found: check "
                          "the heights (--ground) or lower --min-height",
                          source=seg.tile.source)
    return write_text(out, json.dumps(inventory(seg, species, crs), indent=1) + "\n")
