"""Any site on Earth (issue 37): a free-standing façade vs pvlib at 12 sites × 3 dates × N/E/S/W.

Prints, per site, the worst relative difference of the total façade illuminance against pvlib's
Perez transposition (the issue's definition, tolerance 10 %), the share of hour-façades within
10 % by sun-altitude band, the worst direct-sun component difference, and whether radtree's
daylight hours match pvlib's sunrise and sunset. See :mod:`radtree.verify.anywhere`.

    .venv/bin/python benchmarks/anywhere.py [--rays 4096]
"""

from __future__ import annotations

import argparse
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from radtree.verify.anywhere import DATES, SITES, TOLERANCE, compare_site, worst_table


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rays", type=int, default=4096)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    t = time.perf_counter()
    res = []
    with tempfile.TemporaryDirectory() as d:
        for i, p in enumerate(SITES):
            for j, date in enumerate(DATES):
                res.append(compare_site(p, date, Path(d) / f"{i}-{j}", rays=args.rays))
    print(f"{len(SITES)} sites × {len(DATES)} dates × 4 façades, {args.rays} rays/sensor, "
          f"{time.perf_counter() - t:.0f} s")
    print("\n".join(worst_table(res)))
    err = np.concatenate([c.rel_error.ravel() for c in res if c.hours])
    alt = np.concatenate([np.repeat(c.sun_altitude_deg, 4) for c in res if c.hours])
    print(f"\ntotal vs pvlib Perez, within {100 * TOLERANCE:.0f} %: "
          f"{100 * np.mean(err <= TOLERANCE):.1f} % of {len(err)} hour-façades; median "
          f"{100 * np.median(err):.1f} %, p95 {100 * np.quantile(err, 0.95):.1f} %, "
          f"max {100 * err.max():.1f} %")
    for lo, hi in ((0, 5), (5, 15), (15, 60), (60, 80), (80, 91)):
        sel = (alt >= lo) & (alt < hi)
        if sel.any():
            print(f"  sun {lo:>2}–{hi:<2}°: {sel.sum():>4} hour-façades, within 10 % "
                  f"{100 * np.mean(err[sel] <= TOLERANCE):5.1f} %, max {100 * err[sel].max():5.1f} %")
    d_rt = np.concatenate([c.radtree_direct.ravel() for c in res if c.hours])
    d_pv = np.concatenate([c.pvlib_direct.ravel() for c in res if c.hours])
    lit = d_pv > 100.0
    print(f"direct sun component (where pvlib > 100 lx, {lit.sum()} hour-façades): max "
          f"{100 * np.max(np.abs(d_rt[lit] - d_pv[lit]) / d_pv[lit]):.2f} %; max |diff| "
          f"elsewhere {np.max(np.abs(d_rt[~lit] - d_pv[~lit])):.0f} lx")
    bad = [f"{c.place.name} {c.date} ({c.daylight_note})" for c in res if not c.hours_match]
    print("daylight hours vs pvlib sunrise/sunset: " + ("all match" if not bad else
                                                        "MISMATCH " + "; ".join(bad)))


if __name__ == "__main__":
    main()
