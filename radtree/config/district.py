"""``[site]`` inputs from one's own data: a tree inventory and building footprints.

Keys of the ``[site]`` table (read here, hooked into :mod:`radtree.config.reader`):

* ``trees`` — a GeoJSON FeatureCollection of points or a CSV, one tree per feature/row with
  ``species``, ``height_m``, ``crown_diameter_m``, ``crown_base_m`` (metres); optional
  ``crown_shape``, ``photo``, ``id``, ``trunk_diameter_m``;
* ``buildings`` — a GeoJSON FeatureCollection of footprint polygons with ``height_m``;
  optional ``facade_reflectance`` (0–1), ``storeys``, ``window_to_wall`` (0–1), ``id``;
* ``crs`` — the coordinate reference system of a CSV's ``x, y`` columns, or of GeoJSON files
  without a ``crs`` member (default ``EPSG:4326``: longitude, latitude). Everything is
  converted to a local metric frame at the site origin (``[site] latitude, longitude``):
  x east, y north, metres (:mod:`radtree.site.inventory`).
* ``facades`` — ``"street"`` (every building face whose outside is open ground: not a wall
  shared with another building) or a list of ``"BUILDING:FACE"`` selections (face = index
  of the footprint edge, 0-based, counter-clockwise);
* ``facade_spacing_m`` (sensor spacing along a façade, default 3 m), ``window_height_m``
  (sensor height above each storey's floor, default 1.5 m), ``storey_height_m`` (when a
  building gives no ``storeys``, default 3 m), ``facade_chunk`` (façades per traced grid:
  the unit of work of ``simulate --scheduler``, default 8);
* ``turbid_above`` — above this many trees (default 500; 0: never) crowns left at
  ``[tree] representation = "explicit"`` are built as turbid media instead
  (:mod:`radtree.trees.turbid`). Why: the NumPy engine expands the instanced slats tree by
  tree, so memory and time grow with the leaves — measured on the generated city
  (``benchmarks/representations.py``, one hour, 4 036 façade sensors, 128 paths, shared
  machine at load ≈ 22): 250 trees explicit 75 s / 0.41 GiB vs turbid 46 s / 0.21 GiB,
  1 000 trees explicit 85 s / 1.13 GiB (1.25 M triangles) vs turbid 28 s / 0.24 GiB, the
  façade-chunk means within 0.6 % (250) and 2.4 % (1 000). From ≈ 500 trees the slats cost
  about twice the time and three times the memory for the same façade light; below it they
  keep the real leaf placement, and Radiance's form of turbid crowns (``mist``) carries no
  leaf-scattered light, so set 0 to keep slats for Radiance's instanced crowns;
* ``instancing`` — ``"auto"`` (a crown shared by ≥ 2 trees is one Radiance ``instance``
  octree per species × realisation, placed, rotated and scaled per tree; crowns used once
  are built in place), ``"never"`` (every crown in place).

The street canyon generator (``[street]``) stays for the simple case; with ``trees`` but no
``buildings`` the inventory's crowns stand in that canyon instead of the ``[tree.crown]`` row,
its façade where ``[street] facade_line`` says, else placed behind the trees
(:mod:`radtree.site.placement`). A crown reaching a wall follows ``[tree] wall_policy``
(:mod:`radtree.trees.wall_policy`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from radtree.config.spec import Checked, meta
from radtree.errors import ConfigError

INSTANCING = ("auto", "never")
#: the ``[site]`` keys this module reads
DISTRICT_KEYS = ("trees", "buildings", "crs", "facades", "facade_spacing_m", "window_height_m",
                 "storey_height_m", "facade_chunk", "instancing", "turbid_above")


@dataclass(frozen=True)
class District(Checked):
    """Inventory inputs of ``[site]`` (paths resolved against the project folder)."""

    TABLE: ClassVar[str] = "site"
    trees: Path | None = None
    buildings: Path | None = None
    crs: str = "EPSG:4326"
    facades: tuple[str, ...] = ("street",)
    facade_spacing_m: float = field(default=3.0, metadata=meta(0.2, 100.0))
    window_height_m: float = field(default=1.5, metadata=meta(0.1, 10.0))
    storey_height_m: float = field(default=3.0, metadata=meta(1.5, 10.0))
    facade_chunk: int = field(default=8, metadata=meta(1, 10000))
    instancing: str = field(default="auto", metadata=meta(choices=INSTANCING))
    turbid_above: int = field(default=500, metadata=meta(0, 10_000_000))

    def check(self) -> None:
        if self.trees is None and self.buildings is None:
            raise self.fail("trees", "give a tree inventory (trees) or buildings")

    @property
    def all_street_facades(self) -> bool:
        return tuple(self.facades) == ("street",)


def read_district(data: dict[str, Any], base: Path, source: str) -> District | None:
    """The :class:`District` of the ``[site]`` table ``data`` (None without trees/buildings)."""
    if not any(k in data for k in ("trees", "buildings")):
        extra = [k for k in DISTRICT_KEYS if k in data]
        if extra:
            raise ConfigError("needs [site] trees or buildings", source=source,
                              field=f"site.{extra[0]}")
        return None

    def path(key: str) -> Path | None:
        value = data.get(key)
        if value is None:
            return None
        if not isinstance(value, str) or not value:
            raise ConfigError(f"expected a file path, got {value!r}", source=source,
                              field=f"site.{key}")
        p = Path(value) if Path(value).is_absolute() else (base / value).resolve()
        if not p.is_file():
            raise ConfigError(f"file not found: {p}", source=source, field=f"site.{key}")
        return p

    facades = data.get("facades", "street")
    if isinstance(facades, str):
        facades = [facades]
    if not isinstance(facades, list) or not all(isinstance(f, str) for f in facades):
        raise ConfigError(f"expected \"street\" or a list of \"BUILDING:FACE\", got {facades!r}",
                          source=source, field="site.facades")
    kwargs: dict[str, Any] = {k: data[k] for k in ("crs", "facade_spacing_m", "window_height_m",
                                                   "storey_height_m", "facade_chunk",
                                                   "instancing", "turbid_above")
                              if k in data}
    try:
        return District(trees=path("trees"), buildings=path("buildings"),
                        facades=tuple(facades), **kwargs)
    except ConfigError as exc:
        raise ConfigError(getattr(exc, "detail", str(exc)), source=source,
                          field=exc.field) from None
