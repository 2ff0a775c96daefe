"""radtree export: crowns as Honeybee shades with an hourly transmittance schedule, IDF, the
Schedule:File CSV, glTF / OBJ — and the schedule against radtree's own direct-sun trace.

One free-standing louvers crown (2 layers, cover 0.6: a crown the sun gets through), 16 rays
per hour and crown so that the year takes a few seconds.
"""

from __future__ import annotations

import re
import shutil

import numpy as np
import pytest

from radtree.config import EngineParams, load_project
from radtree.light.sky import SkyState
from radtree.light.sun import local_datetime, sun_position
from radtree.pipeline.assemble import facade_frame
from radtree.verify.energyplus import SMALL_PROJECT

from .conftest import needs_radiance

pytest.importorskip("honeybee.model")   # a guard only: CI installs radtree[honeybee]

TOML = SMALL_PROJECT   # one free louvers crown (radtree.verify.energyplus)
RAYS = 16


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    folder = tmp_path_factory.mktemp("export")
    (folder / "radtree.toml").write_text(TOML)
    (folder / "dni.csv").write_text("time,direct_normal_lux\n13:30,80000\n")
    return load_project(folder)


@pytest.fixture(scope="module")
def exported(project, tmp_path_factory):
    """``radtree export PROJECT --format honeybee --definition beam`` (16 rays per hour): the
    HBJSON loaded back with honeybee-core, and the schedules as written (with their crowns and
    leaf states)."""
    from click.testing import CliRunner
    from honeybee.model import Model

    from radtree.cli import main
    from radtree.export.transmittance import (
        CrownSchedule,
        crown_envelopes,
        default_leaf_schedule,
        year_hours,
    )

    out = tmp_path_factory.mktemp("hbjson")
    r = CliRunner().invoke(main, ["export", str(project.root), "--format", "honeybee", "--out",
                                  str(out), "--rays", str(RAYS), "--definition", "beam"])
    assert r.exit_code == 0, r.output
    path = out / "radtree_crowns.hbjson"
    assert f"wrote {path}" in r.output and "1 crown shades" in r.output
    model = Model.from_hbjson(str(path))
    hours = year_hours(project)
    leaf = default_leaf_schedule(project, None, None)
    in_leaf = np.asarray(leaf.in_leaf(np.array([h.month for h in hours]),
                                      np.array([h.day for h in hours])), bool)
    crowns = crown_envelopes(project, project.scenarios[0], facade_frame(project))
    schedules = [CrownSchedule(c, np.array(s.properties.energy.transmittance_schedule.values),
                               in_leaf) for c, s in zip(crowns, model.shade_meshes)]
    return model, schedules


@pytest.fixture(scope="module")
def year(project, exported):
    from radtree.export.transmittance import crown_models

    return crown_models(project, project.scenarios[0], facade_frame(project)), exported[1]


def test_schedule_year_and_seasons(project, year):
    from radtree.export.transmittance import year_hours

    _, schedules = year
    assert len(schedules) == 1
    cs = schedules[0]
    assert cs.values.shape == (8760,)
    assert np.all((cs.values >= 0) & (cs.values <= 1))
    hours = year_hours(project)
    assert hours[0].isoformat() == "2023-01-01T00:30:00-03:00"
    # Mendoza defaults: leaf-on 15 Oct (inclusive) to 1 June (exclusive)
    assert cs.leaf_on.sum() == 24 * (365 - (30 + 31 + 31 + 30 + 14))   # June … 14 Oct bare
    assert cs.leaf_on[0] and not cs.leaf_on[24 * 200]
    # the bare crown passes more of the sun than the leafed one
    noon = np.array([h.hour == 12 for h in hours])
    assert cs.values[noon & ~cs.leaf_on].mean() > cs.values[noon & cs.leaf_on].mean() + 0.1


@needs_radiance
def test_schedule_agrees_with_radiance_direct_sun(project, year, tmp_path):
    """Three hours of the exported schedule (as written in the HBJSON) against radtree's
    Radiance engine tracing the sun (-ab 0) at the same points under the crown:
    E / (DNI · sin altitude), averaged → within 1 %."""
    from radtree.engines.radiance.interface import RadianceEngine
    from radtree.export.transmittance import bundle, year_hours
    from radtree.scene import Scene, SensorGrid

    (meshes, _, materials, _), schedules = year
    cs = schedules[0]
    hours = year_hours(project)
    found = []
    for k in (24 * 14 + 11, 24 * 59 + 16, 24 * 334 + 9):   # 15 Jan 11:30, 1 Mar 16:30, 1 Dec 9:30
        h = hours[k]
        assert cs.leaf_on[k]
        sun = sun_position(local_datetime(h.date().isoformat(), h.strftime("%H:%M"), -3.0),
                           project.site.latitude, project.site.longitude, 750)
        origins = bundle(cs.crown, sun.vector, RAYS)
        grid = SensorGrid("under", origins, np.tile([0, 0, 1.0], (len(origins), 1)))
        scene = Scene(list(meshes), dict(materials), {"under": grid})
        st = SkyState(time=h.strftime("%H:%M"), datetime=h, sun=sun, direct_normal_lux=1e5,
                      sky_model="none", ground_glow=False)
        eng = RadianceEngine()
        plan = eng.prepare(scene, [st], EngineParams(ab=0, lw=1e-6), 0, tmp_path / str(k))
        lux = eng.trace(plan, st.label)["under"].lux
        radiance_tau = float(np.mean(lux / (1e5 * np.sin(np.radians(sun.altitude_deg)))))
        found.append((cs.values[k], radiance_tau))
        assert cs.values[k] == pytest.approx(radiance_tau, rel=0.01), (h, found)
    print("schedule vs Radiance direct sun:", [f"{a:.5f}/{b:.5f} ({100 * (a / b - 1):+.4f} %)"
                                               for a, b in found])
    assert len({round(a, 3) for a, _ in found}) == 3   # three different sun positions


def test_honeybee_round_trip_idf_and_csv(project, exported, year, tmp_path):
    from radtree.export.honeybee import crown_shades, shade_model, write_idf, write_schedule_csv
    from radtree.export.run import leaf_material

    back, schedules = exported
    assert back.check_all(raise_exception=False) == ""
    assert len(back.shade_meshes) == 1 and not back.rooms
    shade = back.shade_meshes[0]
    assert shade.identifier == "radtree_crown_1"
    sched = shade.properties.energy.transmittance_schedule
    assert len(sched.values) == 8760 and sched.schedule_type_limit.identifier == "Fractional"
    assert len(shade.faces) == len(schedules[0].crown.faces)
    (meshes, _, materials, _), _ = year
    leaf = leaf_material(meshes, materials)
    mod = shade.properties.radiance.modifier
    assert mod.identifier == leaf.name == "leaf"
    c, trans, tspec = leaf.coefficients
    assert (mod.r_reflectance, mod.transmitted_diff, mod.transmitted_spec) == pytest.approx(
        (c, trans, tspec))

    model = shade_model(project.name, crown_shades(schedules, leaf))
    idf = write_idf(model, tmp_path).read_text()
    assert idf.count("Shading:Building:Detailed,") == len(shade.faces)
    assert "radtree_crown_1_transmittance" in idf
    shadow = ("ShadowCalculation,\n PolygonClipping,          !- calculation method\n"
              " Periodic,                 !- calculation update method\n"
              " 1,                        !- calculation frequency\n")
    assert shadow in idf

    csv, sidf = write_schedule_csv(schedules, tmp_path)
    lines = csv.read_text().splitlines()
    assert lines[0] == "crown_1" and len(lines) == 1 + 8760
    assert float(lines[1 + 4000]) == pytest.approx(schedules[0].values[4000], abs=1e-6)
    text = sidf.read_text()
    assert "Schedule:File," in text and "crown_transmittance.csv" in text and "8760" in text
    assert shadow in text


def test_total_schedule_by_default_with_its_caveats(project, exported, tmp_path):
    """The default definition (total) passes at least the beam every hour, more on average
    in leaf (the light the crown scatters forward), and the export prints the caveats."""
    from click.testing import CliRunner

    from radtree.cli import main

    r = CliRunner().invoke(main, ["export", str(project.root), "--format", "schedule", "--out",
                                  str(tmp_path), "--rays", str(RAYS)])
    assert r.exit_code == 0, r.output
    assert "transmittance (total)" in r.output
    assert "caveat: EnergyPlus passes a shade's scheduled transmittance on undeviated" in r.output
    assert "PixelCounting makes the shade opaque, EnergyPlus issue #9059" in r.output
    lines = (tmp_path / "crown_transmittance.csv").read_text().splitlines()[1:]
    total = np.array([float(x) for x in lines])
    beam = exported[1][0].values
    on = exported[1][0].leaf_on
    assert np.all(total >= beam - 1e-6)
    print(f"leaf-on mean: beam {beam[on].mean():.4f}, total {total[on].mean():.4f}")
    assert total[on].mean() > beam[on].mean() + 0.01


def test_cli_gltf_and_obj(project, tmp_path):
    import trimesh
    from click.testing import CliRunner

    from radtree.cli import main

    folder = tmp_path / "p"
    shutil.copytree(project.root, folder, ignore=shutil.ignore_patterns("build", "results"))
    for fmt, name in (("gltf", "crown_scene.glb"), ("obj", "crown_scene.obj")):
        r = CliRunner().invoke(main, ["export", str(folder), "--format", fmt, "--out",
                                      str(tmp_path / "out")])
        assert r.exit_code == 0, r.output
        path = tmp_path / "out" / name
        assert f"wrote {path}" in r.output
    glb = trimesh.load(tmp_path / "out" / "crown_scene.glb")
    assert {"facade", "ground", "opposite_facade", "tree_leaves", "tree_trunks"} <= set(
        glb.geometry)
    obj = (tmp_path / "out" / "crown_scene.obj").read_text()
    assert obj.count("\nf ") == sum(len(g.faces) for g in glb.geometry.values())


# --------------------------------------------------------------------------- the registry


def written_inputs(inputs, out):
    """A writer of a format registered by a test: what it got, as text."""
    path = out / "inputs.txt"
    path.write_text(f"{inputs.scenario.name} {inputs.schedules} {inputs.scene} "
                    f"{inputs.honeybee_model}\n")
    return [path]


def test_cli_choices_and_reference_rows_come_from_the_registry():
    from radtree.cli.export import export_command
    from radtree.export import FORMATS
    from radtree.export.registry import EXPORT_FORMATS, NEEDS, reference_rows

    choices = next(p for p in export_command.params if p.name == "fmt").type.choices
    assert list(choices) == list(EXPORT_FORMATS) == list(FORMATS) == [
        "honeybee", "idf", "schedule", "honeybee-scene", "gltf", "obj"]
    rows = reference_rows()
    assert [r[0] for r in rows] == list(EXPORT_FORMATS)
    assert rows[2] == ("schedule", EXPORT_FORMATS["schedule"].summary,
                       "crown, schedules, extra:honeybee")
    assert rows[3][2] == "honeybee_model, scene, extra:honeybee"
    assert rows[4][2] == "scene"
    for name, fmt in EXPORT_FORMATS.items():
        assert callable(fmt.writer()), name
        assert fmt.needs <= set(NEEDS)
        assert name in export_command.help


def test_a_new_format_is_one_writer_and_one_registry_line(project, tmp_path, monkeypatch):
    """A format registered at run time is offered to export_project, gets the scenario with a
    crown and only what it declares (no schedules traced, no scene built)."""
    from radtree.export.registry import EXPORT_FORMATS, ExportFormat
    from radtree.export.run import ExportOptions, export_project

    monkeypatch.setitem(EXPORT_FORMATS, "names", ExportFormat(
        f"{__name__}:written_inputs", "what the writer got", frozenset({"crown"})))
    paths = export_project(project, options=ExportOptions("names", tmp_path / "o"))
    assert paths == [tmp_path / "o" / "inputs.txt"]
    assert paths[0].read_text() == "crown None None None\n"
    with pytest.raises(ValueError, match="unknown needs"):
        ExportFormat(f"{__name__}:written_inputs", "x", frozenset({"annual"}))


def test_bad_export_options_name_the_field(project, tmp_path, monkeypatch):
    from radtree.errors import ConfigError, RadtreeError
    from radtree.export import registry
    from radtree.export.run import ExportOptions, export_project
    from radtree.export.schedule_options import ScheduleOptions

    with pytest.raises(ConfigError, match=r"export\.definition.*'diffuse'.*total, beam"):
        ScheduleOptions(definition="diffuse")
    with pytest.raises(ConfigError, match=r"export\.rays.*got 0"):
        ScheduleOptions(rays=0)
    with pytest.raises(ConfigError, match=r"export\.format.*'png'.*honeybee, idf"):
        ExportOptions("png", tmp_path)
    # a format whose extra is missing stops before tracing, with the pip command
    monkeypatch.setitem(registry.EXTRAS, "honeybee", ("radtree_no_such_module",))
    with pytest.raises(RadtreeError, match=r"pip install 'radtree\[honeybee\]'"):
        export_project(project, options=ExportOptions("schedule", tmp_path / "s"))
    assert not (tmp_path / "s").exists()


def test_scenario_without_crown_refused_and_library_quiet(project, tmp_path, capsys):
    import io

    from radtree import log
    from radtree.errors import ConfigError
    from radtree.export.run import ExportOptions, export_project

    folder = tmp_path / "p"
    shutil.copytree(project.root, folder, ignore=shutil.ignore_patterns("build", "results"))
    toml = folder / "radtree.toml"
    toml.write_text(toml.read_text() + '[[scenario]]\nname = "open"\nmodel = "none"\n')
    p = load_project(folder)
    with pytest.raises(ConfigError, match="scenario 'open' has no crown") as err:
        export_project(p, options=ExportOptions("idf", tmp_path / "x", scenario="open"))
    assert err.value.field == "--scenario"
    path = export_project(p, options=ExportOptions("obj", tmp_path / "o", scenario="open"))[0]
    assert path.name == "open_scene.obj" and capsys.readouterr().out == ""
    stream = io.StringIO()
    log.enable(stream=stream, progress=False)
    try:
        export_project(p, options=ExportOptions("gltf", tmp_path / "o", scenario="open"))
    finally:
        log.disable()
    assert re.fullmatch(rf"open: \d+ meshes, \d+ triangles → {tmp_path}/o/open_scene\.glb\n",
                        stream.getvalue())
