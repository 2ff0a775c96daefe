"""The crown's photograph: the fields of ``[tree]`` shared by every crown model.

``photo`` a fisheye image (``lens``: a :func:`radtree.hemi.get_lens` name or ``poly:a1,a2,…``;
``mask`` = [centre_x, centre_y, radius] px of the 90° circle, else detected) and
``photo_direction``:

* ``"facade"`` — the lens axis is the façade normal, the photo taken at the sensors looking out
  (the study's set-up): the dome crowns (louvers and perforated) are cut where it shows sky;
* ``"upward"`` — the lens axis is vertical, the camera under the crown at ``photo_x_m`` along
  the façade from the sensor centre (x east for a north façade: u, the façade's own axis),
  ``photo_distance_m`` out from the façade and ``photo_height_m`` above the street: the free
  louvers crowns' leaf area density and leaf-inclination distribution are fitted to it. A
  ``photo`` naming a folder fits all its images at once (their spread is reported).

``photo_zenith_deg``: the analysed zenith range 0–that (degrees) of the photo and of every
model rendering compared with it (``radtree hemi check``). The older
``tree.perforated.photo`` / ``lens`` / ``mask`` still work for the perforated crown; the shared
``[tree] photo`` wins when both are set.
"""

from __future__ import annotations

from dataclasses import field
from pathlib import Path
from typing import Any

from radtree.config.clumping import CLUMPING_DEFAULTS
from radtree.config.spec import meta

PHOTO_DIRECTIONS = ("facade", "upward")
#: leaf (slat) inclination: one fixed angle, or drawn from Campbell's ellipsoidal distribution
INCLINATION_DISTRIBUTIONS = ("fixed", "ellipsoidal")


def photo_fields() -> dict[str, Any]:
    """The dataclass fields (name → ``field``) appended to :class:`radtree.config.Tree`."""
    return {
        "photo": field(default=None),
        "lens": field(default="equidistant"),
        "mask": field(default=None, metadata=meta(kind="mask")),
        "photo_direction": field(default="facade", metadata=meta(choices=PHOTO_DIRECTIONS)),
        "photo_x_m": field(default=2.0),
        "photo_distance_m": field(default=3.0, metadata=meta(0.0, lo_open=True)),
        "photo_height_m": field(default=1.5, metadata=meta(0.0)),
        "photo_zenith_deg": field(default=90.0, metadata=meta(10.0, 90.0)),
        # build a crown whose fit to the photo is poor (ring RMS > 0.05 or a parameter at
        # its bound) instead of stopping; the report says so on its first page
        "accept_poor_fit": field(default=False),
    }


def photo_of(tree: Any) -> tuple[Path | None, str, tuple[float, float, float] | None, str]:
    """(photo, lens, mask, where it was set): the shared ``[tree] photo`` or else the older
    ``tree.perforated.photo``."""
    if tree.photo is not None:
        return Path(tree.photo), tree.lens, tree.mask, "tree.photo"
    perf = tree.perforated
    if perf.photo is not None:
        return Path(perf.photo), perf.lens, perf.mask, "tree.perforated.photo"
    return None, tree.lens, tree.mask, ""


#: fields added with the photo (table → field → default): left out of a scenario's parameter
#: hash at their defaults, so the hashes of projects without a photo are unchanged
ADDED_DEFAULTS: dict[str, dict[str, Any]] = {
    "": {"photo": None, "lens": "equidistant", "mask": None, "photo_direction": "facade",
         "photo_x_m": 2.0, "photo_distance_m": 3.0, "photo_height_m": 1.5,
         "photo_zenith_deg": 90.0, "accept_poor_fit": False, "voxels": None,
         "voxels_size_m": None},
    "perforated": {"seed": 1, "realisations": 1},
    "louvers": {"inclination_distribution": "fixed", "ellipsoid_x": 1.0, **CLUMPING_DEFAULTS},
}


def drop_photo_defaults(tree: dict[str, Any]) -> None:
    """Remove the added fields that are at their defaults from a plain ``tree`` dict."""
    for table, defaults in ADDED_DEFAULTS.items():
        d = tree.get(table, {}) if table else tree
        for name, default in defaults.items():
            if name in d and d[name] == default:
                del d[name]
