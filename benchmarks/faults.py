"""Fault benchmark: a Dask worker lost in the middle of a sweep case (issue 23).

Runs a 4-case sweep (open street, scenario B, two hours, Radiance) on a LocalCluster of two
worker processes with ``RADTREE_RADIANCE`` pointing at a Radiance whose ``rtrace`` SIGKILLs
its *parent* — the Dask worker — the first time it traces hour 13:30 (a marker file makes it
happen once). Dask restarts the worker and reruns the lost case; the sweep must finish with
every case and the same numbers as a sequential sweep without the fault. Then it kills the
worker on *every* 13:30 trace and prints what the user is told (a failed case naming the lost
worker; the other cases kept; rerun resumes).

Prints: cases computed / failed, the failure message, wall times, and the largest difference
between the faulty and the clean sweep (lux). Run:
``PYTHONPATH=. .venv/bin/python benchmarks/faults.py``.
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.conftest import copy_project  # noqa: E402

PARAMS = ["street.ground_reflectance=0.1,0.3", "sensors.height_m=4:6:2"]  # 2 × 2 cases
KILL_PARENT = """#!{python} -I
# the first rtrace of hour 1330 (while {marker} is absent, or always) kills its parent
import os, signal, sys
real = {real!r}
if "octrees/1330.oct" in sys.argv and ({always} or not os.path.exists({marker!r})):
    open({marker!r}, "w").close()
    os.kill(os.getppid(), signal.SIGKILL)
os.execv(real, [real, *sys.argv[1:]])
"""


def project(folder: Path) -> Path:
    p = copy_project(folder, hours=["10:30", "13:30"])
    toml = p / "radtree.toml"
    text = re.sub(r'model = "\w+"', 'model = "none"', toml.read_text())
    text = text.replace("[sensors]\n", "[sensors]\ndense_grid = false\n")
    toml.write_text(re.sub(r"^ad = \d+$", "ab = 1\nad = 128", text, flags=re.M))
    return p


def killing_radiance(folder: Path, always: bool) -> Path:
    from radtree.engines.radiance.binaries import find_radiance

    real = find_radiance()
    assert real is not None, "needs Radiance"
    bin_dir = folder / "bin"
    bin_dir.mkdir(parents=True)
    if real.lib_dir is not None:
        (folder / "lib").symlink_to(real.lib_dir)
    for prog in real.bin_dir.iterdir():
        (bin_dir / prog.name).symlink_to(prog)
    (bin_dir / "rtrace").unlink()
    (bin_dir / "rtrace").write_text(KILL_PARENT.format(
        python=sys.executable, real=real.program("rtrace"), marker=str(folder / "killed"),
        always=always))
    (bin_dir / "rtrace").chmod(0o755)
    return bin_dir


def run(p: Path, scheduler: str, out: Path):  # type: ignore[no-untyped-def]
    from radtree.pipeline.options import RunOptions
    from radtree.sweep.run import SweepOptions, run_sweep

    t = time.perf_counter()
    res = run_sweep(p, sweep=SweepOptions(params=PARAMS, out=out, sensitivity=False),
                    run=RunOptions(scenarios=["B"], engine="radiance", scheduler=scheduler,
                                   workers=2))
    return res, time.perf_counter() - t


def main() -> None:
    with tempfile.TemporaryDirectory(prefix="radtree-faults-") as tmp:
        base = Path(tmp)
        p = project(base / "proj")
        clean, t_clean = run(p, "sequential", base / "clean")
        print(f"clean sequential sweep: {len(clean.computed)} cases in {t_clean:.1f} s")
        for always in (False, True):
            os.environ["RADTREE_RADIANCE"] = str(killing_radiance(base / f"rad{always}",
                                                                  always))
            out = base / f"faulty{always}"
            res, t = run(p, "local", out)
            label = "every 13:30 trace" if always else "the first 13:30 trace"
            print(f"worker killed at {label}: {len(res.computed)} computed, "
                  f"{len(res.failed)} failed, {t:.1f} s")
            failures = out / "failures.csv"
            if failures.exists():
                for row in pd.read_csv(failures).itertuples():
                    print(f"  failed {row.case_id}: {str(row.error)[:160]}")
            merged = out / "results.csv"
            if merged.exists() and not always:
                a = pd.read_csv(merged).sort_values(["case_id", "time", "sensor"])
                b = pd.read_csv(base / "clean" / "results.csv").sort_values(
                    ["case_id", "time", "sensor"])
                diff = (a["lux"].to_numpy() - b["lux"].to_numpy())
                print(f"  largest |faulty − clean| = {abs(diff).max():.3g} lux over "
                      f"{len(a)} rows")
            del os.environ["RADTREE_RADIANCE"]
            res2, t2 = run(p, "sequential", out)
            print(f"  rerun without the fault: {len(res2.computed)} computed, "
                  f"{len(res2.reused)} reused, {t2:.1f} s")


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
