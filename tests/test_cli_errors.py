"""One error handler for every command, one exit code per kind of failure (radtree.cli.errors).

0 ok, 1 a bug (unexpected exception), 2 bad input, 3 engine failure, 130 interrupted,
143 terminated (SIGTERM).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from radtree.cli import main
from radtree.cli.errors import (
    BAD_INPUT,
    BUG,
    ENGINE_FAILURE,
    INTERRUPTED,
    OK,
    TERMINATED,
    exit_code,
)
from radtree.errors import ConfigError, EngineError, RadtreeError, Terminated

from .conftest import copy_project, needs_radiance


def run(*args: str):
    return CliRunner().invoke(main, list(args))


@pytest.fixture
def proj(tmp_path: Path) -> Path:
    return copy_project(tmp_path / "p", hours=["12:30"])


def test_exit_codes_of_the_error_types():
    assert (OK, BUG, BAD_INPUT, ENGINE_FAILURE, INTERRUPTED, TERMINATED) == (0, 1, 2, 3, 130, 143)
    assert exit_code(ConfigError("x")) == BAD_INPUT
    assert exit_code(RadtreeError("x")) == BAD_INPUT
    assert exit_code(FileNotFoundError(2, "No such file", "a.csv")) == BAD_INPUT
    assert exit_code(EngineError("x", command=["oconv"])) == ENGINE_FAILURE
    assert exit_code(KeyboardInterrupt()) == INTERRUPTED
    assert exit_code(Terminated()) == TERMINATED
    assert exit_code(ValueError("x")) == BUG
    assert exit_code(ZeroDivisionError()) == BUG


def test_ok_is_0(proj):
    assert run("build", str(proj), "-s", "B", "--no-pictures").exit_code == OK


def test_bad_toml_is_2(proj):
    toml = proj / "radtree.toml"
    toml.write_text(toml.read_text().replace("[site]", "[site", 1))
    for cmd in ("build", "simulate", "report", "sweep", "calibrate", "permeability", "annual"):
        r = run(cmd, str(proj))
        assert r.exit_code == BAD_INPUT, (cmd, r.output)
        assert "not valid TOML" in r.output and "radtree.toml" in r.output, (cmd, r.output)
        assert "Traceback" not in r.output


def test_unknown_scenario_is_2(proj):
    for args in (("build", str(proj), "-s", "Z"), ("simulate", str(proj), "-s", "Z"),
                 ("permeability", str(proj), "-s", "Z", "--values", "0.5")):
        r = run(*args)
        assert r.exit_code == BAD_INPUT, (args, r.output)
        assert "error:" in r.output and "'Z'" in r.output, (args, r.output)


def test_click_usage_errors_are_2(proj):
    assert run("simulate", str(proj), "--engine", "nope").exit_code == BAD_INPUT
    assert run("build").exit_code == BAD_INPUT
    assert run("no-such-command").exit_code == BAD_INPUT


@needs_radiance
def test_failing_radiance_command_is_3(proj, monkeypatch):
    """A project whose rtrace options Radiance rejects: exit 3, naming the command and stderr."""
    from radtree.engines.radiance import interface, writer

    broken = writer.rtrace_options
    for module in (writer, interface):   # the build's Makefile and the engine's plan
        monkeypatch.setattr(module, "rtrace_options", lambda *a, **k: [*broken(*a, **k), "-zz"])
    r = run("simulate", str(proj), "-s", "B", "--engine", "radiance", "--workers", "1")
    assert r.exit_code == ENGINE_FAILURE, r.output
    assert "error: scenario B, hour " in r.output   # named (issue 23)
    assert "the radiance engine failed: rtrace failed (exit 1)" in r.output
    assert "command: rtrace" in r.output and "-zz" in r.output
    assert "stderr:" in r.output
    assert "Traceback" not in r.output


def test_no_usable_engine_is_3(monkeypatch):
    from radtree.engines.registry import ENGINES, engine_class

    for name in ENGINES:
        monkeypatch.setattr(engine_class(name), "available", classmethod(lambda cls: False))
    r = run("doctor")
    assert r.exit_code == ENGINE_FAILURE, r.output
    assert "no usable engine" in r.output


def test_keyboard_interrupt_is_130(proj, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("radtree.pipeline.simulate.simulate_project", interrupted)
    r = run("simulate", str(proj), "--engine", "numpy")
    assert r.exit_code == INTERRUPTED, r.output
    assert "interrupted" in r.output and "resume" in r.output


def _send(signum: int):
    def api(*args, **kwargs):
        os.kill(os.getpid(), signum)
        time.sleep(5)  # the handler raises before this ends
        raise AssertionError("the signal did not interrupt the command")

    return api


@pytest.mark.parametrize("signum, code, word", [(signal.SIGTERM, TERMINATED, "terminated"),
                                                (signal.SIGINT, INTERRUPTED, "interrupted")])
def test_signals_whatever_the_parent_disposition(proj, monkeypatch, signum, code, word):
    """SIGTERM → 143 and SIGINT → 130 even when the parent left the signal ignored."""
    monkeypatch.setattr("radtree.pipeline.build.build_project", _send(signum))
    before = signal.signal(signum, signal.SIG_IGN)
    try:
        r = run("build", str(proj))
        assert signal.getsignal(signum) is signal.SIG_IGN  # restored after the command
    finally:
        signal.signal(signum, before)
    assert r.exit_code == code, r.output
    assert word in r.output


def test_a_bug_is_1_and_not_disguised_as_bad_input(proj, monkeypatch):
    def buggy(*args, **kwargs):
        raise ValueError("an internal invariant broke")

    monkeypatch.setattr("radtree.pipeline.build.build_project", buggy)
    r = run("build", str(proj))
    assert r.exit_code == BUG, r.output
    assert "internal error in 'radtree build': ValueError: an internal invariant broke" in r.output
    assert "--debug" in r.output and "Traceback" not in r.output
    r = run("--debug", "build", str(proj))
    assert r.exit_code == BUG
    assert "Traceback" in r.output and "an internal invariant broke" in r.output


@pytest.mark.parametrize("module", ["radtree", "radtree.cli"])
def test_python_m_radtree(module):
    done = subprocess.run([sys.executable, "-m", module, "--help"], capture_output=True,
                          timeout=120)
    assert done.returncode == OK, done.stderr.decode()
    assert b"Exit codes" in done.stdout and b"simulate" in done.stdout
    assert f"python -m {module}".encode() in done.stdout


@needs_radiance
def test_sigterm_keeps_finished_hours_even_if_the_parent_ignores_it(open_street):
    """A real `radtree simulate` process, held after its first hour (tests/held_run.py, no
    timing): SIGTERM → 143, the finished part kept, no temporaries."""
    held = str(Path(__file__).with_name("held_run.py"))
    cmd = [sys.executable, held, "1", "simulate", str(open_street), "--workers", "1"]

    def ignore_signals():  # the disposition a parent may leave behind
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)

    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            preexec_fn=ignore_signals)
    parts = open_street / "results" / "parts"
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        if parts.exists() and len(list(parts.glob("*.csv"))) >= 1:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the run finished before it could be terminated"
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == TERMINATED, err.decode()
    assert b"terminated" in err
    assert len(list(parts.glob("*.csv"))) == 1
    assert not list(parts.glob(".*tmp"))
    assert not (open_street / "results" / "illuminance.csv").exists()
    # resumable: the lock went with the process, the finished part is reused (issue 23)
    done = run("simulate", str(open_street), "--workers", "1", "-s", "A", "--hour", "10:30")
    assert done.exit_code == OK, done.output
    assert "0 hours traced, 1 reused" in done.output
