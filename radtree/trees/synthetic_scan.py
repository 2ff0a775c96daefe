"""A synthetic street of radtree's own crowns, scanned by the synthetic airborne scanner.

For round trips (``benchmarks/lidar_roundtrip.py``, tests, ``examples/lidar-street``): trees
in a row along x (east) at y = ``row_y_m``, every ``spacing_m``, heights, crown radii and
depths drawn (seeded) from street-tree ranges; each crown a volume-louvers spheroid
(:func:`radtree.trees.volume.build_volume_louvers`, one crown per tree, no wall or neighbour
clipping), scanned with :func:`radtree.lidar.scanner.scan_als` over the ground plane z = 0
(class 2; slats class 5, high vegetation). Trunks are not scanned (their wood would count as
plant area, see :mod:`radtree.lidar.voxels`). The truth per tree: position, height, crown
diameter 2a, crown base, and leaf area (the summed one-sided area of its slats).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from radtree.config import Louvers
from radtree.lidar.clip import write_points
from radtree.lidar.scanner import AlsScan, ScanPoints, ground_plane, scan_als
from radtree.trees.envelope import CrownRowSpec
from radtree.trees.geometry import polygons_to_mesh
from radtree.trees.volume import build_volume_louvers

#: the crowns of the round trip: volume slats, 2 slat crossings on a crown's vertical axis
STREET_LOUVERS = Louvers(arrangement="volume", crossings=2.0, slat_size_m=0.3,
                         inclination_deg=30.0, cover_fraction=1.0, seed=1)
HIGH_VEGETATION, GROUND = 5, 2   # ASPRS classes


@dataclass(frozen=True)
class StreetTree:
    """A tree of the synthetic street (m): trunk at (x, y), total height, crown radius a and
    vertical semi-axis b (crown base = height − 2b)."""

    id: str
    x: float
    y: float
    height_m: float
    crown_radius_m: float
    vertical_radius_m: float

    @property
    def crown_base_m(self) -> float:
        return self.height_m - 2.0 * self.vertical_radius_m

    def spec(self) -> CrownRowSpec:
        b = self.vertical_radius_m
        return CrownRowSpec(centres=np.array([[self.x, self.y, self.height_m - b]]),
                            a=self.crown_radius_m, b=b, n_clip=-np.inf,
                            strips=np.array([[-np.inf, np.inf]]), trunk_radius=0.15,
                            trunk_top=self.crown_base_m + 0.5 * b)


def synthetic_street(count: int = 20, seed: int = 0, spacing_m: float = 9.0,
                     row_y_m: float = 6.0) -> list[StreetTree]:
    """``count`` trees: heights 7–14 m, crown radius 2–3.5 m (≤ 0.45 spacing), vertical
    semi-axis 25–40 % of the height (seeded)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        h = float(rng.uniform(7.0, 14.0))
        a = float(min(rng.uniform(2.0, 3.5), 0.45 * spacing_m))
        b = float(rng.uniform(0.25, 0.40) * h)
        out.append(StreetTree(f"S{i + 1:02d}", (i + 0.5) * spacing_m, row_y_m, h, a, b))
    return out


def _area(poly: np.ndarray) -> float:
    return 0.5 * float(np.linalg.norm(np.cross(poly[1:-1] - poly[0], poly[2:] - poly[0]).sum(0)))


def crown_polygons(tree: StreetTree, index: int, lv: Louvers = STREET_LOUVERS
                   ) -> list[np.ndarray]:
    """The tree's slats (world coordinates, m); the seed is ``lv.seed + index``."""
    polys, _ = build_volume_louvers(tree.spec(), replace(lv, seed=lv.seed + index))
    return polys


def leaf_area_m2(polys: list[np.ndarray]) -> float:
    """Summed one-sided area of convex polygons (m²)."""
    return float(sum(_area(p) for p in polys))


def scan_street(trees: list[StreetTree], scan: AlsScan, lv: Louvers = STREET_LOUVERS,
                margin_m: float = 5.0,
                extra: list[tuple[np.ndarray, np.ndarray, int]] | None = None,
                area: tuple | None = None) -> tuple[ScanPoints, dict[str, float], tuple]:
    """Scan the street: the points, each tree's true leaf area (m²), the scanned rectangle
    (``area`` = (lo, hi), else the trees' extent plus ``margin_m``). ``extra``: more
    meshes (vertices, faces, ASPRS class), e.g. buildings (class 6)."""
    polys_all: list[np.ndarray] = []
    areas: dict[str, float] = {}
    for i, t in enumerate(trees):
        polys = crown_polygons(t, i, lv)
        areas[t.id] = leaf_area_m2(polys)
        polys_all.extend(polys)
    v, f = polygons_to_mesh(polys_all)
    xs = [t.x for t in trees]
    ys = [t.y for t in trees]
    r = max(t.crown_radius_m for t in trees) + margin_m
    lo, hi = area or ((min(xs) - r, min(ys) - r), (max(xs) + r, max(ys) + r))
    parts = [(v, f, HIGH_VEGETATION), (*ground_plane(lo, hi), GROUND), *(extra or [])]
    vs: list[np.ndarray] = []
    fs: list[np.ndarray] = []
    cs: list[np.ndarray] = []
    off = 0
    for pv, pf, pc in parts:
        vs.append(np.asarray(pv, float))
        fs.append(np.asarray(pf, np.int64) + off)
        cs.append(np.full(len(pf), pc))
        off += len(pv)
    return (scan_als(np.vstack(vs), np.vstack(fs), np.concatenate(cs), lo, hi, scan), areas,
            (lo, hi))


def scan_crown(vertices: np.ndarray, faces: np.ndarray, scan: AlsScan,
               margin_m: float = 3.0) -> ScanPoints:
    """One crown mesh (its leaves, class 5) scanned over the ground plane z = 0 (class 2) by
    ``scan``, across the crown's extent plus ``margin_m`` (m)."""
    lo = tuple(vertices[:, :2].min(axis=0) - margin_m)
    hi = tuple(vertices[:, :2].max(axis=0) + margin_m)
    gv, gf = ground_plane(lo, hi)
    return scan_als(np.vstack([vertices, gv]), np.vstack([faces, gf + len(vertices)]),
                    np.r_[np.full(len(faces), HIGH_VEGETATION), np.full(len(gf), GROUND)],
                    lo, hi, scan)


def write_scan(points: ScanPoints, out: str | Path, offset: tuple[float, float] = (0.0, 0.0),
               crs: str | None = None) -> Path:
    """The scan as LAS/LAZ, x, y shifted by ``offset`` (m)."""
    xyz = points.xyz + [offset[0], offset[1], 0.0]
    return write_points(out, xyz, points.classification, points.return_number,
                        points.number_of_returns, crs=crs, source_id=points.line,
                        gps_time=points.time, scan_angle_deg=points.scan_angle_deg,
                        intensity=points.intensity)
