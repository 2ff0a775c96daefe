"""The small CSV inputs of the light: direct normal illuminance per hour, ground reflectance.

* direct normal illuminance table: columns ``time,direct_normal_lux`` (clock time ``HH:MM``,
  lux), '#' comments allowed;
* ground reflectance table: columns ``angle_deg,reflectance`` (sun altitude in degrees, the
  street's reflectance 0–1 at that altitude).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from radtree.config import parse_time
from radtree.errors import ConfigError

MAX_DIRECT_NORMAL_LUX = 150000.0  # above this a DNI value is implausible (klux or W/m²?)


def read_table(path: Path, columns: tuple[str, ...], what: str) -> pd.DataFrame:
    """Read a small CSV with '#' comments and check its columns.

    Every column after the first must hold non-negative numbers; errors name the file, the
    data row and the value as written.
    """
    try:
        df = pd.read_csv(path, comment="#", skipinitialspace=True)
    except FileNotFoundError as exc:
        raise ConfigError(f"{what} not found: {path}") from exc
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{what} {path} is not a readable CSV: {exc}") from exc
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise ConfigError(f"{what} {path}: missing column(s) {', '.join(missing)} "
                          f"(found: {', '.join(map(str, df.columns))})")
    for c in columns[1:]:
        vals = pd.to_numeric(df[c], errors="coerce")
        bad = vals.isna() | ~np.isfinite(vals) | (vals < 0)
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise ConfigError(f"{what} {path}: data row {i + 1}: {c} = "
                              f"{_as_written(path, c, i)} is not a non-negative number")
        df[c] = vals
    return df


def _as_written(path: Path, column: str, row: int) -> str:
    """The text of data row ``row`` (0-based) in ``column`` as the file has it (quoted)."""
    raw = pd.read_csv(path, comment="#", skipinitialspace=True, dtype=str,
                      keep_default_na=False)
    return repr(str(raw[column].iloc[row]))


def direct_normal_table(path: Path) -> dict[str, float]:
    """Clock time ``HH:MM`` → direct normal illuminance (lux) from a DNI table."""
    df = read_table(path, ("time", "direct_normal_lux"), "direct normal illuminance table")
    out: dict[str, float] = {}
    for i, (t, v) in enumerate(zip(df["time"], df["direct_normal_lux"])):
        t = parse_time(str(t).strip(), f"{path.name}, data row {i + 1}, time")
        if v > MAX_DIRECT_NORMAL_LUX:
            raise ConfigError(f"{path}: {t}: direct normal illuminance {v} lx is implausible "
                              "(> 150 000 lx); is the unit klux or W/m²?")
        out[t] = float(v)
    return out


def ground_reflectance_table(path: Path) -> pd.DataFrame:
    """The ground reflectance table (columns ``angle_deg``, ``reflectance``), as written."""
    df = read_table(path, ("angle_deg", "reflectance"), "ground reflectance table")
    angles = pd.to_numeric(df["angle_deg"], errors="coerce")
    bad = ~np.isfinite(angles) | (angles < 0) | (angles > 90)
    if bad.any():
        i = int(np.flatnonzero(bad.to_numpy())[0])
        raise ConfigError(f"ground reflectance table {path}: data row {i + 1}: angle_deg = "
                          f"{_as_written(path, 'angle_deg', i)} is not a sun altitude 0–90°")
    if (df["reflectance"] > 1).any():
        i = int(np.flatnonzero((df["reflectance"] > 1).to_numpy())[0])
        raise ConfigError(f"ground reflectance table {path}: data row {i + 1}: reflectance = "
                          f"{_as_written(path, 'reflectance', i)} is above 1")
    df["angle_deg"] = angles
    return df
