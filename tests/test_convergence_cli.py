"""``radtree convergence`` and its alias ``radtree simulate --convergence`` (issue 42)."""

from __future__ import annotations

import re

import pandas as pd
from click.testing import CliRunner

from radtree.cli import COMMANDS, main
from radtree.cli.convergence import DEPRECATED

from .conftest import copy_project


def _project(tmp_path, name):
    p = copy_project(tmp_path / name, hours=["13:30"])
    toml = p / "radtree.toml"
    toml.write_text(re.sub(r"^rays = \d+", "rays = 64", toml.read_text(), flags=re.M))
    return p


def test_convergence_command_and_its_deprecated_alias_agree(tmp_path):
    """Both print the ladder and write the same results/convergence.csv (the NumPy engine is
    seeded: number for number); only the alias prints the one-line deprecation note."""
    runner = CliRunner()
    assert COMMANDS["convergence"] == "radtree.cli.convergence:convergence_command"
    new, old = _project(tmp_path, "new"), _project(tmp_path, "old")
    a = runner.invoke(main, ["convergence", str(new), "-s", "E", "--engine", "numpy"])
    b = runner.invoke(main, ["simulate", str(old), "-s", "E", "--engine", "numpy",
                             "--convergence"])
    assert a.exit_code == 0, a.output
    assert b.exit_code == 0, b.output
    assert f"warning: {DEPRECATED}" in b.output and DEPRECATED not in a.output
    assert DEPRECATED == "`radtree simulate --convergence` is now `radtree convergence`"
    ta = pd.read_csv(new / "results" / "convergence.csv")
    tb = pd.read_csv(old / "results" / "convergence.csv")
    # the ladder and the -ab simulate uses for the crown model
    assert list(ta["ab"]) == sorted({1, 2, 3, 4, 6, 8, int(ta["model_recommended_ab"][0])})
    assert set(ta["scenario"]) == {"E"}
    assert ta["facade_mean_lux"].gt(0).all()
    pd.testing.assert_frame_equal(ta, tb)
    # the rows logged as the ladder is read, then the table, then where it went
    assert re.search(r"^  E 13:30 -ab 2: \d+ lx \([+-]\d+\.\d%\)$", a.output, flags=re.M)
    assert a.output.rstrip().endswith(f"convergence table → {new / 'results' / 'convergence.csv'}")
    # a second run reuses every step (same table), --fresh traces them again (same numbers)
    again = runner.invoke(main, ["convergence", str(new), "-s", "E", "--engine", "numpy"])
    fresh = runner.invoke(main, ["convergence", str(new), "-s", "E", "--engine", "numpy",
                                 "--fresh"])
    assert again.exit_code == fresh.exit_code == 0
    pd.testing.assert_frame_equal(pd.read_csv(new / "results" / "convergence.csv"), ta)


def test_convergence_is_listed_with_its_options():
    res = CliRunner().invoke(main, ["--help"])
    assert res.exit_code == 0 and re.search(r"^\s+convergence\s", res.output, flags=re.M)
    res = CliRunner().invoke(main, ["convergence", "--help"])
    for option in ("--scenario", "--engine", "--hour", "--workers", "--fresh", "--wait"):
        assert option in res.output
