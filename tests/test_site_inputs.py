"""Bad site inputs (issue 37): one line naming the file, field or feature, the value as written
and the fix; exit 2; nothing half-written. Each check runs in ``new`` and ``build`` alike."""

from __future__ import annotations

from pathlib import Path

import pytest
import tomlkit
from click.testing import CliRunner

from radtree.cli import main
from tests.conftest import ROOT

EPW = ROOT / "examples" / "office-block" / "data" / "mendoza_generated.epw"
MADRID = ["--lat", "40.42", "--lon", "-3.70", "--tz", "Europe/Madrid"]


def _csv(tmp_path: Path, rows: list[str]) -> Path:
    p = tmp_path / "trees.csv"
    p.write_text("id,lon,lat,species,height_m,crown_diameter_m,crown_base_m\n"
                 + "\n".join(rows) + "\n")
    return p


def _refused(res, *parts: str) -> None:
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1, res.output
    for part in parts:
        assert part in lines[0], (part, lines[0])


def test_swapped_longitude_and_latitude_is_named(tmp_path: Path) -> None:
    trees = _csv(tmp_path, ["A,-3.7031,40.4168,Platanus × acerifolia,14,8,3",
                            "B,40.4170,-3.7030,Platanus × acerifolia,14,8,3"])
    res = CliRunner().invoke(main, ["new", str(tmp_path / "p"), *MADRID, "--trees", str(trees),
                                    "--template", "district"])
    _refused(res, "trees.csv", "feature 'B'", "40.417, -3.703", "km from the other trees",
             "longitude and latitude swapped")
    assert not (tmp_path / "p").exists()


def test_inventory_spread_over_10_km_is_refused(tmp_path: Path) -> None:
    """Eight trees on a 4.9 km circle: none far from the rest, a 13.9 km bounding box."""
    import math

    rows = [f"T{k},{-3.70 + 0.0578 * math.cos(k * math.pi / 4):.5f},"
            f"{40.42 + 0.0441 * math.sin(k * math.pi / 4):.5f},Platanus × acerifolia,14,8,3"
            for k in range(8)]
    res = CliRunner().invoke(main, ["new", str(tmp_path / "p"), *MADRID, "--trees",
                                    str(_csv(tmp_path, rows)), "--template", "district"])
    _refused(res, "trees.csv", "the trees spread over 13.", "split the inventory")
    assert not (tmp_path / "p").exists()


def test_all_inputs_far_from_the_given_site(tmp_path: Path) -> None:
    trees = _csv(tmp_path, ["A,40.4168,-3.7031,Platanus × acerifolia,14,8,3",
                            "B,40.4170,-3.7030,Platanus × acerifolia,14,8,3"])
    res = CliRunner().invoke(main, ["new", str(tmp_path / "p"), *MADRID, "--trees", str(trees),
                                    "--template", "district"])
    _refused(res, "trees.csv", "km from the site (latitude 40.42, longitude -3.7",
             "longitude and latitude swapped")
    assert not (tmp_path / "p").exists()


def test_new_checks_the_inventory_as_build_does(tmp_path: Path) -> None:
    trees = _csv(tmp_path, ["A,-3.7031,40.4168,Platanus × acerifolia,fourteen,8,3"])
    res = CliRunner().invoke(main, ["new", str(tmp_path / "p"), *MADRID, "--trees", str(trees),
                                    "--template", "district"])
    _refused(res, "trees.csv", "feature 'A'", "height_m", "'fourteen'")
    assert not (tmp_path / "p").exists()


def test_an_epw_of_another_site_is_refused(tmp_path: Path) -> None:
    res = CliRunner().invoke(main, ["new", str(tmp_path / "p"), *MADRID, "--epw", str(EPW)])
    _refused(res, "mendoza_generated.epw", "latitude -32.89", "more than 0.5°",
             "leave --epw out")
    # … and a project edited afterwards to another site: refused at build, not traced
    res = CliRunner().invoke(main, ["new", str(tmp_path / "q"), "--epw", str(EPW)])
    assert res.exit_code == 0, res.output
    toml = tmp_path / "q" / "radtree.toml"
    doc = tomlkit.parse(toml.read_text())
    doc["site"]["latitude"], doc["site"]["longitude"] = 40.42, -3.70
    toml.write_text(tomlkit.dumps(doc))
    res = CliRunner().invoke(main, ["build", str(tmp_path / "q")])
    _refused(res, "field 'light.epw'", "is for latitude -32.89, longitude -68.83",
             "[site] is at latitude 40.42, longitude -3.7", "clear-sky")
    assert not (tmp_path / "q" / "build").exists()


def test_a_time_zone_changed_after_the_epw_is_refused(tmp_path: Path) -> None:
    res = CliRunner().invoke(main, ["new", str(tmp_path / "q"), "--epw", str(EPW)])
    assert res.exit_code == 0, res.output
    toml = tmp_path / "q" / "radtree.toml"
    doc = tomlkit.parse(toml.read_text())
    doc["site"]["time_zone"] = "UTC-2"
    toml.write_text(tomlkit.dumps(doc))
    res = CliRunner().invoke(main, ["build", str(tmp_path / "q")])
    _refused(res, "field 'light.epw'", "standard time UTC-3 h", "'UTC-2'")


@pytest.mark.parametrize("value, expected", [
    ("Europe/Madird", "not a known IANA time zone"),
    ("UTC+15", "offsets lie between UTC-14 and UTC+14")])
def test_a_bad_time_zone_is_named(tmp_path: Path, value: str, expected: str) -> None:
    res = CliRunner().invoke(main, ["new", str(tmp_path / "p"), "--lat", "40.42", "--lon",
                                    "-3.70", "--tz", value])
    _refused(res, f"'{value}'", expected)
    assert not (tmp_path / "p").exists()


def test_daylight_saving_moves_the_epw_row(tmp_path: Path) -> None:
    """09:00 CEST on 21 June is 08:00 standard time: the EPW row ending at 09 (08:00–09:00)."""
    from radtree.config import load_project
    from radtree.light.clearsky import write_generated_epw
    from radtree.light.weather import epw_hour_illuminance, read_epw

    epw = write_generated_epw(tmp_path / "madrid.epw", "Madrid", 40.42, -3.70, 667.0, 1.0)
    res = CliRunner().invoke(main, ["new", str(tmp_path / "p"), *MADRID, "--elevation", "667",
                                    "--epw", str(epw)])
    assert res.exit_code == 0, res.output
    p = load_project(tmp_path / "p")
    assert p.light.weather == "epw" and p.site.utc_offset_hours == 1.0
    rows = read_epw(epw).illuminance()
    got = epw_hour_illuminance(p, ["09:00", "13:30"])
    assert got["09:00"] == rows[(6, 21, 8)] and got["13:30"] == rows[(6, 21, 13)]
