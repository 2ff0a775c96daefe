"""Tree inventories and building footprints read from GeoJSON / CSV into the local frame.

The local frame: a transverse Mercator projection centred on the site origin (``[site]
latitude, longitude``, WGS 84), so x points east and y north (grid north = true north on the
central meridian), metres, z up (``pyproj``). Inputs are in longitude/latitude (``EPSG:4326``,
the GeoJSON default of RFC 7946) or in a projected CRS named by the GeoJSON file's ``crs``
member (``{"type": "name", "properties": {"name": "EPSG:32719"}}``) or by ``[site] crs``
(CSV: columns ``x, y``, or ``lon, lat`` for geographic coordinates).

Every problem raises one :class:`~radtree.errors.ConfigError` naming the file and the feature
id (``feature 'T017'``): missing or non-positive sizes, unknown CRS, self-intersecting or
degenerate footprints, repeated ids. Species, buildings-vs-trees clashes are checked where
both are known (:func:`check_trees_against_buildings`, :mod:`radtree.trees.district`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from radtree.errors import ConfigError

TREE_REQUIRED = ("species", "height_m", "crown_diameter_m", "crown_base_m")


#: a feature farther than this from the median of the others is refused
MAX_FROM_REST_M = 5000.0
#: features spread over more than this (bounding-box diagonal) are refused
MAX_SPREAD_M = 10000.0
#: a feature farther than this from the site origin ([site] latitude/longitude) is refused
MAX_FROM_SITE_M = 10000.0


@dataclass(frozen=True)
class LocalFrame:
    """Source CRS ↔ local metric frame at the site origin (x east, y north, metres)."""

    crs: str
    latitude: float
    longitude: float

    def _local(self) -> str:
        return (f"+proj=tmerc +lat_0={self.latitude!r} +lon_0={self.longitude!r} +k=1 +x_0=0 "
                "+y_0=0 +ellps=WGS84 +units=m +no_defs")

    def to_local(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.crs == "local":
            return np.asarray(x, float), np.asarray(y, float)
        t = _transformer(self.crs, self._local())
        return tuple(np.asarray(v, float) for v in t.transform(x, y))  # type: ignore[return-value]

    def to_source(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.crs == "local":
            return np.asarray(x, float), np.asarray(y, float)
        t = _transformer(self._local(), self.crs)
        return tuple(np.asarray(v, float) for v in t.transform(x, y))  # type: ignore[return-value]


@lru_cache(maxsize=16)
def _transformer(src: str, dst: str) -> Any:
    from pyproj import Transformer

    return Transformer.from_crs(src, dst, always_xy=True)


def check_crs(crs: str, source: str) -> str:
    """``crs`` if pyproj knows it, else ConfigError naming the file."""
    from pyproj import CRS
    from pyproj.exceptions import CRSError

    if crs == "local":   # already x east, y north in metres from the site origin
        return crs
    try:
        CRS.from_user_input(crs)
    except CRSError as exc:
        raise ConfigError(f"unknown CRS {crs!r} ({exc})", source=source, field="crs") from None
    return crs


@dataclass(frozen=True)
class Feature:
    """One inventory feature: id, geometry coordinates in the source CRS, properties."""

    id: str
    kind: str                      # "Point" | "Polygon"
    coords: Any
    props: dict[str, Any]


def read_features(path: Path, default_crs: str, kind: str, prefix: str
                  ) -> tuple[list[Feature], str]:
    """Features of a GeoJSON FeatureCollection (or, for points, a CSV) and their CRS."""
    src = str(path)
    if path.suffix.lower() == ".csv":
        if kind != "Point":
            raise ConfigError("footprints must be a GeoJSON file of polygons", source=src)
        return _csv_points(path, default_crs, prefix)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ConfigError(f"not valid GeoJSON: {exc}", source=src) from None
    if not isinstance(data, dict) or data.get("type") != "FeatureCollection":
        raise ConfigError("expected a GeoJSON FeatureCollection", source=src)
    crs = default_crs
    named = (data.get("crs") or {}).get("properties", {}).get("name")
    if named:
        crs = str(named)
    check_crs(crs, src)
    out = []
    for i, f in enumerate(data.get("features") or []):
        props = dict((f or {}).get("properties") or {})
        fid = str(props.get("id", f.get("id", f"{prefix}{i + 1}")))
        geom = (f or {}).get("geometry") or {}
        gtype = geom.get("type")
        coords = geom.get("coordinates")
        if gtype == "MultiPolygon" and kind == "Polygon" and coords and len(coords) == 1:
            gtype, coords = "Polygon", coords[0]
        if gtype != kind or coords is None:
            raise ConfigError(f"geometry {gtype!r}, expected a {kind}", source=src,
                              field=f"feature {fid!r}")
        out.append(Feature(fid, kind, coords, props))
    if not out:
        raise ConfigError("no features", source=src)
    _unique_ids(out, src)
    return out, crs


def _csv_points(path: Path, default_crs: str, prefix: str) -> tuple[list[Feature], str]:
    import pandas as pd

    src = str(path)
    df = pd.read_csv(path)
    if {"lon", "lat"} <= set(df.columns):
        xs, ys, crs = df["lon"], df["lat"], "EPSG:4326"
    elif {"x", "y"} <= set(df.columns):
        xs, ys, crs = df["x"], df["y"], default_crs
    else:
        raise ConfigError("expected columns lon, lat or x, y", source=src)
    check_crs(crs, src)
    out = []
    for i, row in enumerate(df.to_dict("records")):
        props = {k: v for k, v in row.items() if not (isinstance(v, float) and math.isnan(v))}
        fid = str(props.get("id", f"{prefix}{i + 1}"))
        out.append(Feature(fid, "Point", [float(xs.iloc[i]), float(ys.iloc[i])], props))
    if not out:
        raise ConfigError("no rows", source=src)
    _unique_ids(out, src)
    return out, crs


def _unique_ids(features: list[Feature], src: str) -> None:
    seen: set[str] = set()
    for f in features:
        if f.id in seen:
            raise ConfigError("id repeats", source=src, field=f"feature {f.id!r}")
        seen.add(f.id)


def number(f: Feature, key: str, src: str, *, lo: float = 0.0, lo_open: bool = True,
           hi: float | None = None, default: float | None = None) -> float:
    """A numeric property of a feature, checked; ConfigError naming the feature id."""
    where = f"feature {f.id!r}"
    if key not in f.props or f.props[key] is None or f.props[key] == "":
        if default is not None:
            return default
        raise ConfigError(f"missing {key}", source=src, field=where)
    try:
        v = float(f.props[key])
    except (TypeError, ValueError):
        raise ConfigError(f"{key} = {f.props[key]!r}, expected a number", source=src,
                          field=where) from None
    if not math.isfinite(v) or (v <= lo if lo_open else v < lo) or (hi is not None and v > hi):
        bound = f"{'>' if lo_open else '≥'} {lo:g}" + (f" and ≤ {hi:g}" if hi is not None else "")
        raise ConfigError(f"{key} = {v:g}, expected {bound}", source=src, field=where)
    return v


@dataclass(frozen=True)
class InventoryTree:
    """One tree in the local frame: trunk at (x, y) m, total ``height_m``, crown diameter and
    crown base height (m above the street); ``species`` as written in the inventory."""

    id: str
    x: float
    y: float
    species: str
    height_m: float
    crown_diameter_m: float
    crown_base_m: float
    crown_shape: str | None = None
    photo: str | None = None
    trunk_diameter_m: float | None = None
    #: the crown's plan outline, a ring of (x, y) in the local frame (m), or None
    outline: tuple[tuple[float, float], ...] | None = None

    @property
    def crown_radius_m(self) -> float:
        return self.crown_diameter_m / 2.0

    @property
    def vertical_radius_m(self) -> float:
        return (self.height_m - self.crown_base_m) / 2.0

    @property
    def plan_reach_m(self) -> float:
        """The farthest the crown may reach from the trunk in plan (m): the crown radius, or
        the farthest outline vertex when that is farther."""
        if not self.outline:
            return self.crown_radius_m
        ring = np.asarray(self.outline) - [self.x, self.y]
        return max(self.crown_radius_m, float(np.hypot(ring[:, 0], ring[:, 1]).max()))


def read_trees(path: Path, frame_crs: str, latitude: float, longitude: float
               ) -> tuple[list[InventoryTree], LocalFrame]:
    """The inventory's trees in the local frame (checked row by row)."""
    src = str(path)
    feats, crs = read_features(path, frame_crs, "Point", "T")
    frame = LocalFrame(crs, latitude, longitude)
    pts = np.array([[float(c) for c in f.coords[:2]] for f in feats])
    xs, ys = frame.to_local(pts[:, 0], pts[:, 1])
    check_spread([f.id for f in feats], pts, np.column_stack([xs, ys]), frame, src, "tree")
    trees = []
    for f, x, y in zip(feats, xs, ys):
        where = f"feature {f.id!r}"
        if not str(f.props.get("species", "")).strip():
            raise ConfigError("missing species", source=src, field=where)
        h = number(f, "height_m", src)
        d = number(f, "crown_diameter_m", src)
        base = number(f, "crown_base_m", src, lo_open=False)
        if base >= h:
            raise ConfigError(f"crown_base_m {base:g} is not below height_m {h:g}", source=src,
                              field=where)
        td = number(f, "trunk_diameter_m", src, default=-1.0)
        trees.append(InventoryTree(
            f.id, float(x), float(y), str(f.props["species"]).strip(), h, d, base,
            (str(f.props["crown_shape"]) if f.props.get("crown_shape") else None),
            (str(f.props["photo"]) if f.props.get("photo") else None),
            None if td < 0 else td, crown_outline(f, frame=frame, src=src)))
    return trees, frame


def crown_outline(f: Feature, *, frame: LocalFrame, src: str
                  ) -> tuple[tuple[float, float], ...] | None:
    """The feature's ``crown_outline`` in the local frame (m): a ring of [x, y] in the
    inventory's coordinates (as ``radtree lidar segment`` writes it) or a GeoJSON Polygon
    (its outer ring); None without one. ConfigError naming the feature for a ring that is
    not a simple polygon of at least 0.01 m² (a trunk outside it: the crown stays a
    spheroid, :mod:`radtree.trees.district`)."""
    from shapely.geometry import Polygon
    from shapely.validation import explain_validity

    raw = f.props.get("crown_outline")
    if raw is None or raw == "":
        return None
    where = f"feature {f.id!r}"
    if isinstance(raw, dict) and raw.get("type") == "Polygon":
        raw = (raw.get("coordinates") or [None])[0]
    try:
        ring = np.array([[float(v) for v in c[:2]] for c in raw])
    except (TypeError, ValueError, IndexError):
        raise ConfigError("crown_outline is not a ring of [x, y] (or a GeoJSON Polygon)",
                          source=src, field=where) from None
    if len(ring) < 3 or not np.all(np.isfinite(ring)):
        raise ConfigError(f"crown_outline has {len(ring)} point(s), expected a ring of at "
                          "least 3 (or remove it: the crown is then a spheroid)", source=src,
                          field=where)
    x, y = frame.to_local(ring[:, 0], ring[:, 1])
    poly = Polygon(np.column_stack([x, y]))
    if not poly.is_valid or poly.area < 0.01:
        why = explain_validity(poly) if not poly.is_valid else f"{poly.area:.3g} m²"
        raise ConfigError(f"crown_outline is not a simple polygon ({why}): fix or remove it "
                          "(the crown is then a spheroid)", source=src, field=where)
    return tuple((float(a), float(b)) for a, b in zip(x, y))


def _geographic(crs: str) -> bool:
    return crs.upper().endswith(("4326", "CRS84"))


def check_spread(ids: list[str], raw: np.ndarray, local: np.ndarray, frame: LocalFrame,
                 src: str, kind: str) -> None:
    """Geographic sanity of features at ``raw`` (source CRS, (n, 2)) and ``local`` (metres
    from the site origin): none farther than :data:`MAX_FROM_REST_M` from the median of all,
    a bounding box within :data:`MAX_SPREAD_M` (diagonal), none farther than
    :data:`MAX_FROM_SITE_M` from the site; else ConfigError naming the feature and the
    likely cause (e.g. longitude and latitude swapped)."""
    if len(local) == 0:
        return
    local = np.where(np.isfinite(local), local, 1e12)
    here = f"latitude {frame.latitude:g}, longitude {frame.longitude:g}"
    rest = np.hypot(*(local - np.median(local, axis=0)).T)
    site = np.hypot(local[:, 0], local[:, 1])
    # the outlier: far from the rest; of equals (two features), the one farther from the site
    i = int(np.argmax(rest + 1e-6 * site))
    if rest[i] > MAX_FROM_REST_M:
        raise ConfigError(
            f"{kind} at {raw[i, 0]:g}, {raw[i, 1]:g} lies {rest[i] / 1000.0:,.1f} km from the "
            f"other {kind}s (at most {MAX_FROM_REST_M / 1000:g} km accepted): "
            f"{_likely_cause(raw[i], frame)}", source=src, field=f"feature {ids[i]!r}")
    span = float(np.hypot(*np.ptp(local, axis=0)))
    if span > MAX_SPREAD_M:
        raise ConfigError(
            f"the {kind}s spread over {span / 1000:.1f} km (bounding-box diagonal; at most "
            f"{MAX_SPREAD_M / 1000:g} km accepted): split the inventory into districts, or "
            "check the coordinates of this one, the farthest from the rest",
            source=src, field=f"feature {ids[i]!r}")
    j = int(np.argmax(site))
    if site[j] > MAX_FROM_SITE_M:
        raise ConfigError(
            f"{kind} at {raw[j, 0]:g}, {raw[j, 1]:g} lies {site[j] / 1000.0:,.1f} km from the "
            f"site ({here}; at most {MAX_FROM_SITE_M / 1000:g} km accepted): "
            f"{_likely_cause(raw[j], frame)}", source=src, field=f"feature {ids[j]!r}")


def _likely_cause(xy: np.ndarray, frame: LocalFrame) -> str:
    if _geographic(frame.crs):
        sx, sy = frame.to_local(np.array([xy[1]]), np.array([xy[0]]))
        if np.hypot(sx[0], sy[0]) <= MAX_FROM_SITE_M:
            return ("longitude and latitude swapped? (GeoJSON and CSV x/lon columns come "
                    "first as longitude) — swap them")
        return ("check its coordinates (longitude first, degrees), [site] crs, and [site] "
                "latitude/longitude")
    if frame.crs == "local":
        return "[site] crs = \"local\" expects metres from the site origin: check the numbers"
    return (f"check its coordinates against [site] crs = {frame.crs!r} (a projected CRS in "
            "metres?) and [site] latitude/longitude")
