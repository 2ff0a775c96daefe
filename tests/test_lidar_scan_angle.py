"""Airborne beams from the LAS scan angle and flight line (radtree.lidar.scan_angle) and the
``[tree] points`` crown built along them (``tree.points_beams``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from radtree.config import load_project
from radtree.lidar.scan_angle import scan_angle_origins
from radtree.lidar.scanner import AlsScan
from radtree.lidar.tile import read_tile
from radtree.trees.points_crown import points_crown_grid
from radtree.trees.synthetic_scan import StreetTree, scan_street, write_scan

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def seam_tree(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float, AlsScan]:
    """One crown on the seam of two flight lines (x = 75 m: lines at x = 0 and 150 m, beams
    tilted ±14° toward each other), 20 pulses/m² a line; its true leaf area (m²)."""
    scan = AlsScan(pulse_density_m2=20.0)
    pts, areas, _ = scan_street([StreetTree("S01", 75.0, 10.0, 10.0, 3.0, 3.0)], scan)
    path = write_scan(pts, tmp_path_factory.mktemp("seam") / "tree.laz")
    return path, areas["S01"], scan


def test_beams_from_scan_angles_match_the_flight(seam_tree) -> None:
    """Both lines' beams rebuilt from the file alone: origins within 0.1 m of the scanner's
    (LAS 1.4 stores the angle to 0.006°); whole-degree angles (``scan_angle_rank``) over one
    tree do not give the beams (RMS residual ≈ 0.3° > 0.1°): None, columns stay."""
    path, _, scan = seam_tree
    tile = read_tile(path)
    assert sorted(np.unique(tile.source_id).tolist()) == [0, 1]
    assert np.ptp(tile.scan_angle_deg) > 20.0
    origins = scan_angle_origins(tile)
    assert origins is not None
    truth = scan.origins(tile.xyz, line=tile.source_id)
    assert np.abs(origins - truth).max() < 0.1
    tile.scan_angle_deg[:] = np.round(tile.scan_angle_deg)
    assert scan_angle_origins(tile) is None
    tile.scan_angle_deg[:] = 0.0
    assert scan_angle_origins(tile) is None


def test_points_crown_along_scan_angle_beams(seam_tree) -> None:
    """``[tree] points`` of the seam crown, 0.85 m voxels: along the beams of its scan angles
    −0.7 % of the true leaf area (+0.5 % before the undersampled voxels were pooled per
    layer), in vertical columns −33.7 % (the tilted beams of two lines
    read as vertical; benchmarks/lidar_als_user.py has the street)."""
    path, truth, _ = seam_tree
    area = {}
    for mode in ("scan_angle", "vertical"):
        project = load_project(ROOT / "examples" / "mendoza-street", {
            "tree.points": str(path), "tree.form": "free", "tree.crown.count": 1,
            "tree.points_beams": mode})
        _, fine, _ = points_crown_grid(project.tree)
        area[mode] = fine.leaf_area_m2 / truth - 1
    assert abs(area["scan_angle"]) < 0.05
    assert area["vertical"] < -0.2
