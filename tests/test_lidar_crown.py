"""Crowns from points: the Beer–Lambert voxel inversion against an analytic turbid layer, its
errors, the synthetic scanner against geometry and ``[tree] points`` crowns (the street round
trip: tests/test_lidar_beams.py)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from radtree.config import Scenario, load_project
from radtree.errors import ConfigError
from radtree.lidar.clip import write_points
from radtree.lidar.scanner import AlsScan, scan_als
from radtree.lidar.voxels import default_voxel_m, tree_voxels

ROOT = Path(__file__).resolve().parents[1]
MENDOZA = ROOT / "examples" / "mendoza-street"


def turbid_layer(pad: float, g: float, top: float, bottom: float, n: int, seed: int
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Thin vertical beams on a jittered grid over 10 m × 10 m through a horizontally uniform
    layer (plant area density ``pad``, projection ``g``) between ``bottom`` and ``top`` m:
    each stops after an exponential free path of rate g·pad (Beer–Lambert) or at the ground."""
    rng = np.random.default_rng(seed)
    side = int(math.sqrt(n))
    g1 = (np.arange(side) + 0.5) * 10.0 / side
    x, y = (v.ravel() for v in np.meshgrid(g1, g1))
    free = rng.exponential(1.0 / (g * pad), len(x))
    z = np.where(free < top - bottom, top - free, 0.0)
    cls = np.where(z > 0, 5, 2)
    return np.column_stack([x, y, z]), cls


def test_voxel_inversion_recovers_a_turbid_layer(tmp_path: Path) -> None:
    """PAD 0.8 m²/m³, G 0.5 between 4 and 10 m: LAI 4.8; 250 000 beams (2 500/m²) on 1 m
    voxels: every layer within 5 % of 0.8 (binomial s.e. ≈ 1–2 %), the total within 1 %."""
    xyz, cls = turbid_layer(0.8, 0.5, 10.0, 4.0, 250_000, seed=3)
    path = write_points(tmp_path / "layer.laz", xyz, cls)
    grid = tree_voxels(path, g=0.5, size_m=1.0)
    assert grid.spacing_m == pytest.approx(0.02, rel=0.01)
    z, area = grid.profile()
    assert list(z[4:10]) == [4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
    assert np.allclose(area[4:10] / 100.0, 0.8, rtol=0.05)   # m² per m of height over 100 m²
    assert area[:4].sum() == 0.0
    assert grid.leaf_area_m2 == pytest.approx(4.8 * 100.0, rel=0.01)


def test_voxel_errors_name_file_and_fix(tmp_path: Path) -> None:
    xyz, cls = turbid_layer(0.5, 0.5, 8.0, 3.0, 2_500, seed=1)   # 25 beams/m², spacing 0.2
    path = write_points(tmp_path / "tree.laz", xyz, cls)
    assert default_voxel_m(0.2) == pytest.approx(1.0)
    with pytest.raises(ConfigError, match=r"tree.laz, field 'tree.points_voxel_m': voxel size "
                                          r"0.3 m is finer than this scan supports: its mean "
                                          r"point spacing is 0.20 m.*use at least 0.60 m"):
        tree_voxels(path, g=0.5, size_m=0.3)
    bare = write_points(tmp_path / "bare.laz", xyz, np.ones(len(xyz)))
    with pytest.raises(ConfigError, match=r"bare.laz, field 'ground': the tile has 0 ground"):
        tree_voxels(bare, g=0.5)
    flat = write_points(tmp_path / "flat.laz", xyz * [1, 1, 0], np.full(len(xyz), 2))
    with pytest.raises(ConfigError, match=r"flat.laz: the tree has 0 point\(s\) 0.5 m or more"):
        tree_voxels(flat, g=0.5)


def test_scanner_against_geometry() -> None:
    """An opaque 4 m × 4 m square 5 m up over a 10 m × 10 m scan: 16 % of the pulses return
    from it (jittered grid), classes from the faces (one thin ray a pulse); five sub-rays a
    pulse over a 1.5 m footprint give two returns (roof then ground) on the square's rim
    only, each with the share of the sub-rays it stopped as its intensity (a pulse's sum 1)."""
    v = np.array([[3, 3, 5], [7, 3, 5], [7, 7, 5], [3, 7, 5],
                  [-50, -50, 0], [60, -50, 0], [60, 60, 0], [-50, 60, 0]], float)
    f = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    cls = np.array([6, 6, 2, 2])
    pts = scan_als(v, f, cls, (0, 0), (10, 10), AlsScan(pulse_density_m2=400, footprint_rays=1,
                                                              seed=2))
    assert len(pts.xyz) == 40_000 and np.all(pts.intensity == 1.0)
    roof = pts.classification == 6
    assert roof.mean() == pytest.approx(0.16, abs=0.004)
    assert np.allclose(pts.xyz[roof, 2], 5.0) and np.allclose(pts.xyz[~roof, 2], 0.0)
    assert set(pts.number_of_returns.tolist()) == {1}
    wide = scan_als(v, f, cls, (0, 0), (10, 10),
                    AlsScan(pulse_density_m2=4, footprint_rays=5, beam_divergence_mrad=5.0,
                            seed=2))
    two = wide.number_of_returns == 2
    assert two.any()
    first = wide.xyz[two & (wide.return_number == 1)]
    last = wide.xyz[two & (wide.return_number == 2)]
    assert np.allclose(first[:, 2], 5.0) and np.allclose(last[:, 2], 0.0)
    rim = np.minimum(np.abs(first[:, :2] - 3), np.abs(first[:, :2] - 7)).min(axis=1)
    assert rim.max() < 0.75 + 0.05   # the footprint radius (300 m × 5 mrad / 2) from the rim
    fifths = wide.intensity * 5
    assert np.allclose(fifths, np.round(fifths)) and np.all(wide.intensity > 0)
    assert np.allclose(np.bincount(np.round(wide.time * 1e5).astype(int),
                                   weights=wide.intensity)[np.unique(
                                       np.round(wide.time * 1e5).astype(int))], 1.0)


@pytest.fixture(scope="module")
def one_tree(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    """One synthetic crown scanned at 25 pulses/m²; its true leaf area (m²)."""
    from radtree.trees.synthetic_scan import StreetTree, scan_street, write_scan

    tree = StreetTree("S01", 10.0, 10.0, 10.0, 3.0, 3.0)
    pts, areas, _ = scan_street([tree], AlsScan(pulse_density_m2=25.0))
    return write_scan(pts, tmp_path_factory.mktemp("tree") / "tree.laz"), areas["S01"]


def test_points_crown_filled_voxel_by_voxel(one_tree, frame) -> None:
    path, true_area = one_tree
    project = load_project(MENDOZA, {"tree.points": str(path), "tree.form": "free",
                                     "tree.crown.count": 1})
    from radtree.pipeline.manifest import input_files
    from radtree.trees.build import build_tree

    tm = build_tree(project, Scenario("p", "louvers", form="free"), frame)
    info = tm.info
    assert info["points_voxel_m"] == pytest.approx(default_voxel_m(info["points_spacing_m"]))
    assert info["points_g_vertical"] == pytest.approx(math.cos(math.radians(30.0)))
    # the crown's leaf area is the inversion's: slats × s² within the seeded rounding (± √n)
    s2 = info["slat_mean_area_m2"]
    n = info["slat_count"] + info["slats_dropped"]
    assert n * s2 == pytest.approx(info["points_leaf_area_m2"], abs=3 * math.sqrt(n) * s2)
    assert info["points_leaf_area_m2"] == pytest.approx(true_area, rel=0.15)
    profile = {k: v for k, v in info.items() if k.startswith("points_leaf_area_m2_z")}
    assert sum(profile.values()) == pytest.approx(info["points_leaf_area_m2"])
    text = " ".join(tm.notes)
    assert "Crowns from the point cloud tree.laz" in text and "wood counted as leaf" in text
    assert "1 crown(s) from tree.laz" in text and "1 spheroid(s)" not in text
    local = frame.to_local(tm.meshes[0].vertices)
    assert local[:, 2].max() < 10.5 and local[:, 2].min() > 3.0
    assert input_files(project)["tree_points"].startswith("tree.laz sha256:")
    with pytest.raises(ConfigError, match="a crown from points is free-standing"):
        build_tree(project, Scenario("d", "louvers", form="dome"), frame)
