"""``radtree calibrate`` on the Mendoza example (a temporary copy)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from radtree.calibrate.direct import calibrate, calibrated_path, sensor_permeability
from radtree.cli import main
from radtree.cli.calibrate import calibrate_command
from radtree.config import load_project
from radtree.errors import RadtreeError
from radtree.site.frame import FacadeFrame
from radtree.trees.build import build_crown

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "mendoza-street"


@pytest.fixture()
def example(tmp_path):
    dst = tmp_path / "mendoza"
    shutil.copytree(EXAMPLE, dst, ignore=shutil.ignore_patterns("build", "results", "report"))
    return dst


def test_calibrate_command_reaches_target(example):
    original = (example / "radtree.toml").read_text()
    result = CliRunner().invoke(calibrate_command, [str(example), "--write"])
    assert result.exit_code == 0, result.output
    assert "Candidates tried" in result.output and "Chosen" in result.output
    assert (example / "radtree.toml").read_text() == original  # never overwritten
    out = example / "radtree.calibrated.toml"
    assert out.exists() and str(out) in result.output
    proj = load_project(out)
    lv = proj.tree.louvers
    assert 1 <= lv.layers <= 12 and 0 < lv.cover_fraction <= 1
    frame = FacadeFrame(proj.street.facade_azimuth_deg)
    achieved = sensor_permeability(build_crown(proj, "louvers", proj.tree.form, frame), proj,
                                   frame)
    assert achieved == pytest.approx(0.055, abs=0.005)
    # the rest of the project is untouched
    assert proj.scenarios == load_project(example).scenarios


def test_calibrate_command_other_target(example):
    result = CliRunner().invoke(calibrate_command, [str(example), "--target", "0.1"])
    assert result.exit_code == 0, result.output
    assert not (example / "radtree.calibrated.toml").exists()  # --write not given
    proj = load_project(example)
    res = calibrate(proj, target=0.1)
    assert res.achieved == pytest.approx(0.1, abs=0.005)
    assert res.parameters["layers"] == proj.tree.louvers.layers  # configured count kept


def test_calibrate_unreachable_target_fails_clearly(example):
    result = CliRunner().invoke(main, ["calibrate", str(example), "--form", "free", "--write",
                                       "--directions", "256"])
    assert result.exit_code == 2, result.output
    assert "NOT reached" in result.output and "nothing written" in result.output
    assert not (example / "radtree.calibrated.toml").exists()


def test_calibrate_errors(example):
    result = CliRunner().invoke(main, ["calibrate", str(example), "--photo-openness"])
    assert result.exit_code == 2 and "tree.perforated.photo" in result.output
    proj = load_project(example)
    with pytest.raises(RadtreeError):
        calibrate(proj, target=1.5)
    assert calibrated_path(proj).name == "radtree.calibrated.toml"


def test_calibrate_homogeneous_and_perforated(example):
    proj = load_project(example)
    res = calibrate(proj, model="homogeneous", form="free")
    assert res.parameters["transmittance"] == pytest.approx(0.055**0.5, abs=1e-5)
    res = calibrate(proj, model="perforated")
    assert res.achieved == pytest.approx(0.055, abs=0.005)
