"""Wall and CPU time of `radtree build` on the Mendoza example (issue 22: ≤ 3 s), as a user runs it.

Each run is the command line in a fresh process on a copy of the example (pictures off unless
``--pictures``), with its own build cache (``RADTREE_CACHE_DIR`` in the temporary folder):
a cold build into an empty folder and an empty cache, with 1 process and with the usable
cores, and of the scenarios whose crowns come from no photo (the 14 folders of the issue); a
build into an empty folder with the crowns in the cache (what any build after the
first is: another project folder, ``--fresh``, a changed hour or sky); a second
`radtree build` on the built folders (every folder current: kept) and a `--fresh` one (every
folder rebuilt, crowns from the cache). CPU includes the spawned workers. The slowest folders
of the cold build are listed from their manifests (geometry and writing seconds).
Run: .venv/bin/python benchmarks/build.py [--repeats N] [--pictures]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RADTREE = Path(sys.executable).with_name("radtree")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=2, help="runs of each case (default 2)")
    ap.add_argument("--pictures", action="store_true", help="draw model.png too")
    args = ap.parse_args()
    cores = len(os.sched_getaffinity(0))
    with tempfile.TemporaryDirectory() as tmp:
        proj = Path(tmp) / "mendoza"
        shutil.copytree(ROOT / "examples" / "mendoza-street", proj,
                        ignore=shutil.ignore_patterns("build", "results", "report", "diagnose",
                                                      "sweep"))
        extra = [] if args.pictures else ["--no-pictures"]
        cache = Path(tmp) / "cache"
        os.environ["RADTREE_CACHE_DIR"] = str(cache)
        plain = _without_photo_crowns(proj)
        rows = []
        for label, opts, clean in (*([(f"cold, the {len(plain)} scenarios without photo",
                                       [a for name in plain for a in ("-s", name)], 2)]
                                     if plain else []),
                                   ("cold, empty cache, 1 process", ["--workers", "1"], 2),
                                   (f"cold, empty cache, {cores} processes", [], 2),
                                   ("empty folder, crowns cached", [], 1),
                                   ("again, folders current (kept)", [], 0),
                                   ("again, --fresh (crowns cached)", ["--fresh"], 0)):
            for _ in range(args.repeats):
                if clean:
                    shutil.rmtree(proj / "build", ignore_errors=True)
                if clean == 2:
                    shutil.rmtree(cache, ignore_errors=True)
                wall, cpu, load = _run([str(RADTREE), "build", str(proj), *extra, *opts])
                rows.append((label, wall, cpu, load))
        print(f"radtree build of the Mendoza example ({len(list((proj / 'build').glob('*/')))} "
              f"folders), {'with' if args.pictures else 'without'} pictures, {cores} cores")
        print(f"{'case':38s} {'wall s':>7s} {'CPU s':>7s} {'load':>5s}")
        for label, wall, cpu, load in rows:
            print(f"{label:38s} {wall:7.2f} {cpu:7.2f} {load:5.2f}")
        shutil.rmtree(proj / "build")
        shutil.rmtree(cache)
        _run([str(RADTREE), "build", str(proj), *extra, "--workers", "1"])
        print("slowest folders (one process):")
        facts = []
        for mf in (proj / "build").glob("*/manifest.json"):
            b = json.loads(mf.read_text())["build"]
            facts.append((b["seconds"]["geometry"] + b["seconds"]["writing"], b))
        for total, b in sorted(facts, key=lambda t: -t[0])[:6]:
            print(f"  {b['scenario']:8s} {total:5.2f} s (geometry {b['seconds']['geometry']:.2f}, "
                  f"writing {b['seconds']['writing']:.2f}; {b['triangles']} triangles)")


def _without_photo_crowns(proj: Path) -> list[str]:
    """The project's scenarios whose crowns come from no photo (the folders the issue timed)."""
    from radtree.config import load_project

    project = load_project(proj)
    if project.tree.photo is not None:
        return []
    return [sc.name for sc in project.scenarios
            if not any(key.endswith(".photo") for key in sc.switches)]


def _run(argv: list[str]) -> tuple[float, float, float]:
    """(wall s, CPU s of the process and its children, load average at the start)."""
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, load


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
