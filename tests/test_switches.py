"""The one registry of dotted keys (radtree.config.switches) at every entry point: the project
file's fields and tables, scenario ``switches``, ``radtree sweep --set`` / ``--param`` and
``[sweep.*]``, diagnose effects, ``load_project`` overrides and the permeability scan. Each
rejection names the key as written and lists the known keys (close matches first)."""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from radtree.cli import main
from radtree.config import (
    FIELD,
    KEYS,
    PATH_FIELDS,
    SWITCH,
    Louvers,
    Scenario,
    SchemaError,
    effective_project,
    known,
    load_project,
    lookup_key,
)
from radtree.config.spec import table_fields
from radtree.config.switches import TABLES, table_keys
from radtree.errors import ConfigError

from .conftest import MENDOZA, copy_project

LOUVERS_FIELDS = [f.name for f in fields(Louvers)]


def _lists_all(message: str, names) -> bool:
    return all(n in message for n in names)


# ---------------------------------------------------------------- the registry itself
def test_every_dataclass_field_is_a_key():
    for table, cls in TABLES.items():
        for f in table_fields(cls):
            if f.name == "ground_reflectance_table" or f"{table}.{f.name}" in TABLES:
                continue  # derived from street.ground_reflectance; a sub-table
            toml = {"as_": "as", "direct_normal_table": "direct_normal"}.get(f.name, f.name)
            assert f"{table}.{toml}" in KEYS, (table, f.name)
    assert set(table_keys("tree.louvers")) == set(LOUVERS_FIELDS)
    assert PATH_FIELDS == ("project.measured", "project.measured_rows",
                           "street.ground_reflectance", "light.direct_normal", "light.epw",
                           "tree.photo", "tree.points", "tree.voxels", "tree.points_scans",
                           "tree.perforated.photo",
                           "tree.bsdf.xml")


def test_toml_names_are_mapped_once():
    assert lookup_key("engine.as").attr == ("engine", "as_")
    assert lookup_key("light.direct_normal", FIELD).attr == ("light", "direct_normal_table")
    with pytest.raises(ConfigError, match=r"unknown switch 'engine\.as_'.*did you mean engine\.as"):
        lookup_key("engine.as_")
    p = load_project(MENDOZA)
    sw = effective_project(p, Scenario("x", "louvers", switches={"engine.as": 16}))
    assert sw.engine.radiance.as_ == 16
    assert load_project(MENDOZA, overrides={"engine.as": 8}).engine.radiance.as_ == 8


def test_switch_uses():
    switches = known(SWITCH)
    assert "reflection.unfiltered" in switches and "tree.louvers.reading" in switches
    assert "engine.ab" in switches and "street.opposite_reflectance" in switches
    for not_switchable in ("office.bays", "site.hours", "light.epw", "project.measured"):
        assert not_switchable not in switches and not_switchable in known(FIELD)
    assert "reflection.unfiltered" not in known(FIELD)
    assert lookup_key("louvers.layers") is lookup_key("tree.louvers.layers")


def test_dataclasses_validate_on_creation():
    with pytest.raises(SchemaError, match=r"tree\.louvers\.layers.*expected ≥ 1") as err:
        Louvers(layers=0)
    assert err.value.key == "tree.louvers.layers"
    with pytest.raises(SchemaError, match=r"tree\.louvers\.transmittance.*exceeds 1"):
        Louvers(transmittance=0.95)
    assert type(Louvers(crossings=15).crossings) is float
    with pytest.raises(SchemaError, match="scenario.model"):
        Scenario("x", "sponge")


def test_unknown_engine_name_names_the_file_field_and_the_engines(tmp_path: Path):
    """Engine names belong to the engine registry: an unknown one fails when the engine is
    chosen, before any tracing, naming the project file, ``engine.name`` and the known names."""
    p = copy_project(tmp_path / "p", {r'^name = "auto" .*$': 'name = "cuda"'})
    res = CliRunner().invoke(main, ["simulate", str(p)])
    assert res.exit_code == 2, res.output
    assert "radtree.toml, field 'engine.name': unknown engine 'cuda'" in res.output
    assert "auto, radiance, numpy" in res.output and "Traceback" not in res.output


# ---------------------------------------------------------------- the project file
def test_project_file_unknown_field_lists_every_known_one(tmp_path: Path):
    p = copy_project(tmp_path / "p", {r"^(layers = 5 .*)$": r"\1\nslat_sise_m = 0.2"})
    with pytest.raises(ConfigError) as err:
        load_project(p)
    msg = str(err.value)
    assert "field 'tree.louvers.slat_sise_m': unknown field" in msg
    assert "did you mean slat_size_m?" in msg
    assert _lists_all(msg.split("known here:")[1], LOUVERS_FIELDS)  # all twelve
    res = CliRunner().invoke(main, ["build", str(p)])
    assert res.exit_code == 2 and "slat_sise_m" in res.output and "Traceback" not in res.output


def test_project_file_unknown_table_lists_every_known_one(tmp_path: Path):
    p = copy_project(tmp_path / "p", {r"^\[tree\.louvers\]$": "[tree.lovers]"})
    with pytest.raises(ConfigError) as err:
        load_project(p)
    msg = str(err.value)
    assert "field 'tree.lovers': unknown table" in msg and "did you mean louvers" in msg
    assert _lists_all(msg, ["dome", "crown", "homogeneous", "perforated", "louvers", "form"])
    p2 = copy_project(tmp_path / "p2", {r"^\[sensors\]$": "[sensor]"})
    with pytest.raises(ConfigError, match=r"field 'sensor': unknown table \(did you mean "
                       r"sensors\? known here: project, site, street, light, tree, sensors"):
        load_project(p2)


# ---------------------------------------------------------------- scenario switches
def test_scenario_switch_unknown_key(tmp_path: Path):
    p = copy_project(tmp_path / "p", {r'^(switches = \{ "louvers\.arrangement" = "volume",)':
                                      r'\1 "reflection.unfilterd" = 0.1,'})
    with pytest.raises(ConfigError) as err:
        load_project(p)
    msg = str(err.value)
    assert "radtree.toml" in msg and "switches.reflection.unfilterd" in msg
    assert "unknown switch 'reflection.unfilterd'; did you mean reflection.unfiltered" in msg
    assert _lists_all(msg, known(SWITCH))
    # a scenario made in code is checked too
    with pytest.raises(ConfigError, match=r"unknown switch 'reflection\.unfilterd'"):
        Scenario("x", "louvers", switches={"reflection.unfilterd": 0.1})


def test_scenario_switch_wrong_type_and_bounds(tmp_path: Path):
    p = copy_project(tmp_path / "p", {r'"louvers\.crossings" = 15': '"louvers.crossings" = "many"'})
    with pytest.raises(ConfigError, match=r"scenario\[6\]\.switches\.louvers\.crossings': "
                       r"expected a number, got 'many' \(tree\.louvers\.crossings: a number "
                       r"≥ 0 and ≤ 60\)"):
        load_project(p)
    with pytest.raises(ConfigError, match=r"switches\.engine\.ab': expected an integer, got 2\.5"):
        Scenario("x", "louvers", switches={"engine.ab": np.float64(2.5)})  # shown as written
    with pytest.raises(ConfigError, match=r"switches\.reflection\.ground': got 'shady', expected "
                       "one of shaded, open"):
        Scenario("x", "louvers", switches={"reflection.ground": "shady"})
    with pytest.raises(ConfigError, match=r"reflection\.unfiltered': got 1\.5, expected ≤ 1"):
        Scenario("x", "louvers", switches={"reflection.unfiltered": 1.5})
    with pytest.raises(ConfigError, match=r"unknown switch 'office\.bays' \(a field of the "
                       "project file that a scenario cannot switch"):
        Scenario("x", "louvers", switches={"office.bays": 5})
    assert Scenario("x", "louvers", switches={"engine.ab": 6.0}).switches == {"engine.ab": 6.0}
    assert effective_project(load_project(MENDOZA), Scenario(
        "x", "louvers", switches={"engine.ab": 6.0})).engine.ab == 6


# ---------------------------------------------------------------- radtree sweep
@pytest.fixture
def small(tmp_path: Path) -> Path:
    return copy_project(tmp_path / "proj", hours=["10:30"])


def test_sweep_set_unknown_key_cli(small: Path):
    res = CliRunner().invoke(main, ["sweep", str(small), "-p", "sensors.height_m=4,5",
                                    "--set", "engine.abb=3", "--scheduler", "sequential",
                                    "--no-progress"])
    assert res.exit_code == 2, res.output
    out = " ".join(res.output.split())
    assert "field 'engine.abb': cannot set engine.abb: not a field of the project file" in out
    assert "did you mean engine.ab" in out and _lists_all(out, known(FIELD))
    assert not (small / "sweep" / "cases").exists()


def test_sweep_param_unknown_key_cli(small: Path):
    res = CliRunner().invoke(main, ["sweep", str(small), "-p", "tree.louvers.slat_sise_m=0.2,0.3",
                                    "--scheduler", "sequential", "--no-progress"])
    assert res.exit_code == 2, res.output
    out = " ".join(res.output.split())
    assert "cannot sweep tree.louvers.slat_sise_m: not a field of the project file" in out
    assert "did you mean tree.louvers.slat_size_m" in out and _lists_all(out, known(FIELD))


def test_sweep_tables_unknown_keys(small: Path):
    from radtree.sweep import plan_sweep

    toml = small / "radtree.toml"
    base = toml.read_text()
    toml.write_text(base + '\n[sweep.params]\n"tree.crown.nope" = [1, 2]\n')
    with pytest.raises(ConfigError, match=r"cannot sweep tree\.crown\.nope: not a field.*"
                       r"known fields: engine\.aa"):
        plan_sweep(small)
    toml.write_text(base + '\n[sweep.set]\n"light.skyy" = "perez"\n')
    with pytest.raises(ConfigError, match=r"cannot set light\.skyy: not a field.*did you mean "
                       r"light\.sky"):
        plan_sweep(small, ["sensors.height_m=4,5"])
    toml.write_text(base)
    with pytest.raises(ConfigError, match=r"tree\.louvers\.arrangement=0:1:2: a numeric range "
                       "for a field holding one of layers, volume"):
        plan_sweep(small, ["tree.louvers.arrangement=0:1:2"])


# ---------------------------------------------------------------- diagnose, overrides, scans
def test_diagnose_effect_keys():
    from radtree.diagnose.catalogue.light import UnfilteredGround
    from radtree.diagnose.effects import (
        EFFECTS,
        EffectContext,
        check_effect_keys,
        get_effect,
    )

    check_effect_keys(EFFECTS)  # the catalogue's keys are all registered

    class Misspelt(UnfilteredGround):
        name = "misspelt"
        key = "reflection.unfilterd"

    with pytest.raises(ConfigError) as err:
        check_effect_keys([Misspelt()])
    msg = str(err.value)
    assert "effect misspelt: switches.reflection.unfilterd" in msg
    assert "did you mean reflection.unfiltered" in msg and _lists_all(msg, known(SWITCH))
    ctx = EffectContext(load_project(MENDOZA))
    sc = ctx.project.scenario("B")
    with pytest.raises(ConfigError, match=r"unknown switch 'reflection\.unfilterd'"):
        Misspelt().switch_on(ctx, sc, 0.1)
    assert get_effect("unfiltered_ground").switch_on(ctx, sc, 0.1).switches[
        "reflection.unfiltered"] == 0.1


def test_overrides_and_permeability_scan_keys():
    with pytest.raises(ConfigError, match=r"unknown field 'tree\.louvers\.slat_sise_m'; did you "
                       r"mean tree\.louvers\.slat_size_m"):
        load_project(MENDOZA, overrides={"tree.louvers.slat_sise_m": 0.2})
    from radtree.calibrate.scan import scan_permeability

    p = load_project(MENDOZA)
    with pytest.raises(ConfigError, match=r"unknown switch 'louvers\.transmitance'.*did you "
                       r"mean louvers\.transmittance"):
        scan_permeability(p, "A", "louvers.transmitance", [0.5])
    with pytest.raises(ConfigError, match=r"got 1\.5, expected ≤ 1"):
        scan_permeability(p, "A", "louvers.transmittance", [0.5, 1.5])
