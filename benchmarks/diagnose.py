"""Wall time of one ``radtree diagnose`` loop on the Mendoza example (NumPy engine).

    .venv/bin/python benchmarks/diagnose.py                    # scenario B, 1024 rays
    .venv/bin/python benchmarks/diagnose.py --scenario A --rays 512
    .venv/bin/python benchmarks/diagnose.py --selftest         # + the whole-catalogue self-test
    .venv/bin/python benchmarks/diagnose.py --selftest --campaign examples/mendoza-street/campaign-rich.toml
                                                               # the rich campaign's self-test
                                                               # (issue 20's ≤ 3 min; its rays)

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
    ap.add_argument("--selftest-rays", type=int, default=None,
                    help="default: the campaign's rays, else 512")
    ap.add_argument("--campaign", type=Path, default=None,
                    help="self-test on what this campaign measures (path from the repository)")
    args = ap.parse_args(argv)

    from radtree.diagnose import DiagnoseOptions, diagnose, selftest
    from radtree.diagnose.campaign import load_campaign
    from radtree.diagnose.run import format_steps

    with tempfile.TemporaryDirectory(prefix="radtree-bench-diag-") as tmp:
        proj = Path(tmp) / "mendoza"
        shutil.copytree(MENDOZA, proj, ignore=shutil.ignore_patterns(
            "build", "results", "report", "diagnose", "sweep"))
        t0 = time.perf_counter()
        res = diagnose(proj, options=DiagnoseOptions(scenario=args.scenario, rays=args.rays))
        wall = time.perf_counter() - t0
        print(f"diagnose loop, Mendoza scenario {args.scenario}, NumPy engine, {args.rays} "
              f"rays/sensor, 7 hours:")
        for line in format_steps(res.loop):
            print(line)
        print(f"  {res.simulations} simulations traced, {res.cache_hits} cache hits")
        print(f"wall time: {wall:.1f} s")
        ok = True
        if args.selftest:
            campaign = None
            if args.campaign is not None:
                # the campaign's measured files are relative to its own folder, in the copy
                src = (ROOT / args.campaign).resolve()
                campaign = load_campaign(proj / src.relative_to(MENDOZA) if
                                         src.is_relative_to(MENDOZA) else src)
            rays = args.selftest_rays or (campaign.rays if campaign is not None and
                                          campaign.rays else 512)
            t0 = time.perf_counter()
            st = selftest(proj, options=DiagnoseOptions(scenario=args.scenario, rays=rays,
                                                    campaign=campaign))
            wall = time.perf_counter() - t0
            cols = ["hidden_effect", "distinguishable", "named_effect", "rmse_before",
                    "rmse_after", "gap_shrinks"]
            print(f"\nself-test, whole catalogue, scenario {args.scenario}, "
                  + (f"campaign {campaign.summary()}, " if campaign is not None else
                     "noise 3 %, ") + f"{rays} rays/sensor:")
            print(st.table()[cols].to_string(index=False, float_format="%.3f"))
            print(f"passed: {st.passed} ({st.simulations} simulations), wall time: {wall:.1f} s")
            ok = st.passed
    return 0 if ok else 1


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    sys.exit(main())
