"""The schema of the one results table (``PROJECT/results/illuminance.csv``): its columns and
their types. Plain data at the bottom of the layers (beside ``config``, ``optics``, ``scene``), so
that every reader — statistics, reports, the pipeline that writes the table
(:mod:`radtree.pipeline.results`: rows, validated read, atomic write) — takes it from one place.

One row per scenario × hour × grid × sensor: illuminance ``lux`` (lux: traced + calculated ground
terms), its Monte Carlo standard error ``lux_stderr`` (lux; NaN when the engine gives none),
sensor position ``x y z`` (m, x east, y north, z up), the ``engine`` that traced it and the
scenario's ``params_hash``; then ``lux_traced``, ``lux_reflected_calc`` and ``reflection`` (and,
for crown realisations, ``lux_realisation_sd`` and ``realisations``).
"""

from __future__ import annotations

#: the written column order (extra columns follow)
RESULT_COLUMNS = [
    "scenario", "model", "datetime", "time", "grid", "sensor", "row", "x", "y", "z",
    "lux", "lux_stderr", "engine", "params_hash",
]
#: optional per-sensor columns (sensor grids' ``labels``): the building id and the façade
#: ``BUILDING:FACE`` (inventory projects), the storey (0 = ground; inventory façades, office
#: rooms, a street's sensor heights) and the office ``room`` ``"STOREY-BAY"``
#: (:mod:`radtree.site.office`); absent in tables whose grids carry none
OPTIONAL_COLUMNS = ("building", "facade", "storey", "room")
#: what a table must have to be read back
REQUIRED_COLUMNS = ("scenario", "model", "time", "grid", "sensor", "row", "lux")
#: the text columns, read as ``str`` (pandas ``dtype=``)
DTYPES = {"scenario": str, "time": str, "row": str, "grid": str, "params_hash": str,
          "engine": str, "model": str, "reflection": str, "building": str, "facade": str,
          "room": str}
