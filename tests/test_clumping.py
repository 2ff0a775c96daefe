"""Clumped foliage (issue 16, "clumping where the photo shows it"): the cluster model against
its analytic limit, the generator keeping the leaf area, the configuration, and the round
trip — a crown of known density, leaf angles and clumping Ω = 0.7 → rendered fisheyes → fit
with the clumping estimated from the photos → true LAD, tilt, Ω and façade illuminance."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from radtree.config import Louvers, Scenario, load_project
from radtree.errors import ConfigError
from tests.conftest import copy_project


def test_cluster_model_limits():
    """Small slats: the Boolean cluster tends to the turbid sphere, Ω(τ) = 3(1 − P)/(2τ) with
    P = 2(1 − (1 + τ)e^−τ)/τ²; Ω = 1 needs no clusters and leaves G untouched."""
    from radtree.trees.clumping import (
        clumped_g,
        cluster_lad,
        cluster_omega,
        slats_per_cluster,
    )

    radius, slat = 0.5, 0.005
    m = slats_per_cluster(0.7, radius, slat)
    tau = 2.0 * radius * cluster_lad(0.7, radius, slat) * 0.5
    p = 2.0 * (1.0 - (1.0 + tau) * math.exp(-tau)) / tau**2
    assert 1.5 * (1.0 - p) / tau == pytest.approx(0.7, abs=0.003)
    assert cluster_omega(m, radius, slat, 0.5) == pytest.approx(0.7, abs=1e-6)
    # denser-looking views (larger projection) are more clumped; Ω = 1 is the identity
    assert cluster_omega(m, radius, slat, 0.8) < 0.7 < cluster_omega(m, radius, slat, 0.3)
    g = np.array([0.3, 0.5, 0.8])
    assert clumped_g(g, 1.0) is g
    assert clumped_g(g, 0.7, radius, slat)[1] == pytest.approx(0.35, abs=1e-6)
    assert slats_per_cluster(1.0, radius, slat) == 0.0


def test_generator_keeps_the_leaf_area(tmp_path):
    """Ω < 1 moves the same slats into clusters: same count and sizes, fewer gaps between
    clusters → the leaves per voxel scatter far more than random slats'."""
    from radtree.pipeline.assemble import make_scene

    proj = load_project(copy_project(tmp_path / "g"), overrides={
        "sensors.dense_grid": False, "sensors.dense_hours": [], "tree.crown.count": 1})
    sw = {"louvers.arrangement": "volume", "louvers.crossings": 2.0}
    plain = make_scene(proj, Scenario(name="P", model="louvers", form="free", switches=sw))
    clumped = make_scene(proj, Scenario(name="K", model="louvers", form="free", switches={
        **sw, "louvers.clumping": 0.6, "louvers.cluster_radius_m": 0.6}))
    a, b = plain.tree.info, clumped.tree.info
    assert a["slats_drawn"] == b["slats_drawn"] and "clumping" not in a
    assert b["clumping"] == 0.6 and b["clusters"] > 10
    assert abs(b["slat_count"] - a["slat_count"]) < 0.02 * a["slat_count"]
    assert "clusters of radius 0.6 m" in " ".join(clumped.tree.notes)

    def dispersion(tree) -> float:
        """Variance / mean of the leaf vertices per 1 m voxel (≈ constant for random slats,
        large for clusters)."""
        v = np.floor(tree.meshes[0].vertices).astype(int)
        _, counts = np.unique(v, axis=0, return_counts=True)
        return float(counts.var() / counts.mean())

    assert dispersion(clumped.tree) > 3.0 * dispersion(plain.tree)


def test_clumping_settings_are_validated():
    assert Louvers().clumping == 1.0 and Louvers().clumping_fit is False
    with pytest.raises(ConfigError, match=r"tree\.louvers\.clumping.*≤ 1"):
        Louvers(clumping=1.2)
    with pytest.raises(ConfigError, match=r"tree\.louvers\.cluster_radius_m"):
        Louvers(cluster_radius_m=0.0)


def test_round_trip_clumped_crown(tmp_path):
    """Known crown: LAD 0.83 m²/m³, ellipsoidal x = 2 (mean tilt 38.5°), slats grouped in
    clusters of 0.2 m, Ω = 0.7 → six synthetic upward photos (seeds 1–6) → one fit with
    ``clumping_fit`` (Ω from the photos' Lang & Xiang clumping): true LAD within 5 %, tilt
    within 3°, Ω within 0.03, façade illuminance (NumPy, same seeds) within 3 % at 10:30 and
    16:30, when the sun reaches the façade through the crown (there an unclumped crown of the
    same density gives 3.2 % more light; at 12:30 only 0.15 %). 512 paths per sensor: the
    façade means' standard errors (~0.5 % each) keep the 3 % check 4 σ wide (at 128 paths a
    different random stream alone moved the difference from −1.2 % to −3.6 %)."""
    from radtree.pipeline.assemble import make_scene
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project
    from radtree.trees.leaf_angles import mean_tilt
    from radtree.verify.photo import KNOWN_CROWN, PHOTO_CROWN, photo_scenarios

    root = copy_project(tmp_path / "rt")
    proj = load_project(root, overrides={
        "site.hours": ["10:30", "16:30"], "sensors.dense_grid": False, "sensors.dense_hours": [],
        "engine.rays": 512, **PHOTO_CROWN})
    known = {**KNOWN_CROWN, "louvers.slat_size_m": 0.1, "louvers.clumping": 0.7,
             "louvers.cluster_radius_m": 0.2}
    original, refit = photo_scenarios(proj, root, known, seeds=range(1, 7), size=250, refit={
        "louvers.clumping": 1.0, "louvers.clumping_fit": True})
    fitted = make_scene(proj, refit).tree
    fit = fitted.photo["fitted"]
    true_lad = make_scene(proj, original).tree.info["density_per_m3"] * 0.1**2
    assert fit["leaf_area_density_m2_m3"] == pytest.approx(true_lad, rel=0.05)
    assert abs(fit["mean_tilt_deg"] - mean_tilt(2.0)) <= 3.0
    assert fit["clumping_fitted"] is True
    assert fit["clumping_omega"] == pytest.approx(0.7, abs=0.03)
    assert fitted.info["clumping"] == pytest.approx(fit["clumping_omega"])
    # the photos show the clumping: their Lang & Xiang index is below the random slats' one
    curve = dict((o, v) for o, v in fit["clumping_curve"])
    assert fit["clumping_lx_model"] < curve[1.0]
    run = replace(proj, scenarios=(original, refit))
    out = simulate_project(run, options=RunOptions(engine="numpy"))
    assert out is not None
    mean = out.table[out.table["grid"] == "facade"].groupby("scenario")["lux"].mean()
    assert mean["R"] == pytest.approx(mean["T"], rel=0.03)
