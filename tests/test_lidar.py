"""radtree.lidar: reading tiles, heights above ground, tree detection, the inventory GeoJSON,
clipping one tree, the command line and its errors (exit 2), and the real-plot floor."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from radtree.cli import main
from radtree.errors import ConfigError
from radtree.lidar.clip import write_points
from radtree.lidar.segment import SegmentConfig, segment_tile
from radtree.lidar.tile import read_tile

ROOT = Path(__file__).resolve().parents[1]
#: the real plot: ../shared beside the repo, or two levels up from a worktree
REAL = next((p for p in (ROOT.parent / "shared/data/lidar/mixed_conifer_west.laz",
                         ROOT.parent.parent / "shared/data/lidar/mixed_conifer_west.laz")
             if p.exists()), None)
#: three spheroidal crowns: x, y (m), height (m), crown radius (m), vertical semi-axis (m)
CROWNS = [(10.0, 10.0, 12.0, 3.0, 3.0), (20.0, 11.0, 8.0, 2.5, 2.0), (15.0, 22.0, 15.0, 4.0, 4.0)]


def nadir_scan(slope: float = 0.0, seed: int = 0, spacing: float = 0.3
               ) -> tuple[np.ndarray, np.ndarray]:
    """A first-return nadir scan (jittered grid) of opaque spheroidal crowns over ground
    z = slope·x: points (n, 3) and classes (2 ground, 5 high vegetation)."""
    rng = np.random.default_rng(seed)
    g = np.arange(0.0, 30.0, spacing)
    x, y = (v.ravel() for v in np.meshgrid(g, g))
    x = x + rng.uniform(0, spacing, len(x))
    y = y + rng.uniform(0, spacing, len(y))
    ground = slope * x
    z = ground.copy()
    cls = np.full(len(x), 2)
    for cx, cy, h, a, b in CROWNS:
        q = 1.0 - ((x - cx) ** 2 + (y - cy) ** 2) / a**2
        top = slope * x + h - b + b * np.sqrt(np.clip(q, 0, None))
        hit = (q > 0) & (top > z)
        z = np.where(hit, top, z)
        cls = np.where(hit, 5, cls)
    return np.column_stack([x, y, z]), cls


@pytest.fixture
def tile(tmp_path: Path) -> Path:
    xyz, cls = nadir_scan(slope=0.1)
    return write_points(tmp_path / "street.laz", xyz + [500000.0, 4000000.0, 100.0], cls,
                        crs="EPSG:32633")


def test_three_crowns_found_with_heights_and_diameters(tile: Path) -> None:
    seg = segment_tile(read_tile(tile))
    assert len(seg.trees) == 3
    for cx, cy, h, a, _ in CROWNS:
        t = min(seg.trees, key=lambda t: math.hypot(t.top_x - 500000 - cx, t.top_y - 4e6 - cy))
        assert math.hypot(t.top_x - 500000 - cx, t.top_y - 4e6 - cy) < 0.5
        assert t.height_m == pytest.approx(h, abs=0.15)    # sloping ground removed
        # crown ratio 0.55 keeps the cells above 0.55 h: the spheroid's width there
        b = CROWNS[[c[2] for c in CROWNS].index(h)][4]
        zc = 0.55 * h - (h - b)
        keep = a * math.sqrt(max(0.0, 1 - (zc / b) ** 2)) if zc > 0 else a
        assert t.crown_diameter_m == pytest.approx(2 * keep, rel=0.1)
        assert 0 < t.crown_base_m < t.height_m
    assert [t.id for t in seg.trees] == ["L001", "L002", "L003"]   # by descending height
    assert seg.trees[0].height_m > seg.trees[1].height_m > seg.trees[2].height_m


def test_one_top_per_dome_flat_crown_and_two_crowns() -> None:
    """A flat crown top with two maxima equal to 2 mm, 2.1 m apart (beyond the 1.5 m of the
    window at 7 m) and a 0.7 m dip between them: one tree (the street's S02 at scanner
    seeds 1, 2 were two). The same two maxima over a 2.2 m saddle: two trees."""
    from radtree.lidar.segment import tree_tops

    cfg = SegmentConfig()
    chm = np.zeros((20, 20))
    ii, jj = np.meshgrid(np.arange(20), np.arange(20), indexing="ij")
    r = np.hypot(ii - 9.5, jj - 9.5) * 0.5          # m from the crown's centre
    chm[r < 3.2] = 6.3                               # a flat top, 6.4 m across
    chm[6, 8], chm[9, 11] = 6.981, 6.979             # two slat tips, 3.6 cells apart
    tops = tree_tops(chm, 0.5, cfg)
    assert tops.tolist() == [[6, 8]]
    chm[r < 3.2] = 4.8                               # a 2 m saddle: two crowns
    for i, j, h in ((6, 8, 6.981), (9, 11, 6.979)):
        chm[np.hypot(ii - i, jj - j) * 0.5 < 0.6] = 6.3
        chm[i, j] = h
    tops = tree_tops(chm, 0.5, cfg)
    assert sorted(tops.tolist()) == [[6, 8], [9, 11]]


def test_segment_cli_writes_inventory_new_reads(tile: Path, tmp_path: Path) -> None:
    out = tmp_path / "trees.geojson"
    r = CliRunner().invoke(main, ["lidar", "segment", str(tile), "--out", str(out),
                                  "--species", "morus_alba"])
    assert r.exit_code == 0, r.output
    assert r.output.startswith("3 trees (8.0–15.0 m high) from ")
    doc = json.loads(out.read_text())
    assert "crs" not in doc   # longitude/latitude (RFC 7946) from the tile's EPSG:32633
    p = doc["features"][0]["properties"]
    assert {"id", "species", "height_m", "crown_diameter_m", "crown_base_m", "points",
            "crown_outline", "top"} <= set(p)
    ring = np.array(p["crown_outline"])
    assert np.allclose(ring[0], ring[-1]) and len(ring) > 8
    from pyproj import Transformer

    lon, lat = Transformer.from_crs("EPSG:32633", "EPSG:4326", always_xy=True).transform(
        500015.0, 4000022.0)   # the highest crown's trunk
    assert p["top"] == pytest.approx([lon, lat], abs=3e-6)   # ≈ 0.3 m
    from radtree.site.inventory import read_trees

    trees, _ = read_trees(out, "EPSG:4326", lat, lon)   # the site origin at that trunk
    assert [t.id for t in trees] == ["L001", "L002", "L003"]
    assert trees[0].height_m == pytest.approx(15.0, abs=0.15)
    assert math.hypot(trees[1].x - (10 - 15), trees[1].y - (10 - 22)) < 0.5   # 12 m crown
    local = tmp_path / "local.geojson"
    CliRunner().invoke(main, ["lidar", "segment", str(tile), "--out", str(local),
                              "--species", "morus_alba", "--crs", "local"])
    doc = json.loads(local.read_text())
    assert doc["crs"]["properties"]["name"] == "local"
    assert doc["features"][0]["geometry"]["coordinates"][0] == pytest.approx(500015, abs=0.5)
    project = tmp_path / "study"
    r = CliRunner().invoke(main, ["new", str(project), "--trees", str(out)])
    assert r.exit_code == 0, r.output
    text = (project / "radtree.toml").read_text()
    assert 'trees = "data/trees.geojson"' in text
    # the site from the trees' longitude/latitude, not the Mendoza fallback
    assert re.search(r"^latitude = 36\.14\d* ", text, re.M), text[:2000]


def test_clip_writes_one_trees_points(tile: Path, tmp_path: Path) -> None:
    out = tmp_path / "tree.laz"
    r = CliRunner().invoke(main, ["lidar", "clip", str(tile), "--tree", "L001", "--out",
                                  str(out)])
    assert r.exit_code == 0, r.output
    pts = read_tile(out)
    seg = segment_tile(read_tile(tile))
    assert len(pts) == int(r.output.split()[2])
    assert np.sum(pts.classification != 2) == seg.trees[0].points
    # crown points within the highest crown's spheroid (x 15, y 22, radius 4), its ground
    # within the cells (0.5 m, diagonal 0.71 m) 2 m (CLIP_MARGIN_M) around the crown
    d = np.hypot(pts.xyz[:, 0] - 500015.0, pts.xyz[:, 1] - 4000022.0)
    assert d[pts.classification != 2].max() < 4.0
    assert 5.5 < d.max() < 4.0 + 2.0 + 0.71
    r = CliRunner().invoke(main, ["lidar", "clip", str(tile), "--tree", "L999", "--out",
                                  str(tmp_path / "x.laz")])
    assert r.exit_code == 2 and "no tree 'L999' in this tile (its trees: L001, L002, L003)" \
        in r.output
    assert not (tmp_path / "x.laz").exists()


def test_ground_filter_and_normalised_heights(tmp_path: Path) -> None:
    xyz, cls = nadir_scan(slope=0.1)
    bare = write_points(tmp_path / "bare.las", xyz, np.ones(len(xyz)))   # no classes
    with pytest.raises(ConfigError, match=r"0 ground points \(classification 2\).*--ground "
                                          r"filter.*--ground heights"):
        segment_tile(read_tile(bare))
    seg = segment_tile(read_tile(bare), SegmentConfig(ground="filter"))
    assert sorted(round(t.height_m) for t in seg.trees) == [8, 12, 15]
    flat, _ = nadir_scan(slope=0.0)
    norm = write_points(tmp_path / "norm.las", flat, np.ones(len(flat)))
    seg = segment_tile(read_tile(norm), SegmentConfig(ground="heights"))
    assert sorted(round(t.height_m, 1) for t in seg.trees) == [8.0, 12.0, 15.0]


def test_bad_tiles_exit_2_naming_file_and_fix(tmp_path: Path) -> None:
    runner = CliRunner()

    def run(path: Path) -> str:
        r = runner.invoke(main, ["lidar", "segment", str(path), "--out",
                                 str(tmp_path / "t.geojson"), "--species", "morus_alba"])
        assert r.exit_code == 2, r.output
        assert not (tmp_path / "t.geojson").exists()
        return " ".join(r.output.split())

    text = tmp_path / "trees.csv"
    text.write_text("x,y\n1,2\n")
    assert f"{text}: not a LAS/LAZ file (it starts with b'x,y\\n'" in run(text)
    xyz, cls = nadir_scan()
    lonlat = xyz * [1e-5, 1e-5, 1.0] + [13.4, 52.5, 0.0]   # x, y in degrees, z in metres
    deg = write_points(tmp_path / "deg.las", lonlat, cls, scale_m=1e-7)
    out = run(deg)
    assert f"{deg}: the tile has no CRS and its x, y span only" in out
    assert "look like longitude/latitude in degrees" in out
    geo = write_points(tmp_path / "geo.las", lonlat, cls, crs="EPSG:4326", scale_m=1e-7)
    assert "is geographic (x, y in degrees): reproject it" in run(geo)
    empty = write_points(tmp_path / "empty.las", np.zeros((0, 3)), np.zeros(0))
    assert f"{empty}: the tile holds no points" in run(empty)
    one = write_points(tmp_path / "one.las", np.array([[1.0, 2.0, 0.0]]), np.array([2]))
    assert f"{one}: the tile holds one point" in run(one)
    low = write_points(tmp_path / "low.las", xyz * [1, 1, 0], np.full(len(xyz), 2))
    assert f"{low}: no tree of at least 2 m found" in run(low)
    nocls = write_points(tmp_path / "nocls.las", xyz, np.ones(len(xyz)))
    assert "--ground filter" in run(nocls)


def test_lidar_help_teaches() -> None:
    r = CliRunner().invoke(main, ["lidar", "segment", "--help"])
    assert r.exit_code == 0
    for words in ("ws = BASE + SLOPE × height", "radtree new --trees", "classification 2",
                  "--crs"):
        assert words in " ".join(r.output.split())


@pytest.mark.skipif(REAL is None, reason="../shared/data/lidar not beside the repo")
def test_real_plot_detection_floor() -> None:
    """benchmarks/lidar.py prints the table: found 81.2 %, false 10.8 %, median height
    error 0.00 m at the defaults; the floor is the issue's targets."""
    from radtree.lidar.evaluate import detection

    d = detection(segment_tile(read_tile(REAL)))
    assert d.reference == 112
    assert d.found_fraction >= 0.80
    assert d.false_fraction <= 0.20
    assert d.median_height_error_m <= 1.0


def test_example_tile_eight_trees_no_roofs() -> None:
    """examples/lidar-street: the eight street trees, not the four roofs (class 6), at their
    trunks (make_tile.py: x 0…30 m, y ±6 m from the street origin) and heights."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "make_tile", ROOT / "examples/lidar-street/make_tile.py")
    assert spec is not None and spec.loader is not None
    make_tile = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make_tile)
    ORIGIN, trees = make_tile.ORIGIN, make_tile.trees

    seg = segment_tile(read_tile(ROOT / "examples/lidar-street/data/street_tile.laz"))
    assert len(seg.trees) == 8
    for t in trees():
        d = min(seg.trees, key=lambda s: math.hypot(s.x - ORIGIN[0] - t.x, s.y - ORIGIN[1] - t.y))
        assert math.hypot(d.x - ORIGIN[0] - t.x, d.y - ORIGIN[1] - t.y) < 0.5
        assert d.height_m == pytest.approx(t.height_m, abs=0.5)
