"""Reliability under faults (issue 23): concurrent runs, killed engines, corrupt state, full
disks, signals, resource limits, determinism.

Every multi-process test is held at a known point (tests/held_run.py: a real radtree process
whose hour K + 1 waits for a signal), so none depends on timing. The project is the Mendoza
example reduced to an open street, one hour and 64 rays per sensor on the NumPy engine.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from radtree.cli import main
from radtree.config import load_project
from radtree.pipeline.results import read_results

from .conftest import copy_project

HELD = str(Path(__file__).with_name("held_run.py"))
TINY = {r'model = "\w+"': 'model = "none"', r"^rays = \d+": "rays = 64",
        r"^dense_spacing_m = .*$": "dense_spacing_m = 3.0"}


@pytest.fixture
def tiny(tmp_path: Path) -> Path:
    """Open street, one hour (10:30), 64 rays per sensor, a coarse façade map."""
    return copy_project(tmp_path / "proj", TINY, hours=["10:30"])


def cli(*args: str):
    return CliRunner().invoke(main, list(args))


def held(k: int | None, *args: str, wait_for: str = "engine:") -> subprocess.Popen:
    """``radtree ARGS`` in a child process held at hour k + 1 (k None: not held), returned once
    its stdout (stderr, for a ``waiting`` line) has printed a line starting with ``wait_for``."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    head = [HELD, str(k)] if k is not None else ["-m", "radtree.cli"]
    proc = subprocess.Popen([sys.executable, *head, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    stream = proc.stderr if wait_for.startswith("waiting") else proc.stdout
    assert stream is not None
    for line in stream:
        if line.startswith(wait_for):
            proc.first_line = line  # type: ignore[attr-defined]
            return proc
    raise AssertionError(f"{args} ended before printing {wait_for!r}: {proc.communicate()}")


# ---------------------------------------------------------------- 1. concurrent runs
def test_second_writer_is_refused_or_waits_and_readers_see_one_table(tiny: Path):
    sim = ["simulate", str(tiny), "--engine", "numpy", "-s", "A", "-s", "B"]
    assert cli(*sim).exit_code == 0
    before = read_results(load_project(tiny))
    shutil.rmtree(tiny / "results" / "parts")
    first = held(1, *sim)                              # holds results/ and build/
    try:
        res = cli(*sim)
        assert res.exit_code == 2
        assert res.stderr.splitlines()[-1].startswith(
            f"error: {tiny / 'results'} is in use by pid {first.pid} "
            f"(radtree simulate {tiny}), since ")
        assert "(or rerun with --wait)" in res.stderr
        assert cli("build", str(tiny)).exit_code == 2  # build/ is held too
        # a reader meanwhile sees the whole previous table (the new one is not written yet)
        pd.testing.assert_frame_equal(read_results(load_project(tiny)), before)
        waiter = held(None, *sim, "--wait", wait_for="waiting")
        assert waiter.first_line.strip() == (  # type: ignore[attr-defined]
            f"waiting for {_holder(first.pid, tiny)} to release {tiny / 'results'}")
        first.send_signal(signal.SIGINT)
        assert first.wait(60) == 130
        out, err = waiter.communicate(timeout=120)
        assert waiter.returncode == 0, err
        assert "1 hours traced, 1 reused" in out       # resumed where the first stopped
    finally:
        if first.poll() is None:
            first.kill()
    # a lock left by a process that is gone is taken over, and said so
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    (tiny / "results" / ".radtree.lock").write_text(json.dumps(
        {"pid": dead.pid, "command": "radtree simulate elsewhere"}))
    res = cli(*sim)
    assert res.exit_code == 0, res.output
    assert (f"note: {tiny / 'results'} was locked by pid {dead.pid} (radtree simulate "
            "elsewhere), which is no longer running; lock taken over") in res.stderr


def _holder(pid: int, tiny: Path) -> str:
    lock = json.loads((tiny / "results" / ".radtree.lock").read_text())
    return f"pid {pid} (radtree simulate {tiny}), since {lock['since']}"
