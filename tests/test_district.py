"""Tree inventories, building footprints and every façade ([site] trees / buildings)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from radtree.config import load_project
from radtree.errors import ConfigError
from tests.conftest import MENDOZA, needs_radiance

DNI = (MENDOZA / "data" / "direct_normal_illuminance.csv").read_text()
LAT, LON = -32.8895, -68.8458

SITE = f"""[site]
name = "test district"
latitude = {LAT}
longitude = {LON}
utc_offset_hours = -3
date = "2024-12-22"
hours = ["12:30"]
"""
REST = """
[light]
direct_normal = "dni.csv"
sky = "none"

[tree]
form = "free"

[tree.louvers]
arrangement = "volume"

[engine]
ab = 1
ad = 64
rays = 48
seed = 3
max_bounces = 1

[[scenario]]
name = "T"
model = "louvers"
reflection = "traced"
"""


def fc(features: list[dict], crs: str | None = None) -> str:
    d: dict = {"type": "FeatureCollection", "features": features}
    if crs:
        d["crs"] = {"type": "name", "properties": {"name": crs}}
    return json.dumps(d)


def point(fid: str, x: float, y: float, **props) -> dict:
    base = {"id": fid, "species": "morus_alba", "height_m": 8.0, "crown_diameter_m": 5.0,
            "crown_base_m": 3.0}
    base.update(props)
    return {"type": "Feature", "properties": {k: v for k, v in base.items() if v is not None},
            "geometry": {"type": "Point", "coordinates": [x, y]}}


def box(fid: str, x0: float, y0: float, x1: float, y1: float, **props) -> dict:
    base = {"id": fid, "height_m": 9.0, "storeys": 3}
    base.update(props)
    ring = [[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]]
    return {"type": "Feature", "properties": {k: v for k, v in base.items() if v is not None},
            "geometry": {"type": "Polygon", "coordinates": [ring]}}


BUILDINGS = [box("N1", -15, 10, 0, 22), box("N2", 0, 10, 15, 22, height_m=6.0, storeys=2),
             box("S1", -15, -22, 15, -10, facade_reflectance=0.6)]
TREES = [point("T1", -8, 5), point("T2", 0, 5), point("T3", 8, -4, species="melia_azedarach",
                                                       crown_diameter_m=4.0)]


def district(tmp: Path, trees: list[dict] = TREES, buildings: list[dict] | None = BUILDINGS,
             crs: str | None = "local", extra: str = "") -> Path:
    tmp.mkdir(parents=True, exist_ok=True)
    (tmp / "dni.csv").write_text(DNI)
    (tmp / "trees.geojson").write_text(fc(trees, crs))
    site = SITE + 'trees = "trees.geojson"\n' + extra
    if buildings is not None:
        (tmp / "buildings.geojson").write_text(fc(buildings, crs))
        site += 'buildings = "buildings.geojson"\nfacade_spacing_m = 5.0\n'
    (tmp / "radtree.toml").write_text(site + REST)
    return tmp


# ---------------------------------------------------------------- bad inventories
def _fails(tmp: Path, **kw) -> str:
    from radtree.pipeline.build import build_project

    p = load_project(district(tmp, **kw))
    with pytest.raises(ConfigError) as exc:
        build_project(p, pictures=False)
    assert not (tmp / "build" / "T").exists()       # nothing half-written
    return str(exc.value)


def test_unknown_species_names_feature_and_known_list(tmp_path):
    msg = _fails(tmp_path, trees=[*TREES, point("T9", 5, 4, species="Quercus imaginaria")])
    assert "feature 'T9'" in msg and "Quercus imaginaria" in msg
    assert "morus_alba" in msg and "melia_azedarach" in msg


def test_tree_inside_building(tmp_path):
    msg = _fails(tmp_path, trees=[*TREES, point("T7", 5, 15)])
    assert "feature 'T7'" in msg and "inside building 'N2'" in msg


def test_crown_through_wall(tmp_path):
    """Under ``[tree] wall_policy = "refuse"`` (the default clips: tests/test_floors.py)."""
    from radtree.pipeline.build import build_project

    p = district(tmp_path, trees=[point("T4", -8, 8.0, crown_diameter_m=6.0)])
    toml = p / "radtree.toml"
    toml.write_text(toml.read_text().replace('form = "free"', 'form = "free"\n'
                                             'wall_policy = "refuse"'))
    with pytest.raises(ConfigError) as exc:
        build_project(load_project(p), pictures=False)
    assert not (tmp_path / "build" / "T").exists()       # nothing half-written
    msg = str(exc.value)
    assert "feature 'T4'" in msg and "reaches a wall of building 'N1'" in msg
    assert "move the trunk 1.02 m further from the wall, or reduce the crown radius" in msg


def test_missing_height(tmp_path):
    msg = _fails(tmp_path, trees=[point("T5", 0, 4, height_m=None)])
    assert "feature 'T5'" in msg and "missing height_m" in msg


def test_self_intersecting_footprint(tmp_path):
    bow = {"type": "Feature", "properties": {"id": "X1", "height_m": 6.0},
           "geometry": {"type": "Polygon", "coordinates": [
               [[20, 10], [30, 20], [30, 10], [20, 20], [20, 10]]]}}
    msg = _fails(tmp_path, buildings=[*BUILDINGS, bow])
    assert "feature 'X1'" in msg and "Self-intersection" in msg


def test_unknown_crs(tmp_path):
    msg = _fails(tmp_path, crs="EPSG:999999")
    assert "unknown CRS 'EPSG:999999'" in msg and "buildings.geojson" in msg


# ---------------------------------------------------------------- inputs
def test_lonlat_to_local_frame_and_back():
    from radtree.site.inventory import LocalFrame

    f = LocalFrame("EPSG:4326", LAT, LON)
    # 1' of latitude ≈ 1848.4 m at −32.9° (WGS 84 meridian arc), due north of the origin
    x, y = f.to_local(np.array([LON, LON]), np.array([LAT, LAT + 1 / 60]))
    assert abs(x[0]) < 1e-6 and abs(y[0]) < 1e-6
    assert abs(x[1]) < 1e-6 and y[1] == pytest.approx(1848.4, abs=1.0)
    lon, lat = f.to_source(x, y)
    assert lat[1] == pytest.approx(LAT + 1 / 60, abs=1e-10) and lon[0] == pytest.approx(LON)


def test_street_facades_leave_shared_walls_out(tmp_path):
    from radtree.site.district import load_district

    d = load_district(load_project(district(tmp_path)))
    ids = {f.id for f in d.facades}
    # N1 and N2 share the wall at x = 0: N1's east face (1) and N2's west face (3) are left out
    assert len(d.facades) == 10 and "N1:1" not in ids and "N2:3" not in ids
    south_of_n1 = next(f for f in d.facades if f.id == "N1:0")
    assert south_of_n1.azimuth_deg == pytest.approx(180.0) and south_of_n1.length_m == 15.0


# ---------------------------------------------------------------- one tree = hand-written
STREET = """
[street]
width_m = 20.0
length_m = 40.0
facade_reflectance = 0.9
ground_reflectance = 0.15

[sensors]
dense_grid = false
"""
CROWN = """
[tree.crown]
count = 1
trunk_distance_m = 3.5
radius_m = 2.5
vertical_radius_m = 2.5
base_height_m = 3.0
"""


def test_one_tree_inventory_reproduces_hand_written_free_crown(tmp_path):
    """The inventory row (x 0, y 3.5, height 8, crown Ø 5, base 3) of Morus alba in the canyon
    gives the façade illuminance of the hand-written row of one free crown with the species'
    leaf optics written out — exactly, on the NumPy engine (same seeds)."""
    from radtree.pipeline.trace import trace_scenario

    p_inv, p_hand = _one_tree_projects(tmp_path)
    a = trace_scenario(p_hand, p_hand.scenario("T"), engine="numpy")
    b = trace_scenario(p_inv, p_inv.scenario("T"), engine="numpy")
    assert len(a) == 8 and a["lux"].min() > 0
    np.testing.assert_array_equal(a["lux"].to_numpy(), b["lux"].to_numpy())


def _one_tree_projects(tmp_path):
    """The one-tree inventory (Morus alba at x 0, y 3.5 in the canyon) and the hand-written
    project of one free crown with the species' leaf optics written out."""
    from radtree.trees.district import species_louvers
    from radtree.trees.species import load_species

    inv = district(tmp_path / "inv", trees=[point("T1", 0.0, 3.5)], buildings=None,
                   extra=STREET)
    p_inv = load_project(inv)
    lv = species_louvers(p_inv.tree, load_species("morus_alba"))
    hand = tmp_path / "hand"
    hand.mkdir()
    (hand / "dni.csv").write_text(DNI)
    louvers = "\n".join(f"{k} = {getattr(lv, k)!r}" for k in (
        "reflectance", "transmittance", "specular_fraction", "inclination_deg",
        "cover_fraction"))
    (hand / "radtree.toml").write_text(SITE + STREET + CROWN + REST.replace(
        'arrangement = "volume"', 'arrangement = "volume"\n' + louvers))
    return p_inv, load_project(hand)


def _tree_meshes(p):
    from radtree.pipeline.assemble import make_scene

    scene = make_scene(p, p.scenario("T")).scene
    return {m.material: m for m in scene.meshes if m.material.startswith("leaf")}


@needs_radiance
def test_one_tree_inventory_radiance_text_and_lux_match(tmp_path):
    """The same on Radiance: the in-place crown is written polygon for polygon (only names
    differ) and rtrace gives the same façade lux."""
    from radtree.pipeline.trace import trace_scenario

    p_inv, p_hand = _one_tree_projects(tmp_path)
    a_mesh = _tree_meshes(p_hand)["leaf"]
    b_mesh = _tree_meshes(p_inv)["leaf_morus_alba"]
    assert a_mesh.n_triangles > 1000
    np.testing.assert_array_equal(a_mesh.vertices, b_mesh.vertices)
    a = trace_scenario(p_hand, p_hand.scenario("T"), engine="radiance")
    b = trace_scenario(p_inv, p_inv.scenario("T"), engine="radiance")
    np.testing.assert_array_equal(a["lux"].to_numpy(), b["lux"].to_numpy())


# ---------------------------------------------------------------- instancing
def test_instance_transform_matches_radiance_order():
    from radtree.scene import Instance

    inst = Instance("p", (10.0, 20.0, 3.0), rotate_z_deg=90.0, scale=2.0)
    np.testing.assert_allclose(inst.apply(np.array([[1.0, 0.0, 0.5]])), [[10.0, 22.0, 4.0]],
                               atol=1e-12)


def test_radiance_instance_text():
    from radtree.engines.radiance.writer import instances_text
    from radtree.optics import Plastic
    from radtree.scene import Instance, Mesh, Scene, SensorGrid

    tri = Mesh("leaf", "m", np.eye(3), np.array([[0, 1, 2]]))
    grid = SensorGrid("g", np.zeros((1, 3)), np.array([[0, 1, 0]]))
    scene = Scene([], {"m": Plastic("m", 0.5)}, {"g": grid}, prototypes={"crown_a": [tri]},
                  instances=[Instance("crown_a", (1.5, -2.0, 4.25), 30.0, 0.8)])
    assert instances_text(scene).splitlines()[2:] == [
        "void instance crown_a.0",
        "9 octrees/prototype_crown_a.oct -rz 30.0000 -s 0.800000 -t 1.50000 -2.00000 4.25000",
        "0", "0"]
    assert scene.n_triangles == 1 and scene.instanced_triangles() == 1
    np.testing.assert_array_equal(scene.solid_meshes()[0].vertices,
                                  np.eye(3) @ np.array([[0.8660254037844387, 0.5, 0],
                                                        [-0.5, 0.8660254037844387, 0],
                                                        [0, 0, 1]]) * 0.8 + [1.5, -2.0, 4.25])


def test_stored_crowns_do_not_grow_with_tree_count(tmp_path):
    """4 vs 16 mulberries along the street: one prototype crown either way; only trunks and
    instance lines grow."""
    from radtree.pipeline.assemble import make_scene

    def scene(n: int, folder: Path):
        rows = [point(f"T{i}", -12 + 24 * i / (n - 1), 4.0 + 0.5 * (i % 2)) for i in range(n)]
        p = load_project(district(folder, trees=rows))
        return make_scene(p, p.scenario("T")).scene

    s4, s16 = scene(4, tmp_path / "a"), scene(16, tmp_path / "b")
    assert len(s4.prototypes) == len(s16.prototypes) == 1
    leaves = {k: sum(m.n_triangles for m in v) for k, v in s16.prototypes.items()}
    trunk = s4.mesh("tree_trunks").n_triangles // 4
    assert s16.n_triangles - s4.n_triangles == 12 * trunk
    assert s16.instanced_triangles() == 16 * sum(leaves.values()) == 4 * s4.instanced_triangles()
    assert len(s16.instances) == 16


# ---------------------------------------------------------------- every façade
UTM = "EPSG:32719"   # UTM zone 19 S: Mendoza at about E 513 000, N 6 361 000
E0, N0 = 513000.0, 6361000.0


def _utm(features: list[dict]) -> list[dict]:
    out = json.loads(json.dumps(features))
    for f in out:
        g = f["geometry"]
        if g["type"] == "Point":
            g["coordinates"] = [g["coordinates"][0] + E0, g["coordinates"][1] + N0]
        else:
            g["coordinates"] = [[[x + E0, y + N0] for x, y in ring] for ring in g["coordinates"]]
    return out


def test_facades_geojson_and_dask_resume(tmp_path):
    """A UTM-projected district on the NumPy engine, on Dask (one local worker): one feature
    per façade with its coordinates back in UTM, the results labelled building/facade/storey,
    the same numbers as the in-process run, and a rerun reuses every part."""
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project

    root = tmp_path / "d"
    root.mkdir()
    (root / "dni.csv").write_text(DNI)
    (root / "trees.geojson").write_text(fc(_utm(TREES), UTM))
    (root / "buildings.geojson").write_text(fc(_utm(BUILDINGS), UTM))
    (root / "radtree.toml").write_text(
        SITE + 'trees = "trees.geojson"\nbuildings = "buildings.geojson"\n'
        'facade_spacing_m = 15.0\nfacade_chunk = 4\n' + REST.replace("rays = 48", "rays = 8"))
    p = load_project(root)
    out = simulate_project(p, options=RunOptions(engine="numpy", scheduler="local", workers=1))
    assert out is not None and out.computed == 3    # 10 façades in chunks of 4
    t = out.table
    assert set(t["building"]) == {"N1", "N2", "S1"} and t["storey"].max() == 2
    assert set(t.groupby("facade")["storey"].nunique()) <= {2, 3}
    gj = json.loads((root / "results" / "facades.geojson").read_text())
    assert gj["type"] == "FeatureCollection" and len(gj["features"]) == 10
    assert gj["crs"]["properties"]["name"] == UTM
    n1 = next(f for f in gj["features"] if f["id"] == "N1:0")
    np.testing.assert_allclose(n1["geometry"]["coordinates"], [[E0 - 15, N0 + 10], [E0, N0 + 10]],
                               atol=1e-6)
    mean = t[t["facade"] == "N1:0"]["lux"].mean()
    assert n1["properties"]["lux_T_12:30"] == pytest.approx(mean, abs=0.05)
    again = simulate_project(p, options=RunOptions(engine="numpy"))
    assert again is not None and again.computed == 0 and again.reused == 3
    fresh = simulate_project(p, options=RunOptions(engine="numpy", fresh=True))
    assert fresh is not None
    key = ["grid", "sensor"]
    a = t.sort_values(key)["lux"].to_numpy()
    b = fresh.table.sort_values(key)["lux"].to_numpy()
    np.testing.assert_array_equal(a, b)


def test_csv_inventory_in_lonlat_matches_geojson(tmp_path):
    """The same two trees as a CSV (lon, lat columns) and as GeoJSON: same local positions;
    a degree of longitude at 32.89° S spans 111 412.84 cos φ − 93.5 cos 3φ ≈ 93 570 m (WGS 84)."""
    from radtree.site.inventory import read_trees

    dlon = 1.0 / (111_412.84 * math.cos(math.radians(LAT)) - 93.5 * math.cos(3 * math.radians(LAT)))
    rows = [("T1", LON + 10 * dlon, LAT), ("T2", LON, LAT)]
    csv = tmp_path / "trees.csv"
    csv.write_text("id,lon,lat,species,height_m,crown_diameter_m,crown_base_m\n" + "".join(
        f"{i},{x!r},{y!r},morus_alba,8,5,3\n" for i, x, y in rows))
    gj = tmp_path / "trees.geojson"
    gj.write_text(fc([point(i, x, y) for i, x, y in rows]))
    a, _ = read_trees(csv, "EPSG:4326", LAT, LON)
    b, _ = read_trees(gj, "EPSG:4326", LAT, LON)
    assert [(t.id, t.x, t.y) for t in a] == [(t.id, t.x, t.y) for t in b]
    assert a[0].x == pytest.approx(10.0, abs=0.01) and abs(a[0].y) < 0.01


@pytest.mark.parametrize("key", ["voxels", "points"])
def test_one_crown_inputs_are_refused_with_an_inventory(key: str) -> None:
    """[tree] voxels / points describe one crown; an inventory's crowns come from its rows:
    refused with the field, the value as written and the fix, not silently ignored."""
    root = Path(__file__).resolve().parents[1] / "examples" / "district"
    with pytest.raises(ConfigError) as err:
        load_project(root, {f"tree.{key}": "data/trees.geojson"} | (
            {"tree.representation": "turbid"} if key == "voxels" else {}))
    msg = str(err.value)
    assert f"tree.{key}" in msg and "'data/trees.geojson'" in msg
    assert "remove [tree] " + key in msg and "[site] trees" in msg
