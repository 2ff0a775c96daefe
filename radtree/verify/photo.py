"""The photo round trip checked (``radtree verify``, path *photo round trip*).

* :func:`hemi_checks` — a synthetic fisheye photo of a Poisson canopy of known LAI (each pixel
  sky with probability exp(−G·LAI / cos θ), G = ½: :func:`radtree.hemi.synthetic.poisson_canopy`)
  analysed as a user's photo: its openness against the closed form ∫ exp(−LAI / (2 cos θ))
  sin θ dθ (claim 1 %, the ring sum's discretisation — the tolerance of
  ``tests/test_hemi_synthetic.py``) and Miller's LAI against the LAI drawn (claim 5 %: issue 16,
  "LAI within 5 %").
* :func:`crown_round_trip` / :func:`round_trip_checks` — a crown of known leaf area density
  and leaf angles (ellipsoidal x = 2, mean tilt 38.5°, no clumping) rendered by radtree as three
  upward photos, fitted back into a crown: density within 5 %, mean tilt within 3°, the refit
  crown's façade illuminance (the seeded engine — NumPy — same seeds) within 3 % of the original's — issue
  16's round trip, the body of ``tests/test_photo_crowns.py``'s round-trip test.
"""

from __future__ import annotations

import logging
import shutil
import tempfile
from collections.abc import Iterable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from radtree.verify.checks import Check

log = logging.getLogger(__name__)

OPENNESS_CLAIM, LAI_CLAIM = 0.01, 0.05
LAD_CLAIM, TILT_CLAIM_DEG, FACADE_CLAIM = 0.05, 3.0, 0.03


def poisson_openness(lai: float) -> float:
    """∫₀^{π/2} exp(−½ LAI / cos θ) sin θ dθ (trapezoid on 20 001 points): the openness of a
    spherical Poisson canopy."""
    z = np.radians(np.linspace(0.0, 90.0, 20001))
    f = np.exp(-0.5 * lai / np.maximum(np.cos(z), 1e-12)) * np.sin(z)
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(z)))


def hemi_checks(lai: float = 2.0, size: int = 2000, seed: int = 11) -> list[Check]:
    """Openness and Miller LAI of a ``size``-pixel synthetic photo of a Poisson canopy."""
    from radtree.hemi import HemiConfig, RingGrid, analyse_array, get_lens, render_fisheye
    from radtree.hemi.synthetic import default_mask, poisson_canopy

    image = render_fisheye(poisson_canopy(lai, 1.0, seed=seed), size)

    def analyse(grid):
        config = HemiConfig(lens=get_lens("equidistant"), mask=default_mask(image.shape[1::-1]),
                            channel="luma", gamma=1.0, threshold=128, grid=grid,
                            outlines=False)
        return analyse_array(image, config).metrics

    openness = analyse(RingGrid(18, 8)).openness
    miller = analyse(RingGrid(35, 8, 0, 70)).lai
    expected = poisson_openness(lai)
    what = f"photo round trip: synthetic fisheye ({size} px) of a Poisson canopy LAI {lai:g}"
    ref = "P(gap) = exp(−G·LAI/cos θ), G = ½ (Poisson canopy), its closed-form integral"
    return [Check(f"{what}, openness", "-", expected, openness, OPENNESS_CLAIM * expected,
                  OPENNESS_CLAIM * expected, ref),
            Check(f"{what}, Miller LAI (0–70°)", "-", lai, miller, LAI_CLAIM * lai,
                  LAI_CLAIM * lai, "the LAI drawn; Miller (1967) integral")]


@dataclass(frozen=True)
class RoundTrip:
    """Known and fitted crown: leaf area density (m²/m³), mean tilt (°), façade mean (lx); the
    photos fitted and the density's spread over them."""

    lad: float
    lad_fit: float
    tilt: float
    tilt_fit: float
    facade: float
    facade_fit: float
    photos: int
    lad_sd: float


#: one wide, flat crown 8 m from the façade photographed upward from 1 m under it (overrides
#: of the Mendoza example for the photo round trips)
PHOTO_CROWN = {"tree.crown.count": 1, "tree.crown.trunk_distance_m": 8.0,
               "tree.crown.radius_m": 7.0, "tree.crown.vertical_radius_m": 2.5,
               "tree.crown.base_height_m": 3.0, "tree.photo_x_m": 1.0,
               "tree.photo_distance_m": 8.0, "tree.photo_height_m": 1.0,
               "tree.photo_zenith_deg": 55.0}
#: the known crown's louvers (ellipsoidal leaf angles x = 2, 3 crossings)
KNOWN_CROWN = {"louvers.arrangement": "volume", "louvers.inclination_distribution": "ellipsoidal",
               "louvers.ellipsoid_x": 2.0, "louvers.crossings": 3.0}


def photo_scenarios(proj: Any, root: Path, known: dict, *, seeds: Iterable[int], size: int,
                    refit: dict | None = None) -> tuple[Any, Any]:
    """Upward photos of the crown ``known`` (louvers switches) rendered at ``size`` px, one per
    seed, into ``root/photos``; returns the known crown's scenario ``T`` and the scenario ``R``
    fitted to the photos from a neutral start (ellipsoidal x = 1, 1 crossing; ``refit``:
    further switches of the fit)."""
    from radtree.config import Scenario
    from radtree.hemi.synthetic import save_png
    from radtree.photo.render import render_scenario
    from radtree.trees.photo import PhotoSource

    src = PhotoSource(root / "none.png", "equidistant", None, "upward", "tree.photo", 55.0)
    (root / "photos").mkdir(exist_ok=True)
    for k in seeds:
        r = render_scenario(proj, Scenario(name="T", model="louvers", form="free", switches={
            **known, "louvers.seed": k}), size, src=src)
        save_png(r.image, root / "photos" / f"crown{k}.png")
    m = r.geometry.mask
    original = Scenario(name="T", model="louvers", reflection="traced", form="free",
                        switches=known)
    fitted = Scenario(name="R", model="louvers", reflection="traced", form="free", switches={
        **known, "louvers.ellipsoid_x": 1.0, "louvers.crossings": 1.0, **(refit or {}),
        "tree.photo": str(root / "photos"), "tree.lens": "equidistant",
        "tree.mask": [m.cx, m.cy, m.radius], "tree.photo_direction": "upward"})
    return original, fitted


def crown_round_trip(root: Path, size: int = 500) -> RoundTrip:
    """Render, fit and trace the known crown in ``root`` (a copy of the Mendoza example):
    three upward photos of ``size`` pixels (crowns of seeds 1–3), one fit."""
    from radtree.config import load_project
    from radtree.engines.registry import seeded_engine
    from radtree.pipeline.assemble import make_scene
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project
    from radtree.trees.leaf_angles import mean_tilt

    proj = load_project(root, overrides={
        "site.hours": ["12:30"], "sensors.dense_grid": False, "sensors.dense_hours": [],
        "engine.rays": 128, **PHOTO_CROWN})
    known = {**KNOWN_CROWN, "louvers.slat_size_m": 0.15}
    original, refit = photo_scenarios(proj, root, known, seeds=(1, 2, 3), size=size)
    fit = make_scene(proj, refit).tree.photo["fitted"]
    lad = make_scene(proj, original).tree.info["density_per_m3"] * 0.15 ** 2
    out = simulate_project(replace(proj, scenarios=(original, refit)),
                           options=RunOptions(engine=seeded_engine().name))
    if out is None:
        raise RuntimeError("the round trip's simulation returned nothing")
    mean = out.table[out.table["grid"] == "facade"].groupby("scenario")["lux"].mean()
    return RoundTrip(lad, fit["leaf_area_density_m2_m3"], mean_tilt(2.0), fit["mean_tilt_deg"],
                     float(mean["T"]), float(mean["R"]), int(fit["photos"]),
                     float(fit["lad_sd"]))


def round_trip_checks(folder: Path | None = None) -> list[Check]:
    """:func:`crown_round_trip` on a copy of the Mendoza example as three checks."""
    from radtree.engines.registry import seeded_engine
    from radtree.verify.compare import MENDOZA

    engine = seeded_engine().name
    with tempfile.TemporaryDirectory(prefix="radtree-verify-photo-") as tmp:
        root = Path(folder or tmp) / "mendoza"
        shutil.copytree(MENDOZA, root, ignore=shutil.ignore_patterns(
            "build", "results", "report", "diagnose", "sweep"))
        rt = crown_round_trip(root)
    what = "photo round trip: known crown → 3 rendered upward photos → fitted crown"
    ref = "the crown rendered (known parameters); issue 16's round trip"
    log.info(f"{what}: {rt}")
    return [Check(f"{what}, leaf area density (m²/m³)", "-", rt.lad, rt.lad_fit,
                  LAD_CLAIM * rt.lad, LAD_CLAIM * rt.lad, ref),
            Check(f"{what}, mean leaf tilt (°)", "-", rt.tilt, rt.tilt_fit, TILT_CLAIM_DEG,
                  TILT_CLAIM_DEG, ref + " (ellipsoidal x = 2)"),
            Check(f"{what}, façade mean at 12:30 (lx), seeded engine, same seeds", engine,
                  rt.facade, rt.facade_fit, FACADE_CLAIM * rt.facade, FACADE_CLAIM * rt.facade,
                  "the known crown traced by the same engine and seeds")]
