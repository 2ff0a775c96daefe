"""How often direct sun reaches the sensors: one straight ray per sensor × hour × crown
realisation towards the sun, through every solid surface of the scene (crown, street,
buildings), its undeviated (specular) transmission multiplied along the way
(:class:`radtree.trees.raycast.DirectTracer`).

For a perforated crown (opaque sheet, T = 0) the ray's transmission is 1 where it leaves
through a hole and 0 elsewhere, so ``reaches`` says whether the sun is seen through a gap — the
lottery of one random gap pattern (``perforated.realisations`` > 1 draws several). Written by
``simulate`` to ``results/direct_sun.csv`` for the perforated scenarios: columns ``scenario,
realisation, time, sensor, sun_altitude_deg, sun_transmission, reaches`` (``realisation`` 1
for a scenario with one crown).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

from radtree.light.sky import SkyState
from radtree.pipeline.realisations import REALISATION_MARK
from radtree.scene import Scene

DIRECT_SUN_COLUMNS = ["scenario", "realisation", "time", "sensor", "sun_altitude_deg",
                      "sun_transmission", "reaches"]
#: a sensor "sees the sun" when at least this share of the beam passes undeviated
REACH_THRESHOLD = 0.5
#: the ray starts this far off the sensor along its normal (clears the wall it sits on)
START_OFFSET_M = 1e-3


def direct_sun_rows(name: str, scene: Scene, states: Iterable[SkyState],
                    grid: str = "facade") -> pd.DataFrame:
    """One row per hour × sensor of ``grid``: the sun beam's straight-line transmission from
    the sensor (0 below the horizon or behind the sensor's plane)."""
    from radtree.trees.raycast import DirectTracer

    parent, _, k = name.partition(REALISATION_MARK)
    g = scene.grids[grid]
    tracer = DirectTracer(scene.solid_meshes(), scene.materials)
    rows = []
    for st in states:
        sun = st.sun.vector
        facing = (g.normals @ sun) > 0.0
        t = np.zeros(len(g.points))
        if st.sun.altitude_deg > 0.0 and st.direct_normal_lux > 0.0 and facing.any():
            origins = g.points[facing] + START_OFFSET_M * g.normals[facing]
            dirs = np.repeat(sun[None, :], int(facing.sum()), axis=0)
            t[facing] = tracer.transmission(origins, dirs)
        rows.append(pd.DataFrame({
            "scenario": parent, "realisation": int(k) if k else 1, "time": st.time,
            "sensor": np.arange(len(g.points)), "sun_altitude_deg": st.sun.altitude_deg,
            "sun_transmission": t, "reaches": t >= REACH_THRESHOLD}))
    return pd.concat(rows, ignore_index=True)[DIRECT_SUN_COLUMNS]


def direct_sun_summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per scenario: realisations, sensor-hours, the share of sensor-hours the sun reaches
    (mean and s.d. over realisations) and the share of realisations in which it reaches at
    least one sensor at some hour."""
    out = []
    for sc, g in table.groupby("scenario", sort=False):
        per = g.groupby("realisation")["reaches"].agg(["mean", "any"])
        out.append({"scenario": sc, "realisations": len(per),
                    "sensor_hours": int(len(g) / len(per)),
                    "reach_share": float(per["mean"].mean()),
                    "reach_share_sd": float(per["mean"].std(ddof=1)) if len(per) > 1 else np.nan,
                    "realisations_reaching": float(per["any"].mean())})
    return pd.DataFrame(out)
