"""``radtree diagnose run | selftest | next | list-effects``: the subcommands, and the old
one-command flags as aliases that print a deprecation note and give the same result."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from radtree.cli import main
from radtree.cli.diagnose import LEGACY_FLAGS, diagnose_command, legacy_args
from radtree.diagnose.loop import LoopOptions
from radtree.diagnose.options import DiagnoseOptions
from radtree.diagnose.registry import EFFECT_REGISTRY
from radtree.errors import ConfigError, RadtreeError
from tests.conftest import MENDOZA, copy_project


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> Path:
    """Mendoza at three hours, 64 rays, no dense grid: a cheap diagnosis."""
    return copy_project(tmp_path_factory.mktemp("diagcli") / "proj",
                        {r"^rays = \d+": "rays = 64",
                         r"^dense_hours = .*$": "dense_grid = false"},
                        hours=["10:30", "13:30", "16:30"])


def _run(*args: str):
    return CliRunner().invoke(main, ["diagnose", *args])


def _note(flag: str, name: str) -> str:
    return f"warning: `radtree diagnose {flag}` is deprecated: use `radtree diagnose {name} ...`"


def test_legacy_args_map_each_flag_to_its_subcommand():
    assert legacy_args(["P", "-s", "B"]) == ["run", "P", "-s", "B"]
    assert legacy_args(["P", "--selftest", "--noise", "0.1"]) == ["selftest", "P", "--noise",
                                                                   "0.1"]
    assert legacy_args(["--next-measurement", "P"]) == ["next", "P"]
    assert legacy_args(["--list-effects"]) == ["list-effects"]
    # a second mode flag stays and is refused by the subcommand as an unknown option
    assert legacy_args(["P", "--selftest", "--next-measurement"]) == [
        "selftest", "P", "--next-measurement"]
    assert set(LEGACY_FLAGS.values()) == set(diagnose_command.commands) - {"run"}


def test_list_effects_alias_same_output():
    new = _run("list-effects", str(MENDOZA), "-s", "B")
    old = _run("--list-effects", str(MENDOZA), "-s", "B")
    assert new.exit_code == 0 and old.exit_code == 0, (new.output, old.output)
    first, rest = old.output.split("\n", 1)
    assert first == _note("--list-effects", "list-effects")
    assert rest == new.output
    assert "deprecated" not in new.output
    assert [ln.split(":")[0] for ln in new.output.splitlines()
            if not ln.startswith(" ")] == list(EFFECT_REGISTRY)


def test_modes_are_subcommands_without_exclusion_checks(small):
    r = _run(str(small), "--selftest", "--measured", "x.csv")
    assert r.exit_code == 2 and "No such option: --measured" in r.output
    r = _run(str(small), "--selftest", "--next-measurement")
    assert r.exit_code == 2 and "No such option: --next-measurement" in r.output
    r = _run("run", str(small), "--candidates", "x.toml")
    assert r.exit_code == 2 and "No such option: --candidates" in r.output
    r = _run("next", str(small), "--margin", "0.1")
    assert r.exit_code == 2 and "No such option: --margin" in r.output


def test_run_alias_same_result(small):
    """``radtree diagnose PROJECT`` and ``radtree diagnose run PROJECT`` write the same
    steps.csv and print the same steps (seeded: identical numbers)."""
    args = ["-s", "A", "--max-steps", "1", "--workers", "1", "--effects",
            "sky_diffuse,unfiltered_ground"]
    out = small / "diagnose"
    new = _run("run", str(small), *args)
    assert new.exit_code == 0, (new.output, new.exception)
    steps_new = (out / "steps.csv").read_text()
    old = _run(str(small), *args)
    assert old.exit_code == 0, (old.output, old.exception)
    assert (out / "steps.csv").read_text() == steps_new
    assert old.output.splitlines()[0] == _note("PROJECT", "run")
    assert "deprecated" not in new.output

    def result_lines(text: str) -> list[str]:
        return [ln for ln in text.splitlines() if ln.startswith("  start ")
                or ln.startswith("  step ") and " + " in ln]

    assert result_lines(old.output) == result_lines(new.output) != []
    assert ": scenario A (" in new.output  # the library's messages come through logging


def test_next_and_selftest_aliases_same_options(small, monkeypatch):
    """The aliases hand the library the same options as the subcommands (the runs
    themselves are covered in tests/test_diagnose.py)."""
    import radtree.diagnose.design as design
    import radtree.diagnose.hidden as hidden

    seen: list[tuple[str, dict]] = []

    class Stop(Exception):
        pass

    def spy(name: str):
        def record(project, **kwargs):
            seen.append((name, {"project": project, **kwargs}))
            raise Stop

        return record

    monkeypatch.setattr(design, "next_measurement", spy("next"))
    monkeypatch.setattr(hidden, "selftest", spy("selftest"))
    common = ["-s", "B", "--rays", "32", "--seed", "5", "--effects", "crown_gaps"]
    for new, old in ((["next", str(small), *common], [str(small), "--next-measurement",
                                                      *common]),
                     (["selftest", str(small), *common, "--noise", "0.02", "--margin", "0.1"],
                      [str(small), *common, "--selftest", "--noise", "0.02", "--margin",
                       "0.1"])):
        for args in (new, old):
            r = CliRunner().invoke(diagnose_command, args)
            assert isinstance(r.exception, Stop), (r.output, r.exception)
    assert [s[0] for s in seen] == ["next", "next", "selftest", "selftest"]
    assert seen[0] == seen[1] and seen[2] == seen[3]
    opts = seen[2][1]["options"]
    assert isinstance(opts, DiagnoseOptions)
    assert (opts.scenario, opts.rays, opts.seed, opts.margin) == ("B", 32, 5, 0.1)
    assert [e.name for e in opts.effects] == ["crown_gaps"] and seen[2][1]["noise"] == 0.02


def test_options_checked_on_creation():
    with pytest.raises(ConfigError, match="diagnose.margin"):
        DiagnoseOptions(margin=1.0)
    with pytest.raises(ConfigError, match="diagnose.rays"):
        DiagnoseOptions(rays=0)
    assert DiagnoseOptions(out_dir="x").folder(Path("/p")) == Path("x")
    assert DiagnoseOptions().folder(Path("/p")) == Path("/p/diagnose")
    loop = DiagnoseOptions(margin=0.1, max_steps=2).loop(first_step_signatures=True)
    assert (loop.margin, loop.max_steps, loop.first_step_signatures) == (0.1, 2, True)
    assert [e.name for e in loop.catalogue] == list(EFFECT_REGISTRY)
    with pytest.raises(RadtreeError, match=r"margin must be in \[0, 1\), got 1.5"):
        LoopOptions(margin=1.5)
