"""Any building, any floor (issue 37 item 4): an even office block with every room sensed,
the ground floor included; street sensors at several heights."""

from __future__ import annotations

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
    from radtree.pipeline.simulate import simulate_project
    from radtree.site.office import office_layout

    proj = load_project(office_copy(tmp_path / "office", EVEN))
    assert proj.office.rooms == "all"
    lay = office_layout(proj)
    assert [n for n, _, _ in lay.sensed] == ["0-0", "0-1", "1-0", "1-1"]
    assert lay.bay_u(0) == (-3.0, 0.0) and lay.bay_u(1) == (0.0, 3.0)   # centred on x_m = 0
    out = simulate_project(proj, engine="numpy", echo=lambda _m: None, progress=False,
                           resume=False)
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
    out = simulate_project(proj, engine="numpy", scenarios=["B"], echo=lambda _m: None,
                           progress=False, resume=False)
    assert out is not None
    t = out.table
    circles = t[~t["grid"].str.startswith("facade_map")]
    assert circles.groupby("grid")["storey"].unique().map(list).to_dict() == {
        "facade@1.5m": [0], "facade@4.5m": [1], "facade@7.5m": [2]}
    # the 4.5 m circle agrees with a one-height project at 4.5 m (independent paths: within
    # four standard errors of the difference of the means)
    one = load_project(street_copy(tmp_path / "one", "height_m = 4.5"))
    single = simulate_project(one, engine="numpy", scenarios=["B"], grids=["facade"],
                              echo=lambda _m: None, progress=False, resume=False)
    assert single is not None and "storey" not in single.table.columns
    a = circles[circles["grid"] == "facade@4.5m"]
    b = single.table[single.table["grid"] == "facade"]
    se = np.sqrt((a["lux_stderr"] ** 2).sum() / 64 + (b["lux_stderr"] ** 2).sum() / 64)
    assert abs(a["lux"].mean() - b["lux"].mean()) < 4 * se + 1e-9
    assert a["lux"].mean() > 10000


def test_one_validator_for_one_or_several_heights(tmp_path):
    for sensors, msg in (("height_m = -1.0", "field 'sensors.height_m': got -1.0, expected > 0"),
                         ("heights_m = [1.5, -1.0]",
                          "field 'sensors.heights_m': got -1.0, expected > 0"),
                         ("heights_m = [1.5, 1.5]", "a height is given twice"),
                         ("heights_m = []", "expected a non-empty list of numbers")):
        with pytest.raises(ConfigError, match=re.escape(msg)):
            load_project(street_copy(tmp_path / str(abs(hash(sensors))), sensors))
