"""Report folder size of each shipped example (issue 38: ≤ 2 MB with the 3-D view kept).

Each example is copied to a temporary folder, built (``radtree build``, so the 3-D view has its
scenes), simulated with the NumPy engine at every hour of the example but few rays (the size of
a report hardly depends on its Monte Carlo noise; ``--one-hour``: its first hour only) and
reported; the script prints the report folder's size, its 3-D view's and its largest files. Run
with the code to compare (e.g. an export of main for "before", this branch for "after"):

    python benchmarks/report_sizes.py [--one-hour] [EXAMPLE ...]
"""

from __future__ import annotations

import re
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ("district", "office-block", "honeybee-office", "mendoza-street")
LIMIT_MB = 2.0


def _small(folder: Path, one_hour: bool) -> None:
    toml = folder / "radtree.toml"
    text = toml.read_text()
    if one_hour:   # measured hours would then lack a simulated value
        text = re.sub(r"^hours = \[\s*\"([0-9:]+)\".*?\]$", r'hours = ["\1"]', text,
                      flags=re.M | re.S)
        text = re.sub(r"^dense_hours = .*$", "", text, flags=re.M)
        text = re.sub(r"^measured(_rows)? = .*$", "", text, flags=re.M)
    text = re.sub(r"^rays = \d+", "rays = 16", text, flags=re.M)
    text = re.sub(r"^ad = \d+", "ad = 32", text, flags=re.M)
    toml.write_text(text)


def _size(path: Path) -> int:
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())


def main(names: list[str], one_hour: bool = False) -> None:
    from radtree.config import load_project
    from radtree.pipeline.build import build_project
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project
    from radtree.report import build_report

    print(f"{'example':18s} {'report (MB)':>11s} {'3-D view (MB)':>13s}  largest files")
    for name in names:
        with tempfile.TemporaryDirectory() as tmp:
            dst = Path(tmp) / name
            shutil.copytree(ROOT / "examples" / name, dst,
                            ignore=shutil.ignore_patterns("build", "results", "report"))
            if name == "honeybee-office":
                shutil.copytree(ROOT / "examples" / "office-block" / "data",
                                Path(tmp) / "office-block" / "data")
            _small(dst, one_hour)
            project = load_project(dst)
            build_project(project, pictures=False)
            simulate_project(project, options=RunOptions(engine="numpy"))
            index = build_report(project)
            folder = index.parent
            view = folder / "view3d.html"
            files = sorted((f for f in folder.rglob("*") if f.is_file()),
                           key=lambda f: -f.stat().st_size)[:3]
            total = _size(folder) / 2**20
            print(f"{name:18s} {total:11.2f} "
                  f"{(view.stat().st_size / 2**20 if view.exists() else 0):13.2f}  "
                  + ", ".join(f"{f.relative_to(folder)} {f.stat().st_size / 2**20:.2f}"
                              for f in files)
                  + ("" if total <= LIMIT_MB else f"   > {LIMIT_MB} MB"), flush=True)


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--one-hour"]
    main(args or list(EXAMPLES), one_hour="--one-hour" in sys.argv[1:])
