"""The permeability scan: real NumPy traces of a reduced Mendoza example, numbers checked
against the statistics module and against each other."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from radtree.calibrate.scan import (
    MEASURED_BAND,
    PermeabilityScan,
    scan_permeability,
    unobstructed_project,
    write_scan,
)
from radtree.cli import main
from radtree.config import load_project
from radtree.stats import nmbe, nrmse
from tests.conftest import copy_project

MEASURED = {"10:30": 1157.0, "13:30": 1592.0}


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    p = copy_project(tmp_path_factory.mktemp("scan") / "proj", hours=["10:30", "13:30"])
    proj = load_project(p)
    return proj, scan_permeability(proj, "A", values=(0.45, 0.5, 0.55), rays=256)


def test_scan_numbers(scan):
    proj, s = scan
    t = s.table
    assert list(t["value"]) == [0.45, 0.5, 0.55]
    # more slat transmittance, more light: both permeabilities and the façade rise
    for col in ["permeability_street", "permeability_unobstructed", "10:30", "13:30"]:
        assert np.all(np.diff(t[col]) > 0), col
    # five layers of 0.5: a few per cent, never above the direct-beam upper bound 0.55^5 ≈ 5 %
    # by more than the diffuse and reflected paths can add
    assert 0.02 < t.loc[1, "permeability_street"] < 0.10
    # the unobstructed reference (no canyon, sun + sky) is brighter than the open street
    assert np.all(t["permeability_unobstructed"] < t["permeability_street"])
    assert np.all(t["permeability_street_se"] < 0.05 * t["permeability_street"])
    m = np.array([MEASURED["10:30"], MEASURED["13:30"]])
    for _, r in t.iterrows():
        sim = np.array([r["10:30"], r["13:30"]])
        assert r["nrmse"] == pytest.approx(nrmse(m, sim), rel=1e-9)
        assert r["nmbe"] == pytest.approx(nmbe(m, sim), rel=1e-9)


def test_unobstructed_reference_is_open_and_global(scan):
    proj, _ = scan
    u = unobstructed_project(proj)
    assert u.light.sky == "perez" and u.street.width_m >= 1000
    assert u.street.opposite_building_height_m < 0.1


def test_band_and_summary():
    t = pd.DataFrame({"value": [1, 2, 3], "permeability_street": [0.04, 0.055, 0.07],
                      "permeability_unobstructed": [0.03, 0.045, 0.06],
                      "nrmse": [0.3, 0.08, 0.2], "nmbe": [0.3, 0.0, -0.2], "r": [0.9] * 3})
    s = PermeabilityScan("A", "louvers.transmittance", t, [])
    lo, hi = s.band_nrmse("permeability_street")
    # interpolated at 5 %: 0.3 + (0.08 − 0.3)·(0.01/0.015); at 6 %: 0.08 + 0.12·(0.005/0.015)
    assert lo == pytest.approx(0.08)
    assert hi == pytest.approx(max(0.3 - 0.22 * 2 / 3, 0.08 + 0.12 / 3))
    # 4.5 % → 0.08 and 6 % → 0.2: at 5 %, 0.08 + 0.12/3 = 0.12
    assert s.band_nrmse("permeability_unobstructed") == pytest.approx((0.12, 0.2))
    text = " ".join(s.summary())
    assert "needs louvers.transmittance 2–2" in text and "5.5–5.5 %" in text
    assert MEASURED_BAND == (0.05, 0.06)


def test_write_scan_and_report_section(scan, tmp_path):
    proj, s = scan
    csv, png = write_scan(s, tmp_path)
    back = pd.read_csv(csv)
    assert list(back["scenario"].unique()) == ["A"] and len(back) == 3
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_bad_values_and_unknown_scenario(tmp_path):
    p = copy_project(tmp_path / "proj", hours=["10:30"])
    r = CliRunner().invoke(main, ["permeability", str(p), "--values", "a:b"])
    assert r.exit_code == 2 and "expected low:high:n" in r.output
    r = CliRunner().invoke(main, ["permeability", str(p), "-s", "Z", "--values", "0.5"])
    assert r.exit_code == 2 and "no scenario 'Z'" in r.output
