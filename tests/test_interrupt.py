"""An interrupted `radtree simulate` keeps finished hours; a rerun computes only the rest.

The interrupted process is held after its second hour (tests/held_run.py), so the test does not
depend on timing: exactly two parts exist when SIGINT arrives.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd

from .conftest import needs_radiance

HELD = str(Path(__file__).with_name("held_run.py"))


@needs_radiance
def test_sigint_keeps_finished_hours_and_resumes(open_street):
    env = dict(os.environ)
    args = ["simulate", str(open_street), "--workers", "1"]
    cmd = [sys.executable, "-m", "radtree.cli", *args]
    # SIGINT ignored in the child, as a backgrounded shell or some CI runners leave it:
    # radtree installs its own handler, so the outcome does not depend on the parent's
    proc = subprocess.Popen([sys.executable, HELD, "2", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=env,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN))
    parts = open_street / "results" / "parts"
    deadline = time.time() + 120
    while time.time() < deadline:
        if parts.exists() and len(list(parts.glob("*.csv"))) >= 2:
            break
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the run finished before it could be interrupted"
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err.decode()
    assert b"interrupted" in err
    finished = sorted(p.name for p in parts.glob("*.csv"))
    assert len(finished) == 2
    assert not list(parts.glob(".*tmp"))                   # no half-written part
    assert sorted(p.name for p in parts.glob("*.json")) == [f"{n}.json" for n in finished]
    assert not (open_street / "results" / "illuminance.csv").exists()
    mtimes = {p.name: p.stat().st_mtime_ns for p in parts.glob("*.csv")}

    done = subprocess.run(cmd, capture_output=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr.decode()
    assert f"{14 - len(finished)} hours traced, {len(finished)} reused" in done.stdout.decode()
    for name, mt in mtimes.items():                       # finished parts were not recomputed
        assert (parts / name).stat().st_mtime_ns == mt
    table = pd.read_csv(open_street / "results" / "illuminance.csv")
    assert len(table[table.grid == "facade"]) == 7 * 2 * 8
