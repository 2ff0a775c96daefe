"""Tree inventories, building footprints and every façade ([site] trees / buildings)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
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
        build_project(p, echo=lambda _m: None, progress=False, pictures=False)
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
    msg = _fails(tmp_path, trees=[point("T4", -8, 8.0, crown_diameter_m=6.0)])
    assert "feature 'T4'" in msg and "through a wall of building 'N1'" in msg


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
    from radtree.trees.district import species_louvers
    from radtree.trees.species import load_species

    inv = district(tmp_path / "inv", trees=[point("T1", 0.0, 3.5)], buildings=None,
                   extra=STREET)
    p_inv = load_project(inv)
    lv = species_louvers(p_inv.tree.louvers, load_species("morus_alba"))
    hand = tmp_path / "hand"
    hand.mkdir()
    (hand / "dni.csv").write_text(DNI)
    louvers = "\n".join(f"{k} = {getattr(lv, k)!r}" for k in (
        "reflectance", "transmittance", "specular_fraction", "slat_size_m", "inclination_deg",
        "crossings"))
    (hand / "radtree.toml").write_text(SITE + STREET + CROWN + REST.replace(
        'arrangement = "volume"', 'arrangement = "volume"\n' + louvers))
    p_hand = load_project(hand)
    a = trace_scenario(p_hand, p_hand.scenario("T"), engine="numpy")
    b = trace_scenario(p_inv, p_inv.scenario("T"), engine="numpy")
    assert len(a) == 8 and a["lux"].min() > 0
    np.testing.assert_array_equal(a["lux"].to_numpy(), b["lux"].to_numpy())
