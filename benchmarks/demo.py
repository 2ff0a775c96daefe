"""`make demo` step by step: wall time, CPU time and peak memory of each command (issue 22).

    python benchmarks/demo.py [--engine numpy|radiance] [--keep DIR] [--compare RESULTS.csv]

Runs the ``radtree`` commands of the Makefile's ``demo`` recipe, in order, on a fresh copy of
``examples/mendoza-street`` (no build, results or report), with ``DEMO_ENGINE`` = ``--engine``
(default: the Makefile's), and prints one line per step and the total after install — the
figure issue 22's target (≤ 120 s on 2 cores) is about. ``--compare`` takes another run's
``results/illuminance.csv`` (e.g. ``--keep`` of a ``--engine radiance`` run) and prints, per
scenario, nRMSE and nMBE against the measurements in both and the hourly façade means'
differences in units of their Monte Carlo standard error (the radtree ``lux_stderr``
column; Radiance's ``-u-`` runs carry none, so their error is not in the denominator).
"""

from __future__ import annotations

import argparse
import os
import re
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


def demo_steps(engine: str | None) -> list[list[str]]:
    """The ``$(BIN)/radtree ...`` lines of the Makefile's demo recipe, variables filled in."""
    text = (ROOT / "Makefile").read_text()
    default = re.search(r"^DEMO_ENGINE \?= (\S+)", text, re.M)
    recipe = text.split("\ndemo:", 1)[1].split("\n\n", 1)[0]
    values = {"EXAMPLE": "EXAMPLE", "DEMO_ENGINE": engine or (default.group(1) if default
                                                              else "auto")}
    steps = []
    for line in recipe.splitlines():
        line = line.strip()
        if not line.startswith("$(BIN)/radtree"):
            continue
        line = re.sub(r"\$\((\w+)\)", lambda m: values.get(m.group(1), m.group(0)), line)
        steps.append(line.split()[1:])
    return steps


def run(engine: str | None, folder: Path) -> float:
    radtree = Path(sys.executable).with_name("radtree")
    total = 0.0
    print(f"{'step':58s} {'wall s':>7s} {'CPU s':>7s} {'peak MiB':>9s}")
    for args in demo_steps(engine):
        args = [str(folder) if a == "EXAMPLE" else a for a in args]
        with tempfile.TemporaryFile("w+") as out:
            t0 = time.perf_counter()
            proc = subprocess.Popen([str(radtree), *args], stdout=out, stderr=subprocess.STDOUT,
                                    text=True)
            _, status, usage = os.wait4(proc.pid, 0)   # this step's own CPU and peak memory
            wall = time.perf_counter() - t0
            proc.returncode = os.waitstatus_to_exitcode(status)
            out.seek(0)
            log = out.read()
        cpu, peak = usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024
        label = " ".join("EXAMPLE" if a == str(folder) else a for a in args)
        print(f"{label[:58]:58s} {wall:7.1f} {cpu:7.1f} {peak:9.0f}", flush=True)
        if proc.returncode != 0:
            print(log[-3000:])
            raise SystemExit(f"step failed (exit {proc.returncode}): {label}")
        total += wall
    print(f"{'total after install':58s} {total:7.1f}   (target 120 s, {os.cpu_count()} CPUs)")
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
