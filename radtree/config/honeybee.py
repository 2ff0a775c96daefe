"""``[site] honeybee = "model.hbjson"``: a Honeybee model as the project's site.

The model (rooms, apertures, doors, shades and their Radiance modifiers, sensor grids) is read
by :mod:`radtree.site.honeybee_model`; here only the project-file side: the path, resolved
against the project folder, and how grids are generated for rooms when the model has none
(work plane ``workplane_height_m`` = 0.8 m above each floor, ``grid_spacing_m`` = 0.5 m).
Model coordinates are used as they are (metres, x east, y north, z up); the crowns of
``[tree]`` stand in radtree's street frame (the studied façade is the plane through the origin
facing ``street.facade_azimuth_deg``), so place the model's façade there.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from radtree.errors import ConfigError

#: the ``[site]`` keys this module reads (the path, and optional grid settings)
SITE_KEYS = ("honeybee", "honeybee_grid_spacing_m", "honeybee_workplane_m")


@dataclass(frozen=True)
class HoneybeeSite:
    """A Honeybee model file (HBJSON) and the settings of the grids generated per room.

    ``workplane_height_m``: height of generated grids above each room's floor (m);
    ``grid_spacing_m``: their cell size (m). Used only for rooms when the model has no grids.
    """

    model: Path
    workplane_height_m: float = 0.8
    grid_spacing_m: float = 0.5

    def __post_init__(self) -> None:
        if not 0.0 < self.grid_spacing_m <= 10.0:
            raise ConfigError(f"got {self.grid_spacing_m!r}, expected a grid spacing in "
                              "(0, 10] m", field="site.honeybee_grid_spacing_m")
        if not 0.0 <= self.workplane_height_m <= 10.0:
            raise ConfigError(f"got {self.workplane_height_m!r}, expected a height in [0, 10] m",
                              field="site.honeybee_workplane_m")

    def digest(self) -> str:
        """SHA-256 of the model file (12 hex digits): a changed model changes the hash."""
        return hashlib.sha256(self.model.read_bytes()).hexdigest()[:12]


def _number(data: dict[str, Any], key: str, default: float, source: str) -> float:
    value = data.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(f"got {value!r}, expected a number (metres)", source=source,
                          field=f"site.{key}")
    return float(value)


def read_honeybee(data: dict[str, Any], base: Path, source: str) -> HoneybeeSite | None:
    """The :class:`HoneybeeSite` of the ``[site]`` table ``data`` (None without ``honeybee``).
    Removes :data:`SITE_KEYS` from ``data`` so the Site table's own check sees only its keys."""
    present = {k: data.pop(k) for k in SITE_KEYS if k in data}
    if "honeybee" not in present:
        if present:
            raise ConfigError(f"{', '.join(present)} given without 'honeybee'", source=source,
                              field=f"site.{next(iter(present))}")
        return None
    value = present["honeybee"]
    if not isinstance(value, str) or not value:
        raise ConfigError(f"got {value!r}, expected the path of a Honeybee model (.hbjson)",
                          source=source, field="site.honeybee")
    path = Path(value) if Path(value).is_absolute() else (base / value).resolve()
    if not path.exists():
        raise ConfigError(f"file not found: {path}", source=source, field="site.honeybee")
    try:
        return HoneybeeSite(path, _number(present, "honeybee_workplane_m", 0.8, source),
                            _number(present, "honeybee_grid_spacing_m", 0.5, source))
    except ConfigError as exc:
        raise ConfigError(str(exc), source=source) from None
