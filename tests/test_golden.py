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
