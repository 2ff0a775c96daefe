"""Measured illuminance: load, validate and tidy the measurement CSV files.

Three shapes of hourly file are accepted (column names are case-insensitive; the value column
may be called ``measured_lux`` or ``lux`` whatever the units):

* ``time,measured_lux``  — the hourly mean of the façade grid (shape ``"mean"``);
* ``time,row,lux``       — hourly means per sensor row (shape ``"row"``);
* ``time,sensor,lux``    — hourly readings per sensor (shape ``"sensor"``; a ``row`` column
  may accompany it).

Units are stated in a ``#`` comment above the header (``# Units: lux`` or ``# Units: klux``) or
passed as ``units=``; values are always returned in lux. Times are local clock times and are
returned as ``HH:MM``. Every failure is a :class:`MeasurementError` naming the file and, where
there is one, the line.

The per-row daily means (``row,sensors,measured_mean_lux``) load with :func:`load_measured_rows`.
"""

from __future__ import annotations

import csv
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import pandas as pd

from radtree.errors import RadtreeError

Units = Literal["lux", "klux"]
ShapeKind = Literal["mean", "row", "sensor"]

#: Above this a reading is not daylight on a façade (direct sun ≈ 100–120 klx plus sky), lux.
MAX_LUX = 200_000.0
#: Below this an hourly daylight grid mean is implausible (usually klux written as lux), lux.
MIN_GRID_MEAN_LUX = 1.0

_UNIT_FACTORS: dict[str, float] = {"lux": 1.0, "klux": 1000.0}
_UNIT_ALIASES = {"lux": "lux", "lx": "lux", "klux": "klux", "klx": "klux", "kilolux": "klux"}
_UNITS_RE = re.compile(r"\bunits?\s*[:=]?\s*(kilolux|klux|klx|lux|lx)\b", re.IGNORECASE)
_TIME_RE = re.compile(r"^(\d{1,2}):(\d{2})$")
_VALUE_COLUMNS = ("measured_lux", "lux")


class MeasurementError(RadtreeError):
    """A measurement file is missing or invalid; the message names the file and the line."""

    def __init__(self, message: str, *, source: str | os.PathLike | None = None,
                 line: int | None = None):
        self.source = str(source) if source is not None else None
        self.line = line
        where = [s for s in (self.source, f"line {line}" if line is not None else None) if s]
        super().__init__(": ".join([*where, message]))


@dataclass(frozen=True)
class MeasuredShape:
    """What a measured hourly file holds.

    ``kind`` is ``"mean"``, ``"row"`` or ``"sensor"``; ``units`` the units the file was written
    in (the returned frame is always lux); ``labels`` the row names or sensor ids (empty for
    ``"mean"``); ``times`` the hours, ``HH:MM``, sorted.
    """

    kind: ShapeKind
    units: Units
    source: Path
    times: tuple[str, ...]
    labels: tuple[str | int, ...] = ()

    @property
    def n_hours(self) -> int:
        """Number of measured hours."""
        return len(self.times)


# --------------------------------------------------------------------------- parsing helpers


@dataclass(frozen=True)
class _Table:
    header: list[str]
    header_line: int
    rows: list[tuple[int, dict[str, str]]]  # (line number, column -> raw text)
    comment_units: str | None


def normalise_time(text: str) -> str:
    """Return a local clock time ``H:MM``/``HH:MM`` as ``HH:MM``; raise RadtreeError otherwise."""
    m = _TIME_RE.match(str(text).strip())
    if not m or int(m.group(1)) > 23 or int(m.group(2)) > 59:
        raise RadtreeError(f"time '{text}' is not a clock time HH:MM (e.g. 10:30)")
    return f"{int(m.group(1)):02d}:{m.group(2)}"


def _read_table(path: Path) -> _Table:
    """Read a commented CSV keeping the file line number of every data row."""
    if not path.is_file():
        raise MeasurementError("measurement file not found", source=path)
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise MeasurementError(f"cannot read measurement file ({exc})", source=path) from exc

    header: list[str] | None = None
    header_line = 0
    rows: list[tuple[int, dict[str, str]]] = []
    units_found: list[tuple[int, str]] = []
    for number, raw in enumerate(lines, start=1):
        text = raw.strip()
        if not text:
            continue
        if text.startswith("#"):
            for match in _UNITS_RE.finditer(text):
                units_found.append((number, _UNIT_ALIASES[match.group(1).lower()]))
            continue
        fields = [f.strip() for f in next(csv.reader([text]))]
        if header is None:
            header = [f.lower() for f in fields]
            header_line = number
            dupes = sorted({c for c in header if header.count(c) > 1})
            if dupes:
                raise MeasurementError(f"repeated column(s) {', '.join(dupes)} in the header",
                                       source=path, line=number)
            continue
        if len(fields) != len(header):
            raise MeasurementError(
                f"{len(fields)} field(s) where the header has {len(header)} "
                f"({', '.join(header)})", source=path, line=number)
        rows.append((number, dict(zip(header, fields))))
    if header is None:
        raise MeasurementError("no header line (the file is empty or only comments)", source=path)
    if not rows:
        raise MeasurementError("no data rows below the header", source=path, line=header_line)
    stated = {u for _, u in units_found}
    if len(stated) > 1:
        lines_txt = ", ".join(f"line {n}: {u}" for n, u in units_found)
        raise MeasurementError(f"conflicting units in the comments ({lines_txt})", source=path)
    return _Table(header, header_line, rows, stated.pop() if stated else None)


def _resolve_units(table: _Table, units: str | None, path: Path) -> Units:
    if units is not None:
        key = _UNIT_ALIASES.get(str(units).strip().lower())
        if key is None:
            raise MeasurementError(f"units={units!r} is not 'lux' or 'klux'", source=path)
        if table.comment_units is not None and table.comment_units != key:
            raise MeasurementError(
                f"the file states units '{table.comment_units}' but units='{key}' was passed",
                source=path)
        return "klux" if key == "klux" else "lux"
    if table.comment_units is None:
        raise MeasurementError(
            "units not stated: add a comment line such as '# Units: lux' (or klux) above the "
            "header, or pass units='lux'|'klux'", source=path)
    return "klux" if table.comment_units == "klux" else "lux"


def _number(text: str, column: str, path: Path, line: int) -> float:
    if text == "":
        raise MeasurementError(f"empty value in column '{column}'", source=path, line=line)
    try:
        value = float(text)
    except ValueError:
        raise MeasurementError(f"'{text}' in column '{column}' is not a number",
                               source=path, line=line) from None
    if math.isnan(value):
        raise MeasurementError(f"NaN in column '{column}'", source=path, line=line)
    if math.isinf(value):
        raise MeasurementError(f"infinite value in column '{column}'", source=path, line=line)
    if value < 0:
        raise MeasurementError(f"negative value {text} in column '{column}'",
                               source=path, line=line)
    return value


def _lux(text: str, column: str, units: Units, path: Path, line: int) -> float:
    value = _number(text, column, path, line) * _UNIT_FACTORS[units]
    if value > MAX_LUX:
        hint = " — is the file in lux rather than klux?" if units == "klux" else ""
        raise MeasurementError(
            f"{value:g} lx in column '{column}' exceeds the plausible maximum of "
            f"{MAX_LUX:,.0f} lx{hint}", source=path, line=line)
    return value


def _label(text: str, column: str, path: Path, line: int) -> str | int:
    if text == "":
        raise MeasurementError(f"empty value in column '{column}'", source=path, line=line)
    if column == "sensor" and re.fullmatch(r"[+-]?\d+", text):
        return int(text)
    return text.lower() if column == "row" else text


def _time(text: str, path: Path, line: int) -> str:
    try:
        return normalise_time(text)
    except RadtreeError as exc:
        raise MeasurementError(str(exc), source=path, line=line) from None


# --------------------------------------------------------------------------- public loaders


def detect_shape(columns: list[str]) -> tuple[ShapeKind, str]:
    """Return (shape kind, value column) for lower-cased header ``columns``; raise if none fits."""
    value = next((c for c in _VALUE_COLUMNS if c in columns), None)
    if "time" in columns and value is not None:
        if "sensor" in columns:
            return "sensor", value
        if "row" in columns:
            return "row", value
        return "mean", value
    raise RadtreeError(
        f"columns ({', '.join(columns)}) fit none of the accepted shapes: "
        "'time,measured_lux' (grid mean), 'time,row,lux' (per row), 'time,sensor,lux' (per sensor)")


def _klux_hint(unit: str) -> str:
    """What to say after an implausibly low value read as lux."""
    return (" — if the values are klux, state '# Units: klux' or pass units='klux'"
            if unit == "lux" else "")


def _same_labels_every_hour(frame: pd.DataFrame, label_col: str | None,
                            lines_by_time: dict[str, list[int]], p: Path
                            ) -> tuple[str | int, ...]:
    """The rows' or sensors' labels, sorted; MeasurementError when an hour lacks one that
    other hours have (``()`` for the mean shape)."""
    if label_col is None:
        return ()
    all_labels = set(frame[label_col])
    for t, group in frame.groupby("time", sort=True):
        missing = all_labels - set(group[label_col])
        if missing:
            raise MeasurementError(
                f"time {t} lacks {label_col}(s) {', '.join(sorted(map(str, missing)))} that "
                "other hours have; every hour needs the same set",
                source=p, line=lines_by_time[str(t)][0])
    return tuple(sorted(all_labels, key=lambda v: (str(type(v)), v)))


def load_measured(path: str | os.PathLike, units: str | None = None
                  ) -> tuple[pd.DataFrame, MeasuredShape]:
    """Load an hourly measured-illuminance CSV in any accepted shape; values returned in lux.

    Returns the tidy frame and its :class:`MeasuredShape`. Columns of the frame:
    ``time, measured_lux`` (mean); ``time, row, measured_lux`` (row);
    ``time, sensor, measured_lux`` plus ``row`` if given (sensor). Sorted by time then label.
    ``units`` ('lux'|'klux') overrides a missing header statement; it must agree with one.
    """
    p = Path(path)
    table = _read_table(p)
    try:
        kind, value_col = detect_shape(table.header)
    except RadtreeError as exc:
        raise MeasurementError(str(exc), source=p, line=table.header_line) from None
    unit = _resolve_units(table, units, p)
    label_col = {"mean": None, "row": "row", "sensor": "sensor"}[kind]
    keep_row = kind == "sensor" and "row" in table.header

    records: list[dict[str, object]] = []
    seen: dict[tuple[str, object], int] = {}
    lines_by_time: dict[str, list[int]] = {}
    for line, fields in table.rows:
        t = _time(fields["time"], p, line)
        rec: dict[str, object] = {"time": t}
        label: object = None
        if label_col is not None:
            label = _label(fields[label_col], label_col, p, line)
            rec[label_col] = label
        if keep_row:
            rec["row"] = _label(fields["row"], "row", p, line)
        rec["measured_lux"] = _lux(fields[value_col], value_col, unit, p, line)
        key = (t, label)
        if key in seen:
            what = f"time {t}" + (f", {label_col} {label}" if label_col else "")
            raise MeasurementError(f"duplicate entry for {what} (first on line {seen[key]})",
                                   source=p, line=line)
        seen[key] = line
        lines_by_time.setdefault(t, []).append(line)
        records.append(rec)

    if label_col == "sensor" and any(isinstance(r["sensor"], str) for r in records):
        for r in records:  # mixed numeric and named ids: keep them all as text
            r["sensor"] = str(r["sensor"])
    frame = pd.DataFrame.from_records(records)
    labels = _same_labels_every_hour(frame, label_col, lines_by_time, p)
    hourly = frame.groupby("time", sort=True)["measured_lux"].mean()
    for t, mean in hourly.items():
        if mean < MIN_GRID_MEAN_LUX:
            at = lines_by_time[str(t)]
            where = "" if len(at) == 1 else f" (lines {', '.join(map(str, at))})"
            raise MeasurementError(
                f"grid mean {mean:g} lx at {t}{where} is below {MIN_GRID_MEAN_LUX:g} lx, "
                f"implausible for daylight{_klux_hint(unit)}", source=p,
                line=at[0] if len(at) == 1 else None)
    sort_cols = ["time"] + ([label_col] if label_col else [])
    frame = frame.sort_values(sort_cols, kind="stable").reset_index(drop=True)
    shape = MeasuredShape(kind=kind, units=unit, source=p,
                          times=tuple(str(t) for t in hourly.index), labels=labels)
    return frame, shape


def load_measured_rows(path: str | os.PathLike, units: str | None = None) -> pd.DataFrame:
    """Load per-row daily means (``row,sensors,measured_mean_lux``); values returned in lux.

    Returns columns ``row`` (lower-case), ``sensors`` (int ≥ 1) and ``measured_mean_lux``,
    in file order.
    """
    p = Path(path)
    table = _read_table(p)
    required = ("row", "sensors", "measured_mean_lux")
    missing = [c for c in required if c not in table.header]
    if missing:
        raise MeasurementError(
            f"missing column(s) {', '.join(missing)}; expected 'row,sensors,measured_mean_lux' "
            f"(found {', '.join(table.header)})", source=p, line=table.header_line)
    unit = _resolve_units(table, units, p)
    records: list[dict[str, object]] = []
    seen: dict[str | int, int] = {}
    for line, fields in table.rows:
        row = _label(fields["row"], "row", p, line)
        if row in seen:
            raise MeasurementError(f"duplicate row '{row}' (first on line {seen[row]})",
                                   source=p, line=line)
        seen[row] = line
        sensors = _number(fields["sensors"], "sensors", p, line)
        if sensors < 1 or sensors != int(sensors):
            raise MeasurementError(f"sensors must be a whole number ≥ 1, got {fields['sensors']}",
                                   source=p, line=line)
        value = _lux(fields["measured_mean_lux"], "measured_mean_lux", unit, p, line)
        if value < MIN_GRID_MEAN_LUX:
            raise MeasurementError(
                f"daily mean {value:g} lx is below {MIN_GRID_MEAN_LUX:g} lx, implausible for "
                f"daylight{_klux_hint(unit)}", source=p, line=line)
        records.append({"row": row, "sensors": int(sensors), "measured_mean_lux": value})
    return pd.DataFrame.from_records(records)


def grid_mean(measured: pd.DataFrame,
              sensors_per_row: Mapping[str, int] | None = None) -> pd.DataFrame:
    """Reduce a tidy measured frame of any shape to the hourly grid mean ``time, measured_lux``.

    Sensor shape: plain mean over sensors. Row shape: mean of row means weighted by the number
    of sensors per row (``sensors_per_row``, required — an unweighted mean of unequal rows would
    be a different quantity). Mean shape: returned as is.
    """
    cols = set(measured.columns)
    if "time" not in cols or "measured_lux" not in cols:
        raise RadtreeError(
            f"measured table needs columns 'time' and 'measured_lux' (has {', '.join(map(str, measured.columns))})")
    measured = measured.assign(time=[normalise_time(str(t)) for t in measured["time"]])
    values = pd.to_numeric(measured["measured_lux"], errors="coerce")
    if not values.map(math.isfinite).all():
        bad = sorted(set(measured.loc[~values.map(math.isfinite), "time"]))
        raise RadtreeError(f"measured table has missing or non-numeric values at {', '.join(bad)}")
    measured = measured.assign(measured_lux=values.astype(float))
    if "sensor" in cols:
        out = measured.groupby("time", sort=True)["measured_lux"].mean().reset_index()
    elif "row" in cols:
        if sensors_per_row is None:
            raise RadtreeError("a per-row measured table needs sensors_per_row to form the grid mean")
        weights = {str(k).lower(): int(v) for k, v in sensors_per_row.items()}
        rows = measured["row"].astype(str).str.lower()
        unknown = sorted(set(rows) - set(weights))
        if unknown:
            raise RadtreeError(f"no sensor count for measured row(s) {', '.join(unknown)}")
        w = rows.map(weights).astype(float)
        weighted = (measured["measured_lux"] * w).groupby(measured["time"]).sum()
        out = (weighted / w.groupby(measured["time"]).sum()).rename("measured_lux").reset_index()
    else:
        out = measured[["time", "measured_lux"]].copy()
        if out["time"].duplicated().any():
            dupes = sorted(set(out.loc[out["time"].duplicated(), "time"]))
            raise RadtreeError(f"measured grid means repeat hour(s) {', '.join(dupes)}")
        out = out.sort_values("time", kind="stable")
    return out.reset_index(drop=True)


def hourly_grid_means(path: str | os.PathLike) -> pd.Series | None:
    """The measured hourly façade-grid means (lux, indexed by time) of a mean- or sensor-shaped
    file; None for a per-row file (its grid mean needs the sensors per row)."""
    frame, shape = load_measured(path)
    if shape.kind == "row":
        return None
    return grid_mean(frame).set_index("time")["measured_lux"].astype(float)
