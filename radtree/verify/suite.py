"""Run the physics suite and write ``verify.csv`` (``check, engine, expected, got, tolerance,
passed``). Quick mode (default) fits in ≈ 2 minutes on 2 cores; ``full`` traces more photons,
more leaf layers, the floating spheres by NumPy too, scenarios A and B of the reduced dome and of
the free volume crown at three hours against NumPy and at noon against Radiance."""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from radtree.engines.registry import seeded_engine
from radtree.fileio import atomic_path
from radtree.verify.checks import (
    FORWARD,
    BackwardPlan,
    Check,
    agreement_checks,
    energy_checks,
    sphere_checks,
    transmission_checks,
)
from radtree.verify.mist import mist_checks
from radtree.verify.turbid import turbid_checks
from radtree.verify.voxels import voxel_checks

log = logging.getLogger(__name__)

# Radiance at -ad 2048 over 64 points per patch took 206 s per scenario and hour on the reduced
# dome (2 cores); at -ad 1024 over 32 points ≈ 75 s, so it is compared at noon only, while NumPy
# (≈ 1 s a case) is compared at every hour.
FULL_PLANS = {"numpy": BackwardPlan(points=64, rays=128),
              "radiance": BackwardPlan(points=32, ad=1024, hours=("12:30",))}

COLUMNS = ["check", "engine", "expected", "got", "tolerance", "claim", "status", "passed",
           "reference"]


@dataclass
class VerifyOutcome:
    checks: list[Check]
    path: Path
    seconds: float

    @property
    def failed(self) -> list[Check]:
        return [c for c in self.checks if c.status == "fail"]

    @property
    def unresolved(self) -> list[Check]:
        return [c for c in self.checks if c.status == "unresolved"]

    @property
    def table(self) -> pd.DataFrame:
        return pd.DataFrame([c.row() for c in self.checks], columns=COLUMNS)


def run_verify(out: Path, *, full: bool = False, backward: list[str] | None = None
               ) -> VerifyOutcome:
    """Every check; ``out`` is the CSV written. ``backward``: the backward engines compared
    with the forward one (default every available one). Each check is logged (INFO) as it is
    made."""
    t0 = time.perf_counter()
    checks: list[Check] = []
    if full:
        checks += transmission_checks(realisations=16, photons=200_000, points=64)
        checks += sphere_checks(realisations=8, photons=400_000, points=64,
                                engines=(FORWARD, seeded_engine().name))
        checks += energy_checks(photons=200_000)
        checks += turbid_checks(rays=64_000)
        checks += voxel_checks(rays=64_000)
        checks += mist_checks()
        for crown in ("louvers dome", "free volume crown"):
            checks += agreement_checks(hours=("10:30", "12:30", "14:30"), scenarios=("A", "B"),
                                       photons=40_000_000, backward=backward, crown=crown,
                                       plans=FULL_PLANS)
        from radtree.engines.radiance.binaries import find_radiance

        if find_radiance() is not None:
            from radtree.verify.threephase import closure_checks

            checks += closure_checks()
    else:
        checks += transmission_checks()
        checks += sphere_checks()
        checks += energy_checks()
        checks += turbid_checks()
        checks += voxel_checks()
        checks += mist_checks()
        checks += agreement_checks(backward=backward)
        checks += agreement_checks(backward=backward, crown="free volume crown",
                                   photons=4_000_000)
    outcome = VerifyOutcome(checks, Path(out), time.perf_counter() - t0)
    outcome.path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(outcome.path) as tmp:
        outcome.table.to_csv(tmp, index=False, float_format="%.6g")
    return outcome
