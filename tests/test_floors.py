"""Any building, any floor (issue 37 item 4): an even office block with every room sensed,
the ground floor included; street sensors at several heights."""

from __future__ import annotations

import logging
import math
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from radtree.config import load_project
from radtree.errors import ConfigError
from radtree.site.frame import FacadeFrame

from .conftest import ROOT, copy_project

OFFICE = ROOT / "examples" / "office-block"


def office_copy(dst: Path, edits: dict[str, str]) -> Path:
    """The office example with regex edits of its radtree.toml (scenario "with" dropped)."""
    shutil.copytree(OFFICE, dst, ignore=shutil.ignore_patterns("build", "results", "report"))
    toml = dst / "radtree.toml"
    text = toml.read_text()
    head, *blocks = text.split("\n[[scenario]]")
    text = "\n[[scenario]]".join([head, *[b for b in blocks if 'name = "with"' not in b]])
    for pat, rep in edits.items():
        text, n = re.subn(pat, rep, text, flags=re.M)
        assert n, pat
    toml.write_text(text)
    return dst


EVEN = {r"^bays = 3": "bays = 2", r"^storeys = 3": "storeys = 2", r"^rooms = .*$": "",
        r"^hours = .*$": 'hours = ["13:30"]', r"^rays = .*$": "rays = 64"}


def test_even_block_senses_every_room_ground_floor_included(tmp_path):
    from radtree.office_summary import office_section_data, write_maps, write_summary
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project
    from radtree.site.office import office_layout

    proj = load_project(office_copy(tmp_path / "office", EVEN))
    assert proj.office.rooms == "all"
    lay = office_layout(proj)
    assert [n for n, _, _ in lay.sensed] == ["0-0", "0-1", "1-0", "1-1"]
    assert lay.bay_u(0) == (-3.0, 0.0) and lay.bay_u(1) == (0.0, 3.0)   # centred on x_m = 0
    out = simulate_project(proj, options=RunOptions(engine="numpy", fresh=True))
    assert out is not None
    table = pd.read_csv(proj.results_dir / "illuminance.csv", dtype={"room": str})
    cols = list(table.columns)
    assert cols[cols.index("params_hash") + 1:cols.index("params_hash") + 3] == ["storey", "room"]
    for grid, per_room in (("facade", 6 * 5), ("workplane", 4 * 10)):
        g = table[table["grid"] == grid]
        assert g.groupby("room").size().to_dict() == {r: per_room for r in
                                                      ("0-0", "0-1", "1-0", "1-1")}
        assert (g["storey"] == g["room"].str[0].astype(int)).all()
    frame = FacadeFrame(proj.street.facade_azimuth_deg)
    ground = table[(table["grid"] == "facade") & (table["storey"] == 0)]
    z = frame.to_local(ground[["x", "y", "z"]].to_numpy(float))[:, 2]
    assert z.min() > 1.25 and z.max() < 1.25 + lay.room_height     # the ground-floor glazing
    # the street is symmetric about the block's centre line: both bays of a storey alike
    fac = table[table["grid"] == "facade"].groupby("room")["lux"].mean()
    assert fac["0-0"] == pytest.approx(fac["0-1"], rel=0.03)
    assert fac["1-0"] == pytest.approx(fac["1-1"], rel=0.03)
    assert fac.min() > 10000                                       # façade in the sun

    summary = pd.read_csv(write_summary(proj, maps=False), dtype={"time": str, "room": str})
    written = write_maps(proj, table[table["grid"] == "workplane"])   # per storey: 2 levels
    assert sorted(p.name for p in written) == ["workplane_s0_1330.png", "workplane_s1_1330.png"]
    assert list(summary.columns[-2:]) == ["storey", "room"]
    assert len(summary) == 2 * 4                                   # grids × rooms
    wp = summary[summary["grid"] == "workplane"].set_index("room")
    for room, g in table[table["grid"] == "workplane"].groupby("room"):
        assert wp.loc[room, "mean_lux"] == pytest.approx(g["lux"].mean(), rel=1e-5)
        assert wp.loc[room, "n_points"] == 40
    data = office_section_data(proj)
    grid = next(g for g in data["grids"] if g["title"].startswith("Work plane"))
    assert [r["label"] for r in grid["rooms"]["rows"]] == [
        "0-0 (storey 0)", "0-1 (storey 0)", "1-0 (storey 1)", "1-1 (storey 1)"]
    # pooled over the rooms: the point-weighted mean of the rooms (equal-area cells)
    pooled = float(grid["rows"][0]["cells"][0]["text"].replace(",", ""))
    assert pooled == pytest.approx(table[table["grid"] == "workplane"]["lux"].mean(), abs=0.5)
    maps = {m["src"] for m in grid["maps"]}
    assert maps == {"office/workplane_s0_1330.png", "office/workplane_s1_1330.png"}
    assert "0-0 (floor 1.25 m)" in data["description"]


def test_rooms_are_checked_against_the_block(tmp_path):
    p = office_copy(tmp_path / "office", {**EVEN, r"^rooms = .*$": 'rooms = ["0-1", "2-0"]'})
    with pytest.raises(ConfigError, match=re.escape(
            "field 'office.rooms': got room '2-0': the block has storeys 0–1 and bays 0–1")):
        load_project(p)
    p = office_copy(tmp_path / "office2", {r"^rooms = .*$": 'rooms = ["ground"]'})
    with pytest.raises(ConfigError, match="expected 'STOREY-BAY' such as '0-1'"):
        load_project(p)


def test_a_room_list_is_the_same_grid_as_in_all(tmp_path):
    """``rooms = ["0-1"]`` gives exactly the points "all" gives that room."""
    from radtree.site.office import office_parts

    one = load_project(office_copy(tmp_path / "a", {**EVEN, r"^rooms = .*$": 'rooms = ["0-1"]'}))
    every = load_project(office_copy(tmp_path / "b", EVEN))
    frame = FacadeFrame(one.street.facade_azimuth_deg)
    g1 = office_parts(one, frame)[2]["workplane"]
    ga = office_parts(every, frame)[2]["workplane"]
    sel = np.array(ga.labels["room"]) == "0-1"
    assert np.array_equal(g1.points, ga.points[sel])
    assert g1.labels == {"storey": [0] * 40, "room": ["0-1"] * 40}


def street_copy(dst: Path, sensors: str) -> Path:
    """The Mendoza street without crowns (scenario B: ground light traced), one hour, few
    paths, a coarse dense map; ``sensors`` replaces the ``height_m`` line of [sensors]."""
    p = copy_project(dst, hours=["13:30"], replace={
        r"^height_m = 5\.0": sensors, r"^rays = \d+": "rays = 256",
        r"^dense_rays = \d+": "dense_rays = 16", r"^dense_spacing_m = 0\.5": "dense_spacing_m = 2.0"})
    text = (p / "radtree.toml").read_text()
    (p / "radtree.toml").write_text(re.sub(r'model = "\w+"', 'model = "none"', text))
    return p


def test_street_with_three_sensor_heights(tmp_path):
    from radtree.pipeline.assemble import make_scene
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project

    proj = load_project(street_copy(tmp_path / "levels", "heights_m = [1.5, 4.5, 7.5]"))
    assert proj.sensors.levels == (1.5, 4.5, 7.5)
    grids = make_scene(proj, proj.scenario("B")).scene.grids
    assert list(grids) == ["facade@1.5m", "facade_map@1.5m", "facade@4.5m", "facade_map@4.5m",
                           "facade@7.5m", "facade_map@7.5m"]
    frame = FacadeFrame(proj.street.facade_azimuth_deg)
    for k, h in enumerate((1.5, 4.5, 7.5)):
        circle = grids[f"facade@{h:g}m"]
        assert len(circle) == 8 and circle.labels == {"storey": [k] * 8}
        assert frame.to_local(circle.points)[:, 2].mean() == pytest.approx(h)
    out = simulate_project(proj, options=RunOptions(engine="numpy", scenarios=["B"],
                                                    fresh=True))
    assert out is not None
    t = out.table
    circles = t[~t["grid"].str.startswith("facade_map")]
    assert circles.groupby("grid")["storey"].unique().map(list).to_dict() == {
        "facade@1.5m": [0], "facade@4.5m": [1], "facade@7.5m": [2]}
    # the 4.5 m circle agrees with a one-height project at 4.5 m (independent paths: within
    # four standard errors of the difference of the means)
    one = load_project(street_copy(tmp_path / "one", "height_m = 4.5"))
    single = simulate_project(one, options=RunOptions(engine="numpy", scenarios=["B"],
                                                      grids=["facade"], fresh=True))
    assert single is not None and "storey" not in single.table.columns
    a = circles[circles["grid"] == "facade@4.5m"]
    b = single.table[single.table["grid"] == "facade"]
    se = np.sqrt((a["lux_stderr"] ** 2).sum() / 64 + (b["lux_stderr"] ** 2).sum() / 64)
    assert abs(a["lux"].mean() - b["lux"].mean()) < 4 * se + 1e-9
    assert a["lux"].mean() > 10000
    # the report reads the circle nearest sensors.height_m (5 m: 4.5 m) as its façade grid
    from radtree.report.data import one_level_as_facade

    notes: list[str] = []
    as_report = one_level_as_facade(proj, t, notes)
    assert as_report[as_report["grid"] == "facade"]["lux"].tolist() == a["lux"].tolist()
    by = t[t["grid"] == "facade@7.5m"]["lux"].mean()
    assert notes[0].startswith("façade sensors at 3 heights ([sensors] heights_m): the report's "
                               "façade grid is the circle at 4.5 m (nearest sensors.height_m 5 m)")
    assert f"storey 2 (7.5m) {by:,.0f} lx" in notes[0]


def test_one_validator_for_one_or_several_heights(tmp_path):
    for sensors, msg in (("height_m = -1.0", "field 'sensors.height_m': got -1.0, expected > 0"),
                         ("heights_m = [1.5, -1.0]",
                          "field 'sensors.heights_m': got -1.0, expected > 0"),
                         ("heights_m = [1.5, 1.5]", "a height is given twice"),
                         ("heights_m = []", "expected a non-empty list of numbers")):
        with pytest.raises(ConfigError, match=re.escape(msg)):
            load_project(street_copy(tmp_path / str(abs(hash(sensors))), sensors))


# ---------------------------------------------------------------- where the façade stands
def inventory_street(tmp: Path, trees: list[dict], crs: str | None, tree_extra: str = "",
                     street_extra: str = "") -> Path:
    """An inventory in the street template (no buildings): tests/test_district's project
    with a 40 m street; ``tree_extra`` goes into [tree], ``street_extra`` into [street]."""
    from tests.test_district import STREET, district

    p = district(tmp, trees=trees, buildings=None, crs=crs,
                 extra=STREET.replace("length_m = 40.0", "length_m = 40.0\n" + street_extra))
    toml = p / "radtree.toml"
    toml.write_text(toml.read_text().replace('form = "free"', 'form = "free"\n' + tree_extra))
    return p


def _lonlat_row():
    """Two trees 10 m either side of the site origin (their centroid), in longitude/latitude."""
    from tests.test_district import LAT, LON, point

    dlon = 10.0 / (111320.0 * math.cos(math.radians(LAT)))
    return [point("A", LON - dlon, LAT), point("B", LON + dlon, LAT)]


def test_inventory_street_without_buildings_builds_behind_the_trees(tmp_path, caplog):
    """The site origin is the trees' centroid: the façade used to pass through it ("tree
    stands inside a building"); now it stands [tree.crown] trunk_distance_m (3 m) behind them."""
    from radtree.pipeline.assemble import make_scene
    from radtree.pipeline.build import build_project

    proj = load_project(inventory_street(tmp_path / "auto", _lonlat_row(), crs=None))
    with caplog.at_level(logging.INFO, logger="radtree"):
        build_project(proj, pictures=False)
    said = [r.getMessage() for r in caplog.records if r.name == "radtree.pipeline.build"]
    placed = [m for m in said if "Façade placed" in m]
    assert len(placed) == 1 and "T: Façade placed 3 m ([tree.crown] trunk_distance_m) behind " \
        "the trunk nearest to it, looking 0° (street.facade_azimuth_deg): to place it " \
        "yourself, set [street] facade_line = [[20.00, -3.00], [-20.00, -3.00]]" in placed[0]
    scene = make_scene(proj, proj.scenario("T")).scene
    facade = next(m for m in scene.meshes if m.name == "facade")
    # (transverse Mercator: trees on the origin's parallel 10 m out lie 5 µm north of it)
    assert np.allclose(facade.vertices[:, 1], -3.0, atol=1e-4)
    assert np.allclose(scene.grids["facade"].points[:, 1], -3.0 + 0.01, atol=1e-4)
    # the same line written out places the façade identically (no note then)
    line = "facade_line = [[20.0, -3.0], [-20.0, -3.0]]"
    explicit = load_project(inventory_street(tmp_path / "line", _lonlat_row(), crs=None,
                                             street_extra=line))
    built = make_scene(explicit, explicit.scenario("T"))
    same = next(m for m in built.scene.meshes if m.name == "facade")
    np.testing.assert_allclose(same.vertices, facade.vertices, atol=1e-4)
    assert not any("Façade placed" in n for n in built.notes)


def test_facade_line_orients_the_facade(tmp_path):
    """A line running north (x1 → x2 = 0,−20 → 0,20) puts a façade looking east (to its
    right) through x = 0; a contradicting facade_azimuth_deg is refused naming both."""
    from radtree.pipeline.assemble import facade_frame
    from tests.test_district import point

    trees = [point("A", 4.0, -5.0), point("B", 4.0, 5.0)]
    p = load_project(inventory_street(tmp_path / "east", trees, crs="local",
                                      street_extra="facade_line = [[0, -20], [0, 20]]"))
    assert p.street.facade_azimuth_deg == pytest.approx(90.0)
    f = facade_frame(p)
    np.testing.assert_allclose(f.normal, [1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(f.to_local(np.array([4.0, 5.0, 0.0])), [-5.0, 4.0, 0.0],
                               atol=1e-9)
    bad = inventory_street(tmp_path / "bad", trees, crs="local", street_extra=(
        "facade_line = [[0, -20], [0, 20]]\nfacade_azimuth_deg = 270"))
    with pytest.raises(ConfigError, match=re.escape(
            "field 'street.facade_azimuth_deg': got 270°, but facade_line [[0.0, -20.0], "
            "[0.0, 20.0]] looks 90.0°")):
        load_project(bad)


def test_tree_behind_the_facade_names_the_fix(tmp_path):
    from radtree.pipeline.build import build_project
    from tests.test_district import point

    p = load_project(inventory_street(tmp_path / "p", [point("A", 0.0, -2.0)], crs="local"))
    with pytest.raises(ConfigError, match=re.escape(
            "field 'feature 'A'': tree stands behind the studied façade (n = -2.00 m across a "
            "20 m street): set [street] facade_line")):
        build_project(p, pictures=False)


# ---------------------------------------------------------------- one crown–wall policy
def test_removed_fraction_is_the_clipped_volume():
    """(1 − t)²(2 + t)/4 against a Monte Carlo of the clipped spheroid (independent)."""
    from radtree.trees.envelope import CrownRowSpec
    from radtree.trees.volume import clipped_volume
    from radtree.trees.wall_policy import removed_fraction

    assert removed_fraction(5.0, 0.0) == 0.5 and removed_fraction(5.0, 5.0) == 0.0
    assert removed_fraction(5.0, -5.0) == 1.0
    for a, b, d in ((5.0, 4.75, 2.985), (3.0, 2.5, 1.0), (2.0, 3.0, -0.5)):
        spec = CrownRowSpec(centres=np.array([[0.0, d, 10.0]]), a=a, b=b, n_clip=0.0,
                            strips=np.array([[-np.inf, np.inf]]), trunk_radius=0.2,
                            trunk_top=9.0)
        vol, se = clipped_volume(spec, samples=400_000, seed=2)
        whole = 4.0 / 3.0 * math.pi * a * a * b
        assert 1.0 - vol / whole == pytest.approx(removed_fraction(a, d), abs=4 * se / whole)


ROW = """
[tree.crown]
count = 1
trunk_distance_m = 3.5
radius_m = 4.0
vertical_radius_m = 2.5
base_height_m = 3.0
"""


def _row_project(tmp: Path, policy: str) -> Path:
    """The one-crown row of tests/test_district (hand-written), its crown radius 4 m: it
    reaches the façade (trunk 3.5 m out)."""
    from tests.test_district import DNI, REST, SITE, STREET

    tmp.mkdir()
    (tmp / "dni.csv").write_text(DNI)
    (tmp / "radtree.toml").write_text(SITE + STREET + ROW + REST.replace(
        'form = "free"', f'form = "free"\nwall_policy = "{policy}"'))
    return tmp


def test_row_crown_clip_note_and_refusal(tmp_path, caplog):
    from radtree.pipeline.build import build_project
    from radtree.trees.wall_policy import removed_fraction

    with caplog.at_level(logging.INFO, logger="radtree"):
        build_project(load_project(_row_project(tmp_path / "clip", "clip")), pictures=False)
    said = [r.getMessage() for r in caplog.records if r.name == "radtree.pipeline.build"]
    pct = 100 * removed_fraction(4.0, 3.5 - 0.015)
    assert f"{pct:.1f}" == "1.2"
    assert '  T: Crown–wall policy "clip": crowns cut at the wall; crown volume removed: the ' \
        "row's crown 1.2 % ([tree] wall_policy = \"refuse\" stops the build instead, with the " \
        'fix)' in said
    p = load_project(_row_project(tmp_path / "refuse", "refuse"))
    with pytest.raises(ConfigError) as exc:
        build_project(p, pictures=False)
    assert str(exc.value).endswith(
        "field 'tree.crown.radius_m': the row's crown (radius 4 m) reaches the façade: its trunk "
        "stands 3.48 m from the wall's clip plane; [tree] wall_policy = \"refuse\": move the "
        "trunk 0.52 m further from the wall ([tree.crown] trunk_distance_m), or reduce "
        "[tree.crown] radius_m to 3.48 m — or set wall_policy = \"clip\"")
    assert not (p.build_dir / "T").exists()


def test_inventory_crown_clip_note_and_refusal(tmp_path, caplog):
    """The same policy for an inventory tree in the canyon (crs local: façade through the
    origin) and against a building: cut at the wall's clip plane, or refused with the fix."""
    from radtree.pipeline.assemble import make_scene
    from radtree.pipeline.build import build_project
    from radtree.trees.wall_policy import removed_fraction
    from tests.test_district import BUILDINGS, district, point

    near = [point("N", 0.0, 2.0, crown_diameter_m=6.0)]   # radius 3 m, trunk 2 m out
    p = load_project(inventory_street(tmp_path / "clip", near, crs="local"))
    with caplog.at_level(logging.INFO, logger="radtree"):
        build_project(p, pictures=False)
    said = [r.getMessage() for r in caplog.records if r.name == "radtree.pipeline.build"]
    pct = 100 * removed_fraction(3.0, 2.0 - 0.015)
    assert f"{pct:.1f}" == "7.6"
    assert any("Crown–wall policy \"clip\": crowns cut at the wall; crown volume removed: "
               "the crown of tree 'N' 7.6 %" in m for m in said)
    leaves = [m for m in make_scene(p, p.scenario("T")).scene.meshes
              if m.material.startswith("leaf")]
    ys = np.concatenate([m.vertices[:, 1] for m in leaves])
    assert ys.min() >= 0.015 - 1e-9 and ys.min() < 0.05      # cut at the plane, up to it

    refuse = inventory_street(tmp_path / "refuse", near, crs="local",
                              tree_extra='wall_policy = "refuse"')
    with pytest.raises(ConfigError, match=re.escape(
            "field 'feature 'N'': the crown of tree 'N' (radius 3 m) reaches the façade: its "
            "trunk stands 1.99 m from the wall's clip plane; [tree] wall_policy = \"refuse\": "
            "move the trunk 1.02 m further from the wall, or reduce the crown radius "
            "(crown_diameter_m / 2, or its crown_outline) to 1.98 m — or set wall_policy = "
            "\"clip\"")):
        build_project(load_project(refuse), pictures=False)

    # against building N1 (south wall at y = 10): the crown keeps y ≤ 10 − 0.015
    q = load_project(district(tmp_path / "bldg", trees=[point("T4", -8, 8.0,
                                                               crown_diameter_m=6.0)],
                              buildings=BUILDINGS))
    built = make_scene(q, q.scenario("T"))
    assert any("removed: the crown of tree 'T4' 7.6 %" in n for n in built.notes)
    ys = np.concatenate([m.vertices[:, 1] for m in built.scene.meshes
                         if m.material.startswith("leaf")])
    assert ys.max() <= 10.0 - 0.015 + 1e-9 and ys.max() > 10.0 - 0.05


def test_honeybee_crowns_follow_the_same_policy(tmp_path):
    """A Honeybee model's crowns stand in the street frame's row: the same note and refusal."""
    pytest.importorskip("honeybee.model")
    from radtree.pipeline.assemble import make_scene
    from tests.test_honeybee_model import CROWN, TOML, write_project

    crown = CROWN.replace("radius_m = 2.5", "radius_m = 3.0")
    p = load_project(write_project(tmp_path / "clip", toml=TOML + crown))
    notes = make_scene(p, p.scenario("crown")).notes
    assert any(n.startswith('Crown–wall policy "clip": crowns cut at the wall; crown volume '
                            "removed: the row's crown 2.1 %") for n in notes)
    q = load_project(write_project(tmp_path / "refuse", toml=TOML + crown.replace(
        'form = "free"', 'form = "free"\nwall_policy = "refuse"')))
    with pytest.raises(ConfigError, match=re.escape(
            "move the trunk 0.52 m further from the wall ([tree.crown] trunk_distance_m), or "
            "reduce [tree.crown] radius_m to 2.48 m")):
        make_scene(q, q.scenario("crown"))


def test_crown_reaching_both_facades_is_refused_under_either_policy(tmp_path):
    from radtree.pipeline.build import build_project
    from tests.test_district import point

    folder = inventory_street(tmp_path / "p", [point("W", 0.0, 2.5, crown_diameter_m=6.0)],
                              crs="local")
    toml = folder / "radtree.toml"
    toml.write_text(toml.read_text().replace("width_m = 20.0", "width_m = 5.0"))
    with pytest.raises(ConfigError, match=re.escape(
            "field 'feature 'W'': the crown of tree 'W' (radius 3 m) reaches two walls (the "
            "façade and the opposite façade); a crown is clipped at one wall only: reduce its "
            "radius to 2.48 m or move its trunk")):
        build_project(load_project(folder), pictures=False)
    assert not (folder / "build" / "T").exists()
