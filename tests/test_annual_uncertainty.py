"""Replicated traces and the jackknife of :mod:`radtree.annual.uncertainty`."""

from __future__ import annotations

import numpy as np
import pytest

from radtree.annual.coefficients import CoefficientRunner, TraceParams
from radtree.annual.uncertainty import grid_metrics, jackknife

from .conftest import needs_radiance
from .test_annual import _tiny_scene, tiny_project  # noqa: F401


@needs_radiance
def test_replicates_are_independent_passes_and_the_first_is_the_plain_run(tmp_path):
    scene = _tiny_scene(room=True)
    plain = CoefficientRunner(scene, ["g"], tmp_path / "plain", 0.2).sky(
        1, TraceParams(ab=2, ad=64, lw=1e-3, nproc=2))
    runner = CoefficientRunner(scene, ["g"], tmp_path / "reps", 0.2)
    params = TraceParams(ab=2, ad=64, lw=1e-3, nproc=2, replicates=3)
    reps = runner.sky_replicates(1, params)
    assert reps.shape == (3, 8, 146, 3)
    # each chunk's first pass draws the plain run's samples: bit for bit the same
    assert np.array_equal(reps[0], plain)
    # later passes sample anew: different estimates of the same coefficients
    total = reps[:, :, 1:].sum(axis=(2, 3))                 # (replicates, sensors)
    assert not np.array_equal(reps[1], reps[0])
    open_field = total[:, :5]                                # the 5 sensors outside the box
    assert np.all(np.abs(open_field[1:] / open_field[0] - 1) < 0.1)
    # more replicates extend fewer: passes 0 and 1 of R = 3 are those of R = 2
    two = runner.sky_replicates(1, TraceParams(ab=2, ad=64, lw=1e-3, nproc=2, replicates=2))
    assert np.array_equal(two, reps[:2])
    # sky() is their mean, and the cache returns the same array
    assert np.allclose(runner.sky(1, params), reps.mean(axis=0))
    assert np.array_equal(runner.sky_replicates(1, params), reps)
    # -ab 0 has no Monte Carlo part: traced once whatever the replicates
    sun = runner.suns_replicates("d", np.array([[0.0, -0.5, 0.866]]), 0, params)
    assert sun.shape == (1, 8, 1, 3)


def test_jackknife_of_a_mean_is_the_standard_error_of_the_mean():
    rng = np.random.default_rng(3)
    reps = [rng.normal(10.0, 2.0, size=(4, 5)) for _ in range(6)]
    est, se = jackknife(reps, lambda a: {"mean": float(a.mean())})
    per_rep = np.array([r.mean() for r in reps])
    assert est["mean"] == pytest.approx(per_rep.mean())
    assert se["mean"] == pytest.approx(per_rep.std(ddof=1) / np.sqrt(6))
    one_est, one_se = jackknife(reps[:1], lambda a: {"mean": float(a.mean())})
    assert one_est["mean"] == pytest.approx(per_rep[0]) and np.isnan(one_se["mean"])


def test_grid_metrics_count_the_stated_bands():
    occupied = np.array([True, True, True, True, False])
    lux = np.array([[50.0, 100.0, 300.0, 3000.0, 9e4],      # DA 50 %: in sDA
                    [20.0, 40.0, 299.0, 3001.0, 0.0]])     # DA 25 %
    got = grid_metrics(lux, occupied)
    assert got["DA300"] == pytest.approx(37.5)
    assert got["sDA"] == pytest.approx(50.0)
    assert got["UDI<100"] == pytest.approx(100 * 3 / 8)
    assert got["UDI100-3000"] == pytest.approx(100 * 4 / 8)   # 100 and 3000 included
    assert got["UDI>3000"] == pytest.approx(100 * 1 / 8)
    assert got["mean_lux"] == pytest.approx(lux[:, :4].mean())


@needs_radiance
def test_annual_with_replicates_reports_the_metrics_standard_errors(tiny_project):  # noqa: F811
    from radtree.annual.run import AnnualOptions, compute_annual
    from radtree.config import load_project

    project = load_project(tiny_project)
    plain = compute_annual(project, options=AnnualOptions(nproc=1, replicates=1))
    assert plain.uncertainty is None
    res = compute_annual(project, options=AnnualOptions(nproc=1, replicates=3))
    assert res.trace.replicates == res.sun_trace.replicates == 3
    u = res.uncertainty
    assert u is not None and len(u) == 4 * 6          # facade × 4 trees × metrics
    assert set(u.tree) == {"with", "without", "leaf_on", "leaf_off"}
    assert set(u.grid) == {"facade"}
    assert (u.se >= 0).all() and u.se.notna().all()
    mean_lux = u[(u.tree == "without") & (u.metric == "mean_lux")].iloc[0]
    assert mean_lux.se > 0                               # the sky coefficients vary
    occ = res.occupied
    e = res.total["without"]["facade"][:, occ]
    assert mean_lux.value == pytest.approx(e.mean(), rel=1e-5)
    # the mean of 3 replicates is a different (better) estimate than the plain run
    assert not np.allclose(res.total["without"]["facade"], plain.total["without"]["facade"])
    with pytest.raises(Exception, match="replicates"):
        AnnualOptions(replicates=2, method="3phase")


def test_sda_se_counts_the_sensors_that_may_flip():
    from radtree.annual.uncertainty import sda_se

    # one sensor on the threshold (p = ½), two far from it: 100/3 · √¼
    assert sda_se(np.array([50.0, 100.0, 0.0]), np.array([10.0, 0.0, 0.0])) == \
        pytest.approx(100 / 3 * 0.5)
    # a sensor 1 SE above: p = Φ(1)
    p = 0.841344746
    assert sda_se(np.array([60.0]), np.array([10.0])) == pytest.approx(100 * np.sqrt(p * (1 - p)))
    assert sda_se(np.array([60.0, 40.0]), np.zeros(2)) == 0.0


def test_default_replicates_by_method():
    from radtree.annual.run import DEFAULT_REPLICATES, AnnualOptions

    assert DEFAULT_REPLICATES == 4
    assert AnnualOptions().replicates is None                # resolved by plan_annual
    assert AnnualOptions(method="3phase").replicates is None
    with pytest.raises(Exception, match="replicates"):
        AnnualOptions(replicates=0)
