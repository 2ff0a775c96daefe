"""radtree.light: the one EPW reader feeds the hourly path, 179 lm/W is written once, light/
knows no engine."""

from __future__ import annotations

import ast
import csv
from pathlib import Path

import pytest

from radtree.config import load_project
from radtree.errors import ConfigError
from radtree.light.hours import hour_states
from radtree.light.weather import read_epw

from .conftest import copy_project

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "radtree"
OFFICE_EPW = ROOT / "examples" / "office-block" / "data" / "mendoza_generated.epw"
# other meanings of the number 179 (not lm/W): the stereographic lens's field limit in degrees
OTHER_179 = {"hemi/lens.py"}


def _csv_row(path: Path, month: int, day: int, hour: int) -> tuple[float, float]:
    """Fields 17, 18 (direct normal, diffuse horizontal illuminance) of an EPW row, by hand."""
    with path.open(newline="") as f:
        for i, row in enumerate(csv.reader(f)):
            if i >= 8 and (int(row[1]), int(row[2]), int(row[3])) == (month, day, hour):
                return float(row[17]), float(row[18])
    raise AssertionError("row not found")


def test_epw_hours_come_from_the_row_ending_after_the_clock_time(tmp_path):
    p = copy_project(tmp_path / "proj", hours=["10:30", "13:00"], replace={
        r'^direct_normal = .*$': f'epw = "{OFFICE_EPW.as_posix()}"',
        r'^sky = "none"': 'sky = "perez"'})
    states = {s.time: s for s in hour_states(load_project(p))}
    for t, ending in (("10:30", 11), ("13:00", 13)):
        dni, dhi = _csv_row(OFFICE_EPW, 12, 22, ending)
        assert (states[t].direct_normal_lux, states[t].diffuse_horizontal_lux) == (dni, dhi)
    assert read_epw(OFFICE_EPW).location == (-32.89, -68.83, -3.0, 750.0)


def test_a_missing_direct_normal_illuminance_names_the_line(tmp_path):
    lines = OFFICE_EPW.read_text().splitlines()
    fields = lines[20].split(",")
    fields[17] = "999999"
    lines[20] = ",".join(fields)
    bad = tmp_path / "bad.epw"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError, match="line 21: direct normal illuminance is missing"):
        read_epw(bad).illuminance()
    (tmp_path / "not.epw").write_text("hello\n")
    with pytest.raises(ConfigError, match="not an EPW file"):
        read_epw(tmp_path / "not.epw")


def _modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        yield path.relative_to(PACKAGE).as_posix(), ast.parse(path.read_text(), str(path))


def test_white_efficacy_179_is_written_once():
    where = [rel for rel, tree in _modules() for node in ast.walk(tree)
             if isinstance(node, ast.Constant) and type(node.value) in (int, float)
             and node.value == 179 and rel not in OTHER_179]
    assert where == ["light/units.py"]


def test_light_imports_no_engine():
    bad = []
    for rel, tree in _modules():
        if not rel.startswith("light/"):
            continue
        for node in ast.walk(tree):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            bad += [f"{rel}: {n}" for n in names if n.startswith("radtree.engines")]
    assert bad == []
