from pathlib import Path

import pytest
from click.testing import CliRunner

from radtree.cli import main
from radtree.config import load_project
from radtree.errors import ConfigError

from .conftest import MENDOZA, copy_project


def test_mendoza_project_loads():
    p = load_project(MENDOZA)
    assert p.site.latitude == -32.89 and p.site.longitude == -68.83
    assert p.site.hours == ("10:30", "11:30", "12:30", "13:30", "14:30", "15:30", "16:30")
    assert p.street.facade_azimuth_deg == 0.0
    assert [s.name for s in p.scenarios] == ["A", "B", "C", "D", "E", "A-sky", "F", "A-photo",
                                             "C-photo", "F-photo"]
    assert [s.reflection for s in p.scenarios] == ["calculated", "traced", "traced",
                                                   "calculated", "traced", "calculated", "traced",
                                                   "calculated", "traced", "traced"]
    assert p.tree.louvers.layers == 5 and p.tree.louvers.specular_fraction == 0.9
    assert p.engine.radiance.as_ == 0 and p.engine.radiance.aa == 0 and p.engine.ab is None


def test_params_hash_changes_with_parameters(tmp_path):
    a = load_project(MENDOZA)
    b = load_project(MENDOZA, overrides={"tree.louvers.layers": 6})
    assert a.params_hash(a.scenarios[0]) != b.params_hash(b.scenarios[0])
    assert a.params_hash(a.scenarios[0]) == load_project(MENDOZA).params_hash(a.scenarios[0])


BAD = [
    # (pattern, replacement, words the message must contain)
    (r"^latitude = -32.89", "", "site.latitude"),                           # missing field
    (r"^latitude = -32.89", 'latitude = "south"', "expected a number"),     # wrong type
    (r'"10:30", "11:30"', '"10.30", "11:30"', "HH:MM"),                       # unknown hour format
    (r"^facade_reflectance = 0.90", "facade_reflectance = -0.2", "street.facade_reflectance"),
    (r"^transmittance = 0.5 ", "transmittance = 0.95 ", "exceeds 1"),        # R + T > 1
    (r'^model = "louvers"', 'model = "sponge"', "expected one of"),
    (r"^width_m = 20.0", "width_m = 20.0\nwidht = 3", "unknown field"),
    (r'^direct_normal = ".*"', 'direct_normal = "nope.csv"', "file not found"),
    (r"^\[site\]", "[site", "not valid TOML"),
]


@pytest.mark.parametrize("pat, rep, words", BAD)
def test_invalid_project_gives_clear_error_and_no_build(tmp_path, pat, rep, words):
    p = copy_project(tmp_path / "p", {pat: rep})
    with pytest.raises(ConfigError) as err:
        load_project(p)
    assert words in str(err.value)
    assert "radtree.toml" in str(err.value)
    result = CliRunner().invoke(main, ["build", str(p)])
    assert result.exit_code == 2
    assert words in result.output
    assert "Traceback" not in result.output
    assert not (p / "build").exists()


def test_sun_below_horizon_is_rejected(tmp_path):
    p = copy_project(tmp_path / "p", hours=["03:30"])
    (p / "data" / "direct_normal_illuminance.csv").write_text("time,direct_normal_lux\n03:30,0\n")
    result = CliRunner().invoke(main, ["build", str(p)])
    assert result.exit_code == 2
    assert "below the horizon" in result.output
    assert not any((p / "build").glob("*/Makefile"))


def test_missing_project(tmp_path):
    result = CliRunner().invoke(main, ["build", str(tmp_path / "nothing")])
    assert result.exit_code == 2
    assert "project file not found" in result.output


def test_overrides_validate(tmp_path):
    with pytest.raises(ConfigError, match="tree.louvers.layers"):
        load_project(MENDOZA, overrides={"tree.louvers.layers": 0})
    assert isinstance(load_project(MENDOZA).root, Path)
