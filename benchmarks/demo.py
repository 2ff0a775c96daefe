"""`make demo` step by step: wall time, CPU time and peak memory of each command (issue 22).

    python benchmarks/demo.py [--engine numpy|radiance] [--keep DIR] [--compare RESULTS.csv]

Runs ``make demo`` on a fresh copy of ``examples/mendoza-street`` (no build, results or
report), with ``DEMO_ENGINE`` = ``--engine`` (default: the Makefile's) and every step timed
(``RUN`` = ``timestep.py``), and prints one line per step (steps run side by side where the
Makefile lets them) and the total after install — the figure issue 22's target (≤ 120 s on 2
cores) is about. ``--compare`` takes another run's
``results/illuminance.csv`` (e.g. ``--keep`` of a ``--engine radiance`` run) and prints, per
scenario, nRMSE and nMBE against the measurements in both and the hourly façade means'
differences in units of their Monte Carlo standard error (the radtree ``lux_stderr``
column; Radiance's ``-u-`` runs carry none, so their error is not in the denominator).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import print_resources_at_exit

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "mendoza-street"
GENERATED = ("build", "results", "report", "diagnose")


def run(engine: str | None, folder: Path) -> float:
    """``make demo`` on ``folder`` (the install already done), each step timed by
    ``timestep.py``; prints one line per step (start and end from the demo's start) and the
    total wall time of the whole ``make demo``."""
    with tempfile.TemporaryDirectory(prefix="radtree-demo-log-") as tmp:
        log = Path(tmp) / "steps.jsonl"
        run = f"{sys.executable} {ROOT / 'benchmarks' / 'timestep.py'} {log}"
        args = ["make", "-s", "-C", str(ROOT), "demo", f"EXAMPLE={folder}", f"RUN={run}"]
        if engine:
            args.append(f"DEMO_ENGINE={engine}")
        with tempfile.TemporaryFile("w+") as out:
            t0 = time.time()
            proc = subprocess.run(args, stdout=out, stderr=subprocess.STDOUT, text=True)
            total = time.time() - t0
            out.seek(0)
            text = out.read()
        steps = [json.loads(line) for line in log.read_text().splitlines()] if log.exists() \
            else []
    print(f"{'step':52s} {'start s':>7s} {'end s':>7s} {'wall s':>7s} {'CPU s':>7s} "
          f"{'peak MiB':>9s}")
    for st in sorted(steps, key=lambda s: s["start"]):
        label = st["step"].replace(str(folder), "EXAMPLE")
        print(f"{label[:52]:52s} {st['start'] - t0:7.1f} {st['end'] - t0:7.1f} "
              f"{st['end'] - st['start']:7.1f} {st['cpu']:7.1f} {st['peak_mib']:9.0f}")
    if proc.returncode != 0:
        print(text[-3000:])
        raise SystemExit(f"make demo failed (exit {proc.returncode})")
    cpu = sum(st["cpu"] for st in steps)
    print(f"{'total after install (make demo, wall)':52s} {total:31.1f}   "
          f"(target 120 s; CPU {cpu:.0f} s on {os.cpu_count()} CPUs)")
    return total


def compare(ours: Path, other: Path) -> None:
    import numpy as np
    import pandas as pd

    from radtree.measurements import load_measured
    from radtree.stats import nmbe, nrmse

    table, _ = load_measured(EXAMPLE / "data" / "measured_vertical_illuminance.csv")
    m = table.set_index("time")["measured_lux"]

    def façade(path: Path) -> pd.DataFrame:
        d = pd.read_csv(path, dtype={"time": str})
        f = d[d["grid"] == "facade"]
        return f.groupby(["scenario", "time"]).agg(
            lux=("lux", "mean"),
            se=("lux_stderr", lambda s: float(np.sqrt((s.fillna(0.0) ** 2).sum())) / len(s)))

    a, b = façade(other), façade(ours)
    print(f"\nthis run against {other}: nRMSE (nMBE) there → here; hourly façade means here − "
          "there, in % and in standard errors")
    for sc in a.index.get_level_values(0).unique():
        x = a.loc[sc].reindex(m.index)
        y = b.loc[sc].reindex(m.index)
        rel = 100 * (y["lux"] / x["lux"] - 1)
        z = (y["lux"] - x["lux"]) / np.sqrt(x["se"] ** 2 + y["se"] ** 2).replace(0, np.nan)
        print(f"  {sc:8s} {nrmse(m, x['lux']):.3f} ({nmbe(m, x['lux']):+.3f}) → "
              f"{nrmse(m, y['lux']):.3f} ({nmbe(m, y['lux']):+.3f}); day mean "
              f"{100 * (y['lux'].mean() / x['lux'].mean() - 1):+.1f} %; hours "
              f"{rel.min():+.1f} … {rel.max():+.1f} %, |z| ≤ {z.abs().max():.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--engine", choices=["numpy", "radiance", "auto"], default=None,
                    help="DEMO_ENGINE (default: the Makefile's)")
    ap.add_argument("--keep", type=Path, help="run in this folder and keep it (else a temp one)")
    ap.add_argument("--compare", type=Path, help="another run's results/illuminance.csv")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="radtree-demo-") as tmp:
        folder = args.keep or Path(tmp) / "mendoza-street"
        if folder.exists():
            shutil.rmtree(folder)
        shutil.copytree(EXAMPLE, folder, ignore=shutil.ignore_patterns(*GENERATED))
        run(args.engine, folder)
        if args.compare is not None:
            compare(folder / "results" / "illuminance.csv", args.compare)


if __name__ == "__main__":
    print_resources_at_exit()
    main()
