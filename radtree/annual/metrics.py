"""Climate-based daylight metrics from hourly illuminance series.

All functions take ``lux`` of shape (sensors, hours) (or (hours,) for one sensor) and a
boolean ``occupied`` mask of shape (hours,); percentages are of the occupied hours.

Bins and thresholds (boundary values stated, since hourly values do land on them):

* **UDI** (useful daylight illuminance, Nabil & Mardaljevic 2005/2006): ``below_100`` E <
  100 lx ("fell short"), ``100_300`` 100 ≤ E < 300 ("supplementary"), ``300_3000``
  300 ≤ E ≤ 3000 ("autonomous", both bounds included), ``above_3000`` E > 3000
  ("exceeded"). The four add up to 100 %.
* **DA₃₀₀** (daylight autonomy): % of occupied hours with E ≥ 300 lx.
* **sDA₃₀₀/₅₀%** (IES LM-83): % of sensors with DA₃₀₀ ≥ 50 %.
* **ASE₁₀₀₀,₂₅₀** (IES LM-83): per sensor, the number of occupied hours whose *direct sun*
  illuminance (sunlight straight from the disc, no sky, no inter-reflection) exceeds
  1000 lx (E > 1000); ASE is the % of sensors with more than 250 such hours (> 250).

LM-83 defines sDA and ASE on the horizontal work plane; values on a façade grid are given
for comparison only. No blinds are operated here (LM-83's sDA closes blinds on sensors that
see direct sun; this run shows the unshaded façade), which is stated in the report.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

UDI_COLUMNS = ("udi_below_100", "udi_100_300", "udi_300_3000", "udi_above_3000")
DA_THRESHOLD = 300.0
SDA_FRACTION = 50.0
ASE_THRESHOLD = 1000.0
ASE_HOURS = 250


def _prep(lux: np.ndarray, occupied: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    e = np.atleast_2d(np.asarray(lux, float))
    occ = np.asarray(occupied, bool)
    if e.shape[1] != occ.shape[0]:
        raise ValueError(f"{e.shape[1]} hours of illuminance but {occ.shape[0]} occupancy flags")
    n = int(occ.sum())
    if n == 0:
        raise ValueError("no occupied hours")
    return e[:, occ], occ, n


def udi(lux: np.ndarray, occupied: np.ndarray) -> pd.DataFrame:
    """UDI bins per sensor (% of occupied hours), columns :data:`UDI_COLUMNS`."""
    e, _, n = _prep(lux, occupied)
    below = (e < 100.0).sum(axis=1)
    supp = ((e >= 100.0) & (e < 300.0)).sum(axis=1)
    auto = ((e >= 300.0) & (e <= 3000.0)).sum(axis=1)
    exceeded = (e > 3000.0).sum(axis=1)
    return pd.DataFrame({c: 100.0 * v / n for c, v in
                         zip(UDI_COLUMNS, (below, supp, auto, exceeded))})


def daylight_autonomy(lux: np.ndarray, occupied: np.ndarray,
                      threshold: float = DA_THRESHOLD) -> np.ndarray:
    """% of occupied hours with E ≥ ``threshold``, per sensor."""
    e, _, n = _prep(lux, occupied)
    return 100.0 * (e >= threshold).sum(axis=1) / n


def spatial_daylight_autonomy(da: np.ndarray, fraction: float = SDA_FRACTION) -> float:
    """% of sensors whose DA reaches ``fraction`` % (DA ≥ fraction)."""
    da = np.asarray(da, float)
    return float(100.0 * np.mean(da >= fraction)) if da.size else float("nan")


def sunlight_hours(direct_lux: np.ndarray, occupied: np.ndarray,
                   threshold: float = ASE_THRESHOLD) -> np.ndarray:
    """Occupied hours with direct-sun illuminance E > ``threshold``, per sensor."""
    e, _, _ = _prep(direct_lux, occupied)
    return (e > threshold).sum(axis=1)


def annual_sunlight_exposure(hours: np.ndarray, limit: int = ASE_HOURS) -> float:
    """% of sensors with more than ``limit`` direct-sun hours."""
    h = np.asarray(hours)
    return float(100.0 * np.mean(h > limit)) if h.size else float("nan")


def sensor_table(lux: np.ndarray, direct_lux: np.ndarray, occupied: np.ndarray
                 ) -> pd.DataFrame:
    """Per sensor: the four UDI bins, DA₃₀₀ and ASE hours."""
    df = udi(lux, occupied)
    df["da_300"] = daylight_autonomy(lux, occupied)
    df["ase_hours"] = sunlight_hours(direct_lux, occupied)
    return df


def monthly_mean(lux: np.ndarray, occupied: np.ndarray, month: np.ndarray) -> np.ndarray:
    """Mean illuminance over sensors and occupied hours of each month (12 values)."""
    e = np.atleast_2d(np.asarray(lux, float))
    out = np.full(12, np.nan)
    for m in range(1, 13):
        sel = np.asarray(occupied, bool) & (np.asarray(month) == m)
        if sel.any():
            out[m - 1] = float(e[:, sel].mean())
    return out


def month_hour_mean(lux: np.ndarray, month: np.ndarray, hour_mid: np.ndarray) -> np.ndarray:
    """(12, 24) mean over sensors and days of the grid illuminance per month and clock hour."""
    e = np.atleast_2d(np.asarray(lux, float)).mean(axis=0)
    out = np.zeros((12, 24))
    hh = np.floor(np.asarray(hour_mid, float)).astype(int)
    mm = np.asarray(month)
    for m in range(12):
        for h in range(24):
            sel = (mm == m + 1) & (hh == h)
            if sel.any():
                out[m, h] = float(e[sel].mean())
    return out
