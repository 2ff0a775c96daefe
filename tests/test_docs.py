"""The user guide cannot go stale: its reference pages are the code's, its commands run.

* The generated reference pages (``docs/gen_reference.py``) equal the committed ones.
* Every ``*COLUMNS`` list in radtree is either a documented results table or named as not one.
* The Python blocks of the worked API example run, in order, in one interpreter.
* Every ``bash`` block of Getting started and the how-to guides runs (``bash -e``) in a scratch
  folder holding a copy of ``examples/``, blocks of a page in order; every file a block names
  with ``# → PATH`` exists afterwards. ``<!-- norun: why -->`` before a block skips it (said
  in the test's output); ``<!-- needs: COMMAND --OPTION -->`` on a page skips the page while
  ``radtree COMMAND --help`` lacks the option (an interface another branch adds).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
sys.path.insert(0, str(DOCS))
import gen_reference  # noqa: E402

RUN_PAGES = ["getting-started.md",
             *sorted(f"how-to/{p.name}" for p in (DOCS / "how-to").glob("*.md"))]
FENCE = re.compile(r"(<!--\s*norun:[^>]*-->\s*\n)?```bash\n(.*?)```", re.S)
NEEDS = re.compile(r"<!--\s*needs:\s*(\S+)\s+(--[\w-]+)\s*-->")
ARROW = re.compile(r"#\s*→\s*([^\s,;()]+)")


def blocks(page: str) -> list[tuple[str, bool]]:
    """(code, runs) of every bash block of a page, in order."""
    text = (DOCS / page).read_text(encoding="utf-8")
    return [(m.group(2), m.group(1) is None) for m in FENCE.finditer(text)]


def named_files(code: str) -> list[str]:
    """The output files a block names (``# → PATH``; a trailing ``/`` names a folder)."""
    return [p.rstrip(".") for p in ARROW.findall(code) if "<" not in p]


def test_reference_pages_match_the_code():
    pages = gen_reference.generate()
    stale = [n for n, t in pages.items()
             if (DOCS / "reference" / n).read_text(encoding="utf-8") != t]
    assert not stale, f"run python docs/gen_reference.py: {stale} differ from the code"


def test_every_results_table_is_documented():
    listed = {ref for _, refs, _, _ in gen_reference.RESULT_TABLES for ref in refs}
    missing = gen_reference.column_constants() - listed - gen_reference.NOT_TABLES
    assert not missing, f"add to docs/gen_reference.py RESULT_TABLES (or NOT_TABLES): {missing}"
    assert gen_reference.column_constants() >= listed


def test_block_parsing():
    text = "a\n<!-- norun: slow -->\n```bash\nmake demo\n```\n```bash\nx  # → out/a.csv\n```\n"
    found = [(m.group(2), m.group(1) is None) for m in FENCE.finditer(text)]
    assert found == [("make demo\n", False), ("x  # → out/a.csv\n", True)]
    assert named_files(found[1][0]) == ["out/a.csv"]


@pytest.mark.slow
@pytest.mark.parametrize("page", RUN_PAGES)
def test_page_commands_run(page, tmp_path, record_property):
    text = (DOCS / page).read_text(encoding="utf-8")
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}"
           f"{os.environ.get('PATH', '')}", "MPLBACKEND": "Agg"}
    for command, option in NEEDS.findall(text):
        helptext = subprocess.run(["radtree", command, "--help"], env=env,
                                  capture_output=True, text=True).stdout
        if option not in helptext:
            record_property("docs_blocks", (page, 0, len(blocks(page)), f"skipped: needs "
                                            f"`radtree {command} {option}`"))
            pytest.skip(f"{page}: needs `radtree {command} {option}`, not in this build")
    shutil.copytree(ROOT / "examples", tmp_path / "examples",
                    ignore=shutil.ignore_patterns("build", "results", "report", "diagnose",
                                                  "sweep", "out", "export"))
    ran = skipped = 0
    for code, runs in blocks(page):
        if not runs:
            skipped += 1
            continue
        proc = subprocess.run(["bash", "-euo", "pipefail", "-c", code], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, (f"{page}: block failed (exit {proc.returncode}):\n{code}"
                                      f"\n--- stdout\n{proc.stdout[-3000:]}\n--- stderr\n"
                                      f"{proc.stderr[-3000:]}")
        for name in named_files(code):
            assert (tmp_path / name).exists(), f"{page}: {name} not written by:\n{code}"
        ran += 1
    record_property("docs_blocks", (page, ran, skipped, ""))
    assert ran + skipped > 0


@pytest.mark.slow
def test_api_example_runs(tmp_path):
    text = (DOCS / "api" / "example.md").read_text(encoding="utf-8")
    code = "\n".join(re.findall(r"```python\n(.*?)```", text, re.S))
    shutil.copytree(ROOT / "examples" / "mendoza-street", tmp_path / "examples" / "mendoza-street",
                    ignore=shutil.ignore_patterns("build", "results", "report", "diagnose"))
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=600, env={**os.environ, "MPLBACKEND": "Agg"})
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert (tmp_path / "examples/mendoza-street/results/illuminance.csv").exists()
    assert "0.0721" in proc.stdout   # the nRMSE the page quotes
