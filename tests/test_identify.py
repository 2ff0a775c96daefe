"""Identifiability (radtree.diagnose.identify): pure NumPy on small matrices."""

from __future__ import annotations

import numpy as np
import pytest

from radtree.diagnose.identify import (
    GROUP_CORR,
    condition_number,
    identifiability,
    joint_intervals,
    linear_interval,
)


def test_orthogonal_signatures_are_separable() -> None:
    s = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]) * 100.0
    ident = identifiability(["a", "b"], s, sigma=10.0)
    assert ident.correlation[0, 1] == pytest.approx(0.0, abs=1e-12)
    assert ident.condition == pytest.approx(1.0)
    assert ident.groups == [["a"], ["b"]]
    assert ident.separable("a", "b") and ident.distinguishable("a")
    assert ident.snr == pytest.approx([np.sqrt(200.0)] * 2)  # √2 · 100 / 10
    assert ident.sentence("a").startswith("named a; with these data it is separable")


def test_identical_signatures_form_one_group() -> None:
    x = np.array([3.0, 5.0, 7.0, 5.0, 3.0])
    s = np.column_stack([x, 2.0 * x, [1.0, -1.0, 1.0, -1.0, 1.0]])
    ident = identifiability(["sky", "ground", "other"], s, sigma=0.1)
    assert ident.correlation[0, 1] == pytest.approx(1.0)
    assert ident.condition == np.inf
    assert ident.groups == [["sky", "ground"], ["other"]]
    assert ident.confounded == [["sky", "ground"]]
    assert not ident.separable("sky", "ground") and not ident.distinguishable("ground")
    assert ident.sentence("sky") == (
        "named sky, but sky and ground are not separable with these data (whitened "
        f"signatures correlate ≥ {GROUP_CORR:.2f}); the choice among them is the lower CV "
        "error only")
    table = ident.table().set_index("effect")
    assert table.loc["ground", "verdict"] == "not separable from sky"
    assert table.loc["other", "verdict"] == "separable"


def test_whitening_changes_the_verdict() -> None:
    # equal in the first two values, apart in the third: the noise decides which counts
    s = np.array([[1.0, 1.0], [1.0, 1.0], [1.0, 0.0]]) * 1000.0
    loud_third = identifiability(["a", "b"], s, sigma=np.array([1.0, 1.0, 100.0]))
    quiet_third = identifiability(["a", "b"], s, sigma=np.array([100.0, 100.0, 1.0]))
    assert loud_third.correlation[0, 1] == pytest.approx(2 / (np.sqrt(2) * np.sqrt(2 + 1e-4)))
    assert loud_third.groups == [["a", "b"]]
    assert quiet_third.correlation[0, 1] == pytest.approx(2e-4 / (np.sqrt(1 + 2e-4)
                                                                  * np.sqrt(2e-4)))
    assert quiet_third.groups == [["a"], ["b"]]
    # anticorrelated signatures are confounded too (|corr|)
    anti = identifiability(["a", "b"], np.array([[1.0, -1.0], [2.0, -2.0]]) * 100, 1.0)
    assert anti.groups == [["a", "b"]]
    # unit noise: Gram of the normalised columns [[1, 1/3], [1/3, 1]], eigenvalues 4/3, 2/3
    s2 = np.array([[1.0, 1.0], [1.0, 1.0], [1.0, -1.0]])
    assert condition_number(s2) == pytest.approx(np.sqrt(2.0), rel=1e-12)


def test_below_noise_is_its_own_verdict() -> None:
    s = np.array([[1.0, 50.0], [2.0, 60.0], [1.0, 40.0]])
    ident = identifiability(["faint", "strong"], s, sigma=10.0)
    assert ident.below_noise("faint") and not ident.below_noise("strong")
    assert ident.groups == [["faint"], ["strong"]]
    assert not ident.distinguishable("faint") and ident.distinguishable("strong")


def test_profile_interval_covers_the_true_strength() -> None:
    """50 seeded synthetic cases: 7 observations, a linear strength, 3 % noise of unknown
    scale; the 95 % profile interval must cover the truth in at least 90 %."""
    covered, widths = 0, []
    for seed in range(50):
        rng = np.random.default_rng(seed)
        x = rng.uniform(200.0, 900.0, 7)          # signature at the reference strength
        truth = rng.uniform(0.2, 2.0) * 12000.0    # lx of diffuse horizontal, say
        sigma = 0.03 * 5000.0
        r = truth / 12000.0 * x + sigma * rng.standard_normal(7)
        iv = linear_interval(x, r, 12000.0, 0.0, 40000.0)
        covered += iv.covers(truth)
        widths.append(iv.hi - iv.lo)
    assert covered >= 45
    assert covered <= 50 and np.median(widths) > 0


def test_joint_intervals_widen_for_confounded_effects() -> None:
    rng = np.random.default_rng(3)
    x = rng.uniform(1.0, 2.0, 12)
    near = x + 0.01 * rng.standard_normal(12)
    far = rng.standard_normal(12)
    r = 1.0 * x + 0.05 * rng.standard_normal(12)
    _, half_conf = joint_intervals(np.column_stack([x, near]), r, 0.05)
    a, half_sep = joint_intervals(np.column_stack([x, far]), r, 0.05)
    assert half_conf[0] > 20 * half_sep[0]
    assert abs(a[0] - 1.0) <= half_sep[0]


def test_step_identifiability_names_the_partners_and_brackets_the_strength() -> None:
    from radtree.diagnose.attribution import Attribution, Signature
    from radtree.diagnose.effects import Strength, get_effect
    from radtree.diagnose.identify import step_identifiability

    hours = np.array([1.0, 1.2, 1.3, 1.35, 1.3, 1.2, 1.0])
    sky = 150.0 * hours                      # lx at 12 000 lx diffuse
    ground = 60.0 * hours ** 1.02           # nearly the same shape
    rng = np.random.default_rng(7)
    measured_minus_model = 1.25 * sky + 3.0 * rng.standard_normal(7)

    def sig(name: str, x: np.ndarray, ref: float, hi: float) -> Signature:
        st = Strength(name, "", 0.0, hi, ref)
        return Signature(get_effect(name), "linear", st, np.array([ref]), x[None, :],
                         np.zeros((1, 1)), ["all"], [], ref)

    sigs = {"sky_diffuse": sig("sky_diffuse", sky, 12000.0, 40000.0),
            "unfiltered_ground": sig("unfiltered_ground", ground, 0.1, 1.0)}
    att = Attribution(measured_minus_model, 1000.0, 100.0, [], sigs, {}, 0.05)
    ident, iv = step_identifiability(att, np.full(7, 1000.0), np.full(7, 5.0))
    assert ident.partners("sky_diffuse") == ["unfiltered_ground"]
    assert ident.sentence("sky_diffuse").startswith(
        "named sky_diffuse, but sky_diffuse and unfiltered_ground are not separable")
    assert iv["sky_diffuse"].covers(15000.0) and iv["sky_diffuse"].hi - iv["sky_diffuse"].lo < 2000
    assert iv["unfiltered_ground"].lo > 0.1   # alone, ground would need > its reference


def test_unique_snr_is_the_signal_beyond_the_others_span() -> None:
    from radtree.diagnose.identify import unique_snr

    a = np.array([1.0, 0.0, 0.0, 1.0]) * 30.0
    b = np.array([0.0, 1.0, 0.0, 1.0]) * 30.0
    c = np.array([0.0, 0.0, 1.0, 0.0]) * 30.0
    # orthogonal to the others: all of its signal (√2 · 30 / 10)
    assert unique_snr(c, np.column_stack([a, b]), 10.0) == pytest.approx(3.0)
    assert unique_snr(c, None, 10.0) == pytest.approx(3.0)
    # identical to another: nothing left
    assert unique_snr(a, 2.0 * a[:, None], 10.0) == pytest.approx(0.0, abs=1e-12)
    # one other at correlation ρ = 1/2: SNR · √(1 − ρ²)
    rho = a @ b / (np.linalg.norm(a) * np.linalg.norm(b))
    assert rho == pytest.approx(0.5)
    assert unique_snr(a, b[:, None], 10.0) == pytest.approx(np.sqrt(18.0) * np.sqrt(0.75))
    # the sum of two others correlates only 0.87 with each, yet the pair reproduces it
    s = a + b
    assert max(s @ a / np.linalg.norm(s) / np.linalg.norm(a),
               s @ b / np.linalg.norm(s) / np.linalg.norm(b)) < 0.9
    assert unique_snr(s, np.column_stack([a, b]), 10.0) == pytest.approx(0.0, abs=1e-12)
    # per-observation noise: the same vectors, the loud observation counts less
    sig = np.array([10.0, 10.0, 10.0, 1000.0])
    assert unique_snr(a, b[:, None], sig) == pytest.approx(3.0, rel=1e-3)


def test_nearest_snr_counts_every_value_and_the_alternatives_reach() -> None:
    from radtree.diagnose.identify import nearest_snr

    # 100 values each at 0.5 σ: per value below the noise, together 5 σ from no change
    s = np.full(100, 0.5)
    assert nearest_snr(s, np.zeros((1, 100)), 1.0) == pytest.approx(5.0)
    # an alternative that can scale to the same shape leaves nothing; a fixed one at half
    # the size leaves half
    assert nearest_snr(s, np.vstack([0.5 * s, s]), 1.0) == pytest.approx(0.0)
    assert nearest_snr(s, 0.5 * s[None, :], 1.0) == pytest.approx(2.5)
    assert nearest_snr(s, np.zeros((0, 100)), 1.0) == np.inf


def test_selftest_rule_separation_against_linear_search_and_binary() -> None:
    """The self-test's alternatives: a linear candidate fits its non-negative amplitude (so an
    opposite-signed signature cannot stand in), a searched one any scanned strength."""
    from radtree.diagnose.attribution import Signature
    from radtree.diagnose.effects import Strength, get_effect
    from radtree.diagnose.hidden import alternatives, margin_snr
    from radtree.diagnose.identify import nearest_snr

    n = 50
    x = np.linspace(1.0, 2.0, n)
    sigma = np.full(n, 0.1)

    def lin(v: np.ndarray) -> Signature:
        st = Strength("s", "", 0.0, 1.0, 0.1, "linear")
        return Signature(get_effect("unfiltered_ground"), "linear", st, np.array([0.1]),
                         v[None, :], np.zeros((1, 1)), ["all"], [], 0.1)

    assert nearest_snr(x, alternatives(lin(3.0 * x), x, sigma), sigma) == pytest.approx(0.0)
    # anticorrelated: amplitude clipped at 0, the whole signal remains
    far = nearest_snr(x, alternatives(lin(-x), x, sigma), sigma)
    assert far == pytest.approx(np.linalg.norm(x / sigma))
    st = Strength("layers", "", 1.0, 2.0, 1.0, "search", grid=(1.0, 2.0), integer=True)
    search = Signature(get_effect("fewer_stages"), "search", st, np.array([1.0, 2.0]),
                       np.vstack([0.5 * x, 2.0 * x]), np.zeros((2, 1)), ["all"], [], 1.0)
    # integer strengths: 0, 0.5 x or 2 x — the nearest is 0.5 x, 0.5 ‖x/σ‖ away
    assert nearest_snr(x, alternatives(search, x, sigma), sigma) == pytest.approx(
        0.5 * np.linalg.norm(x / sigma))
    # the loop's 5 % margin: 1 − 1/√(1 + q²) = 0.05
    q = margin_snr(0.05)
    assert 1.0 - 1.0 / np.sqrt(1.0 + q * q) == pytest.approx(0.05)
