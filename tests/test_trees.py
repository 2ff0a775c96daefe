"""Crown models: building in both forms, envelopes, bounds, switches and errors."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from radtree.config import Scenario
from radtree.errors import ConfigError, RadtreeError
from radtree.scene import Scene
from radtree.sensor_grid import facade_circle, facade_dense_grid
from radtree.site.frame import FacadeFrame
from radtree.site.street import street_materials, street_meshes
from radtree.trees.build import TreeModel, apply_switches, build_crown, build_tree
from radtree.trees.envelope import CLIP_MARGIN_M, crown_row_spec
from radtree.trees.louvers_dome import dome_layer_radii, dome_slat_bound
from radtree.trees.louvers_free import free_slat_bound
from radtree.trees.picture import render_model_png

MODELS = ("homogeneous", "perforated", "louvers")
FORMS = ("dome", "free")
STREET_NAMES = {"facade_paint", "ground", "opposite_facade"}


@pytest.fixture(scope="module")
def built(project, frame):
    return {(form, model): build_crown(project, model, form, frame)
            for form in FORMS for model in MODELS}


def local(frame: FacadeFrame, model: TreeModel) -> np.ndarray:
    return np.vstack([frame.to_local(m.vertices) for m in model.meshes])


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("model", MODELS)
def test_build_tree_contract(project, frame, form, model):
    sc = Scenario(name="x", model=model, form=form)
    tm = build_tree(project, sc, frame)
    assert isinstance(tm, TreeModel)
    assert tm.meshes and tm.triangles == sum(m.n_triangles for m in tm.meshes) > 0
    assert not STREET_NAMES & set(tm.materials)
    assert tm.notes and tm.build_seconds >= 0
    assert tm.recommended_ab >= 3
    # the crown goes into a scene with the street without clashes
    mats = {**street_materials(project.street), **tm.materials}
    scene = Scene(street_meshes(project.street, frame) + tm.meshes, mats,
                  {"facade": facade_circle(project.sensors, frame)})
    assert scene.n_triangles > tm.triangles
    assert all(np.isfinite(m.vertices).all() for m in tm.meshes)


def test_none_model_is_empty(project, frame):
    tm = build_tree(project, Scenario(name="open", model="none"), frame)
    assert tm.meshes == [] and tm.materials == {} and tm.triangles == 0


def test_notes_say_what_was_built(built):
    assert any("T = 0.0550" in n for n in built["dome", "homogeneous"].notes)
    assert any("√permeability" in n for n in built["free", "homogeneous"].notes)
    assert built["free", "homogeneous"].info["transmittance"] == pytest.approx(0.055**0.5)
    louv = " ".join(built["dome", "louvers"].notes)
    n = built["dome", "louvers"].info["layers"]
    assert "study reading" in louv and f"-ab ≥ {int(n) + 2}" in louv
    assert built["dome", "louvers"].recommended_ab == int(n) + 2
    assert "random gap pattern" in " ".join(built["dome", "perforated"].notes)


def test_dome_clears_ground_and_encloses_sensors(project, frame, built):
    for model in MODELS:
        pts = local(frame, built["dome", model])
        assert pts[:, 2].min() > 0.5
        assert pts[:, 1].min() >= -1e-9  # never behind the façade
        r = np.linalg.norm(pts - [project.sensors.x_m, 0.0, project.sensors.height_m], axis=1)
        assert r.max() <= project.tree.dome.radius_m + 1e-6
        # nothing of the crown within the sensor circle's neighbourhood
        assert r.min() > project.sensors.radius_m + 0.1


def test_dome_radius_must_clear_ground(project, frame):
    sc = Scenario(name="x", model="homogeneous", form="dome",
                  switches={"dome.radius_m": 5.0})
    with pytest.raises(ConfigError, match=r"tree\.dome\.radius_m"):
        build_tree(project, sc, frame)
    sc = Scenario(name="x", model="louvers", form="dome", switches={"dome.radius_m": 0.2})
    with pytest.raises(ConfigError, match=r"tree\.dome\.radius_m"):
        build_tree(project, sc, frame)


@pytest.mark.parametrize("clearance", [0.0, 0.2])
def test_free_crown_never_intersects_facade_nor_contains_sensors(project, frame, clearance):
    tree = replace(project.tree, crown=replace(project.tree.crown, clearance_m=clearance))
    n_clip = max(clearance, project.sensors.offset_m + CLIP_MARGIN_M)
    spec = crown_row_spec(tree, project.sensors, project.street)
    assert spec.n_clip == pytest.approx(n_clip)
    grids = [facade_circle(project.sensors, frame), facade_dense_grid(project.sensors, frame)]
    for g in grids:
        assert not spec.inside(frame.to_local(g.points)).any()
    for model in MODELS:
        tm = build_crown(project, model, "free", frame, tree)
        pts = local(frame, tm)
        assert pts[:, 1].min() >= n_clip - 1e-9, model
        assert pts[:, 2].min() >= -1e-9
    # with clearance 0 the crown reaches the wall: some vertices on the clip plane
    if clearance == 0.0:
        tm = build_crown(project, "homogeneous", "free", frame, tree)
        assert np.isclose(local(frame, tm)[:, 1], n_clip).any()


def test_triangle_counts_bounded(project, built):
    lv = project.tree.louvers
    from radtree.trees.envelope import dome_spec

    dome = dome_spec(project.tree, project.sensors, project.street)
    radii = dome_layer_radii(dome, lv, project.sensors)
    d = built["dome", "louvers"]
    assert d.info["slat_count"] <= dome_slat_bound(radii, lv)
    assert d.triangles == 2 * d.info["slat_count"]
    assert 2000 <= d.info["slat_count"] <= 4000  # "a few thousand slats" at 0.3 m, R = 4 m
    spec = crown_row_spec(project.tree, project.sensors, project.street)
    f = built["free", "louvers"]
    leaves = f.meshes[0].n_triangles
    assert f.info["slat_count"] <= free_slat_bound(spec, lv)
    assert leaves <= 3 * free_slat_bound(spec, lv)
    res = project.tree.perforated.resolution
    assert built["dome", "perforated"].triangles <= 5.2 * res**2
    assert built["dome", "homogeneous"].triangles <= 5.2 * (project.tree.dome.segments // 4) ** 2
    for m in built.values():
        assert m.triangles <= 60_000


def test_slat_geometry(built, frame):
    d = built["dome", "louvers"].info
    assert 0.15 <= d["slat_side_min_m"] and d["slat_side_max_m"] <= 0.5
    assert d["slat_mean_area_m2"] == pytest.approx(0.09, rel=0.15)
    leaves = built["free", "louvers"].meshes[0]
    tri = frame.to_local(leaves.vertices)[leaves.faces]
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    tilt = np.degrees(np.arccos(np.abs(nrm[:, 2])))
    assert np.allclose(tilt, 30.0, atol=1e-6)  # free slats inclined exactly 30°


def test_deterministic(project, frame):
    a = build_crown(project, "louvers", "free", frame)
    b = build_crown(project, "louvers", "free", frame)
    assert np.array_equal(a.meshes[0].vertices, b.meshes[0].vertices)
    tree, _ = apply_switches(project.tree, {"louvers.seed": 7})
    c = build_crown(project, "louvers", "free", frame, tree)
    assert not np.array_equal(a.meshes[0].vertices[:100], c.meshes[0].vertices[:100])


def test_switches(project, frame):
    tree, changed = apply_switches(project.tree, {
        "louvers.layers": 5, "tree.louvers.specular_fraction": 0, "homogeneous.transmittance": 0.2,
        "sky": "perez", "ground.black": True})  # non-tree switches are left to others
    assert tree.louvers.layers == 5 and tree.louvers.specular_fraction == 0.0
    assert tree.homogeneous.transmittance == 0.2 and len(changed) == 3
    tree, _ = apply_switches(project.tree, {"louvers.reading": "gap"})
    assert tree.louvers.cover_fraction == 0.5 and tree.louvers.transmittance == 0.05
    tm = build_tree(project, Scenario(name="g", model="louvers",
                                      switches={"louvers.reading": "gap"}), frame)
    assert "gap reading" in " ".join(tm.notes) and "switches" in tm.notes[0]
    assert tm.info["tau_crown_direct"] == pytest.approx(0.5 ** project.tree.louvers.layers)
    tm = build_tree(project, Scenario(name="h", model="homogeneous", form="dome",
                                      switches={"homogeneous.transmittance": 0.2}), frame)
    assert tm.materials["crown_shell"].transmittance == pytest.approx(0.2)


@pytest.mark.parametrize("switches, field", [
    ({"louvers.transmittance": 0.95}, "tree.louvers.transmittance"),
    ({"louvers.layers": 0}, "tree.louvers.layers"),
    ({"louvers.layers": 9}, "tree.louvers.layers"),
    ({"louvers.cover_fraction": 1.5}, "tree.louvers.cover_fraction"),
    ({"louvers.slat_size_m": 0.01}, "tree.louvers.slat_size_m"),
    ({"louvers.colour": 1}, "switches.louvers.colour"),
    ({"louvers.layers": "four"}, "switches.louvers.layers"),
    ({"louvers.reading": "poetic"}, "switches.louvers.reading"),
    ({"homogeneous.transmittance": 0.95}, "tree.homogeneous.transmittance"),
    ({"perforated.resolution": 2}, "tree.perforated.resolution"),
])
def test_invalid_parameters_dome(project, frame, switches, field):
    model = next(iter(switches)).split(".")[0]
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        build_tree(project, Scenario(name="x", model=model, form="dome", switches=switches),
                   frame)


@pytest.mark.parametrize("switches, field", [
    ({"crown.trunk_distance_m": 0.1}, "tree.crown.trunk_distance_m"),
    ({"crown.radius_m": 25.0}, "tree.crown.radius_m"),
    ({"crown.spacing_m": 0.3}, "tree.crown.spacing_m"),
    ({"crown.count": 30}, "tree.crown.count"),
])
def test_invalid_parameters_free(project, frame, switches, field):
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        build_tree(project, Scenario(name="x", model="homogeneous", form="free",
                                     switches=switches), frame)


def test_bad_photo_is_an_error_not_a_fallback(project, frame, tmp_path):
    bad = tmp_path / "not_a_photo.jpg"
    bad.write_text("nope")
    sc = Scenario(name="x", model="perforated", form="dome",
                  switches={"perforated.photo": str(bad)})
    with pytest.raises(RadtreeError):
        build_tree(project, sc, frame)


def test_picture(project, frame, built, tmp_path):
    out = render_model_png(built["free", "louvers"], None, tmp_path / "model.png", frame,
                           extra_meshes=street_meshes(project.street, frame),
                           sensor_points=facade_circle(project.sensors, frame).points)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(tmp_path.glob(".*tmp"))
    # the way `radtree build` calls it: (model, scene, path)
    tm = built["dome", "perforated"]
    mats = {**street_materials(project.street), **tm.materials}
    scene = Scene(street_meshes(project.street, frame) + tm.meshes, mats,
                  {"facade": facade_circle(project.sensors, frame)})
    out = render_model_png(tm, scene, tmp_path / "scene.png")
    assert out.stat().st_size > 10_000


def test_clip_polygons_cuts_each_polygon_at_its_plane():
    """Sutherland–Hodgman on many polygons at once: a unit square cut at x ≥ 0.25 keeps
    0.75 × 1 with its corners in order; a triangle wholly kept is unchanged; polygons wholly
    on the other side count 0."""
    from radtree.trees.geometry import clip_polygons

    sq = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    tri = np.array([[2, 0, 0], [3, 0, 0], [2, 1, 0], [0, 0, 0]], float)   # 3 corners used
    gone = sq - [5, 0, 0]
    corner = np.array([[-1, 0, 0], [0, 0, 0], [-1, 1, 0], [-2, 1, 0]], float)
    polys = np.stack([sq, tri, gone, corner])
    out, count = clip_polygons(polys, np.array([4, 3, 4, 4]), np.array([1.0, 0, 0]), 0.25)
    assert count.tolist() == [4, 3, 0, 0]
    np.testing.assert_allclose(out[0, :4], [[0.25, 0, 0], [1, 0, 0], [1, 1, 0], [0.25, 1, 0]])
    np.testing.assert_array_equal(out[1, :3], tri[:3])
    # a second cut (y ≤ 0.5) of the result: the shoelace area is 0.75 × 0.5
    out, count = clip_polygons(out, count, np.array([0, -1.0, 0]), -0.5)
    xy = out[0, :count[0], :2]
    area = 0.5 * abs(np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1]))
    assert count[0] == 4 and area == pytest.approx(0.375)
