"""Office-block rooms in the summary and the report (:mod:`radtree.office_summary`): the
rooms' names, a grid's rows pooled over its rooms, and the per-room report table.

Rooms are named ``"STOREY-BAY"`` (storey 0 = the ground floor, bay 0 = the leftmost office
seen from the street; :mod:`radtree.site.office`). Illuminance in lux; the grids are equal-area
grids, so point counts weight areas.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd


def fmt(v: float, digits: int = 0) -> str:
    """``v`` with thousands separators and ``digits`` decimals; "–" when missing."""
    if v is None or not np.isfinite(v):
        return "–"
    return f"{v:,.{digits}f}"


def scenario_pair(g: pd.DataFrame, scen_order: list[str]
                  ) -> tuple[list[str], dict[str, str], tuple[str, str] | None]:
    """The scenarios of summary rows ``g`` (in ``scen_order``), their ``tree`` label, and the
    (with, without) pair when there is exactly one of each."""
    scens = [s for s in scen_order if s in set(g["scenario"])]
    tree_of = {s: str(g[g["scenario"] == s]["tree"].iloc[0]) for s in scens}
    withs = [s for s in scens if tree_of[s] == "with"]
    withouts = [s for s in scens if tree_of[s] == "without"]
    pair = (withs[0], withouts[0]) if len(withs) == 1 and len(withouts) == 1 else None
    return scens, tree_of, pair


def room_names(table: pd.DataFrame) -> pd.Series:
    """The ``room`` column as text, "" where a row has none."""
    return table["room"].astype("string").fillna("").astype(str)


def whole_grid(summary: pd.DataFrame) -> pd.DataFrame:
    """One grid's summary rows pooled over its rooms, per scenario and hour: the rooms' cells
    are equal-area cells, so means and area bands are point-count-weighted means, the minimum
    and maximum the rooms' extremes, U₀ their min / the pooled mean. One room: unchanged."""
    rooms = room_names(summary) if "room" in summary.columns else None
    if rooms is None or rooms.nunique() <= 1:
        return summary
    out = []
    for _, g in summary.groupby(["scenario", "time"], sort=False):
        n = g["n_points"].to_numpy(float)

        def pooled(col: str, g: pd.DataFrame = g, n: np.ndarray = n) -> float:
            return float(np.dot(g[col].to_numpy(float), n) / n.sum())

        mean = pooled("mean_lux")
        lo = float(g["min_lux"].min())
        out.append({**g.iloc[0].to_dict(), "n_points": int(n.sum()), "mean_lux": mean,
                    "min_lux": lo, "max_lux": float(g["max_lux"].max()),
                    "uniformity": lo / mean if mean > 0 else math.nan,
                    **{c: pooled(c) for c in ("pct_below_300", "pct_300_2000",
                                              "pct_above_2000")},
                    "storey": pd.NA, "room": "all"})
    return pd.DataFrame(out, columns=summary.columns)


#: The per-room table of a grid: summary column (mean over the hours), label, decimals.
ROOM_COLUMNS = [("mean_lux", "day mean lx", 0), ("pct_300_2000", "% 300–2000", 0)]


def rooms_data(g: pd.DataFrame, scen_order: list[str]) -> dict[str, Any] | None:
    """Per sensed room (rows, in the summary's order) and scenario: the day's mean of the
    hourly mean and of the useful band, and the with / without ratio when there is a pair
    (None for one room)."""
    rooms = [r for r in dict.fromkeys(room_names(g)) if r]
    if len(rooms) <= 1:
        return None
    scens, tree_of, pair = scenario_pair(g, scen_order)
    day = g.groupby(["room", "scenario"])[[c for c, _, _ in ROOM_COLUMNS]].mean()
    rows = []
    for r in rooms:
        cells = [{"text": fmt(float(day.loc[(r, s), c]), d) if (r, s) in day.index else "–",
                  "num": True} for s in scens for c, _, d in ROOM_COLUMNS]
        if pair:
            w, wo = (float(day.loc[(r, s), "mean_lux"]) if (r, s) in day.index else None
                     for s in pair)
            cells.append({"text": f"{100 * w / wo:.0f} %" if w is not None and wo else "–",
                          "num": True})
        storey = g[g["room"] == r]["storey"].iloc[0]
        rows.append({"label": f"{r} (storey {storey})", "cells": cells})
    return {"scenarios": [{"name": s, "tree": tree_of[s]} for s in scens],
            "columns": [c[1] for c in ROOM_COLUMNS], "pair": pair is not None, "rows": rows}
