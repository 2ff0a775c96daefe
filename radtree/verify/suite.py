"""Run the physics suite and write ``verify.csv`` (``check, engine, expected, got, tolerance,
claim, status, passed, reference, seconds``). Quick mode (default) fits in ≈ 2 minutes on 2
cores; ``full`` samples every row until its 3 standard errors fit inside its claim (more leaf
area with smaller leaves, stratified backward points, the forward engine to a precision target),
adds the floating spheres by NumPy, scenarios A and B of the reduced dome and of the free volume
crown at three hours against NumPy and at noon against Radiance, and the three-phase closure.

The output paths beyond the engines (issue 40 item 6) have a group each: ``annual``
(:mod:`radtree.verify.annual`, with Radiance), ``honeybee``
(:mod:`radtree.verify.honeybee`), ``energyplus`` (:mod:`radtree.verify.energyplus`; the
pyranometer rows ``--full``), ``gltf`` (:mod:`radtree.verify.gltf`), ``photo``
(:mod:`radtree.verify.photo`; the crown round trip ``--full``) and ``diagnose``
(:mod:`radtree.verify.diagnose`; the self-test ``--full``). Quick mode adds 18 rows in ≈ 16 s
(load ≈ 5 on 2 cores), ``--full`` 42 rows in ≈ 270 s.

The suite is cut into row groups (:data:`GROUPS`) that can run as separate processes
(``radtree verify --full --group G -o G.csv``) and be merged into one page
(``radtree verify --merge a.csv --merge b.csv --page docs/validation.md``)."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from radtree.engines.registry import seeded_engine
from radtree.errors import install_extra
from radtree.fileio import atomic_path
from radtree.verify.checks import (
    FORWARD,
    BackwardPlan,
    Check,
    LayerPlan,
    agreement_checks,
    energy_checks,
    sphere_checks,
    transmission_checks,
)
from radtree.verify.mist import mist_checks
from radtree.verify.turbid import turbid_checks
from radtree.verify.voxels import voxel_checks

log = logging.getLogger(__name__)

# --full backward plans: stratified points (2 per cell) carry most of the spatial noise away, so
# many cheap points beat few expensive ones. Free crown A 12:30 (load ≈ 12 on 2 cores): NumPy
# 64 uniform points × 128 rays 1.96 % SE, 128 stratified × 128 0.50 %, 512 stratified × 128
# 0.20 %; Radiance 32 stratified points at -ad 1024 1.58 % (113 s), 128 at -ad 256 0.51 %.
FULL_PLANS = {"numpy": BackwardPlan(points=512, rays=64),
              "radiance": BackwardPlan(points=128, ad=256, hours=("12:30",))}
#: --full forward runs of the agreement rows: rounds of 2 M photons until 3 combined standard
#: errors (with the noisiest backward estimate, traced first) reach 90 % of the 2 % claim
#: (:func:`radtree.verify.checks.forward_target`; never below 0.2 %, at most 128 M photons: the
#: dome B 10:30 needs ≈ 110 M)
FULL_PHOTONS, FULL_REL_SE, FULL_MAX_PHOTONS = 2_000_000, 0.002, 128_000_000
#: --full leaf layers: 14 × 14 detectors under a 18 m layer of 3.5 cm leaves, layers added until
#: every zenith's 3 SE is within 80 % of its 1 % claim (at most 16)
FULL_LAYERS = LayerPlan(detectors=14, leaf=0.035, realisations=16, min_realisations=3,
                        resolve=0.8)
HOURS = ("10:30", "12:30", "14:30")

COLUMNS = ["check", "engine", "expected", "got", "tolerance", "claim", "status", "passed",
           "reference", "seconds"]


def _agreement(full: bool, backward: list[str] | None, crown: str) -> list[Check]:
    if full:
        return agreement_checks(hours=HOURS, scenarios=("A", "B"), backward=backward,
                                crown=crown, plans=FULL_PLANS, photons=FULL_PHOTONS,
                                rel_se=FULL_REL_SE, max_photons=FULL_MAX_PHOTONS)
    return agreement_checks(backward=backward, crown=crown,
                            photons=4_000_000 if crown == "louvers dome" else 2_000_000)


def _threephase(full: bool, backward: list[str] | None) -> list[Check]:
    from radtree.engines.radiance.binaries import find_radiance

    if not full or find_radiance() is None:
        return []
    from radtree.verify.threephase import closure_checks

    return closure_checks()


def _radiance() -> bool:
    from radtree.engines.radiance.binaries import find_radiance

    return find_radiance() is not None


def _annual(full: bool, _b: list[str] | None) -> list[Check]:
    """Annual vs point-in-time rtrace at six hours on open ground (needs Radiance; ≈ 5 s);
    with ``--full`` also ``radtree annual`` of one louvers crown."""
    if not _radiance():
        return []
    from radtree.verify.annual import annual_checks, crown_annual_checks

    return annual_checks() + crown_annual_checks() if full else annual_checks()


def _honeybee(full: bool, _b: list[str] | None) -> list[Check]:
    """The honeybee-scene export read back (and traced with Radiance), if the honeybee extra
    is installed; else one row saying so."""
    from radtree.export.registry import EXPORT_FORMATS

    if not EXPORT_FORMATS["honeybee-scene"].available():
        return [missing_extra("Honeybee export", "honeybee")]
    from radtree.verify.honeybee import honeybee_checks

    return honeybee_checks(trace=_radiance(), repeats=8 if full else 0)


def _energyplus(full: bool, _b: list[str] | None) -> list[Check]:
    """The exported IDF read back (quick: 4 rays per hour); with ``--full`` also the total
    schedule against pyranometers (three crown models × three suns, ≈ 3–5 min)."""
    from radtree.export.registry import EXPORT_FORMATS

    if not EXPORT_FORMATS["schedule"].available():
        return [missing_extra("EnergyPlus schedules", "honeybee")]
    from radtree.verify.energyplus import idf_checks, total_checks

    return idf_checks(rays=16) + total_checks() if full else idf_checks(rays=4)


def _gltf(_full: bool, _b: list[str] | None) -> list[Check]:
    from radtree.verify.gltf import gltf_checks

    return gltf_checks()


def _photo(full: bool, _b: list[str] | None) -> list[Check]:
    from radtree.verify.photo import hemi_checks, round_trip_checks

    return hemi_checks(size=2000) + round_trip_checks() if full else hemi_checks(size=1000)


def _diagnose(full: bool, _b: list[str] | None) -> list[Check]:
    from radtree.verify.diagnose import fit_checks, selftest_checks

    return fit_checks() + selftest_checks() if full else fit_checks()


def missing_extra(path: str, extra: str) -> Check:
    """A row saying ``path`` was not checked: its extra is not installed (``unresolved``: not
    a failure of radtree, never a pass)."""
    return Check(f"{path}: not checked, its extra is missing ({install_extra(extra)})",
                 "-", 0.0, 0.0, 1.0, 0.0, "—")


#: the row groups in page order: name → (full?, backward engines) → checks
GROUPS: dict[str, Callable[[bool, list[str] | None], list[Check]]] = {
    "layers": lambda full, _b: (transmission_checks(photons=100_000, plan=FULL_LAYERS) if full
                                else transmission_checks()),
    "spheres": lambda full, _b: (sphere_checks(
        realisations=8, photons=400_000, points=512, engines=(FORWARD, seeded_engine().name))
        if full else sphere_checks()),
    "energy": lambda full, _b: energy_checks(photons=200_000) if full else energy_checks(),
    "media": lambda full, _b: (turbid_checks(rays=64_000) + voxel_checks(rays=64_000)
                               + mist_checks() if full else
                               turbid_checks() + voxel_checks() + mist_checks()),
    "agreement-dome": lambda full, b: _agreement(full, b, "louvers dome"),
    "agreement-free": lambda full, b: _agreement(full, b, "free volume crown"),
    "threephase": _threephase,
    "annual": _annual,
    "honeybee": _honeybee,
    "energyplus": _energyplus,
    "gltf": _gltf,
    "photo": _photo,
    "diagnose": _diagnose,
}


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
        t = pd.DataFrame([c.row() for c in self.checks], columns=COLUMNS)
        t["seconds"] = round(self.seconds, 1)
        return t


def run_verify(out: Path, *, full: bool = False, backward: list[str] | None = None,
               groups: Iterable[str] | None = None) -> VerifyOutcome:
    """The checks of ``groups`` (default every one of :data:`GROUPS`); ``out`` is the CSV
    written. ``backward``: the backward engines compared with the forward one (default every
    available one). Each check is logged (INFO) as it is made."""
    chosen = list(groups) if groups else list(GROUPS)
    unknown = [g for g in chosen if g not in GROUPS]
    if unknown:
        raise ValueError(f"unknown verify group(s) {unknown}: choose from {list(GROUPS)}")
    t0 = time.perf_counter()
    checks: list[Check] = []
    for g in GROUPS:
        if g in chosen:
            t = time.perf_counter()
            checks += GROUPS[g](full, backward)
            log.info(f"verify group {g}: {time.perf_counter() - t:.0f} s")
    outcome = VerifyOutcome(checks, Path(out), time.perf_counter() - t0)
    outcome.path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(outcome.path) as tmp:
        outcome.table.to_csv(tmp, index=False, float_format="%.6g")
    return outcome


def read_checks(path: Path) -> tuple[list[Check], float]:
    """The checks of a ``verify.csv`` and the seconds its run took."""
    t = pd.read_csv(path, keep_default_na=False, na_values={"expected": [""], "got": [""]})
    checks = [Check(str(r.check), str(r.engine), float(r.expected), float(r.got),
                    float(r.tolerance), float(r.claim), str(r.reference))
              for r in t.itertuples(index=False)]
    seconds = float(t["seconds"].max()) if "seconds" in t.columns and len(t) else 0.0
    return checks, seconds
