"""Turbid voxel crowns from a voxel file or a point cloud (radtree.trees.turbid_voxels,
radtree.trees.voxel_file): reading and its errors, placement on the trunks, the manifest's
leaf area and profile, the Radiance engine's refusal."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from radtree.config import Scenario, load_project
from radtree.engines.common.voxels import refuse_voxels
from radtree.errors import ConfigError, EngineError
from radtree.media_voxels import VoxelCrowns
from radtree.trees.voxel_file import read_voxel_file

ROOT = Path(__file__).resolve().parents[1]
MENDOZA = ROOT / "examples" / "mendoza-street"


def _write(path: Path, rows: list[tuple], header: str = "x_m,y_m,z_m,pad_m2_m3") -> Path:
    path.write_text(header + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")
    return path


def _block(pad: float = 1.0) -> list[tuple]:
    """3 × 3 × 3 voxels of 0.5 m centred 4.5 m over the trunk base; the top layer denser."""
    return [(x, y, z, pad * (2.0 if z == 5.0 else 1.0)) for x in (-0.5, 0.0, 0.5)
            for y in (-0.5, 0.0, 0.5) for z in (4.0, 4.5, 5.0)]


def test_voxel_file_is_read_on_its_lattice(tmp_path: Path) -> None:
    rows = [r for r in _block() if not (r[0] == 0.0 and r[2] == 4.5)]   # a gap: empty voxels
    vf = read_voxel_file(_write(tmp_path / "v.csv", rows))
    assert vf.size_m == pytest.approx(0.5) and vf.pad.shape == (3, 3, 3)
    np.testing.assert_allclose(vf.corner, [-0.75, -0.75, 3.75])
    assert vf.pad[1, :, 1].sum() == 0.0 and vf.pad[0, 0, 2] == 2.0
    assert vf.pad.sum() * 0.125 == pytest.approx(sum(r[3] for r in rows) * 0.125)
    # a sparse file: the side must be given, or is the smallest spacing found
    sparse = _write(tmp_path / "s.csv", [(0.0, 0.0, 4.0, 1.0), (1.0, 0.0, 4.0, 1.0)])
    assert read_voxel_file(sparse).pad.shape == (2, 1, 1)
    assert read_voxel_file(sparse, 0.5).pad.shape == (3, 1, 1)


@pytest.mark.parametrize(("rows", "header", "size", "message"), [
    ([(0, 0, 4)], "x_m,y_m,z_m", None, r"missing column\(s\) pad_m2_m3; found x_m, y_m, z_m"),
    ([(0, 0, 4, -0.5), (0.5, 0, 4, 1)], None, None,
     r"data row 1: pad_m2_m3 = -0.5, expected a plant area density ≥ 0"),
    ([(0, 0, 4, 1), (0.5, 0, 4, 1), (0.8, 0, 4, 1)], None, 0.5,
     r"data row 3: the centre \(0.8, 0, 4\) m is not on the 0.5 m lattice.*irregular grid"),
    ([(0, 0, 4, 1), (0.5, 0, 4, 1), (0, 0, 4, 2)], None, None,
     r"data rows 1 and 3 are the same voxel"),
    ([(0, 0, 4, "x")], None, 0.5, r"data row 1: pad_m2_m3 = 'x' is not a finite number"),
    ([(0, 0, 4, 1)], None, None, r"one voxel only: give its side, tree.voxels_size_m"),
])
def test_voxel_file_errors_name_file_row_and_fix(tmp_path: Path, rows, header, size,
                                                 message) -> None:
    path = _write(tmp_path / "bad.csv", rows, header or "x_m,y_m,z_m,pad_m2_m3")
    with pytest.raises(ConfigError, match=r"bad.csv, field 'tree.voxels': " + message):
        read_voxel_file(path, size)


def test_missing_voxel_file_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="not found"):
        read_voxel_file(tmp_path / "none.csv", 0.5)
    with pytest.raises(ConfigError, match=r"tree.voxels.*representation = \"turbid\""):
        load_project(MENDOZA, {"tree.voxels": str(_write(tmp_path / "v.csv", _block()))})


def test_voxel_file_crowns_on_every_trunk(tmp_path: Path, frame) -> None:
    from radtree.pipeline.manifest import input_files
    from radtree.trees.build import build_tree

    path = _write(tmp_path / "crown.csv", _block())
    project = load_project(MENDOZA, {"tree.voxels": str(path), "tree.representation": "turbid",
                                     "tree.form": "free"})
    tm = build_tree(project, Scenario("v", "louvers", form="free"), frame)
    media = tm.media
    assert isinstance(media, VoxelCrowns) and len(media) == 3 and len(media.pads) == 1
    # the row's trunks at u = sensors.x_m + (−8, 0, 8), n = 3 (trunk_distance_m)
    local = frame.to_local(media.origins)
    xs = project.sensors.x_m
    np.testing.assert_allclose(local, [[xs - 8.75, 2.25, 3.75], [xs - 0.75, 2.25, 3.75],
                                       [xs + 7.25, 2.25, 3.75]], atol=1e-9)
    np.testing.assert_allclose(media.axis_i[0], frame.along[:2])
    info = tm.info
    assert info["voxels_size_m"] == 0.5 and info["voxels_leaf_area_m2"] == pytest.approx(
        (18 + 9 * 2) * 0.125)
    assert info["leaf_area_m2"] == pytest.approx(3 * 36 * 0.125)
    assert info["voxels_leaf_area_m2_z4.75_5.25"] == pytest.approx(9 * 2 * 0.125)
    assert sum(v for k, v in info.items() if "_z" in k) == pytest.approx(4.5)
    assert "Turbid voxel crowns" in " ".join(tm.notes) and tm.meshes[0].name == "tree_trunks"
    assert input_files(project)["tree_voxels"].startswith("crown.csv sha256:")
    from radtree.pipeline.manifest import manifest

    rec = manifest(project, engines=[])["crown_voxels"]
    assert rec["voxel_size_m"] == 0.5 and rec["voxels"] == [3, 3, 3] and len(rec["sha256"]) == 64
    assert rec["leaf_area_m2_per_crown"] == pytest.approx(4.5)
    assert rec["profile"][2] == {"z_bottom_m": 4.75, "z_top_m": 5.25, "leaf_area_m2": 2.25}
    with pytest.raises(ConfigError, match="is free-standing"):
        build_tree(project, Scenario("d", "louvers", form="dome"), frame)


def test_points_as_turbid_voxels(tmp_path: Path, frame) -> None:
    """One synthetic crown scanned at 25 pulses/m²: its grid on the trunk, the leaf area the
    inversion's (three crowns), the profile in the info, the NumPy engine's shadow through it,
    Radiance refuses it."""
    from radtree.lidar.scanner import AlsScan
    from radtree.trees.build import build_tree
    from radtree.trees.synthetic_scan import StreetTree, scan_street, write_scan

    tree = StreetTree("S01", 10.0, 10.0, 10.0, 3.0, 3.0)
    pts, areas, _ = scan_street([tree], AlsScan(pulse_density_m2=25.0))
    path = write_scan(pts, tmp_path / "tree.laz")
    project = load_project(MENDOZA, {"tree.points": str(path), "tree.representation": "turbid",
                                     "tree.form": "free", "tree.crown.count": 1})
    tm = build_tree(project, Scenario("p", "louvers", form="free"), frame)
    media = tm.media
    assert isinstance(media, VoxelCrowns) and len(media) == 1
    info = tm.info
    assert info["points_leaf_area_m2"] == pytest.approx(areas["S01"], rel=0.15)
    assert media.leaf_area() == pytest.approx(info["points_leaf_area_m2"], rel=0.05)  # the cut
    profile = [v for k, v in info.items() if k.startswith("points_leaf_area_m2_z")]
    assert sum(profile) == pytest.approx(info["points_leaf_area_m2"])
    lo, hi = media.bounds()
    assert lo[0, 2] == 0.0 and 9.0 < hi[0, 2] < 11.0
    from radtree.engines.common.media import media_tracer

    tr = media_tracer(media, materials=tm.materials)
    assert tr is not None
    trunk = frame.to_world(np.array([[project.sensors.x_m, 3.0, 0.5]]))
    t = tr.transmittance(trunk, np.array([[0.0, 0.0, 1.0]]))[0]
    assert 0.0 < t < math.exp(-0.1)   # straight up through the crown

    class _S:
        media = tm.media

    with pytest.raises(EngineError, match="cannot trace voxel crowns"):
        refuse_voxels(_S(), engine="radiance")  # type: ignore[arg-type]
