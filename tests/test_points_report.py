"""A crown from points in the build manifest and the report (issue 41 item 2): the point file's
SHA-256, voxel size, leaf area and vertical profile recorded with numbers; the profile figure
and the crown beside its points drawn with data; the section rendered in HTML and Markdown."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from radtree.config import load_project
from radtree.fileio import file_sha256
from tests.conftest import ROOT, copy_project

TILE = ROOT / "examples" / "lidar-street" / "data" / "street_tile.laz"
SCENARIO = """
[[scenario]]
name = "P"
model = "louvers"
reflection = "traced"
form = "free"

[[scenario]]
name = "Q"
model = "louvers"
reflection = "traced"
form = "free"
switches = { "louvers.realisations" = 2 }
"""


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory):
    """The Mendoza project with one free crown from tree L001 of the example tile, scenario
    P built."""
    from radtree.lidar.clip import clip_tree
    from radtree.pipeline.build import build_project

    root = tmp_path_factory.mktemp("points")
    p = copy_project(root / "proj", replace={r'^form = "dome".*$': 'form = "free"\n'
                                             'points = "tree.laz"', r"^count = 3$": "count = 1"})
    clip_tree(TILE, "L001", p / "tree.laz")
    (p / "radtree.toml").write_text((p / "radtree.toml").read_text() + SCENARIO)
    project = load_project(p)
    build_project(project, ["P", "Q"], pictures=False)
    return project


def test_manifest_records_points_file_voxel_area_and_profile(built) -> None:
    from radtree.lidar.voxels import default_voxel_m

    mf = json.loads((built.build_dir / "P" / "manifest.json").read_text())
    rec = mf["build"]["points_crown"]
    assert rec["file"] == "tree.laz"
    assert rec["sha256"] == file_sha256(built.root / "tree.laz")
    assert mf["inputs"]["tree_points"] == f"tree.laz sha256:{rec['sha256']}"
    assert rec["voxel_m"] == pytest.approx(default_voxel_m(rec["point_spacing_m"]))
    assert 0.2 < rec["point_spacing_m"] < 0.5           # 10 pulses/m²
    prof = rec["profile"]
    n = len(prof["z_bottom_m"])
    assert n >= 4 and all(len(prof[k]) == n for k in prof)
    np.testing.assert_allclose(np.diff(prof["z_bottom_m"]), rec["voxel_m"], atol=1e-3)
    np.testing.assert_allclose(np.subtract(prof["z_top_m"], prof["z_bottom_m"]),
                               rec["voxel_m"], atol=1e-3)
    assert sum(prof["leaf_area_m2"]) == pytest.approx(rec["leaf_area_m2"])
    np.testing.assert_allclose(prof["leaf_area_m2_per_m"],
                               np.array(prof["leaf_area_m2"]) / rec["voxel_m"])
    assert 20.0 < rec["leaf_area_m2"] < 200.0             # a 10 m tree of Ø 6 m
    assert rec["leaf_area_m2"] == pytest.approx(mf["build"]["info"]["points_leaf_area_m2"])


def _shares(png: Path) -> tuple[float, float]:
    """Shares of green pixels (the slats, tab:green at any opacity) and of mid-grey ones (the
    scan: grey 0.35, neither black axes nor light grid lines)."""
    from PIL import Image

    with Image.open(png) as im:
        a = np.asarray(im.convert("RGB"), int)
    r, g, b = a[..., 0], a[..., 1], a[..., 2]
    green = (g > r + 25) & (g > b + 25)
    grey = (np.abs(r - g) < 8) & (np.abs(g - b) < 8) & (r >= 60) & (r <= 180)
    return float(green.mean()), float(grey.mean())


def test_report_section_profile_and_side_views(built, tmp_path: Path) -> None:
    """Both figures written with data: grey scan and green slats in each; the built slats'
    leaf area per layer sums to the scan's within 5 % (slats cut at the wall-side plane and
    dropped at the trunk); the section renders in HTML and Markdown."""
    from radtree.report.points_figures import slat_profile
    from radtree.report.sections import Section, render_section
    from radtree.report.sections.points import crown_views, points_crown_data

    data = points_crown_data(built, tmp_path, pd.DataFrame({"scenario": ["P"]}))
    assert data is not None and data["scenario"] == "P" and not data["problem"]
    files = [tmp_path / f["file"] for f in data["figures"]]
    assert [f.name for f in files] == ["points_profile.png", "points_crown.png"]
    for f, least in zip(files, (0.002, 0.02)):
        green, grey = _shares(f)
        assert green > least and grey > 0.002, (f.name, green, grey)
    views = crown_views(built, built.scenario("P"))
    assert len(views.points) > 150 and len(views.slats) > 500
    assert np.abs(views.points[:, :2]).max() < 5.0 and views.points[:, 2].min() >= 0.5
    mf = json.loads((built.build_dir / "P" / "manifest.json").read_text())
    rec = mf["build"]["points_crown"]
    area = slat_profile(views.slats, layer_m=rec["voxel_m"], layers=len(rec["profile"]
                                                                        ["z_bottom_m"]))
    assert area.sum() == pytest.approx(rec["leaf_area_m2"], rel=0.05)
    assert data["rows"] and float(data["rows"][0]["area"]) > 0
    html = render_section(Section("points_crown", data))
    md = render_section(Section("points_crown", data), html=False)
    for text in (html, md):
        assert "Crown from points" in text and rec["sha256"] in text
        assert "figures/points_profile.png" in text and "figures/points_crown.png" in text


def test_no_points_no_record() -> None:
    from radtree.trees.points_crown import points_record

    assert points_record(None, {"points_leaf_area_m2": 1.0}) is None
    assert points_record("tree.laz", {"slat_count": 3.0}) is None


def test_section_finds_the_first_crown_realisation(built) -> None:
    """A points crown traced as several random crowns (Q@1, Q@2) is shown by Q@1's build."""
    from radtree.report.sections.points import points_scenario

    sc, record = points_scenario(built, ["Q"])
    assert sc.name == "Q@1" and record["file"] == "tree.laz"
    assert (built.build_dir / "Q@2" / "manifest.json").is_file()
