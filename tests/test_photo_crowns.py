"""Crowns from the photograph, checked against the photograph (issue 16): perforated
realisations and the direct-sun lottery, the louvers dome cut by the (real, stand-in) façade
photo, free crowns fitted to upward photos (round trip), bad photo input, provenance, the
check table and its report section."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from radtree.config import Scenario, load_project
from radtree.errors import ConfigError
from tests.conftest import MENDOZA, copy_project, needs_radiance

PHOTO = MENDOZA / "data" / "fisheye_chestnut_standin.jpg"
FAST = {"sensors.dense_grid": False, "sensors.dense_hours": [], "engine.rays": 64}


@pytest.fixture(scope="module")
def mendoza(tmp_path_factory):
    root = copy_project(tmp_path_factory.mktemp("photo") / "m", photo=True)
    return load_project(root, overrides={**FAST, "site.hours": ["10:30", "13:30"]})


# ---------------------------------------------------------------- item 6: realisations
def test_perforated_realisations_and_direct_sun(mendoza):
    from radtree.light.hours import hour_states
    from radtree.pipeline.assemble import make_scene
    from radtree.pipeline.realisations import realisations_of
    from radtree.pipeline.sunreach import direct_sun_rows, direct_sun_summary

    sc = replace(mendoza.scenario("C"), switches={"perforated.realisations": 2,
                                                  "perforated.seed": 5,
                                                  "perforated.resolution": 16})
    subs = realisations_of(mendoza, sc)
    assert [s.name for s in subs] == ["C@1", "C@2"]
    assert [s.switches["perforated.seed"] for s in subs] == [5, 6]
    # each crown an independent Monte Carlo sample too
    assert [s.switches["engine.seed"] for s in subs] == [mendoza.engine.seed,
                                                         mendoza.engine.seed + 1]
    rows = []
    for s in subs:
        built = make_scene(mendoza, s)
        rows.append(direct_sun_rows(s.name, built.scene, hour_states(mendoza, s)))
    t = pd.concat(rows)
    assert list(t.columns) == ["scenario", "realisation", "time", "sensor",
                               "sun_altitude_deg", "sun_transmission", "reaches"]
    assert set(t["sun_transmission"].unique()) <= {0.0, 1.0}      # opaque sheet: hole or not
    summary = direct_sun_summary(t)
    assert summary.loc[0, "realisations"] == 2 and summary.loc[0, "sensor_hours"] == 16
    # analytic ends: no holes → no sun; all holes → the sun reaches every sensor facing it
    for openness, expect in ((0.0, 0.0), (1.0, 1.0)):
        s = replace(sc, switches={"perforated.openness": openness, "perforated.resolution": 8})
        built = make_scene(mendoza, s)
        d = direct_sun_rows("C", built.scene, hour_states(mendoza, s))
        assert d["reaches"].mean() == expect


def test_photo_realisations_are_an_error(mendoza):
    from radtree.pipeline.realisations import realisations_of

    sc = Scenario(name="C-photo", model="perforated", switches={
        "tree.photo": str(PHOTO), "perforated.realisations": 2})
    with pytest.raises(ConfigError, match="one fixed pattern"):
        realisations_of(mendoza, sc)


# ---------------------------------------------------------------- items 1, 3, 4: the dome
def test_louvers_dome_from_the_facade_photo_matches_it(mendoza, tmp_path):
    """A-photo: the real photo, every shell cut on one shared grid → ring × segment RMS."""
    from radtree.photo.check import CHECK_COLUMNS, check_scenario, write_check
    from radtree.report.sections.photo import photo_check_data

    proj = load_project(mendoza.source, overrides=FAST)
    sc = proj.scenario("A-photo")   # three shells instead of five: quicker, still every layer
    sc = replace(sc, switches={**sc.switches, "louvers.layers": 3})
    out = check_scenario(proj, sc, 500)
    assert out.rms <= 0.02
    assert out.rendering.seconds["triangles"] > 20_000     # cut slat pieces
    assert abs(out.model.metrics.openness - out.photos[0].metrics.openness) < 0.003
    write_check(proj, [out])
    table = pd.read_csv(proj.results_dir / "photo_check.csv")
    assert list(table.columns) == CHECK_COLUMNS
    assert len(table) == 9 * 8 and set(table["scenario"]) == {"A-photo"}
    assert table["zenith_max_deg"].max() == 90.0
    data = photo_check_data(proj, tmp_path / "report")
    assert data["scenarios"][0]["rms"] == f"{out.rms:.4f}"
    assert {im["kind"] for im in data["scenarios"][0]["images"]} == {"photo", "model"}
    assert (tmp_path / "report" / "photo_check_A-photo_model.png").is_file()


def test_hemi_render_and_check_commands(mendoza):
    from click.testing import CliRunner

    from radtree.cli import main

    root = str(mendoza.root)
    r = CliRunner().invoke(main, ["hemi", "check", root, "-s", "C-photo", "--size", "300"])
    assert r.exit_code == 0, r.output
    assert "C-photo: gap-fraction RMS 0.0" in r.output and "photo_check.csv" in r.output
    rows = pd.read_csv(mendoza.results_dir / "photo_check.csv")
    assert set(rows["scenario"]) >= {"C-photo"} and len(rows[rows["scenario"] == "C-photo"]) == 72
    r = CliRunner().invoke(main, ["hemi", "render", root, "-s", "C-photo", "--size", "200"])
    assert r.exit_code == 0, r.output
    assert (mendoza.results_dir / "photo_render" / "C-photo.png").is_file()
    assert (mendoza.results_dir / "photo_render" / "C-photo" / "rings.csv").is_file()
    r = CliRunner().invoke(main, ["hemi", "check", root, "-s", "A"])
    assert r.exit_code == 2 and "has no photo" in r.output


@needs_radiance
@pytest.mark.radiance
def test_radiance_fisheye_picture(mendoza):
    from click.testing import CliRunner

    from radtree.cli import main

    r = CliRunner().invoke(main, ["hemi", "render", str(mendoza.root), "-s", "C-photo",
                                  "--size", "100", "--radiance", "13:30", "--radiance-size",
                                  "24", "--radiance-ab", "0"])
    assert r.exit_code == 0, r.output
    out = mendoza.results_dir / "photo_render"
    assert (out / "C-photo_1330.hdr").read_bytes().startswith(b"#?RADIANCE")
    assert (out / "C-photo_1330.bmp").read_bytes()[:2] == b"BM"


def test_section_only_with_the_check_file(mendoza, tmp_path):
    from radtree.report.sections import Section, render_section
    from radtree.report.sections.photo import photo_check_data

    empty = load_project(copy_project(tmp_path / "e"), overrides=FAST)
    assert photo_check_data(empty, tmp_path / "r") is None
    html = render_section(Section("photo_check", {"scenarios": [{
        "scenario": "A-photo", "rms": "0.0050", "ring_rms": "0.0010", "images": [],
        "rings": [{"zenith": "0–10°", "photo": "0.055", "model": "0.054"}],
        "metrics": [{"what": "model", "lai": "–", "openness": "0.0409"}]}]}))
    assert "Crown against its photo" in html and "stand-in" in html and "0.0409" in html


def test_provenance_in_the_manifest(mendoza):
    from radtree.pipeline.build import build_project

    proj = load_project(mendoza.source, overrides=FAST)
    facts = build_project(proj, ["C-photo"], pictures=False)
    mf = json.loads((proj.build_dir / "C-photo" / "manifest.json").read_text())
    photo = mf["build"]["photo"]
    assert photo == json.loads(json.dumps(facts["C-photo"]["photo"], default=str))
    from radtree.fileio import file_sha256

    assert photo["photos"][0]["sha256"] == file_sha256(PHOTO)
    assert photo["photos"][0]["mask_px"] == [1136.0, 852.0, 754.0]
    assert "FC-E8" in photo["photos"][0]["lens"] and photo["photos"][0]["direction"] == "facade"


# ---------------------------------------------------------------- item 2: the round trip
def test_round_trip_known_crown_render_fit(tmp_path):
    """A crown of known leaf area density, ellipsoidal leaf angles (x = 2, mean tilt 38.5°)
    and no clumping (random slats) → three synthetic upward photos (crowns of seeds 1–3) →
    one fit: density within 5 %, mean tilt within 3°, and the refit crown's façade
    illuminance (NumPy, same seeds) within 3 % of the original's
    (:func:`radtree.verify.photo.crown_round_trip`, also a row of ``radtree verify --full``)."""
    from radtree.verify.photo import crown_round_trip

    rt = crown_round_trip(copy_project(tmp_path / "rt"))
    print(rt)
    assert rt.lad_fit == pytest.approx(rt.lad, rel=0.05)
    assert abs(rt.tilt_fit - rt.tilt) <= 3.0
    assert rt.photos == 3 and rt.lad_sd > 0  # several photos → one fit + spread
    assert rt.facade_fit == pytest.approx(rt.facade, rel=0.03)


def test_fixed_inclination_option_keeps_30_degrees(mendoza):
    from radtree.trees.leaf_angles import draw_inclinations, mean_tilt

    assert mendoza.tree.louvers.inclination_distribution == "fixed"
    a = np.degrees(draw_inclinations(np.random.default_rng(0), 200_000, 1.0))
    assert a.mean() == pytest.approx(mean_tilt(1.0), abs=0.2)
    assert mean_tilt(1.0) == pytest.approx(57.3, abs=0.1)   # spherical: 1 rad


# ---------------------------------------------------------------- bad photo input
def _dome(mendoza, **sw):
    from radtree.pipeline.assemble import make_scene

    return make_scene(mendoza, Scenario(name="X", model="perforated", switches={
        "perforated.resolution": 8, **sw}))


def test_bad_photo_messages(mendoza, tmp_path):
    from radtree.hemi.synthetic import render_fisheye, save_png

    with pytest.raises(ConfigError, match=r"tree\.photo_direction.*a facade photo is needed"):
        _dome(mendoza, **{"tree.photo": str(PHOTO), "tree.photo_direction": "upward"})
    with pytest.raises(ConfigError, match=r"tree\.lens.*unknown lens 'fisheye9000'"):
        _dome(mendoza, **{"tree.photo": str(PHOTO), "tree.lens": "fisheye9000"})
    noise = tmp_path / "noise.png"
    save_png((np.random.default_rng(1).random((300, 400)) * 255).astype(np.uint8), noise)
    with pytest.raises(ConfigError, match="does not look like a circular fisheye photo"):
        _dome(mendoza, **{"tree.photo": str(noise)})
    circle = tmp_path / "circle.png"
    save_png(render_fisheye(lambda z, a: z < 40, 400), circle)
    with pytest.raises(ConfigError, match=r"tree\.mask.*does not match the image circle"):
        _dome(mendoza, **{"tree.photo": str(circle), "tree.mask": [150, 200, 120]})
    text = tmp_path / "photo.jpg"
    text.write_text("not an image")
    with pytest.raises(ConfigError, match=r"field 'tree\.photo'"):
        _dome(mendoza, **{"tree.photo": str(text)})
    with pytest.raises(ConfigError, match="an upward photo is needed"):
        from radtree.pipeline.assemble import make_scene

        make_scene(mendoza, Scenario(name="F", model="louvers", form="free", switches={
            "tree.photo": str(PHOTO), "louvers.arrangement": "volume"}))


def test_old_perforated_photo_field_still_works(mendoza):
    old = _dome(mendoza, **{"perforated.photo": str(PHOTO), "perforated.lens": "FC-E8",
                            "perforated.mask": [1136, 852, 754]})
    new = _dome(mendoza, **{"tree.photo": str(PHOTO), "tree.lens": "FC-E8",
                            "tree.mask": [1136, 852, 754]})
    assert old.info["hole_fraction"] == new.info["hole_fraction"] > 0.03
    assert old.tree.photo["field"] == "tree.perforated.photo"
    shutil.rmtree(mendoza.build_dir, ignore_errors=True)


def test_canopy_rectangles_cover_exactly_the_canopy_cells():
    from radtree.trees.photo_cut import _runs

    rng = np.random.default_rng(5)
    for share in (0.05, 0.5, 0.95):
        grid = rng.random((23, 17)) > share
        grid[4:9, 3:12] = True                  # a block the rows must merge into one
        r0, r1, a, b = _runs(grid)
        cover = np.zeros(grid.shape, int)
        for i0, i1, j0, j1 in zip(r0, r1, a, b):
            cover[i0:i1 + 1, j0:j1] += 1
        assert np.array_equal(cover, grid.astype(int))   # every canopy cell once, no sky cell
        rows = sum(len(np.flatnonzero(np.diff(np.r_[0, row.astype(int), 0]) == 1))
                   for row in grid)
        assert len(r0) < rows                      # fewer pieces than one per row run


def test_slats_clipped_to_boxes_as_geos_does():
    """The vectorised Sutherland–Hodgman cut of the photo dome against GEOS (shapely) on 4 000
    random convex quads and boxes (disjoint, overlapping, inside, containing): the same
    polygons (symmetric difference < 1e-12 of the area), empty where GEOS is empty, and the
    slat's winding kept."""
    import shapely

    from radtree.trees.photo_cut import _areas, _clip_to_boxes

    rng = np.random.default_rng(11)
    n = 4000
    centre = rng.uniform(-1, 1, (n, 1, 2))
    angle = np.sort(rng.uniform(0, 2 * np.pi, (n, 4)), axis=1)    # counter-clockwise corners
    radius = rng.uniform(0.05, 0.6, (n, 1))
    quads = centre + radius[:, :, None] * np.stack([np.cos(angle), np.sin(angle)], axis=2)
    lo = rng.uniform(-1.2, 1.0, (n, 2))
    boxes = np.column_stack([lo, lo + rng.uniform(0.01, 1.5, (n, 2))])
    xy, count = _clip_to_boxes(quads, boxes)
    geos = shapely.intersection(shapely.polygons(quads), shapely.box(*boxes.T))
    area = _areas(xy, count)
    np.testing.assert_allclose(area, shapely.area(geos), rtol=0, atol=1e-12)
    hit = count >= 3
    assert 0.1 * n < hit.sum() < 0.9 * n                    # both cases are exercised
    assert np.all(shapely.area(geos[~hit]) < 1e-12)
    ours = np.array([shapely.Polygon(xy[i, :count[i]]) for i in np.flatnonzero(hit)])
    sym = shapely.area(shapely.symmetric_difference(ours, geos[hit]))
    assert sym.max() < 1e-12 * max(1.0, area.max())
    assert np.all(shapely.is_ccw(shapely.get_exterior_ring(ours)))
