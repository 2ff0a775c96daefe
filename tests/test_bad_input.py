"""Bad input, every command: one short clear line, no traceback, a non-zero exit code."""

from __future__ import annotations

import math
import os
import re
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from radtree.cli import main
from radtree.config import load_project
from radtree.errors import ConfigError
from radtree.optics import Glass, Plastic, Trans, transmissivity_from_transmittance

from .conftest import CHESTNUT, copy_project


def run(args: list[str], env: dict | None = None):
    return CliRunner().invoke(main, args, env=env)


def assert_clear_failure(result, *words: str) -> None:
    assert result.exit_code in (2, 3), result.output  # bad input, or an engine failure
    assert "Traceback" not in result.output
    text = result.output.strip()
    assert text, "no message"
    lines = [ln for ln in text.splitlines() if ln.strip()]
    start = next((i for i, ln in enumerate(lines) if ln.lower().startswith("error")), 0)
    assert len(lines) - start <= 4, text   # the error: one line (+ command and stderr)
    for w in words:
        assert w.lower() in text.lower(), (w, text)


@pytest.fixture
def proj(tmp_path: Path) -> Path:
    return copy_project(tmp_path / "p", hours=["12:30", "13:30"])


def edit(p: Path, pat: str, rep: str) -> Path:
    toml = p / "radtree.toml"
    text, n = re.subn(pat, rep, toml.read_text(), flags=re.M)
    assert n
    toml.write_text(text)
    return p


# ---------------------------------------------------------------- build / simulate
@pytest.mark.parametrize("cmd", ["build", "simulate", "report"])
def test_missing_project(cmd, tmp_path):
    assert_clear_failure(run([cmd, str(tmp_path / "nope")]), "project file not found")


@pytest.mark.parametrize("cmd", ["build", "simulate"])
def test_unreadable_project_file(cmd, proj):
    (proj / "radtree.toml").write_bytes(b"\xff\xfe\x00garbage")
    assert_clear_failure(run([cmd, str(proj)]), "radtree.toml")


@pytest.mark.parametrize("pat, rep, words", [
    (r"^facade_reflectance = 0.90", "facade_reflectance = nan", "finite"),
    (r"^transmittance = 0.5 ", "transmittance = -0.5 ", "expected ≥ 0"),
    (r"^transmittance = 0.5 ", "transmittance = 0.95 ", "exceeds 1"),
    (r"^width_m = 20.0", 'width_m = "twenty"', "expected a number"),
    (r"^count = 8", "count = 0", "sensors.count"),
    (r'^hours = \[.*\]', 'hours = ["25:00"]', "HH:MM"),
    (r'^hours = \[.*\]', "hours = []", "non-empty list"),
])
def test_bad_fields(proj, pat, rep, words):
    edit(proj, pat, rep)
    for cmd in ("build", "simulate"):
        assert_clear_failure(run([cmd, str(proj)]), words)
    assert not (proj / "build").exists()
    assert not (proj / "results").exists()


def test_negative_dni_and_missing_data_file(proj):
    (proj / "data/direct_normal_illuminance.csv").write_text("time,direct_normal_lux\n12:30,-5\n")
    assert_clear_failure(run(["simulate", str(proj)]), "non-negative")
    (proj / "data/direct_normal_illuminance.csv").unlink()
    assert_clear_failure(run(["build", str(proj)]), "file not found")


def test_hour_missing_from_dni_table(proj):
    (proj / "data/direct_normal_illuminance.csv").write_text("time,direct_normal_lux\n12:30,100\n")
    assert_clear_failure(run(["build", str(proj)]), "13:30")


def test_sun_below_horizon(proj):
    edit(proj, r'^hours = \[.*\]', 'hours = ["23:30"]')
    (proj / "data/direct_normal_illuminance.csv").write_text("time,direct_normal_lux\n23:30,0\n")
    assert_clear_failure(run(["simulate", str(proj)]), "below the horizon")


def test_unknown_scenario_and_hour(proj):
    assert_clear_failure(run(["build", str(proj), "-s", "Z"]), "no scenario named")
    assert_clear_failure(run(["simulate", str(proj), "--hour", "09:00"]), "unknown hour")


def test_missing_radiance_binary(proj):
    env = {"RADTREE_NO_RADIANCE": "1"}
    from radtree.engines.radiance import binaries

    binaries.find_radiance.cache_clear()
    try:
        os.environ["RADTREE_NO_RADIANCE"] = "1"
        assert_clear_failure(run(["simulate", str(proj), "--engine", "radiance"], env=env),
                             "Radiance was not found" if False else "not found")
    finally:
        del os.environ["RADTREE_NO_RADIANCE"]
        binaries.find_radiance.cache_clear()


def test_failing_radiance_binary(proj, tmp_path, monkeypatch):
    """A Radiance program that fails: the error names the command and its stderr."""
    from radtree.engines.radiance import binaries

    fake = tmp_path / "fakebin"
    fake.mkdir()
    for prog in binaries.REQUIRED:
        f = fake / prog
        f.write_text("#!/bin/sh\necho \"$0: fatal - cannot open scene\" >&2\nexit 1\n")
        f.chmod(0o755)
    monkeypatch.setattr(binaries, "find_radiance",
                        lambda: binaries.RadianceInstall(fake, None, "PATH"))
    r = run(["simulate", str(proj), "-s", "B", "--engine", "radiance"])
    assert_clear_failure(r, "failed", "cannot open scene")


def test_empty_sensor_grid_is_rejected():
    from radtree.scene import SensorGrid

    with pytest.raises(ValueError, match="no points"):
        SensorGrid("g", [], [])


# ---------------------------------------------------------------- report
def test_report_without_results(proj):
    assert_clear_failure(run(["report", str(proj)]), "no results")


# ---------------------------------------------------------------- hemi
def test_hemi_missing_and_corrupt(tmp_path):
    assert_clear_failure(run(["hemi", str(tmp_path / "none.jpg")]))
    bad = tmp_path / "bad.jpg"
    bad.write_bytes(b"not a jpeg at all")
    assert_clear_failure(run(["hemi", str(bad), "--out", str(tmp_path / "o")]), "bad.jpg")


def test_hemi_mask_outside_image(tmp_path):
    photo = CHESTNUT
    r = run(["hemi", str(photo), "--mask", "5000,852,754", "--out", str(tmp_path / "o")])
    assert_clear_failure(r, "mask")


# ---------------------------------------------------------------- calibrate / sweep
def test_calibrate_bad_target(proj):
    assert_clear_failure(run(["calibrate", str(proj), "--target", "1.5"]))
    assert_clear_failure(run(["calibrate", str(proj / "nothing")]))


def test_sweep_bad_parameter(proj):
    assert_clear_failure(run(["sweep", str(proj), "--param", "tree.nope.x=1,2"]), "nope")
    assert_clear_failure(run(["sweep", str(proj), "--param", "tree.louvers.layers=3:"]))


# ---------------------------------------------------------------- property-based
@settings(max_examples=60, deadline=None)
@given(st.floats(min_value=1e-6, max_value=0.9183))
def test_converter_roundtrip(tn):
    g = Glass("g", transmissivity_from_transmittance(tn))
    assert 0 < g.transmissivity <= 1.0 + 2e-4
    assert g.transmittance == pytest.approx(tn, rel=1e-6, abs=1e-9)


@settings(max_examples=80, deadline=None)
@given(st.floats(0, 1), st.floats(0, 1), st.floats(0, 1))
def test_trans_accepts_exactly_the_physical_optics(r, td, ts):
    if r + td + ts > 1 + 1e-9 or r + td + ts == 0:
        with pytest.raises(ValueError):
            Trans("x", r, td, ts)
    else:
        c, trans, tspec = Trans("x", r, td, ts).coefficients
        assert c * (1 - trans) == pytest.approx(r, abs=1e-9)
        assert c * trans * tspec == pytest.approx(ts, abs=1e-9)


@settings(max_examples=40, deadline=None)
@given(st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                 st.text(alphabet="abcXYZ019 .-", max_size=5),
                 st.booleans(), st.integers(-10, 10)))
def test_loader_rejects_or_accepts_reflectance_cleanly(tmp_path_factory, value):
    p = copy_project(tmp_path_factory.mktemp("h") / "p")
    toml = p / "radtree.toml"
    if isinstance(value, str):
        lit = '"' + value.replace("\\", "").replace('"', "") + '"'
    elif isinstance(value, bool):
        lit = "true" if value else "false"
    elif isinstance(value, float) and math.isnan(value):
        lit = "nan"
    elif isinstance(value, float) and math.isinf(value):
        lit = "inf" if value > 0 else "-inf"
    else:
        lit = repr(value)
    toml.write_text(re.sub(r"^facade_reflectance = 0.90", f"facade_reflectance = {lit}",
                           toml.read_text(), flags=re.M))
    ok = (not isinstance(value, bool | str) and isinstance(value, int | float)
          and math.isfinite(value) and 0 <= value <= 1)
    if ok:
        assert load_project(p).street.facade_reflectance == float(value)
    else:
        with pytest.raises(ConfigError, match="street.facade_reflectance"):
            load_project(p)
    shutil.rmtree(p)


@settings(max_examples=40, deadline=None)
@given(st.floats(-2, 2))
def test_plastic_range(rho):
    if 0 <= rho <= 1:
        assert Plastic("p", rho).reflectance == rho
    else:
        with pytest.raises(ValueError):
            Plastic("p", rho)


# ---------------------------------------------------------------- diagnose
def test_diagnose_bad_measurements(proj, tmp_path):
    bad = tmp_path / "m.csv"
    bad.write_text("# Units: lux\ntime,measured_lux\n12:30,1600\n13:30,-4\n")
    assert_clear_failure(run(["diagnose", str(proj), "--measured", str(bad)]), "line")
    assert_clear_failure(run(["diagnose", str(proj), "--measured", str(tmp_path / "no.csv")]))
    assert_clear_failure(run(["diagnose", str(tmp_path / "nothing")]))
    assert not (proj / "diagnose" / "steps.csv").exists()
