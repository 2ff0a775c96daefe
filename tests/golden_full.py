"""Golden Radiance tables at the examples' own settings, compared per row in standard errors.

``tests/golden_cases.py`` holds reduced runs compared to the last digit. These tables are the
shipped examples as a user runs them with Radiance — every hour (10:30–16:30), every scenario
of the Mendoza street but the photo-derived ones (A–F and A-sky; F with its 8 crown
realisations), and the office block's two scenarios — with the examples' engine settings
(``-ad 2048``, ``-aa 0``, ``-lw`` as written, rtrace's fixed seed ``-u-``), only the dense
façade map left out (sensors.dense_grid = false). Each row stores

* ``lux`` — the fixed-seed value (the same platform and Radiance give it to the digit);
* ``lux_se`` — its Monte Carlo standard error: a second run with a clock seed (``-u+``) gives
  a difference d per row; per (scenario, time, grid) the relative SE is pooled over its
  sensors, s = √(mean((d / lux)²) / 2), and ``lux_se`` = s · lux.

``tests/test_golden.py`` reruns the fixed-seed tables and requires every row within
:data:`Z_MAX` combined standard errors, z = (new − golden) / (√2 · lux_se): another
platform's or Radiance version's sampling moves rows by ~1 SE, a change of physics by many.

``python -m tests.golden_full`` (from the repository root; long: both runs of both examples)
rewrites ``tests/golden/*_full.csv`` — only in a commit of its own that says why.

Both tables are compared in every test run (the office's 980 rows cost ≈ 300 CPU-s).
"""

from __future__ import annotations

import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from tests.conftest import drop_photo_scenarios

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "tests" / "golden"
KEYS = ["scenario", "time", "grid", "sensor"]
#: largest |z| a row may reach: ~700 rows, P(|z| > 5) ≈ 6e-7 per row for Gaussian noise
Z_MAX = 5.0
EXAMPLES = {"mendoza_radiance_full": "mendoza-street", "office_radiance_full": "office-block"}


def _copy(example: str, dst: Path) -> Path:
    shutil.copytree(ROOT / "examples" / example, dst, ignore=shutil.ignore_patterns(
        "build", "results", "report", "diagnose", "sweep"))
    toml = dst / "radtree.toml"
    toml.write_text(drop_photo_scenarios(toml.read_text()))
    return dst


def run_table(name: str, workdir: Path, seed_flag: str = "-u-") -> pd.DataFrame:
    """The example's per-sensor Radiance table (KEYS + lux) traced with rtrace ``seed_flag``."""
    from radtree.config import load_project
    from radtree.engines.radiance import writer
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project

    proj = load_project(_copy(EXAMPLES[name], workdir / f"{name}{seed_flag}"),
                        overrides={"sensors.dense_grid": False})
    saved = writer.FIXED_SEED
    writer.FIXED_SEED = seed_flag          # the golden runs: -u-; the SE run: -u+
    try:
        # the illuminance only: the tree impact (the NumPy engine's attribution, ≈ 60 s of the
        # office's 7 hours) is not part of the table
        out = simulate_project(proj, options=RunOptions(engine="radiance", fresh=True,
                                                        tree_impact=False))
    finally:
        writer.FIXED_SEED = saved
    assert out is not None
    t = out.table[KEYS + ["lux"]].copy()
    t["scenario"], t["time"] = t["scenario"].astype(str), t["time"].astype(str)
    return t.sort_values(KEYS).reset_index(drop=True)


def with_se(fixed: pd.DataFrame, clock: pd.DataFrame) -> pd.DataFrame:
    """``fixed`` with ``lux_se``: the relative difference to ``clock`` pooled per
    (scenario, time, grid) (module text)."""
    both = fixed.merge(clock, on=KEYS, suffixes=("", "_clock"), validate="1:1")
    rel = (both["lux"] - both["lux_clock"]) / both["lux"].where(both["lux"] > 0)
    s = (rel ** 2).groupby([both[k] for k in KEYS[:3]]).transform("mean") ** 0.5 / np.sqrt(2)
    out = fixed.copy()
    out["lux_se"] = (s.fillna(0.0) * both["lux"]).to_numpy()
    return out


def z_scores(golden: pd.DataFrame, new: pd.DataFrame) -> pd.Series:
    """Per row (new − golden) / (√2 · lux_se); rows with lux_se 0 must match exactly
    (z 0 when equal, inf otherwise)."""
    both = golden.merge(new, on=KEYS, suffixes=("", "_new"), validate="1:1")
    if len(both) != len(golden) or len(both) != len(new):
        raise AssertionError(f"rows differ: golden {len(golden)}, new {len(new)}, "
                             f"matched {len(both)}")
    d = both["lux_new"] - both["lux"]
    se = np.sqrt(2.0) * both["lux_se"]
    z = np.where(se > 0, d / se.where(se > 0, 1.0), np.where(d == 0, 0.0, np.inf))
    return pd.Series(z, index=pd.MultiIndex.from_frame(both[KEYS]))


def read_golden(name: str) -> pd.DataFrame:
    return pd.read_csv(GOLDEN / f"{name}.csv", dtype={"time": str, "scenario": str})


def main() -> None:
    names = sys.argv[1:] or list(EXAMPLES)
    GOLDEN.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="radtree-golden-full-") as tmp:
        for name in names:
            t0 = time.perf_counter()
            fixed = run_table(name, Path(tmp))
            t1 = time.perf_counter()
            clock = run_table(name, Path(tmp), "-u+")
            table = with_se(fixed, clock)
            path = GOLDEN / f"{name}.csv"
            table.to_csv(path, index=False, float_format="%.10g", lineterminator="\n")
            rel = (table["lux_se"] / table["lux"]).replace([np.inf], np.nan)
            print(f"{name}: {len(table)} rows → {path}; fixed-seed run {t1 - t0:.0f} s, "
                  f"clock-seeded {time.perf_counter() - t1:.0f} s; relative SE median "
                  f"{rel.median():.4f}, max {rel.max():.4f}", flush=True)


if __name__ == "__main__":
    main()
