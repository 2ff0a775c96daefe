"""Shared fixtures: a reduced copy of the Mendoza example in a temporary folder."""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import pytest
from hypothesis import settings

# Property tests draw the same examples every run (derandomize, no example database): a CI
# run cannot fail on a draw no earlier run made. HYPOTHESIS_PROFILE=explore draws afresh.
settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))

# The build cache (radtree.cache) is off in tests: a test that changes a crown builder would
# otherwise be served another test's crown. tests/test_build_cache.py turns it on in tmp_path.
os.environ["RADTREE_CACHE_DIR"] = "off"

ROOT = Path(__file__).resolve().parents[1]
MENDOZA = ROOT / "examples" / "mendoza-street"
SHARED = ROOT.parent / "shared"
#: The real fisheye photo: ../shared's, or the byte-identical copy the Mendoza example ships
#: (a clean clone without ../shared beside it still runs every photo test).
CHESTNUT = next((p for p in (SHARED / "data" / "fisheye" / "chestnut_coolpix4500_fc-e8.jpg",
                             MENDOZA / "data" / "fisheye_chestnut_standin.jpg") if p.exists()),
                MENDOZA / "data" / "fisheye_chestnut_standin.jpg")


def drop_photo_scenarios(text: str) -> str:
    """The project text without its ``[[scenario]]`` blocks named ``*-photo``."""
    head, *blocks = text.split("\n[[scenario]]")
    kept = [b for b in blocks if not re.search(r'^name = "[^"]*-photo"', b, re.M)]
    return "\n[[scenario]]".join([head, *kept])


def copy_project(dst: Path, replace: dict[str, str] | None = None,
                 hours: list[str] | None = None, photo: bool = False) -> Path:
    """Copy the Mendoza example to ``dst``; regex replacements on its radtree.toml. The
    photo-derived scenarios (A-photo, C-photo, F-photo: tests/test_photo_crowns.py) are left
    out unless ``photo``."""
    shutil.copytree(MENDOZA, dst, ignore=shutil.ignore_patterns("build", "results", "report",
                                                                "diagnose", "sweep"))
    toml = dst / "radtree.toml"
    text = toml.read_text()
    if not photo:
        text = drop_photo_scenarios(text)
    for pat, rep in (replace or {}).items():
        text, n = re.subn(pat, rep, text, flags=re.M)
        assert n, f"pattern {pat!r} not found in radtree.toml"
    if hours is not None:
        text = re.sub(r"^hours = \[.*\]$", "hours = [" + ", ".join(f'"{h}"' for h in hours) + "]",
                      text, flags=re.M)
        text = re.sub(r"^dense_hours = .*$", "", text, flags=re.M)
    toml.write_text(text)
    return dst


def radiance_available() -> bool:
    from radtree.engines.radiance.binaries import find_radiance

    return find_radiance() is not None


@pytest.fixture(scope="module")
def project():
    """The shipped Mendoza example project (read-only)."""
    from radtree.config import load_project

    return load_project(MENDOZA)


@pytest.fixture(scope="module")
def frame(project):
    """The Mendoza façade frame."""
    from radtree.site.frame import FacadeFrame

    return FacadeFrame(project.street.facade_azimuth_deg)


needs_radiance = pytest.mark.skipif(not radiance_available(), reason="Radiance not found")


@pytest.fixture
def open_street(tmp_path: Path) -> Path:
    """Mendoza without crowns (open street), two hours, two scenarios (A calculated, B traced)."""
    p = copy_project(tmp_path / "proj", hours=["10:30", "13:30"])
    text = (p / "radtree.toml").read_text()
    text = re.sub(r'model = "\w+"', 'model = "none"', text)
    (p / "radtree.toml").write_text(text)
    return p


def pytest_terminal_summary(terminalreporter):
    """The guide's shell blocks run by tests/test_docs.py, page by page, and their count."""
    rows = [v for key in ("passed", "skipped", "failed")
            for r in terminalreporter.stats.get(key, [])
            for k, v in getattr(r, "user_properties", []) if k == "docs_blocks"]
    if not rows:
        return
    terminalreporter.write_sep("-", "user guide: shell blocks run (tests/test_docs.py)")
    for page, ran, skipped, note in sorted(rows):
        terminalreporter.write_line(f"{page}: {ran} run, {skipped} not run {note}".rstrip())
    terminalreporter.write_line(f"total: {sum(r[1] for r in rows)} blocks run, "
                                f"{sum(r[2] for r in rows)} not run")


#: The suite's longest test (≈ 300 CPU-s of rtrace): collected first, so that a worker starts it
#: at once while the other works through the queue (``make pytest`` runs ``--dist worksteal``:
#: whichever worker runs dry takes half of the other's queue), and no worker waits on it at
#: the end.
FIRST = ("tests/test_golden.py::test_office_radiance_every_hour",)


def pytest_collection_modifyitems(config, items):
    """:data:`FIRST` to the front of the collection (a stable sort: the rest keep their order)."""
    items.sort(key=lambda item: not item.nodeid.startswith(FIRST))
