"""EPW weather files: direct normal and diffuse horizontal illuminance for the project's hours.

EPW rows are hourly, labelled by the hour *ending* (hour 11 = 10:00–11:00). A clock time
HH:MM is read from the row whose interval contains it (HH:30 → row HH+1). Fields used (0-based):
1 month, 2 day, 3 hour, 17 direct normal illuminance (lux), 18 diffuse horizontal illuminance.
"""

from __future__ import annotations

import csv
from datetime import date as _date
from pathlib import Path

from radtree.errors import ConfigError

DNI_LUX, DHI_LUX = 17, 18


def read_epw(path: Path) -> dict[tuple[int, int, int], tuple[float, float]]:
    """(month, day, hour-ending) → (direct normal lux, diffuse horizontal lux)."""
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as exc:
        raise ConfigError(f"cannot read EPW file {path}: {exc}") from exc
    if len(lines) < 9 or not lines[0].startswith("LOCATION"):
        raise ConfigError(f"{path} is not an EPW file (no LOCATION header)")
    out = {}
    for i, row in enumerate(csv.reader(lines[8:]), start=9):
        if not row:
            continue
        try:
            key = (int(row[1]), int(row[2]), int(row[3]))
            dni, dhi = float(row[DNI_LUX]), float(row[DHI_LUX])
        except (IndexError, ValueError) as exc:
            raise ConfigError(f"{path}: line {i}: malformed EPW data row") from exc
        if dni >= 999900:  # EPW missing-value code
            raise ConfigError(f"{path}: line {i}: direct normal illuminance is missing (999999)")
        out[key] = (dni, dhi)
    return out


def epw_hour_values(project, hours: list[str]) -> dict[str, float]:
    """DNI (lux) per clock time from the project's EPW file (DHI via :func:`epw_diffuse`)."""
    return {h: v[0] for h, v in _values(project, hours).items()}


def epw_diffuse(project, hours: list[str]) -> dict[str, float]:
    return {h: v[1] for h, v in _values(project, hours).items()}


def _values(project, hours: list[str]) -> dict[str, tuple[float, float]]:
    data = read_epw(project.light.epw)
    d = _date.fromisoformat(project.site.date)
    out = {}
    for h in hours:
        hh, mm = (int(x) for x in h.split(":"))
        ending = hh + 1 if mm > 0 else max(hh, 1)
        key = (d.month, d.day, ending)
        if key not in data:
            raise ConfigError(f"EPW file {project.light.epw} has no row for {d} hour {ending}")
        out[h] = data[key]
    return out
