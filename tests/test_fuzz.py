"""Fuzzing (issue 23): mutated project files, CSVs and weather files end in success or in one
clear ``error:`` line with exit 2 — never a traceback, never exit 1 (a bug).

Hypothesis mutates the reduced Mendoza example (open street, one hour, 64 rays) line by line;
every example runs the real command line in-process on the cheap path
(``simulate --dry-run --engine numpy``: project, weather, hour states, scene, engine plan), and
the measurement loaders directly. Few examples, derandomised: the same cases every run.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from radtree.cli import main
from radtree.errors import RadtreeError
from radtree.measurements import load_measured, load_measured_rows

from .conftest import ROOT, copy_project
from .test_faults import TINY

EPW = ROOT / "examples" / "office-block" / "data" / "mendoza_generated.epw"
FUZZ = settings(max_examples=20, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow])

#: what a value may become (TOML literals, some of them not TOML at all)
TOML_VALUES = ["nan", "inf", "-inf", "-1", "0", "1e9", "99999999999999999999", '"x"', '""',
               "true", "[]", "{}", '"', "[1, 2", "1979-05-27", '"../nope.csv"', "-0.5", "0.5",
               '"10:30"', '["25:99"]', '"ñandú"', "= 1"]
#: what a CSV cell may become
CELLS = ["", "nan", "NaN", "inf", "-5", "1e400", "abc", "10:30", "25:99", "ñ", '"', ";", "1,2",
         "0", "-0", "1e-300", "  7 ", "\t"]


def assert_clean(res) -> None:  # type: ignore[no-untyped-def]
    """Success, or exit 2 with exactly one ``error:`` line and no traceback."""
    assert "Traceback" not in res.output, res.output
    assert res.exit_code in (0, 2), (res.exit_code, res.output, res.exception)
    if res.exit_code:
        errors = [line for line in res.stderr.splitlines() if line.startswith("error: ")]
        assert len(errors) == 1, res.stderr


def dry_run(project: Path):  # type: ignore[no-untyped-def]
    return CliRunner().invoke(main, ["simulate", str(project), "--engine", "numpy", "-s", "A",
                                     "--dry-run"])


def mutate_lines(lines: list[str], data: st.DataObject, values: list[str], sep: str) -> None:
    """One edit of ``lines`` in place: a value or cell replaced, a line dropped, doubled,
    cut short, or a key renamed."""
    i = data.draw(st.integers(0, len(lines) - 1), label="line")
    op = data.draw(st.sampled_from(["value", "value", "drop", "double", "cut", "rename"]),
                   label="op")
    line = lines[i]
    if op == "drop":
        del lines[i]
    elif op == "double":
        lines.insert(i, line)
    elif op == "cut":
        lines[i] = line[: data.draw(st.integers(0, max(0, len(line) - 1)), label="cut at")]
    elif sep == "=" and op == "rename" and "=" in line:
        key, rest = line.split("=", 1)
        lines[i] = key.rstrip() + data.draw(st.sampled_from(["x", "_", "é"])) + " =" + rest
    elif sep == "=":
        if re.match(r"^\s*[\w.\"-]+\s*=", line):
            lines[i] = line.split("=", 1)[0] + "= " + data.draw(st.sampled_from(values),
                                                                 label="value")
    else:
        cells = line.split(sep)
        k = data.draw(st.integers(0, len(cells) - 1), label="cell")
        cells[k] = data.draw(st.sampled_from(values), label="value")
        lines[i] = sep.join(cells)


def _tiny(folder: Path, replace: dict[str, str] | None = None) -> Path:
    return copy_project(folder / "p", {**TINY, **(replace or {})}, hours=["10:30"])


@FUZZ
@given(st.data())
def test_mutated_project_file(data):  # type: ignore[no-untyped-def]
    with tempfile.TemporaryDirectory() as tmp:
        proj = _tiny(Path(tmp))
        toml = proj / "radtree.toml"
        lines = toml.read_text().splitlines()
        for _ in range(data.draw(st.integers(1, 2), label="edits")):
            mutate_lines(lines, data, TOML_VALUES, "=")
        toml.write_text("\n".join(lines) + "\n")
        assert_clean(dry_run(proj))


@FUZZ
@given(st.data(), st.sampled_from(["direct_normal_illuminance.csv", "concrete_reflectance.csv",
                                   "measured_vertical_illuminance.csv", "measured_rows.csv"]))
def test_mutated_csv_files(data, name):  # type: ignore[no-untyped-def]
    with tempfile.TemporaryDirectory() as tmp:
        proj = _tiny(Path(tmp))   # ground_reflectance is data/concrete_reflectance.csv
        path = proj / "data" / name
        if data.draw(st.booleans(), label="bytes"):
            raw = path.read_bytes()
            path.write_bytes(raw[: data.draw(st.integers(0, len(raw)), label="truncate")]
                             + data.draw(st.sampled_from([b"", b"\xff\xfe\x00", b"\n\n,,\n"])))
        else:
            lines = path.read_text().splitlines()
            mutate_lines(lines, data, CELLS, ",")
            path.write_text("\n".join(lines) + "\n")
        if name.startswith("measured"):
            loader = load_measured if name == "measured_vertical_illuminance.csv" \
                else load_measured_rows
            try:
                loader(path)
            except RadtreeError as exc:     # what the command line prints as its error line
                assert name in str(exc) and "\n" not in str(exc), str(exc)
        else:
            assert_clean(dry_run(proj))


@settings(max_examples=6, deadline=None, derandomize=True, database=None)
@given(st.data())
def test_mutated_weather_file(data):  # type: ignore[no-untyped-def]
    with tempfile.TemporaryDirectory() as tmp:
        proj = _tiny(Path(tmp), {r'^direct_normal = .*$': 'epw = "data/weather.epw"'})
        epw = proj / "data" / "weather.epw"
        lines = EPW.read_text().splitlines()
        # the header, and the 22 December hours the project reads (10:00–11:00 local)
        day = next(i for i, line in enumerate(lines) if re.match(r"^\d{4},12,22,11,", line))
        window = list(range(0, 8)) + list(range(day - 1, day + 2))
        i = data.draw(st.sampled_from(window), label="line")
        sub = [lines[i]]
        mutate_lines(sub, data, CELLS, ",")
        lines[i:i + 1] = sub
        epw.write_text("\n".join(lines) + "\n")
        assert_clean(dry_run(proj))
