"""Planar periodic samples of a crown layer, for its BSDF (:mod:`radtree.bsdf`).

A sample is one periodic cell, ``width`` × ``height`` m in x (horizontal tangent) and y
("up"), of the crown layer, lying in ``-thickness ≤ z ≤ 0``. The Radiance BSDF convention
(genBSDF's) holds: +z points to the *inside* (the room, the sensors), the exterior is −z. The
engine tiles the cell periodically (every slat has its copies one period away) and samples
the centre cell, so light may wander sideways up to the tiled margin.

* :func:`dome_slab` — the sensor dome's slat shells as planar layers at the dome's layer
  spacing: the same slat size, cover, optics and shear along the branches; slats tilted
  about the horizontal tangent as the dome's slats are where the shell is seen at
  ``elevation_deg`` from the dome centre (:func:`radtree.trees.louvers_dome.slat_normals`).
  Rows are one slat high *as seen along the layer normal* (the dome's rows are one slat high
  seen from the centre), so with cover 1 every normal line crosses every layer once.
* :func:`volume_slab` — the free crowns' volume arrangement: slats at random through a slab of
  ``depth`` m at the crown's fitted density ρ (:func:`radtree.trees.volume.volume_density`),
  normals inclined α at random azimuths.
* :func:`branch_slab` — the leaf-off state: opaque bark sticks at the branch inclination, as
  many as give a vertical (plan-view) cover ``cover`` (Poisson: cover = 1 − exp(−Σ l·d·cos β / A)).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from radtree.config import Louvers, Sensors, Street, Tree
from radtree.errors import ConfigError
from radtree.optics import KLEMS_FULL_RINGS, Material, Plastic
from radtree.trees.envelope import dome_spec
from radtree.trees.louvers import LouverOptics
from radtree.trees.louvers_dome import dome_layer_radii, slat_normals
from radtree.trees.model import BARK_REFLECTANCE, LEAF, TRUNK
from radtree.trees.volume import _slat_corners, volume_density

#: slats per cell side (at cover 1) of the periodic cell: the period is ~8 slats
CELL_SLATS = 8


@dataclass
class SlabSample:
    """One periodic cell: polygons (k, 4, 3) per material name, in metres (see module text)."""

    name: str
    polygons: dict[str, np.ndarray]
    materials: dict[str, Material]
    width: float
    height: float
    thickness: float
    notes: list[str] = field(default_factory=list)
    info: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name, poly in self.polygons.items():
            if name not in self.materials:
                raise ValueError(f"slab '{self.name}': polygons of undefined material {name!r}")
            if poly.ndim != 3 or poly.shape[1:] != (4, 3):
                raise ValueError(f"slab '{self.name}': polygons must be (k, 4, 3)")
        if not (self.width > 0 and self.height > 0 and self.thickness > 0):
            raise ValueError(f"slab '{self.name}': width, height and thickness must be > 0")

    @property
    def count(self) -> int:
        return sum(len(p) for p in self.polygons.values())


def _to_back(polygons: dict[str, np.ndarray], margin: float = 1e-3
             ) -> tuple[dict[str, np.ndarray], float]:
    """Shift every polygon so the sample's front (largest z) is ``margin`` behind z = 0;
    returns the shifted polygons and the thickness (|lowest z|)."""
    allz = np.concatenate([p[..., 2].ravel() for p in polygons.values() if len(p)])
    dz = -float(allz.max()) - margin
    out = {k: p + np.array([0.0, 0.0, dz]) for k, p in polygons.items()}
    return out, float(-(allz.min() + dz))


@dataclass(frozen=True)
class _SlabGrid:
    """The planar sample's slats: sides ``e1`` (along x) and ``e2`` (in the slat plane),
    cosine ``c0`` of the slat tilt from the layer normal, row pitch (m), cell width (m) and
    the cell's slats along x and rows along y."""

    e1: np.ndarray
    e2: np.ndarray
    c0: float
    pitch_y: float
    cell_x: float
    nx: int
    ny: int

    @property
    def width(self) -> float:
        return self.nx * self.cell_x

    @property
    def height(self) -> float:
        return self.ny * self.pitch_y


def dome_slab(tree: Tree, sensors: Sensors, street: Street, elevation_deg: float = 30.0,
              source: str | None = None) -> SlabSample:
    """The dome's slat shells as a planar periodic stack (see the module text): the slats as
    tilted at ``elevation_deg``, laid row by row in every layer, checked, shifted back."""
    lv = tree.louvers
    spec = dome_spec(tree, sensors, street, source)
    radii = dome_layer_radii(spec, lv, sensors, source)
    s, f = lv.slat_size_m, lv.cover_fraction
    g = _slab_grid(lv, elevation_deg=elevation_deg)
    quads = _slab_quads(radii, lv=lv, grid=g)
    depth = 0.5 * s * abs(g.e2[2])
    spacing = float(radii[1] - radii[0]) if len(radii) > 1 else float("inf")
    if depth >= 0.5 * spacing:
        raise ConfigError(f"slat layers would touch in the planar sample (slat depth ±{depth:.2f}"
                          f" m, layers {spacing:.2f} m apart)", source=source,
                          field="tree.louvers.layers")
    polys, thickness = _to_back({LEAF: quads})
    optics = LouverOptics.of(lv)
    tilt = math.degrees(math.acos(min(1.0, g.c0)))
    notes = [f"Planar sample of the dome's {lv.layers} slat shells: layers "
             f"{spacing if len(radii) > 1 else 0:.3f} m apart (the dome's radii "
             f"{radii[0]:.2f}–{radii[-1]:.2f} m), slats {s:g} m, cover {f:g}, tilted "
             f"{tilt:.1f}° from the layer normal (the dome's "
             f"slats where the shell is seen {elevation_deg:g}° above the horizon); periodic "
             f"cell {g.width:.2f} × {g.height:.2f} m, {len(quads)} slats. "
             + optics.describe() + "."]
    info = {"layers": float(lv.layers), "layer_spacing_m": spacing if len(radii) > 1 else 0.0,
            "slat_tilt_deg": tilt,
            "elevation_deg": elevation_deg, "slats": float(len(quads)),
            "tau_crown_direct": optics.tau_crown_direct}
    return SlabSample("dome_leaf_on", polys, {LEAF: optics.material()}, g.width, g.height,
                      thickness, notes, info)


def _slab_grid(lv: Louvers, *, elevation_deg: float) -> _SlabGrid:
    """The dome's slats where the shell is seen ``elevation_deg`` above the horizon, in the
    sample's frame (x along the shell's horizontal tangent, outward = −z)."""
    s, f = lv.slat_size_m, lv.cover_fraction
    el = math.radians(elevation_deg)
    d = np.array([[0.0, math.cos(el), math.sin(el)]])        # outward, seen from the centre
    up = np.array([0.0, -math.sin(el), math.cos(el)])        # towards higher elevation
    m, c = slat_normals(d, lv.inclination_deg)
    m_local = np.array([m[0, 0], float(m[0] @ up), -float(m[0] @ d[0])])   # outward = −z
    # the slat's second side: in the slat plane, perpendicular to x
    e2 = np.cross(m_local, [1.0, 0.0, 0.0])
    e2 /= np.linalg.norm(e2)
    e2 *= np.sign(e2[1]) or 1.0
    pitch_y = s * abs(e2[1])                                 # a row is one slat high, seen along z
    return _SlabGrid(np.array([1.0, 0.0, 0.0]), e2, float(c[0]), pitch_y, s / f, CELL_SLATS,
                     max(2, int(round(CELL_SLATS * s / pitch_y))))


def _slab_quads(radii: np.ndarray, *, lv: Louvers, grid: _SlabGrid) -> np.ndarray:
    """Slat quads (k, 4, 3) of every layer (z = −(r − r₀)), rows sheared along the branches
    as on the dome (one seeded stream per layer, as :func:`~radtree.trees.louvers_dome`)."""
    s, f = lv.slat_size_m, lv.cover_fraction
    nx, cell_x, pitch_y = grid.nx, grid.cell_x, grid.pitch_y
    tanb = math.tan(math.radians(lv.branch_inclination_deg))
    h1 = np.array([-0.5, 0.5, 0.5, -0.5]) * s
    h2 = np.array([-0.5, -0.5, 0.5, 0.5]) * s
    layers = []
    for k, child in enumerate(np.random.SeedSequence(lv.seed).spawn(len(radii))):
        rng = np.random.default_rng(child)
        z = -(float(radii[k]) - float(radii[0]))
        offset = rng.uniform(0.0, 1.0)
        for j in range(grid.ny):
            if j > 0:
                offset = (offset + grid.c0 * f / tanb + rng.uniform(-0.25, 0.25)) % 1.0
            left = (offset + np.arange(nx)) * cell_x
            if f < 1.0:
                left = left + rng.uniform(0.0, (1.0 - f) * cell_x, nx)
            xc = left + 0.5 * s
            yc = (j + 0.5) * pitch_y
            centres = np.stack([xc, np.full(nx, yc), np.full(nx, z)], axis=1)
            layers.append(centres[:, None, :] + h1[None, :, None] * grid.e1
                          + h2[None, :, None] * grid.e2)
    return np.concatenate(layers)


def volume_slab(lv: Louvers, vertical_semi_axis_m: float, depth_m: float,
                source: str | None = None, density_scale: float = 1.0,
                normal_elevation_deg: float = 90.0) -> SlabSample:
    """Slats at random through a slab of ``depth_m`` at the fitted crown density ρ (times
    ``density_scale``: the chord samples of :func:`chord_samples`), their normals inclined
    α from the world vertical at random azimuths, for an envelope facet whose outward normal
    is ``normal_elevation_deg`` above the horizon (90: the top of the crown, slab normal =
    vertical). In the sample's frame (z the inward normal, y the facet's upward tangent, as
    the Radiance BSDF material with up = world +z) the vertical is (0, cos e, −sin e)."""
    if not depth_m > 0:
        raise ConfigError(f"got {depth_m}, expected a positive slab depth", source=source,
                          field="tree.bsdf.depth_m")
    s = lv.slat_size_m
    rho = volume_density(lv, vertical_semi_axis_m) * density_scale
    width = height = CELL_SLATS * s
    n = int(round(rho * width * height * depth_m))
    if n < 1:
        raise ConfigError(f"a slab of {depth_m:g} m holds no slat at density {rho:.2f} m⁻³",
                          source=source, field="tree.bsdf.depth_m")
    rng = np.random.default_rng(np.random.SeedSequence(lv.seed))
    centres = rng.random((n, 3)) * [width, height, depth_m] - [0.0, 0.0, depth_m]
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    quads = _slat_corners(centres, phi, s, math.radians(lv.inclination_deg))
    # drawn about z, then turned about x by γ = 90° − e: z → (0, −sin γ, cos γ), the
    # facet's vertical up to sign (slats are two-sided)
    g = math.radians(90.0 - normal_elevation_deg)
    if g:
        rel = quads - centres[:, None, :]
        y, z = rel[..., 1].copy(), rel[..., 2].copy()
        rel[..., 1], rel[..., 2] = y * math.cos(g) - z * math.sin(g), y * math.sin(g) + z * math.cos(g)
        quads = centres[:, None, :] + rel
    polys, thickness = _to_back({LEAF: quads})
    optics = LouverOptics.of(lv)
    lam = rho * s * s * math.cos(math.radians(lv.inclination_deg)) * depth_m
    notes = [f"Planar slab of the volume crown: {n} slats of {s:g} m at the fitted density "
             f"{rho:.2f} m⁻³ through {depth_m:.2f} m, normals {lv.inclination_deg:g}° from the "
             f"vertical at random azimuths, the facet's outward normal "
             f"{normal_elevation_deg:g}° above the horizon (a line along the slab normal "
             f"crosses {lam:.2f} slats on average at the top, e = 90°); periodic cell "
             f"{width:.2f} × {height:.2f} m. "
             + optics.describe_slat() + "."]
    info = {"density_per_m3": rho, "depth_m": depth_m, "slats": float(n),
            "normal_elevation_deg": normal_elevation_deg,
            "normal_crossings": lam,
            "tau_normal_direct": math.exp(-lam * (1.0 - optics.t_specular))}
    return SlabSample("volume_leaf_on", polys, {LEAF: optics.material()}, width, height,
                      thickness, notes, info)


def branch_slab(cover: float, depth_m: float, inclination_deg: float, diameter_m: float,
                seed: int = 1, cell_m: float = 2.4, min_sticks: int = 1) -> SlabSample:
    """Leaf-off: opaque square-section bark sticks (length ≤ one cell) at ``inclination_deg``
    from the slab plane, random azimuths, with plan-view cover ``cover`` (0 < cover < 1). The
    cell grows (up to 16-fold in side) until it holds ``min_sticks``: a sparse cover would
    otherwise be rounded to one stick."""
    if not 0.0 < cover < 1.0:
        raise ConfigError(f"got branch cover {cover}, expected between 0 and 1",
                          field="tree.bsdf.leaf_off")
    beta = math.radians(inclination_deg)

    def expected(cell: float) -> tuple[float, float]:
        length = min(cell, depth_m / max(math.sin(beta), 1e-3))
        return -math.log(1.0 - cover) * cell * cell / (length * math.cos(beta) * diameter_m), \
            length

    grown = cell_m
    while expected(grown)[0] < min_sticks and grown < 16.0 * cell_m:
        grown = min(16.0 * cell_m, grown * 1.25)
    cell_m = grown
    sticks, length = expected(cell_m)
    n = max(1, int(round(sticks)))
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    z0 = depth_m * rng.random(n) * (1.0 - length * math.sin(beta) / depth_m) - depth_m
    start = np.stack([rng.random(n) * cell_m, rng.random(n) * cell_m, z0], axis=1)
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    axis = np.stack([np.cos(phi) * math.cos(beta), np.sin(phi) * math.cos(beta),
                     np.full(n, math.sin(beta))], axis=1)
    side1 = np.cross(axis, [0.0, 0.0, 1.0])
    side1 /= np.linalg.norm(side1, axis=1)[:, None]
    side2 = np.cross(axis, side1)
    faces = []
    half = 0.5 * diameter_m
    for a, b in ((side1, side2), (side2, -side1), (-side1, -side2), (-side2, side1)):
        p0 = start + half * (a + b)
        p1 = start + half * (a - b)
        faces.append(np.stack([p0, p1, p1 + length * axis, p0 + length * axis], axis=1))
    polys, thickness = _to_back({TRUNK: np.concatenate(faces)})
    notes = [f"Leaf-off slab: {n} opaque bark sticks (ρ {BARK_REFLECTANCE:g}) of "
             f"{diameter_m * 100:.0f} cm × {length:.2f} m at {inclination_deg:g}° through "
             f"{depth_m:.2f} m, plan-view cover {100 * cover:.1f} % (the bare crown's)."]
    return SlabSample("leaf_off", polys, {TRUNK: Plastic(TRUNK, BARK_REFLECTANCE)}, cell_m,
                      cell_m, thickness, notes, {"branch_cover": cover, "sticks": float(n)})


class RingDimensions:
    """``width`` / ``height`` (m) of a sample made of ``rings`` (planar samples of one size)."""

    rings: list[SlabSample]

    @property
    def width(self) -> float:
        return self.rings[0].width

    @property
    def height(self) -> float:
        return self.rings[0].height


@dataclass
class RingSamples(RingDimensions):
    """A crown *envelope* sample: one planar sample per Klems θ ring of incidence
    (:data:`radtree.optics.KLEMS_FULL_RINGS`); ring k's sample supplies the BSDF columns of the
    incident patches of ring k. ``thickness``: the half chord at normal incidence (m)."""

    name: str
    rings: list[SlabSample]
    thickness: float
    notes: list[str] = field(default_factory=list)
    info: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if len(self.rings) != len(KLEMS_FULL_RINGS):
            raise ValueError(f"envelope sample '{self.name}': {len(self.rings)} ring samples, "
                             f"expected {len(KLEMS_FULL_RINGS)}")

    @property
    def count(self) -> int:
        return sum(r.count for r in self.rings)


def chord_rings(half_chord_m: float, min_depth_m: float) -> list[tuple[float, float]]:
    """(slab depth m, optical-depth scale) per Klems ring for a crossing of a crown envelope.

    A straight line entering a sphere of radius R at incidence θ (from the surface normal)
    runs a chord 2 R cos θ inside: each of its two crossings of the envelope carries the half
    chord R cos θ. A planar slab of depth D at density scale c is crossed along c D / cos θ,
    so ring k (centre θ_k) takes c_k D_k = R cos² θ_k, with D_k = max(R cos² θ_k,
    ``min_depth_m``) (a slab thinner than a few slats is no random medium) and c_k ≤ 1."""
    out = []
    for _, _, centre, _ in KLEMS_FULL_RINGS:
        target = half_chord_m * math.cos(math.radians(centre)) ** 2
        depth = min(half_chord_m, max(target, min_depth_m))
        out.append((depth, target / depth))
    return out


def chord_samples(make: Callable[[float, float], SlabSample], half_chord_m: float,
                  min_depth_m: float, name: str, notes: list[str]) -> RingSamples:
    """The :class:`RingSamples` of ``make(depth, scale)`` over :func:`chord_rings`."""
    rings = chord_rings(half_chord_m, min_depth_m)
    samples = [make(d, c) for d, c in rings]
    text = ", ".join(f"{ring[2]:g}°: {c * d:.2f} m" for ring, (d, c) in
                     zip(KLEMS_FULL_RINGS, rings))
    notes = [*notes, f"Envelope crossing (chord): each Klems ring of incidence θ has its own "
             f"planar sample whose optical depth is that of the half chord R cos θ of a crown of "
             f"R = {half_chord_m:.2f} m (a line entering a sphere at θ runs 2 R cos θ inside), "
             f"as slab depth at full density — {text}; ring-to-ring exchanges made reciprocal "
             f"(Helmholtz) by averaging each pair."]
    info = {"half_chord_m": half_chord_m, **{f"ring{k}_depth_m": d * c
                                               for k, (d, c) in enumerate(rings)}}
    return RingSamples(name, samples, half_chord_m, notes, info)
