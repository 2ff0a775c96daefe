"""The office-block application: geometry, grids, user geometry, summary, and real Radiance."""

from __future__ import annotations

import math
import re
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from radtree.config import EngineParams, load_project
from radtree.errors import ConfigError
from radtree.light.sky import SkyState
from radtree.light.sun import SunPosition, local_datetime
from radtree.office_summary import (
    area_fractions,
    grid_statistics,
    office_section_data,
    summarise,
    write_summary,
)
from radtree.optics import Glass, Plastic
from radtree.report.sections import Section, render_section
from radtree.scene import Mesh, Scene, SensorGrid
from radtree.site.frame import FacadeFrame
from radtree.site.office import frame_width_for, office_layout, office_parts
from radtree.site.user_geometry import load_user_meshes, triangulate_polygon

from .conftest import ROOT, needs_radiance

OFFICE = ROOT / "examples" / "office-block"


@pytest.fixture(scope="module")
def project():
    return load_project(OFFICE)


def copy_office(dst: Path, replace_: dict[str, str] | None = None) -> Path:
    shutil.copytree(OFFICE, dst, ignore=shutil.ignore_patterns("build", "results", "report"))
    toml = dst / "radtree.toml"
    text = toml.read_text()
    for pat, rep in (replace_ or {}).items():
        text, n = re.subn(pat, rep, text, flags=re.M)
        assert n, pat
    toml.write_text(text)
    return dst


def with_office(project, **changes):
    return replace(project, office=replace(project.office, **changes))


def mesh_area(mesh: Mesh) -> float:
    return mesh.area()


# ---------------------------------------------------------------- geometry and grids
def test_grids_counts_normals_and_inside_the_central_office(project):
    frame = FacadeFrame(project.street.facade_azimuth_deg)
    meshes, materials, grids, notes = office_parts(project, frame)
    assert set(grids) == {"facade", "workplane"}
    lay = office_layout(project)
    room = lay.room(1, 1)
    o = project.office

    fg = grids["facade"]
    assert len(fg) == 6 * 5                                  # 3 m × 2.5 m at 0.5 m cells
    assert np.allclose(fg.normals, frame.normal)
    loc = frame.to_local(fg.points)
    assert np.allclose(loc[:, 1], 0.01)                     # 1 cm out of the façade
    assert np.all((loc[:, 0] > room.u0) & (loc[:, 0] < room.u1))
    assert np.all((loc[:, 2] > room.z0) & (loc[:, 2] < room.z1))
    assert loc[:, 2].mean() == pytest.approx(5.0, abs=0.01)  # centred near the measured 5 m
    assert len(set(fg.rows)) == 5 and fg.rows[0].startswith("z=")

    wg = grids["workplane"]
    assert len(wg) == 4 * 10                                 # (3 − 1) m × (6 − 1) m at 0.5 m
    assert np.allclose(wg.normals, [0, 0, 1])
    loc = frame.to_local(wg.points)
    assert np.allclose(loc[:, 2], room.z0 + 0.8)
    assert np.all(room.contains(loc))
    assert loc[:, 0].min() - room.u0 >= o.wall_offset_m - 1e-9
    assert room.u1 - loc[:, 0].max() >= o.wall_offset_m - 1e-9
    assert -loc[:, 1].max() >= o.wall_offset_m - 1e-9
    assert loc[:, 1].min() - room.n0 >= o.wall_offset_m - 1e-9
    # equal-area cells: evenly spaced, symmetric about the room's axis
    assert np.allclose(np.unique(np.round(loc[:, 0], 6)), [-0.75, -0.25, 0.25, 0.75])
    assert any("results read in 1 office(s)" in n and ": 1-1;" in n for n in notes)
    assert set(fg.labels["room"]) == {"1-1"} and set(wg.labels["storey"]) == {1}


def test_facade_with_openings_and_materials(project):
    frame = FacadeFrame(project.street.facade_azimuth_deg)
    meshes, materials, _, _ = office_parts(project, frame)
    names = [m.name for m in meshes]
    assert len(names) == len(set(names))
    assert "facade_paint" not in materials                   # the street's, reused by name
    by = {m.name: m for m in meshes}
    assert by["facade"].material == "facade_paint"
    lay = office_layout(project)
    o = project.office
    opening = o.width_m * (lay.head - lay.sill)
    n_off = o.bays * o.storeys
    st = project.street
    # façade paint + openings cover the whole façade
    assert by["facade"].area() + n_off * opening == pytest.approx(st.length_m
                                                                  * st.building_height_m)
    # frame covers frame_fraction of each opening, glazing the rest
    assert by["office_frames"].area() == pytest.approx(o.frame_fraction * n_off * opening)
    assert by["office_glazing"].area() == pytest.approx((1 - o.frame_fraction) * n_off * opening)
    g = materials["glazing"]
    assert isinstance(g, Glass) and g.transmittance == pytest.approx(o.glazing_transmittance,
                                                                     abs=1e-3)
    assert isinstance(materials["office_floor"], Plastic)
    assert materials["office_floor"].reflectance == 0.2
    assert materials["office_wall"].reflectance == 0.5
    assert materials["office_ceiling"].reflectance == 0.7
    # every surface lies at or behind the façade plane
    for m in meshes:
        assert frame.to_local(m.vertices)[:, 1].max() <= 1e-9
    assert frame_width_for(3.0, 2.5, 0.0, 2) == 0.0


@pytest.mark.parametrize("changes", [
    {},
    {"window_sill_m": 0.9, "window_head_m": 2.2, "storey_height_m": 3.0, "frame_fraction": 0.2},
    {"bays": 1, "storeys": 1, "frame_fraction": 0.0, "rooms": "all"},
    {"bays": 4, "storeys": 2, "rooms": "all"},
])
def test_rooms_are_closed(project, changes):
    """Rays from random points inside every office, in random directions, all stay inside."""
    import trimesh

    project = with_office(project, **changes)
    frame = FacadeFrame(project.street.facade_azimuth_deg)
    meshes, _, _, _ = office_parts(project, frame)
    verts, faces, off = [], [], 0
    for m in meshes:
        verts.append(m.vertices)
        faces.append(m.faces + off)
        off += len(m.vertices)
    tm = trimesh.Trimesh(np.vstack(verts), np.vstack(faces), process=False)
    lay = office_layout(project)
    rng = np.random.default_rng(3)
    n = 3000
    for j in range(project.office.bays):
        for k in range(project.office.storeys):
            r = lay.room(j, k)
            local = np.column_stack([rng.uniform(r.u0, r.u1, n), rng.uniform(r.n0, r.n1, n),
                                     rng.uniform(r.z0, r.z1, n)])
            d = rng.normal(size=(n, 3))
            d /= np.linalg.norm(d, axis=1)[:, None]
            locs, idx_ray, _ = tm.ray.intersects_location(frame.to_world(local), d,
                                                          multiple_hits=False)
            assert len(set(idx_ray.tolist())) == n, f"rays escape office ({j}, {k})"
            hit_local = frame.to_local(locs)
            tol = 1e-6
            assert np.all((hit_local[:, 0] >= r.u0 - tol) & (hit_local[:, 0] <= r.u1 + tol)
                          & (hit_local[:, 1] >= r.n0 - tol) & (hit_local[:, 1] <= r.n1 + tol)
                          & (hit_local[:, 2] >= r.z0 - tol) & (hit_local[:, 2] <= r.z1 + tol))


def test_slab_kept_between_storeys(project):
    lay = office_layout(project)
    assert lay.room(1, 0).z1 < lay.room(1, 1).z0            # ceiling below the next floor
    roomy = office_layout(with_office(project, storey_height_m=2.8, ground_floor_m=0.9))
    assert roomy.room_height == 2.5


@pytest.mark.parametrize("changes, field", [
    ({"window_head_m": 2.7}, "office.window_head_m"),
    ({"window_sill_m": 1.0, "window_head_m": 0.9}, "office.window_sill_m"),
    ({"storeys": 7}, "office.storeys"),
    ({"bays": 27}, "office.bays"),
    ({"wall_offset_m": 1.5}, "office.wall_offset_m"),
    ({"workplane_height_m": 2.6}, "office.workplane_height_m"),
])
def test_bad_office_is_a_config_error(project, changes, field):
    with pytest.raises(ConfigError, match=re.escape(field)):
        office_layout(with_office(project, **changes))


def test_make_scene_replaces_street_facade_and_grids(project):
    from radtree.pipeline.assemble import make_scene

    built = make_scene(project, project.scenario("without"))
    assert set(built.scene.grids) == {"facade", "workplane"}
    facades = [m for m in built.scene.meshes if m.name == "facade"]
    assert len(facades) == 1 and facades[0].n_triangles > 2
    assert built.triangles == sum(m.n_triangles for m in built.scene.meshes)


# ---------------------------------------------------------------- user geometry
def test_user_meshes_obj_stl_ply_and_rad(tmp_path):
    import trimesh

    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    paths = []
    for ext in ("obj", "stl", "ply"):
        p = tmp_path / f"box.{ext}"
        box.export(str(p))
        paths.append(p)
    rad = tmp_path / "ell.rad"
    rad.write_text("# an L-shaped (non-convex) wall and a triangle\n"
                   "whatever polygon ell\n0\n0\n18\n 0 0 0  2 0 0  2 0 1  1 0 1  1 0 2  0 0 2\n"
                   "\nwhatever polygon tri 0 0 9 0 0 0 1 0 0 0 1 0\n")
    extra = [(p, "facade_paint") for p in paths] + [(rad, "ground")]
    meshes = load_user_meshes(extra, {"facade_paint": 1, "ground": 1})
    assert [m.name for m in meshes] == ["user_box", "user_box_2", "user_box_3", "user_ell"]
    for m in meshes[:3]:
        assert m.material == "facade_paint"
        assert m.area() == pytest.approx(box.area)
    assert meshes[3].material == "ground"
    assert meshes[3].n_triangles == 4 + 1
    assert meshes[3].area() == pytest.approx(3.0 + 0.5)


def test_user_geometry_enters_the_scene(tmp_path, project):
    import trimesh

    from radtree.pipeline.assemble import make_scene

    path = tmp_path / "kiosk.stl"
    trimesh.creation.box(extents=(2.0, 2.0, 2.5)).apply_translation([5, 8, 1.25]).export(str(path))
    proj = replace(project, extra_geometry=((path, "opposite_facade"),))
    built = make_scene(proj, proj.scenario("without"))
    kiosk = built.scene.mesh("user_kiosk")
    assert kiosk.material == "opposite_facade" and kiosk.n_triangles == 12


def test_user_geometry_errors(tmp_path):
    bad = tmp_path / "ball.rad"
    bad.write_text("void plastic white 0 0 5 .5 .5 .5 0 0\nwhite sphere ball 0 0 4 0 0 0 1\n")
    with pytest.raises(ConfigError, match=r"'plastic' 'white' is not supported.*polygon"):
        load_user_meshes([(bad, "facade_paint")])
    short = tmp_path / "short.rad"
    short.write_text("m polygon p 0 0 9 0 0 0 1 0 0\n")
    with pytest.raises(ConfigError, match="ends inside"):
        load_user_meshes([(short, "m")])
    ok = tmp_path / "ok.rad"
    ok.write_text("m polygon p 0 0 9 0 0 0 1 0 0 0 1 0\n")
    with pytest.raises(ConfigError, match=r"'leaf'.*known: facade_paint, ground"):
        load_user_meshes([(ok, "leaf")], {"facade_paint": 1, "ground": 1})
    with pytest.raises(ConfigError, match="unsupported file type"):
        load_user_meshes([(tmp_path / "ok.rad", "m"), (_touch(tmp_path / "x.dxf"), "m")])


def _touch(p: Path) -> Path:
    p.write_text("")
    return p


def test_triangulate_square_and_concave():
    sq = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    assert len(triangulate_polygon(sq)) == 2
    arrow = np.array([[0, 0, 0], [2, 1, 0], [0, 2, 0], [1, 1, 0]], float)  # concave at (1,1)
    t = triangulate_polygon(arrow)
    area = sum(0.5 * abs(np.cross(arrow[b] - arrow[a], arrow[c] - arrow[a])[2]) for a, b, c in t)
    assert area == pytest.approx(1.0)


# ---------------------------------------------------------------- summary
def test_area_fractions_bounds_included():
    lux = np.array([0.0, 299.999, 300.0, 1000.0, 2000.0, 2000.001, 50000.0, 300.0])
    below, useful, above = area_fractions(lux)
    assert below == pytest.approx(100 * 2 / 8)
    assert useful == pytest.approx(100 * 4 / 8)             # 300, 1000, 2000, 300
    assert above == pytest.approx(100 * 2 / 8)
    assert below + useful + above == pytest.approx(100)
    assert area_fractions([300.0, 2000.0]) == (0.0, 100.0, 0.0)
    s = grid_statistics(np.array([100.0, 300.0, 500.0]))
    assert s["mean_lux"] == 300.0 and s["uniformity"] == pytest.approx(1 / 3)
    assert s["pct_below_300"] == pytest.approx(100 / 3)
    with pytest.raises(ValueError):
        area_fractions([])


def _fake_results(project) -> pd.DataFrame:
    frame = FacadeFrame(project.street.facade_azimuth_deg)
    _, _, grids, _ = office_parts(project, frame)
    rows = []
    for scen, model, factor in (("with", "louvers", 0.1), ("without", "none", 1.0)):
        for h, t in enumerate(("10:30", "13:30")):
            for g in grids.values():
                base = 3000.0 if g.name == "facade" else np.linspace(5000, 100, len(g))
                lux = np.broadcast_to(base, (len(g),)) * factor * (1 + h)
                rows.append(pd.DataFrame({
                    "scenario": scen, "model": model, "time": t, "grid": g.name,
                    "sensor": np.arange(len(g)), "row": g.rows, "x": g.points[:, 0],
                    "y": g.points[:, 1], "z": g.points[:, 2], "lux": lux}))
    return pd.concat(rows, ignore_index=True)


def test_summary_csv_maps_and_html(tmp_path, project):
    p = copy_office(tmp_path / "office")
    proj = load_project(p)
    table = _fake_results(proj)
    (proj.results_dir).mkdir(parents=True)
    table.to_csv(proj.results_dir / "illuminance.csv", index=False)
    out = write_summary(proj)
    s = pd.read_csv(out, dtype={"time": str})
    for col in ("time", "grid", "tree", "mean_lux", "min_lux", "max_lux", "uniformity",
                "pct_below_300", "pct_300_2000", "pct_above_2000", "scenario"):
        assert col in s.columns
    assert len(s) == 2 * 2 * 2
    assert set(s[s["scenario"] == "without"]["tree"]) == {"without"}
    assert set(s[s["scenario"] == "with"]["tree"]) == {"with"}
    f = s[(s.grid == "facade") & (s.time == "10:30")].set_index("scenario")
    assert f.loc["without", "mean_lux"] == pytest.approx(3000)
    assert f.loc["without", "pct_above_2000"] == 100 and f.loc["with", "pct_below_300"] == 0
    assert f.loc["with", "pct_300_2000"] == 100               # exactly 300 lx: useful
    pngs = sorted(x.name for x in (proj.report_dir / "office").glob("*.png"))
    assert pngs == sorted(["facade_1030.png", "facade_1330.png", "workplane_1030.png",
                           "workplane_1330.png", "facade_hourly.png", "workplane_hourly.png"])
    html = render_section(Section("office", office_section_data(proj)))
    assert html.count("<table") == 2 and "office/workplane_1330.png" in html
    assert "% 300–2000" in html and "day mean" in html
    assert summarise(table).shape[0] == 8


def test_summary_needs_results(tmp_path):
    from radtree.errors import RadtreeError

    proj = load_project(copy_office(tmp_path / "office"))
    with pytest.raises(RadtreeError, match="radtree simulate"):
        write_summary(proj)


# ---------------------------------------------------------------- real Radiance
def f_corner(a: float, b: float, c: float) -> float:
    """View factor from an upward-facing point to a vertical a × b rectangle at distance c
    whose corner is at the point's normal-foot (b: height above the point's plane)."""
    s = math.hypot(b, c)
    return (math.atan(a / c) - c / s * math.atan(a / s)) / (2 * math.pi)


def f_contour(point: np.ndarray, normal: np.ndarray, poly: np.ndarray) -> float:
    """Lambert's contour formula for a planar polygon (independent check)."""
    r = poly - point
    total = 0.0
    for i in range(len(r)):
        a, b = r[i], r[(i + 1) % len(r)]
        g = np.cross(a, b)
        ang = math.atan2(np.linalg.norm(g), float(np.dot(a, b)))
        total += ang * float(np.dot(normal, g)) / np.linalg.norm(g)
    return abs(total) / (2 * math.pi)


def test_view_factor_formulas_agree():
    for a, b, c in ((1.5, 1.7, 1.0), (3.0, 0.5, 4.0), (0.2, 2.0, 0.3)):
        poly = np.array([[0, c, 0], [a, c, 0], [a, c, b], [0, c, b]], float)
        assert f_corner(a, b, c) == pytest.approx(f_contour(np.zeros(3), np.array([0, 0, 1.0]),
                                                            poly), rel=1e-9)
    assert f_corner(1e9, 1e9, 1.0) == pytest.approx(0.25, rel=1e-6)


@needs_radiance
def test_unglazed_opening_under_uniform_sky_matches_view_factor(project):
    """Black room behind an open (unglazed) façade opening, uniform sky L, -ab 1, -aa 0:
    E = π·L·F(point → part of the opening above the work plane)."""
    from radtree.engines.radiance.engine import trace_hour

    proj = with_office(project, floor_reflectance=0.0, wall_reflectance=0.0,
                       ceiling_reflectance=0.0, frame_fraction=0.0)
    frame = FacadeFrame(proj.street.facade_azimuth_deg)
    meshes, materials, _, _ = office_parts(proj, frame)
    meshes = [m for m in meshes if m.name != "office_glazing"]
    materials = {**materials, "facade_paint": Plastic("facade_paint", 0.0)}
    lay = office_layout(proj)
    room = lay.room(1, 1)
    wp = room.z0 + proj.office.workplane_height_m
    depths = np.array([0.75, 1.5, 3.0, 5.0])
    offsets = np.array([0.0, 0.0, 0.0, 0.8])                   # along u from the centre
    local = np.column_stack([offsets, -depths, np.full(len(depths), wp)])
    grid = SensorGrid("wp", frame.to_world(local), np.tile([0, 0, 1.0], (len(depths), 1)))
    L = 5000.0
    st = SkyState("12:00", local_datetime("2024-12-22", "12:00", -3), SunPosition(60.0, 0.0),
                  0.0, sky_model="uniform", zenith_luminance=L, ground_glow=False)
    lux = trace_hour(Scene(meshes, materials, {"wp": grid}), st,
                     EngineParams(ab=1, aa=0.0, ad=16384, as_=0))["wp"].lux
    b = lay.head - proj.office.workplane_height_m              # opening above the work plane
    half = proj.office.width_m / 2
    for e, c, du in zip(lux, depths, offsets):
        F = f_corner(half - du, b, c) + f_corner(half + du, b, c)
        assert e == pytest.approx(math.pi * L * F, rel=0.03), (c, du)


# The crowns lower the façade's mean every hour: asserted on the office's Radiance golden run
# at the example's settings (tests/test_golden.py, office_radiance_full: its 0.5 m grids, all seven hours).
