"""Honeybee models in: the reader, its errors, and the cross-tool check against honeybee-radiance.

The cross-tool check builds a one-room model with honeybee-core (a 3 m × 5 m × 2.5 m office,
one window of 40 % of the north wall, Honeybee's default modifiers, no trees), traces it with
radtree's Radiance engine, then traces honeybee-radiance's *own* Radiance translation of the
same model (``model_to_rad``) with ``rtrace`` and radtree's rtrace options, sky, ground
material and ground plane → the work-plane illuminances must agree within 1 %.

The sky is the hour's Perez sky without the sun (direct normal 0): with ``-u-`` both octrees
then draw the same ambient samples and the comparison measures the translation, not noise
(measured: 4e-5 at -ad 256 to 8192), so a modest -ab 2 -ad 256 suffices. With the sun in, its small floor patch is sampled differently by the two
octrees and single sensors differ by 5 % at ``-ab 1 -ad 8192``. The check with the sun
(:func:`test_cross_tool_with_the_sun`, winter solstice 12:30: the sun on the work plane) compares
the direct sun per sensor at ``-ab 0`` (0.5 %) and the mean total over eight independent
fixed-seed estimates per octree (2 % or 3 combined standard errors).
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from radtree.config import load_project
from radtree.errors import ConfigError
from radtree.verify.honeybee import CROWN, TOML, office_model, write_project

from .conftest import needs_radiance

pytest.importorskip("honeybee.model")   # a guard only: CI installs radtree[honeybee]

def test_reader_meshes_materials_grids(tmp_path):
    from radtree.pipeline.assemble import make_scene

    project = load_project(write_project(tmp_path / "p"))
    sc = project.scenarios[0]
    built = make_scene(project, sc)
    scene = built.scene
    names = {m.name for m in scene.meshes}
    assert {"hb_generic_wall_0.50", "hb_generic_floor_0.20", "hb_generic_ceiling_0.80",
            "hb_generic_exterior_window_vis_0.64", "ground"} <= names
    glass = scene.materials["generic_exterior_window_vis_0.64"]
    assert glass.transmissivity == pytest.approx(0.6975761815, abs=1e-9)
    assert scene.materials["generic_wall_0.50"].reflectance == pytest.approx(0.5)
    # window area = 40 % of the 3 × 2.5 m wall; walls keep the rest (punched)
    assert scene.mesh("hb_generic_exterior_window_vis_0.64").area() == pytest.approx(3.0)
    walls = scene.mesh("hb_generic_wall_0.50").area()
    assert walls == pytest.approx(2 * 3 * 2.5 + 2 * 5 * 2.5 - 3.0)
    grid = scene.grids["office"]
    assert len(grid) == 15       # 3 × 5 cells of 1 m
    assert np.allclose(grid.points[:, 2], 0.8) and np.allclose(grid.normals, [0, 0, 1])
    assert scene.mesh("ground").vertices[:, 2].max() == pytest.approx(-0.01)


def bad(tmp_path: Path, name: str, text: str) -> str:
    folder = tmp_path / name
    folder.mkdir()
    (folder / "model.hbjson").write_text(text)
    (folder / "dni.csv").write_text("time,direct_normal_lux\n13:30,80000\n")
    (folder / "radtree.toml").write_text(TOML)
    from radtree.pipeline.assemble import make_scene

    with pytest.raises(ConfigError) as exc:
        p = load_project(folder)
        make_scene(p, p.scenarios[0])
    return str(exc.value)


def test_bad_models_one_clear_message(tmp_path):
    good = office_model().to_dict()
    msg = bad(tmp_path, "json", "{not json")
    assert "model.hbjson, field 'site.honeybee': not a Honeybee model (not readable JSON" in msg
    msg = bad(tmp_path, "type", json.dumps({"type": "Room", "identifier": "x"}))
    assert "not a Honeybee model (its 'type' is 'Room', expected 'Model')" in msg
    newer = dict(good, version="99.0.0")
    msg = bad(tmp_path, "newer", json.dumps(newer))
    assert "written with Honeybee schema 99.0.0, newer than the installed" in msg
    feet = dict(good, units="Feet")
    msg = bad(tmp_path, "feet", json.dumps(feet))
    assert "units are 'Feet'; radtree works in metres" in msg
    m = office_model()
    floor = [f for f in m.rooms[0].faces if f.normal.z < -0.99][0]
    d = m.to_dict()
    d["rooms"][0]["faces"] = [f for f in d["rooms"][0]["faces"]
                              if f["identifier"] != floor.identifier]
    msg = bad(tmp_path, "nofloor", json.dumps(d))
    assert "room 'office' (office) has no floor face" in msg
    for m in (msg, bad(tmp_path, "metal", json.dumps(with_metal(good)))):
        assert m.count("model.hbjson") == 1 and m.count("\n") == 0   # one line, file once
    assert "modifier 'shiny' is a Radiance metal; radtree reads plastic, glass and trans" in m
    from click.testing import CliRunner

    from radtree.cli import main

    r = CliRunner().invoke(main, ["build", str(tmp_path / "feet")])
    assert r.exit_code == 2       # bad input, no traceback
    assert "units are 'Feet'; radtree works in metres" in r.output and "Traceback" not in r.output


def with_metal(model_dict: dict) -> dict:
    from honeybee.model import Model
    from honeybee_radiance.modifier.material import Metal

    model = Model.from_dict(model_dict)
    model.rooms[0].faces[1].properties.radiance.modifier = Metal("shiny", 0.8, 0.8, 0.8)
    return model.to_dict()


def rtrace_lux(build: Path, hb_files: list[Path], opts: list[str], pts: str) -> np.ndarray:
    from radtree.engines.radiance.binaries import require_radiance
    from radtree.engines.radiance.writer import rgb_to_lux

    env = require_radiance().env()
    oct_path = build.parent / "hb.oct"
    scene = [*map(str, hb_files), "skies/1330_ground.rad", "geometry/ground.rad",
             "skies/1330.sky"]
    with oct_path.open("wb") as fh:
        subprocess.run(["oconv", *scene], cwd=build, stdout=fh, check=True, env=env)
    out = subprocess.run(["rtrace", *opts, str(oct_path)], cwd=build, input=pts.encode(),
                         capture_output=True, check=True, env=env).stdout
    return rgb_to_lux(np.loadtxt(out.decode().splitlines()).reshape(-1, 3))


@pytest.fixture(scope="module")
def traced(tmp_path_factory):
    """The one-room model traced by radtree (Radiance): scenario ``open`` (the model alone) and
    ``crown`` (a radtree crown added in front of the window); built, simulated, reported."""
    from radtree.pipeline.build import build_project
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project
    from radtree.report import build_report

    folder = write_project(tmp_path_factory.mktemp("hb") / "p", dni=0.0,
                           toml=TOML.replace("[sensors]", "[sensors]\nheight_m = 1.5") + CROWN)
    project = load_project(folder)
    build_project(project, pictures=False)
    simulate_project(project, options=RunOptions(engine="radiance"))
    index = build_report(project)
    return project, pd.read_csv(project.results_dir / "illuminance.csv"), index


@needs_radiance
def test_cross_tool_radtree_vs_honeybee_radiance(traced, tmp_path):
    """radtree's trace of the model and rtrace on honeybee-radiance's translation agree < 1 %."""
    from honeybee.model import Model
    from honeybee_radiance.writer import model_to_rad

    from radtree.engines.radiance.writer import rtrace_options

    project, table, _ = traced
    sel = table[(table["grid"] == "office") & (table["scenario"] == "open")]
    ours = sel.sort_values("sensor")["lux_traced"].to_numpy()
    model = Model.from_hbjson(str(project.honeybee.model))
    geometry, modifiers = model_to_rad(model)
    (tmp_path / "modifiers.rad").write_text(modifiers)
    (tmp_path / "model.rad").write_text(geometry)
    build = project.build_dir / "open"
    opts = rtrace_options(project.engine, 2)
    assert opts[:6] == ["-h", "-I", "-u-", "-ab", "2", "-ad"] and opts[6] == "256"
    assert not model.properties.radiance.sensor_grids   # radtree generated the room's grid
    theirs = rtrace_lux(build, [tmp_path / "modifiers.rad", tmp_path / "model.rad"], opts,
                        (build / "grids" / "office.pts").read_text())
    assert len(ours) == len(theirs) == 15
    assert ours.min() > 10 and ours.max() > 1000   # daylight reaches every sensor
    rel = np.abs(ours / theirs - 1)
    assert rel.max() < 0.01, f"max |radtree / honeybee-radiance − 1| = {rel.max():.4f}"
    print(f"cross-tool: 15 sensors, mean {ours.mean():.2f} vs {theirs.mean():.2f} lx, "
          f"max deviation {100 * rel.max():.4f} %")


@needs_radiance
def test_report_shows_both_grids_and_honeybee_results(traced):
    """With a radtree crown added, the report shows the model's grid and the façade grid for
    both scenarios, and writes each grid's results in honeybee-radiance's layout."""
    project, table, index = traced
    html = index.read_text()
    section = html[html.index('<section id="honeybee">'):]
    section = section[:section.index("</section>")]
    for sc in ("open", "crown"):
        for grid in ("office", "facade"):
            mean = table[(table["scenario"] == sc) & (table["grid"] == grid)]["lux"].mean()
            assert f"<td>{sc}</td><td>{grid}</td><td>13:30</td>" in section
            assert f'<td class="num">{mean:.0f}</td>' in section
    office = table[table["grid"] == "office"].groupby("scenario")["lux"].mean()
    assert office["crown"] < 0.95 * office["open"]     # the crown shades the room
    folder = index.parent / "honeybee"
    for sc in ("open", "crown"):
        res = np.loadtxt(folder / sc / "1330" / "office.res")
        want = table[(table["scenario"] == sc) & (table["grid"] == "office")].sort_values(
            "sensor")["lux"].to_numpy()
        assert np.allclose(res, want, atol=0.006)
        info = json.loads((folder / sc / "1330" / "grids_info.json").read_text())
        assert info == [{"count": 15, "name": "office", "identifier": "office", "group": "",
                         "full_id": "office"}]
    from honeybee.model import Model

    back = Model.from_hbjson(str(folder / "model.hbjson"))
    assert [g.identifier for g in back.properties.radiance.sensor_grids] == ["office"]


CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@needs_radiance
@pytest.mark.skipif(CHROMIUM is None, reason="chromium not installed (.ci/run installs it)")
def test_3d_view_draws_in_headless_chromium(traced, tmp_path):
    """The report's 3-D view opens from the report folder with no network and draws the scene:
    a headless Chromium screenshot (virtual time, no sleeps) is mostly not background."""
    from PIL import Image

    _, _, index = traced
    html = index.read_text()
    assert '<iframe src="view3d.html"' in html
    view = index.parent / "view3d.html"
    text = view.read_text()
    assert not re.search(r"<script[^>]*\ssrc=", text)   # viewer inline: nothing to fetch
    assert len(text) < 1_000_000 and 'getContext("webgl"' in text   # the light viewer
    shot = tmp_path / "view.png"
    subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                    "--no-first-run", "--disable-extensions", "--window-size=640,480",
                    "--virtual-time-budget=5000", f"--screenshot={shot}", view.as_uri()],
                   check=True, capture_output=True, timeout=120)
    img = np.asarray(Image.open(shot).convert("RGB"), float)
    assert img.shape[:2] == (480, 640)
    plot = img[72:446, 20:500]                     # the 3-D scene: below the buttons, left of
    #                                                the colour bar
    background = np.all(plot > 250, axis=2)
    green = (plot[..., 1] > plot[..., 0] + 25) & (plot[..., 1] > plot[..., 2] + 25)
    assert (~background).mean() > 0.3              # the scene fills the view
    assert green.mean() > 0.01                     # the crown (green leaves) is drawn
    assert plot.std() > 20                         # not a flat canvas


def test_annual_results_in_honeybee_layout(tmp_path):
    """radtree annual's hourly arrays → honeybee-radiance's annual folders (.ill per grid)."""
    from radtree.config.honeybee import HoneybeeSite
    from radtree.export.honeybee import write_annual_results
    from radtree.site.honeybee_model import model_grids

    model = office_model()
    grids, _ = model_grids(model, HoneybeeSite(tmp_path / "m.hbjson", 0.8, 1.0))
    n = len(grids["office"])
    days = np.repeat(np.arange(365), 24)
    month = np.searchsorted(np.cumsum([31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31]),
                            days, side="right") + 1
    day = days - np.concatenate([[0], np.cumsum([31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30])]
                                )[month - 1] + 1
    hour = np.tile(np.arange(24) + 0.5, 365)
    up = (hour > 6) & (hour < 19)
    lux = np.where(up, 100.0 + np.arange(n)[:, None] + hour[None, :], 0.0)
    path = tmp_path / "hourly.npz"
    np.savez(path, month=month, day=day, hour=hour, total__with__office=lux,
             direct__with__office=lux / 2, total__with__facade=lux[:2])
    folders = write_annual_results(path, model, tmp_path / "annual")
    assert [f.name for f in folders] == ["with"]
    hours = np.loadtxt(folders[0] / "sun-up-hours.txt")
    assert len(hours) == 365 * 13 and hours[0] == 6.5 and hours[-1] == 364 * 24 + 18.5
    ill = np.loadtxt(folders[0] / "__static_apertures__/default/total/office.ill")
    assert ill.shape == (n, 365 * 13)
    assert ill[3, 0] == pytest.approx(103 + 6.5)
    direct = np.loadtxt(folders[0] / "__static_apertures__/default/direct/office.ill")
    assert np.allclose(direct, ill / 2, atol=0.05)
    assert json.loads((folders[0] / "grids_info.json").read_text())[0]["count"] == n == 15


def test_example_model_is_the_scripts_and_loads():
    """examples/honeybee-office: the committed model.hbjson is what make_model.py makes, and
    the project reads it (two offices, their grids, the context shade, interior wall once)."""
    import importlib.util

    from radtree.pipeline.assemble import make_scene

    from .conftest import ROOT

    folder = ROOT / "examples" / "honeybee-office"
    spec = importlib.util.spec_from_file_location("make_model", folder / "make_model.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    made = module.make_model()
    project = load_project(folder)
    scene = make_scene(project, project.scenario("model")).scene
    committed = json.loads((folder / "model.hbjson").read_text())
    assert [r["identifier"] for r in committed["rooms"]] == [r.identifier for r in made.rooms]
    assert {g: len(scene.grids[g]) for g in ("Office_1", "Office_2")} == {
        "Office_1": 96, "Office_2": 96}   # (4 − 0) × (6 − 0) m at 0.5 m cells
    assert scene.mesh("hb_generic_exterior_window_vis_0.64").area() == pytest.approx(
        2 * 0.4 * 4 * 3)
    assert scene.mesh("hb_generic_exterior_shade_0.35").area() == pytest.approx(40 * 12)
    # walls: façade minus windows, back, outer sides, and the shared wall once (of the
    # interior pair), not twice
    walls = 2 * (4 * 3 * 0.6 + 4 * 3) + 2 * 6 * 3 + 6 * 3
    assert scene.mesh("hb_generic_wall_0.50").area() == pytest.approx(walls)


@pytest.fixture(scope="module")
def sun_build(tmp_path_factory):
    """The one-room model built by radtree on the winter solstice at 12:30 (sun 33° up, 5°
    from north: it falls through the north window onto the work plane), its octree made."""
    from radtree.engines.radiance.binaries import require_radiance
    from radtree.pipeline.build import build_project

    toml = TOML.replace('date = "2024-12-22"', 'date = "2024-06-21"').replace(
        'hours = ["13:30"]', 'hours = ["12:30"]')
    folder = write_project(tmp_path_factory.mktemp("hbsun") / "p", toml=toml)
    (folder / "dni.csv").write_text("time,direct_normal_lux\n12:30,80000\n")
    project = load_project(folder)
    build_project(project, pictures=False)
    build = project.build_dir / "open"
    subprocess.run(["make", "octrees/1230.oct"], cwd=build, env=require_radiance().env(),
                   check=True, capture_output=True)
    return project, build


def _rtrace_repeats(build: Path, octree: Path, opts: list[str], repeats: int) -> np.ndarray:
    """(repeats, sensors) lux: the office grid fed ``repeats`` times to one fixed-seed rtrace
    (each copy draws its own random numbers: independent, reproducible estimates)."""
    from radtree.engines.radiance.binaries import require_radiance
    from radtree.engines.radiance.writer import rgb_to_lux

    pts = (build / "grids" / "office.pts").read_text()
    out = subprocess.run(["rtrace", *opts, str(octree)], cwd=build, input=(pts * repeats).encode(),
                         capture_output=True, check=True, env=require_radiance().env()).stdout
    return rgb_to_lux(np.loadtxt(out.decode().splitlines()).reshape(-1, 3)).reshape(repeats, -1)


@needs_radiance
def test_cross_tool_with_the_sun(sun_build, tmp_path):
    """With the sun: radtree's octree and honeybee-radiance's translation of the same model
    (same sky, ground and options): the direct sun (-ab 0) per sensor within 0.5 % (of the
    sunlit sensors' values; the others both 0), and the total (-ab 2 -ad 1024, eight
    independent fixed-seed estimates each) mean within 2 % or 3 combined standard errors."""
    from honeybee.model import Model
    from honeybee_radiance.writer import model_to_rad

    from radtree.engines.radiance.binaries import FIXED_SEED, require_radiance

    project, build = sun_build
    model = Model.from_hbjson(str(project.honeybee.model))
    geometry, modifiers = model_to_rad(model)
    (tmp_path / "modifiers.rad").write_text(modifiers)
    (tmp_path / "model.rad").write_text(geometry)
    hb = tmp_path / "hb.oct"
    with hb.open("wb") as fh:
        subprocess.run(["oconv", str(tmp_path / "modifiers.rad"), str(tmp_path / "model.rad"),
                        "skies/1230_ground.rad", "geometry/ground.rad", "skies/1230.sky"],
                       cwd=build, stdout=fh, check=True, env=require_radiance().env())
    ours_oct = build / "octrees" / "1230.oct"
    direct = ["-h", "-I", FIXED_SEED, "-ab", "0"]
    a, b = (_rtrace_repeats(build, o, direct, 1)[0] for o in (ours_oct, hb))
    lit = a > 1.0
    assert lit.sum() >= 3 and (~lit).sum() >= 1      # the sun patch covers some sensors
    assert np.all(b[~lit] <= 1e-3 * a.max())
    rel = np.abs(b[lit] / a[lit] - 1.0)
    assert rel.max() < 0.005, rel
    total = ["-h", "-I", FIXED_SEED, "-ab", "2", "-ad", "1024", "-aa", "0", "-lw", "1e-4"]
    A, B = (_rtrace_repeats(build, o, total, 8).mean(axis=1) for o in (ours_oct, hb))
    se = float(np.hypot(A.std(ddof=1), B.std(ddof=1)) / np.sqrt(len(A)))
    diff = float(B.mean() - A.mean())
    print(f"with the sun: direct {int(lit.sum())} sunlit sensors, max |Δ| "
          f"{100 * rel.max():.3f} %; total mean radtree {A.mean():.1f}, honeybee "
          f"{B.mean():.1f} lx ({100 * diff / A.mean():+.2f} %, {diff / se:+.2f} SE)")
    assert abs(diff) <= max(0.02 * A.mean(), 3.0 * se)


def test_annual_results_load_in_honeybee_radiance_postprocess(tmp_path):
    """radtree's annual folder (write_annual_results) read by honeybee-radiance-postprocess
    gives radtree's own DA300 and UDI per sensor (occupied 8–18 h, sun-down hours dark)."""
    pytest.importorskip("honeybee_radiance_postprocess")
    from honeybee_radiance_postprocess.results.annual_daylight import AnnualDaylight

    from radtree.annual.metrics import daylight_autonomy, udi
    from radtree.annual.schedule import occupied
    from radtree.config.honeybee import HoneybeeSite
    from radtree.export.honeybee import write_annual_results
    from radtree.site.honeybee_model import model_grids

    model = office_model()
    grids, _ = model_grids(model, HoneybeeSite(tmp_path / "m.hbjson", 0.8, 1.0))
    assert len(grids["office"]) == 15
    days = np.repeat(np.arange(365), 24)
    ends = np.cumsum([31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31])
    month = np.searchsorted(ends, days, side="right") + 1
    day = days - np.concatenate([[0], ends[:-1]])[month - 1] + 1
    hour = np.tile(np.arange(24) + 0.5, 365)
    up = (hour > 6) & (hour < 19)
    rng = np.random.default_rng(7)              # every UDI band reached, no value on a limit
    lux = np.where(up, np.exp(rng.uniform(np.log(20.0), np.log(9000.0), (15, hour.size))),
                   0.0).round(1)               # as the .ill files write them (0.1 lx)
    lux[np.isin(lux, [100.0, 300.0, 3000.0])] += 0.1
    path = tmp_path / "hourly.npz"
    np.savez(path, month=month, day=day, hour=hour, total__with__office=lux,
             direct__with__office=lux / 2)
    folder = write_annual_results(path, model, tmp_path / "annual")[0]
    occ = occupied(hour, (8.0, 18.0))
    res = AnnualDaylight(str(folder), schedule=occ.astype(int).tolist())
    da, _, u, lower, upper, info = res.annual_metrics(threshold=300, min_t=100, max_t=3000)
    assert [g["full_id"] for g in info] == ["office"]
    ours = udi(lux, occ)
    assert np.allclose(np.asarray(da[0]), daylight_autonomy(lux, occ), atol=1e-6)
    assert np.allclose(np.asarray(lower[0]), ours["udi_below_100"], atol=1e-6)
    assert np.allclose(np.asarray(u[0]), ours["udi_100_300"] + ours["udi_300_3000"], atol=1e-6)
    assert np.allclose(np.asarray(upper[0]), ours["udi_above_3000"], atol=1e-6)
    assert 5.0 < ours["udi_above_3000"].mean() < 60.0 and ours["udi_below_100"].mean() > 20.0
