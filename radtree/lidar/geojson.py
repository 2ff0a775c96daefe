"""The trees of a segmented tile as an inventory GeoJSON that ``radtree new --trees`` reads.

One ``Point`` feature per tree at the crown's area centroid (the trunk position an airborne
scan can offer; the top is in ``top_x``, ``top_y``), with the properties the inventory reader
(:func:`radtree.site.inventory.read_trees`) needs — ``id``, ``species``, ``height_m``,
``crown_diameter_m``, ``crown_base_m`` — and ``points`` (the crown's point count) and
``crown_outline`` (the crown's outline, a closed ring of [x, y] in the same coordinates).

Coordinates are the tile's (metres). The file's ``crs`` member names the CRS: the tile's own
(as EPSG:code when pyproj finds one, else its WKT), or ``crs`` given by the user (``--crs``;
``"local"`` = already the site's local frame, x east and y north in metres from the site
origin). A tile without a CRS and no ``crs`` gets no ``crs`` member: its x, y are the tile's
metres, and ``radtree new`` or ``[site] crs`` must be told their CRS before they can meet
longitude/latitude data.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from radtree.errors import ConfigError
from radtree.fileio import write_text
from radtree.lidar.segment import Segmentation


def crs_name(wkt: str | None, given: str | None, source: str) -> str | None:
    """The CRS to record: ``given`` (checked) or the tile's as ``EPSG:code`` / WKT, or None."""
    from radtree.site.inventory import check_crs

    if given:
        return check_crs(given, source)
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
    feats = []
    for t in seg.trees:
        feats.append({"type": "Feature", "id": t.id,
                      "geometry": {"type": "Point", "coordinates": [round(t.x, 3),
                                                                    round(t.y, 3)]},
                      "properties": {
                          "id": t.id, "species": species.strip(),
                          "height_m": round(t.height_m, 2),
                          "crown_diameter_m": round(t.crown_diameter_m, 2),
                          "crown_base_m": round(t.crown_base_m, 2), "points": t.points,
                          "top_x": round(t.top_x, 3), "top_y": round(t.top_y, 3),
                          "crown_outline": [[round(float(x), 3), round(float(y), 3)]
                                            for x, y in t.outline]}})
    doc: dict[str, Any] = {"type": "FeatureCollection", "features": feats}
    name = crs_name(seg.tile.crs, crs, seg.tile.source)
    if name is not None:
        doc = {"type": "FeatureCollection", "crs": {"type": "name",
                                                     "properties": {"name": name}},
               "features": feats}
    return doc


def write_inventory(seg: Segmentation, out: str | Path, species: str,
                    crs: str | None = None) -> Path:
    """Write :func:`inventory` to ``out`` (atomically)."""
    if not seg.trees:
        raise ConfigError(f"no tree of at least {seg.config.min_height_m:g} m found: check "
                          "the heights (--ground) or lower --min-height",
                          source=seg.tile.source)
    return write_text(out, json.dumps(inventory(seg, species, crs), indent=1) + "\n")
