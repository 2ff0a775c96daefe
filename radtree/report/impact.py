"""What the trees do: each with-trees scenario against the scenario without trees, per façade,
storey and room, hour by hour and over the day (issue 38).

**The pair.** The baseline is the scenario marked ``baseline = true`` in the project file, else
the one scenario named ``open`` (the ``radtree new`` template), else the only scenario whose
crown model is ``none``. Every other scenario with a crown (model ≠ ``none``) is compared with
it; the one named ``trees`` comes first. No baseline → no pair → no tree-impact section.

**The targets** (``level``, ``target``):

* ``façade`` — in an inventory project each simulated façade (``BUILDING:FACE``, the results'
  ``facade`` column); otherwise the façade sensor grid ``facade``;
* ``storey`` — in an inventory project each building's storey (``BUILDING storey N``, 0 =
  ground floor), over all its simulated façades;
* ``building`` — in an inventory project each building, over all its simulated façade sensors;
* ``room`` — every other sensor grid (office rooms' work planes, Honeybee sensor grids), by its
  name; the dense façade map ``facade_map`` is left out (the same façade as ``facade``).

**The numbers.** ``with_lux`` / ``without_lux``: mean illuminance over the target's sensors (lx)
at each hour both scenarios were traced (``time`` = ``HH:MM``), and over those hours (``time`` =
``day``: the mean of the hourly means); ``change_lux`` = with − without (negative: the trees take
light), ``change_pct`` = 100 · change / without; ``change_stderr`` the Monte Carlo standard
error of the change (from both scenarios' per-sensor standard errors, independent; NaN when the
engine gives none).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from radtree.config import Project

#: the grids that are façades (not rooms) in a non-inventory project
FACADE_GRIDS = ("facade", "facade_map")
LEVELS = ("façade", "storey", "building", "room")
DAY = "day"
IMPACT_COLUMNS = ["trees", "baseline", "level", "target", "time", "n_sensors", "with_lux",
                  "without_lux", "change_lux", "change_stderr", "change_pct"]


@dataclass(frozen=True)
class Pair:
    """A scenario with trees (``trees``) and the one without (``baseline``)."""

    trees: str
    baseline: str


def baseline_name(project: Project, present: list[str]) -> str | None:
    """The scenario the trees are measured against (see the module doc), or None."""
    marked = [s.name for s in project.scenarios if s.baseline and s.name in present]
    if marked:
        return marked[0]
    if "open" in present:
        return "open"
    bare = [s.name for s in project.scenarios if s.model == "none" and s.name in present]
    return bare[0] if len(bare) == 1 else None


def tree_pairs(project: Project, present: list[str]) -> list[Pair]:
    """Each with-trees scenario of the results against the baseline (``trees`` first)."""
    base = baseline_name(project, present)
    if base is None:
        return []
    models = {s.name: s.model for s in project.scenarios}
    with_trees = [n for n in present if n != base and models.get(n, "none") != "none"]
    with_trees.sort(key=lambda n: n != "trees")
    return [Pair(n, base) for n in with_trees]


def is_inventory(results: pd.DataFrame) -> bool:
    """Whether the results come from an inventory (district) project: per-façade labels."""
    return "facade" in results.columns and bool(results["facade"].notna().any())


def target_rows(results: pd.DataFrame) -> pd.DataFrame:
    """The results rows with their ``level`` and ``target`` (one row per level a sensor
    counts in: an inventory façade sensor counts for its façade and its storey)."""
    parts = []
    if is_inventory(results):
        fac = results[results["facade"].notna()]
        parts.append(fac.assign(level="façade", target=fac["facade"].astype(str)))
        if "storey" in fac.columns and fac["storey"].notna().any():
            st = fac[fac["storey"].notna()]
            parts.append(st.assign(level="storey", target=[
                f"{b} storey {int(float(s))}" for b, s in zip(st["building"], st["storey"])]))
        if "building" in fac.columns and fac["building"].notna().any():
            bd = fac[fac["building"].notna()]
            parts.append(bd.assign(level="building", target=bd["building"].astype(str)))
        rest = results[results["facade"].isna()]
    else:
        fac = results[results["grid"].astype(str) == "facade"]
        parts.append(fac.assign(level="façade", target="facade"))
        rest = results
    rooms = rest[~rest["grid"].astype(str).isin(FACADE_GRIDS)]
    parts.append(rooms.assign(level="room", target=rooms["grid"].astype(str)))
    return pd.concat(parts, ignore_index=True) if parts else results.iloc[0:0]


def _means(rows: pd.DataFrame) -> pd.DataFrame:
    se2 = rows["lux_stderr"].astype(float) ** 2
    g = rows.assign(_se2=se2).groupby(["level", "target", "time"], sort=False)
    # an engine that estimates no standard error (Radiance) leaves it unknown, not zero
    out = g.agg(lux=("lux", "mean"), n=("lux", "size"),
                se2=("_se2", lambda v: v.sum() if v.notna().all() else np.nan))
    out["se"] = np.sqrt(out["se2"]) / out["n"]
    return out.drop(columns="se2")


def impact_frame(results: pd.DataFrame, pairs: list[Pair]) -> pd.DataFrame:
    """Per pair, level, target and hour (and ``day``): the columns :data:`IMPACT_COLUMNS`."""
    frames = []
    tagged = target_rows(results)
    for p in pairs:
        w = _means(tagged[tagged["scenario"].astype(str) == p.trees])
        o = _means(tagged[tagged["scenario"].astype(str) == p.baseline])
        both = w.reset_index().merge(o.reset_index(), on=["level", "target", "time"],
                                     suffixes=("_w", "_o"))
        if both.empty:
            continue
        both = both.sort_values(["level", "target", "time"], key=lambda c: c.map(
            {lv: i for i, lv in enumerate(LEVELS)}) if c.name == "level" else c)
        day = both.groupby(["level", "target"], sort=False).agg(
            lux_w=("lux_w", "mean"), lux_o=("lux_o", "mean"), n_w=("n_w", "first"),
            se_w=("se_w", lambda v: math.sqrt(float(np.sum(np.asarray(v) ** 2))) / len(v)),
            se_o=("se_o", lambda v: math.sqrt(float(np.sum(np.asarray(v) ** 2))) / len(v)),
        ).reset_index().assign(time=DAY)
        both = pd.concat([both, day], ignore_index=True)
        change = both["lux_w"] - both["lux_o"]
        frames.append(pd.DataFrame({
            "trees": p.trees, "baseline": p.baseline, "level": both["level"],
            "target": both["target"], "time": both["time"], "n_sensors": both["n_w"].astype(int),
            "with_lux": both["lux_w"], "without_lux": both["lux_o"], "change_lux": change,
            "change_stderr": np.hypot(both["se_w"], both["se_o"]),
            "change_pct": np.where(both["lux_o"] > 0, 100.0 * change / both["lux_o"].where(
                both["lux_o"] > 0, 1.0), np.nan)}))
    if not frames:
        return pd.DataFrame(columns=IMPACT_COLUMNS)
    out = pd.concat(frames, ignore_index=True)[IMPACT_COLUMNS]
    rank = {lv: i for i, lv in enumerate(LEVELS)}
    out = out.assign(_l=out["level"].map(rank), _d=out["time"] == DAY)
    return out.sort_values(["_l", "trees", "target", "_d", "time"], kind="stable").drop(
        columns=["_l", "_d"]).reset_index(drop=True)


def sensor_change(results: pd.DataFrame, pair: Pair) -> pd.DataFrame:
    """Per sensor (grid, sensor, x, y, z): the day-mean % change of ``pair`` (site plans)."""
    keys = ["grid", "sensor"]
    w = results[results["scenario"].astype(str) == pair.trees].groupby(keys)
    o = results[results["scenario"].astype(str) == pair.baseline].groupby(keys)["lux"].mean()
    out = w.agg(x=("x", "first"), y=("y", "first"), z=("z", "first"), lux=("lux", "mean"))
    out = out.join(o.rename("lux_o"), how="inner").reset_index()
    out["change_pct"] = 100.0 * (out["lux"] - out["lux_o"]) / out["lux_o"].where(
        out["lux_o"] > 0)
    return out
