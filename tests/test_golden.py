"""Every number unchanged: the reduced Mendoza and office runs match tests/golden/ to the digit.

The cases and their reductions are in :mod:`tests.golden_cases`; ``python -m tests.golden_cases``
rewrites the files (only in a commit of its own that says why the numbers moved).
"""

from __future__ import annotations

import difflib
from pathlib import Path

import pytest

from tests.conftest import needs_radiance
from tests.golden_cases import CASES, GOLDEN, as_text


def assert_table_unchanged(name: str, tmp_path: Path) -> None:
    """The regenerated table's CSV text equals tests/golden/<name>.csv (diff shown if not)."""
    expected = (GOLDEN / f"{name}.csv").read_text()
    got = as_text(CASES[name](tmp_path))
    diff = "".join(list(difflib.unified_diff(
        expected.splitlines(True), got.splitlines(True), "golden", "now", n=0))[:40])
    assert got == expected, f"{name} differs from tests/golden/{name}.csv:\n{diff}"


@pytest.mark.parametrize("name", ["mendoza_numpy", "office_numpy"])
def test_numpy_tables_unchanged(name, tmp_path):
    assert_table_unchanged(name, tmp_path)


@needs_radiance
@pytest.mark.radiance
@pytest.mark.parametrize("name", ["mendoza_radiance", "office_radiance"])
def test_radiance_tables_unchanged(name, tmp_path):
    assert_table_unchanged(name, tmp_path)


def assert_within_standard_errors(name: str, tmp_path: Path):
    """Every row of the rerun table within Z_MAX combined standard errors of the golden one
    (tests/golden_full.py; the same platform: equal); the rerun table is returned."""
    import time

    import numpy as np

    from tests.golden_full import Z_MAX, read_golden, run_table, z_scores

    if not (GOLDEN / f"{name}.csv").exists():
        pytest.skip(f"tests/golden/{name}.csv not generated yet: python -m tests.golden_full")
    t0 = time.perf_counter()
    new = run_table(name, tmp_path)
    z = z_scores(read_golden(name), new)
    worst = z.abs().idxmax()
    print(f"{name}: {len(z)} rows, max |z| {np.abs(z).max():.2f} at {worst}, "
          f"{time.perf_counter() - t0:.0f} s")
    assert np.abs(z).max() <= Z_MAX, z[np.abs(z) > Z_MAX].head(20)
    return new


@needs_radiance
@pytest.mark.radiance
@pytest.mark.slow
def test_mendoza_radiance_every_hour_at_the_examples_settings_within_standard_errors(tmp_path):
    """Every hour of the Mendoza street (A–F, A-sky) at its own settings (tests/golden_full.py)."""
    assert_within_standard_errors("mendoza_radiance_full", tmp_path)


@needs_radiance
@pytest.mark.radiance
@pytest.mark.slow
def test_office_radiance_every_hour_at_the_examples_settings_within_standard_errors(tmp_path):
    """The office block exactly as the example runs it (-ad 2048, -ab 6, its 0.5 m façade and
    work-plane grids; both scenarios, all seven hours; 980 rows): every sensor within Z_MAX
    standard errors of tests/golden/office_radiance_full.csv (tests/golden_full.py); and the
    crowns lower the façade's mean every hour (with < without)."""
    t = assert_within_standard_errors("office_radiance_full", tmp_path)
    mean = t[t["grid"] == "facade"].groupby(["time", "scenario"])["lux"].mean().unstack()
    assert len(mean) == 7
    assert (mean["with"] < mean["without"]).all(), mean
