"""Crown outlines: a free crown whose horizontal section follows a plan polygon (issue 41).

An inventory tree may carry its crown's outline (``crown_outline``, e.g. the watershed
region of ``radtree lidar segment``). Its crown is then *the spheroid's vertical profile
scaled into the outline*, a star-shaped body about the trunk axis: with r(θ) the distance in
plan from the trunk (x_t, y_t) to the outline in direction θ (the farthest crossing of the
ray), ρ the plan distance of a point from the trunk axis and z_c = crown base + b,

    (ρ / r(θ))² + ((z − z_c) / b)² ≤ 1.

Every horizontal section is the outline shrunk towards the trunk by √(1 − ((z − z_c)/b)²):
the full outline at z_c, a point at base and top. A circle of radius a about the trunk gives
r = a: the spheroid of :mod:`radtree.trees.envelope`. The body's volume is (4/3)·b·A with
A = ½∮ r(θ)² dθ, the outline's area when the outline is star-shaped from the trunk (every
point of it seen from the trunk; otherwise A is that of its radial hull, and the crown covers
the hidden pockets too). A vertical line through the trunk still crosses 2b of crown, so the
species' leaf area density (set on that line, :func:`radtree.trees.volume.volume_density`)
keeps its optical depth there, and the crown's leaf area is density × volume.

Round outlines: when r(θ) stays within :data:`ROUND_TOLERANCE` of the row's crown radius
(``crown_diameter_m`` / 2) in every direction, the crown is the spheroid — the same slats, the
same instancing as a tree without an outline.

r(θ) is tabulated on :data:`ANGLES` directions (exact ray–edge crossings) and interpolated
linearly; slat centres are placed by mapping points uniform in the unit ball to points uniform
in the body (:meth:`CrownOutline.from_ball`), so one random stream serves both shapes.
Angles θ in the plan are counter-clockwise from +x (east, or u along the façade); metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: directions r(θ) is tabulated on
ANGLES = 2048
#: an outline within this fraction of the crown radius in every direction is round
ROUND_TOLERANCE = 0.05


def ring_area(ring: np.ndarray) -> float:
    """Area (m²) of a closed or open ring (k, 2) by the shoelace formula."""
    x, y = np.asarray(ring, float)[:, 0], np.asarray(ring, float)[:, 1]
    return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def contains(ring: np.ndarray, *, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Which plan points (x, y) lie inside the ring (even–odd rule)."""
    r = np.asarray(ring, float)
    px, py = np.asarray(x, float).ravel(), np.asarray(y, float).ravel()
    ax, ay = r[:, 0], r[:, 1]
    bx, by = np.roll(ax, -1), np.roll(ay, -1)
    inside = np.zeros(len(px), bool)
    for x0, y0, x1, y1 in zip(ax, ay, bx, by):
        if y0 == y1:
            continue
        crosses = (py >= min(y0, y1)) & (py < max(y0, y1))
        xc = x0 + (py - y0) * (x1 - x0) / (y1 - y0)
        inside ^= crosses & (px < xc)
    return inside


def radial_function(ring: np.ndarray, *, centre: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """r(θ): distance from ``centre`` to the farthest crossing of the ray at angle θ with the
    ring's edges (0 where the ray meets none)."""
    r = np.asarray(ring, float)
    p = r - np.asarray(centre, float)[None, :]
    q = np.roll(p, -1, axis=0)
    e = q - p                                            # edges p → q
    d = np.column_stack([np.cos(theta), np.sin(theta)])  # (n, 2)
    # c + t·d = p + s·e  →  t·d − s·e = p ; Cramer's rule per (ray, edge)
    den = d[:, None, 0] * (-e[None, :, 1]) - d[:, None, 1] * (-e[None, :, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (p[None, :, 0] * (-e[None, :, 1]) - p[None, :, 1] * (-e[None, :, 0])) / den
        s = (d[:, None, 0] * p[None, :, 1] - d[:, None, 1] * p[None, :, 0]) / den
    hit = (np.abs(den) > 1e-15) & (s >= -1e-12) & (s <= 1.0 + 1e-12) & (t > 0)
    return np.asarray(np.where(hit, t, 0.0).max(axis=1), float)


@dataclass(frozen=True)
class CrownOutline:
    """A crown's plan outline about its trunk: the ring (k, 2) and the trunk ``centre`` (2,)
    in the crown's frame (m), r(θ) on :data:`ANGLES` directions θ_j = 2πj/n, and the share of
    the body's volume up to each θ_j (``cdf``, 0 … 1, for :meth:`from_ball`)."""

    ring: np.ndarray
    centre: np.ndarray
    radii: np.ndarray
    cdf: np.ndarray

    @classmethod
    def of(cls, ring: np.ndarray, *, centre: np.ndarray) -> CrownOutline:
        """The outline of ``ring`` about ``centre`` (which must lie inside it)."""
        ring = np.asarray(ring, float)
        if len(ring) > 1 and np.allclose(ring[0], ring[-1]):
            ring = ring[:-1]
        theta = np.arange(ANGLES + 1) * (2.0 * math.pi / ANGLES)
        radii = radial_function(ring, centre=centre, theta=theta[:-1])
        r2 = np.append(radii, radii[0]) ** 2
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (r2[:-1] + r2[1:]))])
        return cls(ring, np.asarray(centre, float), radii, cum / cum[-1])

    @property
    def area_m2(self) -> float:
        """A = ½∮ r² dθ (m²): the plan area of the body's widest section."""
        r2 = self.radii ** 2
        return float(0.5 * np.sum(0.5 * (r2 + np.roll(r2, -1))) * 2.0 * math.pi / ANGLES)

    @property
    def max_radius_m(self) -> float:
        return float(self.radii.max())

    def reach(self, offsets: np.ndarray) -> np.ndarray:
        """r(θ) towards plan offsets (…, 2) from the trunk (m)."""
        d = np.asarray(offsets, float)
        theta = np.mod(np.arctan2(d[..., 1], d[..., 0]), 2.0 * math.pi)
        grid = np.arange(ANGLES + 1) * (2.0 * math.pi / ANGLES)
        return np.interp(theta, grid, np.append(self.radii, self.radii[0]))

    def extent_towards(self, direction: np.ndarray) -> float:
        """How far the outline reaches from the trunk along the plan unit ``direction`` (m)."""
        return float(np.max((self.ring - self.centre) @ np.asarray(direction, float)))

    def is_round(self, radius: float, *, tolerance: float = ROUND_TOLERANCE) -> bool:
        """r(θ) within ``tolerance``·radius of ``radius`` in every direction."""
        return bool(np.all(np.abs(self.radii - radius) <= tolerance * radius))

    def from_ball(self, x: np.ndarray, *, b: float) -> np.ndarray:
        """Offsets from the crown centre (k, 3) of points ``x`` uniform in the unit ball,
        mapped to points uniform in the body: the azimuth's share t = θ/2π goes to the θ' at
        which the body's volume share is t, the plan radius scales by r(θ'), z by b."""
        x = np.asarray(x, float)
        rho = np.hypot(x[:, 0], x[:, 1])
        t = np.mod(np.arctan2(x[:, 1], x[:, 0]), 2.0 * math.pi) / (2.0 * math.pi)
        grid = np.arange(ANGLES + 1) * (2.0 * math.pi / ANGLES)
        th = np.interp(t, self.cdf, grid)
        r = rho * np.interp(th, grid, np.append(self.radii, self.radii[0]))
        return np.column_stack([r * np.cos(th), r * np.sin(th), x[:, 2] * b])
