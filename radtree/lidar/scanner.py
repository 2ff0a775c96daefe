"""A synthetic airborne laser scanner: ray-cast pulses onto triangle meshes → LAS points.

For round trips (scan radtree's own crowns, rebuild them from the points, compare). Flight
lines run along ``heading_deg`` (clockwise from north) every ``line_spacing_m``, at
``altitude_m`` above z = 0. Each line scans a swath of width ``line_spacing_m / (1 −
sidelap)`` centred on it, so neighbouring swaths share ``sidelap`` of their width (default 30 %,
the lateral overlap recommended for ALS: "insufficient overlap between scans, especially in
combination with significant relief differences, can lead to the formation of an area without
data", TOPODRONE, *Overlaps between scans and the height of the scanned objects*; with no
sidelap, beams of the two lines tilt away from each other at the swaths' seam and leave a
wedge above it that no beam crosses, a crown standing there is seen from one side only). In
its swath each line lands pulses on its own jittered grid of ``pulse_density_m2`` pulses per m²
(on the ground, per pass; seeded), fired in the vertical plane across the line, so a pulse's
zenith angle is its across-track scan angle (≤ atan(swath / 2 / altitude)). Every return
records its flight line (LAS ``point_source_id``, :attr:`ScanPoints.line`) and its pulse's
emission time (LAS ``gps_time``, :attr:`ScanPoints.time`: pulse index / ``PULSE_RATE_HZ``)
and its scan angle (LAS ``scan_angle``, :attr:`ScanPoints.scan_angle_deg`): with the flight
geometry these give each beam's path (:meth:`AlsScan.origins`), which the voxel inversion
follows (:mod:`radtree.lidar.beams`); without it, the scan angle and flight line alone
(:mod:`radtree.lidar.scan_angle`).

Footprint: a pulse is ``footprint_rays`` parallel sub-rays spread uniformly over a disc of
diameter ``altitude · beam_divergence_mrad / 1000`` (m) across the beam (default 16 sub-rays
over 0.15 m). Each sub-ray stops at the first surface it meets (trimesh, Embree when
installed); the sub-rays' hits are sorted by range and grouped into returns separated by at
least ``range_resolution_m`` (1.5 m: a stated value, not a particular sensor's); a pulse
records up to ``max_returns`` returns (first … last, 4 by default), each at the mean position
of its sub-rays' hits, with the class of its first hit's face and as intensity the share of
the pulse's sub-rays it stopped (:attr:`ScanPoints.intensity`, 0–1; LAS ``intensity`` × 65535:
every surface equally reflective). Leaf transmittance does not pass laser light on (a
sub-ray ends at its hit). Discrete-return airborne scanners record several returns a pulse:
the USGS 3DEP Lidar Base Specification (v2.1, "Collection requirements", usgs.gov) requires
multiple discrete returns, at least three a pulse, with an intensity for each (normalised
linearly to 16 bits), and LAS point records carry each return's "return number" within its
pulse and the pulse's "number of returns" (e.g. ArcGIS Pro's ``LasPoint.NumberOfReturns``:
"the total number of returns for a given pulse"). With 16 sub-rays a pulse grazing a 0.3 m
slat goes on to the leaves and ground below it, as a real footprint does; with one
(``footprint_rays = 1``, the default until 2026-12-08) every pulse has exactly one return,
the first surface along a thin beam. Units: metres, z up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from radtree.config.spec import Checked, meta


@dataclass(frozen=True)
class AlsScan(Checked):
    """The scanner (module text): density per m², angles in degrees, lengths in metres."""

    TABLE: ClassVar[str] = "scan"
    pulse_density_m2: float = field(default=20.0, metadata=meta(0.1, 10000.0))
    altitude_m: float = field(default=300.0, metadata=meta(10.0, 10000.0))
    line_spacing_m: float = field(default=150.0, metadata=meta(1.0, 10000.0))
    heading_deg: float = field(default=0.0, metadata=meta(0.0, 360.0))
    beam_divergence_mrad: float = field(default=0.5, metadata=meta(0.0, 10.0))
    footprint_rays: int = field(default=16, metadata=meta(1, 64))
    range_resolution_m: float = field(default=1.5, metadata=meta(0.0, 100.0))
    max_returns: int = field(default=4, metadata=meta(1, 15))
    sidelap: float = field(default=0.3, metadata=meta(0.0, 0.9))
    seed: int = 0

    @property
    def half_swath_m(self) -> float:
        """Half the swath width of one line (m): line spacing / (1 − sidelap) / 2."""
        return 0.5 * self.line_spacing_m / (1.0 - self.sidelap)

    def _axes(self) -> tuple[np.ndarray, np.ndarray]:
        h = math.radians(self.heading_deg)
        along = np.array([math.sin(h), math.cos(h)])   # the flight direction
        across = np.array([math.cos(h), -math.sin(h)])  # to its right
        return along, across

    def origins(self, xyz: np.ndarray, *, line: np.ndarray) -> np.ndarray:
        """Where the beam of each return (x, y, z m; ``line``: its flight line) was fired:
        the beam lies in the vertical plane across the line through the return, so the
        origin is the return's along-track position on line ``line``, at the altitude."""
        along, across = self._axes()
        xy = np.asarray(xyz, float)[:, :2]
        s = xy @ along
        signed = (np.asarray(line, np.int64) + 32768) % 65536 - 32768   # LAS id: uint16
        c = signed * self.line_spacing_m
        return np.column_stack([s[:, None] * along + c[:, None] * across,
                                np.full(len(xy), self.altitude_m)])


#: pulses per second of the synthetic scanners (only orders the LAS ``gps_time`` stamps)
PULSE_RATE_HZ = 100_000.0


@dataclass(frozen=True)
class ScanPoints:
    """Returns: positions (n, 3) m, ASPRS classes, return number and number of returns, the
    flight line or scan position (LAS point source id), the pulse's emission time (s) and, of
    airborne scans, its scan angle (degrees from nadir, positive to the right of the flight
    direction: LAS ``scan_angle``)."""

    xyz: np.ndarray
    classification: np.ndarray
    return_number: np.ndarray
    number_of_returns: np.ndarray
    line: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    scan_angle_deg: np.ndarray = field(default_factory=lambda: np.zeros(0))
    intensity: np.ndarray = field(default_factory=lambda: np.zeros(0))


def _pulses(lo: np.ndarray, hi: np.ndarray, scan: AlsScan, rng: np.random.Generator
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ground aim points (k, 2), unit directions (k, 3) and flight lines (k,) of the pulses
    over [lo, hi]: every line whose swath reaches the rectangle fires its own jittered grid."""
    step = 1.0 / math.sqrt(scan.pulse_density_m2)
    _, across = scan._axes()
    corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    cc = corners @ across
    w, sp = scan.half_swath_m, scan.line_spacing_m
    first, last = math.ceil((cc.min() - w) / sp), math.floor((cc.max() + w) / sp)
    gx, gy = np.arange(lo[0], hi[0], step), np.arange(lo[1], hi[1], step)
    x, y = (v.ravel() for v in np.meshgrid(gx, gy))
    aims, dirs, lines = [], [], []
    for line in range(first, last + 1):
        aim = np.column_stack([x, y]) + rng.uniform(0.0, step, (len(x), 2))
        offset = aim @ across - line * sp                       # from the line, m
        keep = np.abs(offset) <= w
        aim, offset = aim[keep], offset[keep]
        d = np.column_stack([offset[:, None] * across[None, :],
                             np.full(len(aim), -scan.altitude_m)])
        aims.append(aim)
        dirs.append(d / np.linalg.norm(d, axis=1)[:, None])
        lines.append(np.full(len(aim), line))
    return np.vstack(aims), np.vstack(dirs), np.concatenate(lines)


def scan_als(vertices: np.ndarray, faces: np.ndarray, face_class: np.ndarray,
             lo: tuple[float, float], hi: tuple[float, float], scan: AlsScan) -> ScanPoints:
    """Scan the triangles (``face_class``: the ASPRS class of each face) over the rectangle
    ``lo``…``hi`` (x, y m); see the module text."""
    import trimesh

    mesh = trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces, np.int64),
                           process=False)
    rng = np.random.default_rng(scan.seed)
    aim, d, lines = _pulses(np.asarray(lo, float), np.asarray(hi, float), scan, rng)
    k = len(aim)
    m = scan.footprint_rays
    # sub-rays: uniform on the footprint disc, in the plane across the beam
    radius = 0.5 * scan.altitude_m * scan.beam_divergence_mrad / 1000.0
    r = radius * np.sqrt(rng.random((k, m)))
    phi = rng.uniform(0.0, 2.0 * math.pi, (k, m))
    if m == 1:
        r[:] = 0.0
    e1 = np.cross(d, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(d, e1)
    start = np.column_stack([aim, np.zeros(k)]) - d * (scan.altitude_m / -d[:, 2])[:, None]
    origins = (start[:, None, :] + (r * np.cos(phi))[..., None] * e1[:, None, :]
               + (r * np.sin(phi))[..., None] * e2[:, None, :]).reshape(-1, 3)
    dirs = np.repeat(d, m, axis=0)
    loc, ray, tri = mesh.ray.intersects_location(origins, dirs, multiple_hits=False)
    xyz, cls, number, total, pulse_of, share = echoes(loc, pulse=ray // m, dist=np.einsum(
        "ij,ij->i", loc - origins[ray], dirs[ray]), tri=tri, face_class=face_class,
        pulses=k, resolution_m=scan.range_resolution_m, rays=m)
    keep = number <= scan.max_returns
    xyz, cls, number, pulse_of = xyz[keep], cls[keep], number[keep], pulse_of[keep]
    total = np.minimum(total[keep], scan.max_returns)
    _, across = scan._axes()
    angle = np.degrees(np.arctan2(d[:, :2] @ across, -d[:, 2]))   # + right of the line
    return ScanPoints(xyz, cls, number, total, lines[pulse_of], pulse_of / PULSE_RATE_HZ,
                      angle[pulse_of], share[keep])


def echoes(loc: np.ndarray, *, pulse: np.ndarray, dist: np.ndarray, tri: np.ndarray,
           face_class: np.ndarray, pulses: int, resolution_m: float, rays: int = 1
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sub-ray hits (``loc`` (h, 3), their pulse, range m, face) grouped into returns: sorted
    by range within a pulse, a new return where the range jumps by ≥ ``resolution_m``; each
    at the mean of its hits, with its first hit's class. (xyz, class, return number, number
    of returns of the pulse, pulse, share) per return, in pulse order; share: the return's
    sub-rays among the pulse's ``rays`` (the part of the footprint it intercepted, which
    its intensity records)."""
    order = np.lexsort((dist, pulse))
    pulse, dist, loc, tri = pulse[order], dist[order], loc[order], tri[order]
    new = np.ones(len(pulse), bool)
    new[1:] = (pulse[1:] != pulse[:-1]) | (np.diff(dist) >= resolution_m)
    ret = np.cumsum(new) - 1
    n_ret = int(ret[-1] + 1) if len(ret) else 0
    xyz = np.zeros((n_ret, 3))
    np.add.at(xyz, ret, loc)
    hits = np.bincount(ret, minlength=n_ret)
    xyz /= np.maximum(hits, 1)[:, None]
    cls = np.asarray(face_class)[tri[new]].astype(np.uint8)
    pulse_of = pulse[new]
    first = np.ones(n_ret, bool)
    first[1:] = pulse_of[1:] != pulse_of[:-1]
    number = np.arange(n_ret) - np.maximum.accumulate(np.where(first, np.arange(n_ret), 0)) + 1
    total = np.bincount(pulse_of, minlength=pulses)[pulse_of]
    return (xyz, cls, number.astype(np.uint8), total.astype(np.uint8), pulse_of,
            hits / float(rays))


def ground_plane(lo: tuple[float, float], hi: tuple[float, float], margin: float = 50.0
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Two triangles of the plane z = 0 covering ``lo``…``hi`` with a margin (m)."""
    x0, y0 = lo[0] - margin, lo[1] - margin
    x1, y1 = hi[0] + margin, hi[1] + margin
    v = np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]])
    return v, np.array([[0, 1, 2], [0, 2, 3]])
