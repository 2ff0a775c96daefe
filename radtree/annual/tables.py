"""The annual run's tables: per sensor (annual.csv), per grid and month (annual_summary.csv,
annual_monthly.csv), from the hourly illuminance of an :class:`~radtree.annual.run.AnnualResult`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

import radtree.annual.metrics as metrics

TREES = ("with", "without")
ANNUAL_COLUMNS = ["grid", "sensor", "tree", "udi_below_100", "udi_100_300", "udi_300_3000",
                  "udi_above_3000", "da_300", "ase_hours"]
SUMMARY_COLUMNS = ["grid", "tree", "sda_300_50", "ase_1000_250", "month", "mean_lux"]
MONTHLY_COLUMNS = ["grid", "tree", "month", "mean_lux", "mean_direct_lux", "leaf_on_days",
                   "days", "crown"]




def annual_tables(result: Any) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """annual.csv, annual_summary.csv and annual_monthly.csv as data frames of an
    :class:`~radtree.annual.run.AnnualResult`."""
    rows, summary, monthly = [], [], []
    wea = result.wea
    days_in_month = np.array([31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31])
    leaf_days = np.array([int(np.sum(result.in_leaf[(wea.month == m) & (wea.hour < 1)]))
                          for m in range(1, 13)])
    for g in result.grids:
        for tree in TREES:
            lux, dire = result.total[tree][g], result.direct[tree][g]
            t = metrics.sensor_table(lux, dire, result.occupied)
            t.insert(0, "tree", tree)
            t.insert(0, "sensor", np.arange(len(t)))
            t.insert(0, "grid", g)
            rows.append(t)
            sda = metrics.spatial_daylight_autonomy(t["da_300"].to_numpy())
            ase = metrics.annual_sunlight_exposure(t["ase_hours"].to_numpy())
            means = metrics.monthly_mean(lux, result.occupied, wea.month)
            dmeans = metrics.monthly_mean(dire, result.occupied, wea.month)
            for m in range(12):
                summary.append({"grid": g, "tree": tree, "sda_300_50": sda,
                                "ase_1000_250": ase, "month": m + 1, "mean_lux": means[m]})
                ld = int(leaf_days[m]) if tree == "with" else 0
                crown = ("none" if tree == "without" else "leaf" if ld == days_in_month[m]
                         else "bare" if ld == 0 else "mixed")
                monthly.append({"grid": g, "tree": tree, "month": m + 1, "mean_lux": means[m],
                                "mean_direct_lux": dmeans[m], "leaf_on_days": ld,
                                "days": int(days_in_month[m]), "crown": crown})
    annual = pd.concat(rows, ignore_index=True)[ANNUAL_COLUMNS]
    return (annual, pd.DataFrame(summary)[SUMMARY_COLUMNS],
            pd.DataFrame(monthly)[MONTHLY_COLUMNS])
