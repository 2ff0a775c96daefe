"""Wall time of one ``radtree diagnose`` loop on the Mendoza example (NumPy engine).

    .venv/bin/python benchmarks/diagnose.py                    # scenario B, 1024 rays
    .venv/bin/python benchmarks/diagnose.py --scenario A --rays 512
    .venv/bin/python benchmarks/diagnose.py --selftest         # + the whole-catalogue self-test

The example is copied to a temporary folder (the outputs do not touch the repository). Printed:
the steps (effect, strength, nRMSE and cross-validated nRMSE before/after), the number of
simulations (each = 7 hours of the façade grid), cache hits and the wall time; with
``--selftest`` the self-test table, whether it passed and its wall time.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MENDOZA = ROOT / "examples" / "mendoza-street"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="B")
    ap.add_argument("--rays", type=int, default=1024)
    ap.add_argument("--selftest", action="store_true")
    ap.add_argument("--selftest-rays", type=int, default=512)
    args = ap.parse_args(argv)

    from radtree.diagnose import diagnose, selftest
    from radtree.diagnose.run import format_steps

    with tempfile.TemporaryDirectory(prefix="radtree-bench-diag-") as tmp:
        proj = Path(tmp) / "mendoza"
        shutil.copytree(MENDOZA, proj, ignore=shutil.ignore_patterns(
            "build", "results", "report", "diagnose", "sweep"))
        t0 = time.perf_counter()
        res = diagnose(proj, scenario=args.scenario, rays=args.rays, echo=None)
        wall = time.perf_counter() - t0
        print(f"diagnose loop, Mendoza scenario {args.scenario}, NumPy engine, {args.rays} "
              f"rays/sensor, 7 hours:")
        for line in format_steps(res.loop):
            print(line)
        print(f"  {res.simulations} simulations traced, {res.cache_hits} cache hits")
        print(f"wall time: {wall:.1f} s")
        ok = True
        if args.selftest:
            t0 = time.perf_counter()
            st = selftest(proj, scenario=args.scenario, rays=args.selftest_rays, echo=None)
            wall = time.perf_counter() - t0
            cols = ["hidden_effect", "distinguishable", "named_effect", "rmse_before",
                    "rmse_after", "gap_shrinks"]
            print(f"\nself-test, whole catalogue, scenario {args.scenario}, noise 3 %, "
                  f"{args.selftest_rays} rays/sensor:")
            print(st.table()[cols].to_string(index=False, float_format="%.3f"))
            print(f"passed: {st.passed} ({st.simulations} simulations), wall time: {wall:.1f} s")
            ok = st.passed
    return 0 if ok else 1


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    sys.exit(main())
