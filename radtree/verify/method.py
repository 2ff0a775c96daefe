"""What the study's numbers owe to its method: the Mendoza scenes A–E traced the study's way
(reference case §7) and with one setting changed at a time, and the dome-radius scan.

:func:`run_method_study` writes ``PROJECT/method/hourly.csv`` — one row per (variant, dome
radius, scenario, hour): the façade mean of the 8 sensors (lux), its standard error, the engine
and its photons/rays — from a project set up as the study ran (``examples/mendoza-tracepro``:
forward engine, 1 m sun beam, ray splitting, threshold 0.05). The variants (:data:`VARIANTS`):

* ``study`` — the project as written (the emulation);
* ``threshold 0.005`` — the study's lower threshold (it tried it on the perforated model);
* ``no threshold`` — the same 1 m beam, Russian roulette instead of splitting + killing:
  unbiased, so the difference to ``study`` is what the threshold removes;
* ``whole-scene sun, dome`` — sunlight over the whole scene, converged (NumPy backward
  engine, which agrees with the forward engine within 2 %: ``radtree verify``): the
  difference to ``no threshold`` is what the 1 m beam removes;
* ``whole-scene sun, free crown`` — the same with free-standing crowns instead of the
  sensor dome.

and the ``study`` settings at each dome radius of ``radii`` (the study gives none; where
the louvers' five layers of 0.3 m slats do not fit in a small dome the slats are shrunk until
they do: column ``slat_m``).
:mod:`radtree.report.sections.method` turns the file into the report section.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.config import Project, load_project
from radtree.engines.registry import photon_engines
from radtree.errors import RadtreeError
from radtree.fileio import atomic_path
from radtree.pipeline.trace import trace_scenario

log = logging.getLogger(__name__)

FOLDER = "method"
HOURLY = "hourly.csv"
STUDY = "study"
RADII_M = (0.5, 1.0, 1.5, 2.0, 3.0, 4.0)
SCENARIOS = ("A", "B", "C", "D", "E")
SLAT_SCALES = (0.8, 0.6, 0.5, 0.4, 0.3, 0.2)  # slat shrink factors tried in a small dome


COLUMNS = ["variant", "radius_m", "scenario", "time", "lux", "stderr", "engine", "photons",
           "slat_m"]


def read_method(root: Path) -> pd.DataFrame | None:
    """Every ``method/*.csv`` of the project together (first occurrence of a (variant, radius,
    scenario, hour) kept), or None when there is none."""
    files = sorted((root / FOLDER).glob("*.csv"))
    if not files:
        return None
    t = pd.concat([pd.read_csv(f, dtype={"time": str}) for f in files], ignore_index=True)
    return t.drop_duplicates(["variant", "radius_m", "scenario", "time"]).reset_index(drop=True)


def _resume(path: Path, photons: int) -> pd.DataFrame:
    if not path.exists():
        return pd.DataFrame(columns=COLUMNS)
    t = pd.read_csv(path, dtype={"time": str})
    keep = ~t["engine"].isin(photon_engines()) | (t["photons"] == photons)
    return t.loc[keep, COLUMNS].reset_index(drop=True)


@dataclass(frozen=True)
class Variant:
    """One way of tracing: a label, the project overrides, the engine, what it changes."""

    label: str
    overrides: dict[str, Any]
    engine: str
    changes: str


VARIANTS = (
    Variant(STUDY, {}, "forward", "the study's method: 1 m beam, ray splitting, threshold 0.05"),
    Variant("threshold 0.005", {"engine.forward_threshold": 0.005}, "forward",
            "threshold 0.05 → 0.005"),
    Variant("no threshold", {"engine.forward_splitting": False}, "forward",
            "splitting + killing → Russian roulette (unbiased), same beam"),
    Variant("whole-scene sun, dome", {"engine.rays": 1024}, "numpy",
            "1 m beam → sunlight over the whole scene (converged, NumPy backward)"),
    Variant("whole-scene sun, free crown", {"tree.form": "free", "engine.rays": 1024},
            "numpy",
            "sensor dome → free-standing crowns, whole-scene sun (converged)"),
)


def _hourly(project: Project, name: str, engine: str) -> pd.DataFrame:
    rows = trace_scenario(project, project.scenario(name), engine, grids=["facade"])
    g = rows.groupby("time")
    out = pd.DataFrame({"lux": g["lux"].mean(),
                        "stderr": g["lux_stderr"].apply(lambda s: float((s ** 2).sum()) ** 0.5
                                                        / len(s))}).reset_index()
    out["scenario"] = name
    return out


def _fitting(root: Path, ov: dict[str, Any], proj: Project, name: str, engine: str
             ) -> tuple[pd.DataFrame, Project]:
    """The scenario's hourly façade means; when the louvers' layers of the project's slats do
    not fit in the dome, with the slats shrunk (s₀ × 0.8, 0.6, … 0.2) until they do."""
    try:
        return _hourly(proj, name, engine), proj
    except RadtreeError as exc:
        if proj.scenario(name).model != "louvers" or "tree.louvers" not in str(exc):
            raise
        err = exc
    s0 = proj.tree.louvers.slat_size_m
    for k in SLAT_SCALES:
        small = load_project(root, overrides={**ov, "tree.louvers.slat_size_m":
                                              round(s0 * k, 4)})
        small = replace(small, engine=replace(small.engine, name=engine))
        try:
            return _hourly(small, name, engine), small
        except RadtreeError as exc:
            err = exc
    raise err


def run_method_study(root: Path, *, photons: int = 1_000_000, radii: Sequence[float] = RADII_M,
                     scenarios: Sequence[str] = SCENARIOS, variants: Sequence[str] | None = None,
                     resume: bool = True, file: str = HOURLY) -> Path:
    """Trace every variant and the radius scan of the project in ``root``; write and return
    ``root/method/hourly.csv``. ``photons`` per hour for the forward runs (the project's count
    is the study's reading; fewer keep the scan affordable). The file is rewritten after every
    scenario; with ``resume`` the (variant, radius, scenario) already in it at the same photon
    count are kept and not traced again. ``file``: another name in ``method/`` (runs in
    parallel write different files; the report reads them all). Each traced scenario is
    logged (INFO); one that cannot be traced is a warning and is left out."""
    base = load_project(root)
    chosen = [v for v in VARIANTS if variants is None or v.label in variants]
    jobs: list[tuple[Variant, float]] = [(v, base.tree.dome.radius_m) for v in chosen]
    study = next(v for v in VARIANTS if v.label == STUDY)
    jobs += [(study, float(r)) for r in radii if float(r) != base.tree.dome.radius_m
             or study not in chosen]
    out = root / FOLDER / file
    table = _resume(out, photons) if resume else pd.DataFrame(columns=COLUMNS)
    done = set(zip(table["variant"], table["radius_m"].astype(float), table["scenario"]))
    for variant, radius in jobs:
        ov = {**variant.overrides, "tree.dome.radius_m": radius, "engine.photons": photons,
              "sensors.dense_grid": False}
        proj = load_project(root, overrides=ov)
        proj = replace(proj, engine=replace(proj.engine, name=variant.engine))
        for name in scenarios:
            if (variant.label, float(radius), name) in done:
                continue
            try:
                h, use = _fitting(root, ov, proj, name, variant.engine)
            except RadtreeError as exc:
                log.warning(f"{variant.label}, dome {radius:g} m, {name}: not traced ({exc})")
                continue
            h["variant"], h["radius_m"], h["engine"] = variant.label, radius, variant.engine
            h["slat_m"] = use.tree.louvers.slat_size_m
            h["photons"] = (photons if variant.engine in photon_engines()
                            else proj.engine.numpy.rays)
            log.info(f"  {variant.label}, dome {radius:g} m, {name}: "
                     + " ".join(f"{v:.0f}" for v in h["lux"]))
            table = pd.concat([table, h[COLUMNS]], ignore_index=True)
            out.parent.mkdir(parents=True, exist_ok=True)
            with atomic_path(out) as tmp:   # after every scenario: an interrupted run resumes
                table.to_csv(tmp, index=False, float_format="%.6g")
    return out
