"""The forward engine's stratified, importance-allocated launch (``focus_m``): unbiased against
analytic illuminances (light that arrives from far away, by a floor reflection, and from the
whole sky), a smaller standard error than the uniform launch at the same photon count, every
lumen accounted for, and a bad radius refused with one message."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radtree.engines.forward import ForwardSettings, trace_forward
from radtree.engines.forward.strata import Stratum, allocate, reallocate, ring_edges
from radtree.engines.numpy.scenes import sky_state
from radtree.errors import ConfigError
from radtree.optics import Plastic
from radtree.scene import Scene, SensorGrid, quad
from radtree.verify.compare import reduced_dome_project

DNI = 80000.0
DOWN = np.array([0.0, 0.0, -1.0])
HALF, HEIGHT, RHO, SIDE = 10.0, 1.0, 0.5, 2.0


def _corner(a: float, b: float) -> float:
    """View factor from a differential area to a parallel a × b rectangle (its corner below
    the element), a and b in units of the height (Howell's catalogue, case B-3)."""
    sa, sb = math.sqrt(1 + a * a), math.sqrt(1 + b * b)
    return (a / sa * math.atan(b / sa) + b / sb * math.atan(a / sb)) / (2.0 * math.pi)


def _floor_view_factor(x: float, y: float) -> float:
    """From a downward element at (x, y, HEIGHT) to the floor square of half side HALF."""
    return sum(_corner(abs(cx - x) / HEIGHT, abs(cy - y) / HEIGHT)
               for cx in (-HALF, HALF) for cy in (-HALF, HALF))


def _floor_scene() -> tuple[Scene, float]:
    """A 20 m white-ish Lambertian floor (ρ 0.5) and a 2 m downward detector 1 m above it: it
    sees only sunlight the floor reflected, from anywhere on the floor. Expected: ρ · E_h ·
    (the detector's mean view factor to the floor, midpoint rule on 40 × 40 points)."""
    g = SensorGrid("facade", [[0.3, -0.2, HEIGHT]], [DOWN])
    scene = Scene([quad("floor", "floor", np.array([[-HALF, -HALF, 0], [HALF, -HALF, 0],
                                                     [HALF, HALF, 0], [-HALF, HALF, 0]], float))],
                  {"floor": Plastic("floor", RHO)}, {"facade": g})
    u = (np.arange(40) + 0.5) / 40 * SIDE - SIDE / 2
    f = np.mean([_floor_view_factor(0.3 + a, -0.2 + b) for a in u for b in u])
    return scene, RHO * DNI * math.sin(math.radians(60)) * f


def test_floor_reflection_unbiased_and_tighter_than_the_uniform_launch():
    scene, expected = _floor_scene()
    st = sky_state("none", altitude=60, azimuth=30, dni=DNI, ground_glow=False)
    runs = {f: trace_forward(scene, st, ForwardSettings(photons=150_000, max_bounces=1,
                                                        patch_m=SIDE, focus_m=f))
            for f in (None, 0.5)}
    for f, r in runs.items():
        got, se = float(r.grids["facade"].lux[0]), float(r.grids["facade"].stderr[0])
        print(f"floor reflection, focus {f}: expected {expected:.0f}, got {got:.0f} ± {se:.0f}")
        assert abs(got - expected) <= 3 * se
        assert abs(r.ledger.balance) < 1e-9 * r.ledger.launched
    se_u, se_f = (float(runs[f].grids["facade"].stderr[0]) for f in (None, 0.5))
    assert se_f < 0.03 * expected
    assert se_f < 0.5 * se_u
    focused = runs[0.5]
    assert focused.strata is not None and focused.pilot_photons > 0
    assert sum(s.traced for s in focused.strata) == focused.photons


def test_rounds_reallocated_keep_the_floor_reflection():
    """The precision loop over the rings (rounds of 5 000 photons to a 1.5 % error), each
    round after the first allotted from all photons so far, the first (sizing) round traced
    but not counted: the analytic value within 3 standard errors, every lumen accounted for."""
    scene, expected = _floor_scene()
    st = sky_state("none", altitude=60, azimuth=30, dni=DNI, ground_glow=False)
    r = trace_forward(scene, st, ForwardSettings(photons=5_000, max_bounces=1, patch_m=SIDE,
                                                 focus_m=0.5, target_rel_se=0.015, seed=2))
    got, se = r.grid_mean("facade")
    print(f"floor reflection, {r.rounds} rounds: expected {expected:.0f}, got {got:.0f} ± {se:.0f}")
    assert r.rounds > 1 and r.strata is not None
    assert sum(s.traced for s in r.strata) == r.photons + r.sizing_photons > r.photons
    assert se <= 0.015 * got and abs(got - expected) <= 3 * se
    assert abs(r.ledger.balance) < 1e-9 * r.ledger.launched


def test_stages_reallocate_within_a_round_and_keep_the_floor_reflection():
    """One round in 4 stages (engine.forward_stages): the rings allotted again before each
    stage from all photons so far, each stage its own batches (4 × 32 rows), the photons of
    the one round counted once; the analytic value within 3 standard errors, every lumen
    accounted for; a round with fewer photons than batches a stage is refused."""
    scene, expected = _floor_scene()
    st = sky_state("none", altitude=60, azimuth=30, dni=DNI, ground_glow=False)
    one, four = (trace_forward(scene, st, ForwardSettings(photons=100_000, max_bounces=1,
                                                          patch_m=SIDE, focus_m=0.5, batches=32,
                                                          stages=k, seed=4))
                 for k in (1, 4))
    assert one.batches["facade"].shape == (32, 1) and four.batches["facade"].shape == (128, 1)
    assert four.rounds == one.rounds == 1 and four.strata is not None
    assert sum(s.traced for s in four.strata) == four.photons
    assert abs(four.photons - one.photons) <= 32 * len(four.strata) * 4   # rounded per ring
    for r in (one, four):
        got, se = r.grid_mean("facade")
        print(f"floor reflection, {r.batches['facade'].shape[0] // 32} stage(s): expected "
              f"{expected:.0f}, got {got:.0f} ± {se:.0f}")
        assert abs(got - expected) <= 3 * se and se < 0.03 * expected
        assert abs(r.ledger.balance) < 1e-9 * r.ledger.launched
    with pytest.raises(ConfigError, match="engine.forward_stages"):
        ForwardSettings(photons=100, batches=32, stages=4)


def test_splitting_near_the_target_keeps_the_floor_reflection():
    """Diffuse events within 5 m of the detector split into 4 children (flux and threshold
    reference divided): the same expected tally, a smaller standard error, every lumen
    accounted for."""
    scene, expected = _floor_scene()
    st = sky_state("none", altitude=60, azimuth=30, dni=DNI, ground_glow=False)
    r = trace_forward(scene, st, ForwardSettings(photons=100_000, max_bounces=1, patch_m=SIDE,
                                                 focus_m=0.5, split=4, split_radius_m=5.0))
    got, se = float(r.grids["facade"].lux[0]), float(r.grids["facade"].stderr[0])
    print(f"floor reflection, split ×4: expected {expected:.0f}, got {got:.0f} ± {se:.0f}")
    assert se < 0.015 * expected and abs(got - expected) <= 3 * se
    assert abs(r.ledger.balance) < 1e-9 * r.ledger.launched


def test_guided_scattering_keeps_the_floor_reflection():
    """Half the floor's diffuse directions aimed at a 1 m sphere around the detector, the flux
    corrected by the Lambertian over the mixture density: the same expectation, a standard
    error below half the Lambertian one at the same photons, the ledger still balanced."""
    scene, expected = _floor_scene()
    st = sky_state("none", altitude=60, azimuth=30, dni=DNI, ground_glow=False)
    se = {}
    for q in (0.0, 0.5):
        r = trace_forward(scene, st, ForwardSettings(photons=100_000, max_bounces=1,
                                                     patch_m=SIDE, focus_m=0.5, guide=q,
                                                     guide_radius_m=1.0))
        got, se[q] = float(r.grids["facade"].lux[0]), float(r.grids["facade"].stderr[0])
        print(f"floor reflection, guide {q}: expected {expected:.0f}, got {got:.0f} ± {se[q]:.0f}")
        assert abs(got - expected) <= 3 * se[q]
        assert abs(r.ledger.balance) < 1e-9 * r.ledger.launched
    assert se[0.5] < 0.5 * se[0.0]


def test_uniform_sky_through_the_rings():
    """A uniform sky of luminance L: E = π L on an upward patch, with the sky's photons
    stratified in rings around the patch for every direction."""
    st = sky_state("uniform", zenith_luminance=1000.0, ground_glow=False)
    g = SensorGrid("facade", [[0, 0, 0.0]], [np.array([0.0, 0.0, 1.0])])
    floor = quad("floor", "floor", np.array([[-5, -5, -0.5], [5, -5, -0.5], [5, 5, -0.5],
                                              [-5, 5, -0.5]], float))
    r = trace_forward(Scene([floor], {"floor": Plastic("floor", 0.0)}, {"facade": g}), st,
                      ForwardSettings(photons=200_000, focus_m=0.5))
    got, se = float(r.grids["facade"].lux[0]), float(r.grids["facade"].stderr[0])
    print(f"uniform sky, rings: expected {math.pi * 1000:.1f} got {got:.1f} ± {se:.1f}")
    assert se < 0.02 * math.pi * 1000 and abs(got - math.pi * 1000) <= 3 * se


def test_ring_edges_and_allocation():
    assert ring_edges(0.5, 10.0).tolist() == [0, 0.5, 1, 1.5, 2, 3, 4, 6, 8, 12]
    strata = [Stratum(0, 0, 1, sigma=0.0), Stratum(0, 1, 2, sigma=4.0, cost=4.0),
              Stratum(0, 2, 3, sigma=0.0), Stratum(0, 3, 4, sigma=0.0)]
    allocate(strata, 10_000, 16)
    n = [s.photons for s in strata]
    assert all(k % 16 == 0 and k > 0 for k in n)
    # weights 0 → 1 (half the neighbour's 2), 2, 1, 0 → floor only
    assert n[0] == n[2] and n[1] > n[0] > n[3]
    assert n[3] == 16 * math.ceil(10_000 * 0.1 / 4 / 16)


def test_reallocation_pools_the_main_rounds():
    """A ring the pilot saw nothing from (σ 0 over 1 000 photons) that the main round found
    (per-photon σ 30 over 9 000 photons) is allotted ∝ the pooled σ = √(9 000 · 30² / 10 000)
    = 28.5 on the next round, no longer the floor's share."""
    strata = [Stratum(0, 0, 1, sigma=10.0, seen=1000, var_sum=1000 * 10.0 ** 2),
              Stratum(0, 1, 2, sigma=0.0, seen=1000, var_sum=0.0),
              Stratum(1, 0, 1, sigma=0.0, seen=1000, var_sum=0.0)]
    allocate(strata, 10_000, 16)
    before = strata[1].photons
    strata[1].seen += 9000
    strata[1].var_sum += 9000 * 30.0 ** 2
    reallocate(strata, 10_000, 16)
    assert strata[1].sigma == pytest.approx(math.sqrt(0.9) * 30.0)
    assert strata[0].sigma == 10.0 and strata[2].sigma == 0.0
    w = np.array([0.5 * 28.46, 28.46, 0.0])   # the first: half its neighbour's (allocate)
    expect = 0.1 / 3 + 0.9 * w / w.sum()
    assert strata[1].photons > 1.8 * before
    assert [s.photons for s in strata] == pytest.approx(10_000 * expect, abs=16)


def test_bad_split_and_guide_are_named():
    for value in (0, 1.5, True):
        with pytest.raises(ConfigError, match="engine.forward_split"):
            ForwardSettings(split=value)
    for share in (-0.1, 1.0, True):
        with pytest.raises(ConfigError, match="engine.forward_guide"):
            ForwardSettings(guide=share)
    with pytest.raises(ConfigError, match="engine.forward_guide_radius_m"):
        ForwardSettings(guide=0.5, guide_radius_m=0.0)


@pytest.mark.parametrize("value", [0.0, -1.0, float("nan")])
def test_bad_focus_is_named(value):
    with pytest.raises(ConfigError, match="engine.forward_focus_m"):
        ForwardSettings(focus_m=value)
    with pytest.raises(ConfigError, match="engine.forward_split_radius_m"):
        ForwardSettings(split=2, split_radius_m=value)
    with pytest.raises(ConfigError, match="engine.forward_focus_m"):
        reduced_dome_project(scenario_overrides={"engine.forward_focus_m": value})
