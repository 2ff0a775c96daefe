"""Species in crowns: the species library's public face for the crown builders (layer 4).

The data (:class:`Species`, :func:`load_species`, :func:`known_species`, phenology
:meth:`Species.leaf_area_fraction`) is :mod:`radtree.config.species` (plain data, readable by
the project and inventory readers); this module re-exports it and builds crown settings from a
species and a tree's size — the existing crown models (:mod:`radtree.trees.build`) and the
calibrations then do the work::

    from radtree.trees.species import crown_size, load_species, species_tree
    sp = load_species("platanus_x_acerifolia")
    size = crown_size(sp, height_m=12.5, crown_diameter_m=10.0, crown_base_m=3.0)
    tree = species_tree(project.tree, sp, size)    # a [tree] with the species' optics
    sp.leaf_area_fraction(100, 48.1)               # leaf-out ramp in spring (north)

Lengths in metres; the crown is the spheroid of :class:`radtree.config.Crown` (horizontal
radius ``radius_m``, vertical semi-axis ``vertical_radius_m``, base ``base_height_m`` above the
street).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import Any

from radtree.config import Tree
from radtree.config.species import (
    CROWN_SHAPES,
    LEAF_ANGLE_DISTRIBUTIONS,
    SOUTHERN_SHIFT_DAYS,
    Species,
    find_species,
    known_species,
    load_species,
    louvers_cover_fraction,
    species_library,
    tree_defaults,
)
from radtree.errors import ConfigError

__all__ = ["CROWN_SHAPES", "LEAF_ANGLE_DISTRIBUTIONS", "SOUTHERN_SHIFT_DAYS", "CrownSize",
           "Species", "crown_size", "find_species", "known_species", "load_species", "louvers_cover_fraction",
           "species_library", "species_tree", "tree_defaults"]


@dataclass(frozen=True)
class CrownSize:
    """A crown spheroid: horizontal ``radius_m``, vertical semi-axis ``vertical_radius_m``,
    crown base ``base_height_m`` above the ground (m); top = base + 2 × vertical radius."""

    radius_m: float
    vertical_radius_m: float
    base_height_m: float

    def __post_init__(self) -> None:
        for name in ("radius_m", "vertical_radius_m", "base_height_m"):
            v = getattr(self, name)
            if not isinstance(v, int | float) or math.isnan(v) or v <= 0:
                raise ConfigError(f"got {v!r}, expected a length > 0 m", field=name)

    @property
    def height_m(self) -> float:
        return self.base_height_m + 2.0 * self.vertical_radius_m


def crown_size(sp: Species, height_m: float, crown_diameter_m: float,
               crown_base_m: float | None = None, crown_shape: str | None = None,
               where: str = "tree") -> CrownSize:
    """The crown of a tree ``height_m`` tall with a crown ``crown_diameter_m`` across.

    With ``crown_base_m`` the crown fills base → top; without it the crown's height is the
    shape's (``crown_shape``, default the species') vertical/horizontal ratio × diameter,
    hung from the top. ``where`` names the tree in messages (an inventory id)."""
    shape = crown_shape or sp.crown_shape
    if shape not in CROWN_SHAPES:
        raise ConfigError(f"{where}: got crown_shape {shape!r}, expected one of "
                          f"{', '.join(CROWN_SHAPES)}", field="crown_shape")
    for name, v in (("height_m", height_m), ("crown_diameter_m", crown_diameter_m)):
        if not isinstance(v, int | float) or math.isnan(v) or v <= 0:
            raise ConfigError(f"{where}: got {name} {v!r}, expected a length > 0 m", field=name)
    radius = crown_diameter_m / 2.0
    if crown_base_m is None:
        vertical = min(CROWN_SHAPES[shape] * radius, 0.45 * height_m)
        base = height_m - 2.0 * vertical
    else:
        if not 0 < crown_base_m < height_m:
            raise ConfigError(f"{where}: crown_base_m {crown_base_m!r} must lie between 0 and "
                              f"the tree height {height_m} m", field="crown_base_m")
        base, vertical = crown_base_m, (height_m - crown_base_m) / 2.0
    return CrownSize(radius, vertical, base)


def species_tree(tree: Tree, sp: Species, size: CrownSize | None = None,
                 keep: Iterable[str] = ()) -> Tree:
    """``tree`` with the species' leaf optics, leaf tilt and permeability (the fields of
    :func:`tree_defaults`, for the louvers layers of ``tree``) and, given ``size``, its crown
    size. ``keep``: dotted ``table.field`` names left as they are in ``tree`` (set by the user)."""
    kept = set(keep)
    given: dict[str, dict[str, Any]] = {}
    for name in kept:
        table, _, attr = name.partition(".")
        given.setdefault(table, {})[attr] = getattr(getattr(tree, table), attr)
    given.setdefault("louvers", {}).update(layers=tree.louvers.layers,
                                           arrangement=tree.louvers.arrangement,
                                           crossings=tree.louvers.crossings)
    tables = {}
    for table, values in tree_defaults(sp, given).items():
        new = {k: v for k, v in values.items() if f"{table}.{k}" not in kept}
        tables[table] = replace(getattr(tree, table), **new)
    if size is not None:
        crown = {k: getattr(size, k) for k in ("radius_m", "vertical_radius_m",
                                               "base_height_m")
                 if f"crown.{k}" not in kept}
        tables["crown"] = replace(tree.crown, **crown)
    return replace(tree, **tables)
