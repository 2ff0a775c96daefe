"""One crown–wall policy for every mode: ``[tree] wall_policy = "clip" | "refuse"``.

A crown reaches a wall when its horizontal semi-axis ``a`` (m) exceeds the distance ``d`` (m)
from its trunk axis to the wall's clip plane — the plane ``n_clip`` in front of the wall
(:func:`radtree.trees.envelope.clip_plane`: ``max([tree.crown] clearance_m, sensors.offset_m +
5 mm)``, so no crown contains a façade sensor). The same rule in every mode:

* row crowns ``[tree.crown]`` (the street template, the office block and Honeybee models, whose
  crowns stand in the same row before the studied façade): ``d = trunk_distance_m − n_clip``;
* inventory trees without buildings: the studied façade and the opposite one of the canyon;
* inventory trees with buildings: the nearest wall of each building whose roof is above the
  crown base, the plane through the wall's nearest point facing the trunk (a tree near a
  building's corner is clipped by the plane perpendicular to the line to the corner).

``clip`` (the default) cuts the crown at the plane and prints a note of the crown volume
removed, per tree, in percent of its spheroid (:func:`removed_fraction`). ``refuse`` stops the
build with one :class:`~radtree.errors.ConfigError` naming the tree and the exact fix: move
the trunk ``a − d`` m further from the wall, or reduce the crown radius to ``d`` (rounded to the
centimetre, outwards). A crown reaching two walls at once is refused under either policy
(clipping at one plane only is built).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from radtree.errors import ConfigError

#: the notes of the policy start so (``radtree build`` prints them)
NOTE_PREFIX = "Crown–wall policy"


def removed_fraction(radius_m: float, distance_m: float) -> float:
    """Fraction of a spheroid's volume (horizontal semi-axis ``radius_m``, any vertical one) on
    the far side of a vertical plane ``distance_m`` from its axis: the spherical cap fraction
    (1 − t)²(2 + t)/4 with t = d/a (the vertical semi-axis scales cap and whole alike)."""
    t = min(1.0, max(-1.0, distance_m / radius_m))
    return (1.0 - t) ** 2 * (2.0 + t) / 4.0


@dataclass(frozen=True)
class WallReach:
    """A crown reaching a wall: who (``tree``, for messages), which wall, its crown radius
    and the distance from its trunk axis to the wall's clip plane (m); ``field``: the field
    a refusal names; ``radius_field``/``distance_field``: how the fix is written."""

    tree: str
    wall: str
    radius_m: float
    distance_m: float
    field: str
    radius_field: str = "the crown radius"
    distance_field: str = ""

    @property
    def removed(self) -> float:
        return removed_fraction(self.radius_m, self.distance_m)

    def fix(self) -> str:
        """The two exact fixes, rounded outwards to the centimetre."""
        move = math.ceil((self.radius_m - self.distance_m) * 100.0 - 1e-6) / 100.0
        radius = math.floor(self.distance_m * 100.0 + 1e-6) / 100.0
        where = f" ({self.distance_field})" if self.distance_field else ""
        return (f"move the trunk {move:.2f} m further from the wall{where}, or reduce "
                f"{self.radius_field} to {radius:.2f} m")


def apply_wall_policy(policy: str, reaches: list[WallReach], source: str | None) -> list[str]:
    """The policy's notes (``clip``) or its ConfigError (``refuse``) for these crowns."""
    if not reaches:
        return []
    if policy == "refuse":
        r = reaches[0]
        more = f" ({len(reaches) - 1} more crown(s) too)" if len(reaches) > 1 else ""
        raise ConfigError(
            f"{r.tree} (radius {r.radius_m:g} m) reaches {r.wall}: its trunk stands "
            f"{r.distance_m:.2f} m from the wall's clip plane{more}; [tree] wall_policy = "
            f"\"refuse\": {r.fix()} — or set wall_policy = \"clip\"", source=source,
            field=r.field)
    per = ", ".join(f"{r.tree} {100.0 * r.removed:.1f} %" for r in reaches)
    return [f"{NOTE_PREFIX} \"clip\": crowns cut at the wall; crown volume removed: {per} "
            "([tree] wall_policy = \"refuse\" stops the build instead, with the fix)"]


def two_walls(tree: str, walls: list[str], radius_m: float, nearest_m: float, field: str,
              source: str | None) -> ConfigError:
    """The error of a crown reaching two walls (refused under either policy)."""
    radius = math.floor(nearest_m * 100.0 + 1e-6) / 100.0
    return ConfigError(f"{tree} (radius {radius_m:g} m) reaches two walls ({' and '.join(walls)}"
                       f"); a crown is clipped at one wall only: reduce its radius to "
                       f"{radius:.2f} m or move its trunk", source=source, field=field)
