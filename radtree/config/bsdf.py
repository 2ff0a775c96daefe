"""``[tree.bsdf]``: how the crown layer's BSDF is computed and used (``[tree] representation``).

``representation = "explicit"`` (default) traces the crown's slats; ``"bsdf"`` replaces the
sensor dome (or the free crowns' envelopes) by a shell carrying the crown layer's Klems BSDF
(Radiance ``BSDF`` material; the NumPy and forward engines refuse it with a clear error);
``"turbid"`` makes the free volume crowns turbid media of the slats' leaf area density, leaf
angles, clumping and optics (:mod:`radtree.trees.turbid`; NumPy and forward engines).

rfluxmtx sampling: ``samples`` rays per Klems patch (``-c``), ``ab`` (0: the crown model's
recommendation), ``ad``, ``lw``; ``tiles`` × ``tiles`` periodic copies of the sample cell.
``bands``: the sensor dome's shell is cut into this many elevation bands of equal width
(|elevation| 0–90°, the lower half mirrored), each with the BSDF of the slats as tilted at the
band's middle elevation (the dome's slats turn with elevation); ``bands = 1``: one BSDF, the
slats as tilted where the shell is seen ``elevation_deg`` above the horizon. ``sectors``
(sensor dome, ``curvature`` traced or rings): each band is cut further into this many equal
sectors of the horizontal angle from the façade normal (−90° … 90°), each with the view from
the centre traced through its own part of the curved dome (the part near the wall's rim passes
grazing light along the wall differently from the part facing the street). ``segments``: the
dome's BSDF shell is meshed with this many segments around (``segments`` / 4 rings; 0: the
dome's ``tree.dome.segments``). Defaults 5 sectors and 192 segments (48 rings): on the
reference-case dome (scenario B, 7 hours, 24 runs) every hourly façade mean within 4.1 % of the
explicit slats', where 1 sector on the dome's 12 rings is 8.6 % off at 10:30 (CHANGELOG.md, crown
BSDFs) — the curvature rows then take ≈ 100 s once instead of ≈ 9 s, a 7-hour trace 26–41 s
instead of 10–14 s.

Free crowns: ``depth_m`` is the crown depth one crossing of the envelope carries at normal
incidence (0: the crown's vertical semi-axis, so the two crossings of a vertical line through
the centre add up to the crown's height). ``crossing = "chord"`` (default): at incidence θ a
crossing carries the half chord ``depth_m`` · cos θ of a sphere (one planar sample per Klems
ring, :func:`radtree.trees.slab.chord_samples`); ``"slab"``: one slab ``depth_m`` deep,
crossed along ``depth_m`` / cos θ — grazing light, which passes the rim of a real crown
through a short chord, then crosses the thickest layer. ``curvature`` (sensor dome):
``"traced"`` (default) replaces the planar sample's view from the dome's centre (the row of
the normal outgoing patch, patch by patch) by the one traced through the curved dome's own
slats (:mod:`radtree.pipeline.dome_curvature`); ``"rings"`` only rescales that row ring by
ring to the traced ring sums (the planar azimuthal shape kept; the correction before);
``"planar"`` keeps the flat stack's (a given ``xml`` is used as it is).
``wall_depth`` (free crowns reaching the wall, chord crossing): the wall cap's crown depth per
Klems patch as seen from the sensors' point on the cap (``"sensors"``, default,
:mod:`radtree.pipeline.wall_cap`), or per ring as at the cap's foot point (``"centre"``: the
half chord h cos ψ, h the crown centre's distance from the cap; before).
``material``: the shell's Radiance material, ``"BSDF"`` or ``"aBSDF"`` (the XML's
straight-through peak passes shadow and view rays unscattered: the sun is seen through the
shell directly instead of found by ambient sampling; Radiance ``src/rt/m_bsdf.c``
``compute_through``). Default ``"aBSDF"``: one default run of scenario B's dome within 5 % of
the slats every hour for four independently computed XML sets (worst 3.4–4.7 %), where
``"BSDF"`` missed by up to 9.9 %; the trace takes as long (``benchmarks/bsdf_single.py``).
``tensor_tree``: 0, or the log2 resolution
of an extra rank-4 tensor-tree XML. ``xml``: use this leaf-on XML instead of computing it
(computed XMLs are cached under ``build/bsdf/<scenario>/``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

from radtree.config.spec import Checked, SchemaError, meta

REPRESENTATIONS = ("explicit", "bsdf", "turbid")
CROSSINGS = ("chord", "slab")
CURVATURES = ("traced", "rings", "planar")
WALL_DEPTHS = ("sensors", "centre")
SHELL_MATERIALS = ("BSDF", "aBSDF")


@dataclass(frozen=True)
class CrownBsdf(Checked):
    """The crown BSDF's sampling and files (see the module text); lengths m, angles degrees."""

    TABLE: ClassVar[str] = "tree.bsdf"
    samples: int = field(default=500, metadata=meta(1, 100000))
    ab: int = field(default=0, metadata=meta(0, 20))
    ad: int = field(default=2, metadata=meta(1, 100000))
    lw: float = field(default=1e-3, metadata=meta(0.0, 1.0, lo_open=True))
    tiles: int = field(default=9, metadata=meta(1, 41))
    elevation_deg: float = field(default=30.0, metadata=meta(0.0, 90.0))
    bands: int = field(default=3, metadata=meta(1, 9))
    sectors: int = field(default=5, metadata=meta(1, 9))
    segments: int = field(default=192, metadata=meta(0, 1024))
    depth_m: float = field(default=0.0, metadata=meta(0.0, 50.0))
    crossing: str = field(default="chord", metadata=meta(choices=CROSSINGS))
    curvature: str = field(default="traced", metadata=meta(choices=CURVATURES))
    wall_depth: str = field(default="sensors", metadata=meta(choices=WALL_DEPTHS))
    tensor_tree: int = field(default=0, metadata=meta(0, 6))
    material: str = field(default="aBSDF", metadata=meta(choices=SHELL_MATERIALS))
    xml: Path | None = None

    def check(self) -> None:
        if self.tiles % 2 == 0:
            raise SchemaError(f"got {self.tiles}, expected an odd number (a centre cell)",
                              "tree.bsdf.tiles")
        if self.segments and self.segments < 4:
            raise SchemaError(f"got {self.segments}, expected 0 or at least 4",
                              "tree.bsdf.segments")
        if self.tensor_tree not in (0, 4, 5, 6):
            raise SchemaError(f"got {self.tensor_tree}, expected 0 or 4–6",
                              "tree.bsdf.tensor_tree")
