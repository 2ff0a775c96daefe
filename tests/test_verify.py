"""The physics suite: G functions against their closed forms, a reduced run of each check
family, and ``radtree verify``'s table and exit status."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from radtree.verify import Check, energy_checks, sphere_checks, transmission_checks
from radtree.verify.leaves import (
    LEAF_DISTRIBUTIONS,
    g_function,
    leaf_angle_density,
    leaf_layer,
    sample_inclinations,
    uncollided_transmission,
)


@pytest.mark.parametrize("zenith", [0.0, 30.0, 60.0, 85.0])
def test_spherical_g_is_one_half(zenith):
    assert g_function("spherical", zenith) == pytest.approx(0.5, abs=1e-4)


def test_g_at_the_zenith_is_the_mean_leaf_cosine():
    # planophile: (2/π)∫(1 + cos 2t) cos t dt = 8/(3π); erectophile 4/(3π)
    assert g_function("planophile", 0.0) == pytest.approx(8 / (3 * math.pi), abs=1e-4)
    assert g_function("erectophile", 0.0) == pytest.approx(4 / (3 * math.pi), abs=1e-4)


@pytest.mark.parametrize("dist", LEAF_DISTRIBUTIONS)
def test_g_is_normalised_and_crosses_one_half_near_57_degrees(dist):
    # ∫ G(θ) sin θ dθ = 1/2 for every distribution; all G curves meet near 57.5°
    th = np.radians(np.linspace(0.05, 89.95, 900))
    g = np.array([g_function(dist, math.degrees(t)) for t in th])
    assert float(np.sum(g * np.sin(th)) * (th[1] - th[0])) == pytest.approx(0.5, abs=2e-3)
    assert g_function(dist, 57.5) == pytest.approx(0.5, abs=0.01)


@pytest.mark.parametrize("dist", LEAF_DISTRIBUTIONS)
def test_sampled_inclinations_follow_the_density(dist):
    t = sample_inclinations(dist, 200_000, np.random.default_rng(1))
    hist, edges = np.histogram(t, bins=9, range=(0, math.pi / 2), density=True)
    mid = (edges[:-1] + edges[1:]) / 2
    f = leaf_angle_density(dist, mid)
    f = f / (np.sum(f) * (edges[1] - edges[0]))
    assert np.allclose(hist, f, rtol=0.05, atol=0.02)


def test_leaf_layer_has_the_stated_leaf_area_index():
    m = leaf_layer("l", "black", lai=2.0, distribution="planophile", extent=6.0,
                   z_bottom=1.0, z_top=2.0, size=0.1, rng=np.random.default_rng(2))
    assert m.area() / 36.0 == pytest.approx(2.0, rel=0.03)


def test_transmission_check_reduced():
    checks = transmission_checks(realisations=2, photons=20_000, engines=("forward", "numpy"),
                                 lais=(1.0,), distributions=("planophile",), zeniths=(60.0,))
    assert len(checks) == 2
    expected = uncollided_transmission("planophile", 1.0, 60.0)
    for c in checks:
        print(c)
        assert c.expected == pytest.approx(expected)
        assert c.tolerance < 0.1 * expected
        assert c.status != "fail", c        # within 3 SE; a pass needs them inside 1 %
        assert c.passed is (c.tolerance <= c.claim)


def test_floating_spheres_match_their_numerical_integral():
    checks = sphere_checks(realisations=1, photons=60_000, zeniths=(30.0,))
    (c,) = checks
    print(c)
    assert 0.3 < c.expected < 0.7          # the spheres shade part of the floor, not all of it
    assert c.tolerance < 0.03 * c.expected
    assert c.status != "fail", c
    assert c.passed is (c.tolerance <= c.claim)


def test_sphere_integral_of_a_single_sphere_overhead():
    # one sphere straight above a point: optical depth G·u·2R, u = 3·LAI/(4R)
    from radtree.verify.spheres import Spheres, optical_depth

    sp = Spheres(np.array([[0.0, 0.0, 2.0]]), 1.0, 3.75)
    tau = optical_depth(np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0]]), np.array([0, 0, 1.0]), sp)
    assert tau == pytest.approx([0.5 * 3.75 * 2.0, 0.0])


def test_energy_checks_pass():
    checks = energy_checks(photons=20_000)
    for c in checks:
        print(c)
    assert [c.passed for c in checks] == [True, True, True]


def _fake_suite(monkeypatch, checks):
    import radtree.verify.suite as suite

    monkeypatch.setattr(suite, "transmission_checks", lambda **_k: checks)
    monkeypatch.setattr(suite, "energy_checks", lambda **_k: [])
    monkeypatch.setattr(suite, "sphere_checks", lambda **_k: [])
    monkeypatch.setattr(suite, "agreement_checks", lambda **_k: [])
    monkeypatch.setattr(suite, "turbid_checks", lambda **_k: [])
    monkeypatch.setattr(suite, "voxel_checks", lambda **_k: [])
    monkeypatch.setattr(suite, "mist_checks", lambda **_k: [])
    for group in ("annual", "honeybee", "energyplus", "gltf", "photo", "diagnose"):
        monkeypatch.setitem(suite.GROUPS, group, lambda _full, _b: [])


@pytest.mark.parametrize("got, code", [(1.0, 0), (2.0, 1)])
def test_verify_command_writes_the_table_and_fails_on_a_failure(monkeypatch, tmp_path, got,
                                                                 code):
    from radtree.cli import main

    _fake_suite(monkeypatch, [Check("a check", "forward", 1.0, got, 0.1)])
    out = tmp_path / "verify.csv"
    res = CliRunner().invoke(main, ["verify", "--out", str(out)])
    assert res.exit_code == code, res.output
    t = pd.read_csv(out)
    assert list(t.columns) == ["check", "engine", "expected", "got", "tolerance", "claim",
                               "status", "passed", "reference", "seconds"]
    assert bool(t["passed"][0]) is (code == 0)
    assert ("FAIL" in res.output) is (code == 1)


@pytest.mark.parametrize("got, tolerance, claim, status", [
    (1.01, 0.02, 0.02, "pass"),        # within a tolerance that is the claim
    (1.03, 0.02, 0.02, "fail"),        # outside
    (1.03, 0.05, 0.02, "unresolved"),  # within 3 SE wider than the claim: not a pass
    (1.08, 0.05, 0.02, "fail"),
])
def test_a_check_never_passes_on_a_tolerance_wider_than_its_claim(got, tolerance, claim,
                                                                   status):
    c = Check("x", "numpy", 1.0, got, tolerance, claim)
    assert c.status == status
    assert c.passed is (status == "pass")


def test_quick_verify_exits_zero_on_unresolved_and_the_page_lists_every_path(monkeypatch,
                                                                            tmp_path):
    from radtree.cli import main
    from radtree.verify.page import OUTPUT_PATHS

    _fake_suite(monkeypatch, [
        Check("agreement: forward vs numpy", "forward", 100.0, 103.0, 6.0, 2.0, "numpy"),
        Check("three-phase chain vs rcontrib", "radiance", 1.0, 1.01, 0.03, None, "rcontrib")])
    page = tmp_path / "docs" / "validation.md"
    res = CliRunner().invoke(main, ["verify", "--out", str(tmp_path / "v.csv"), "--page",
                                    str(page)])
    assert res.exit_code == 0, res.output
    assert "1 unresolved" in res.output
    text = page.read_text()
    rows = [r for r in text.splitlines() if r.startswith("| ")][1:]
    assert rows[0].split(" | ")[-1] == "unresolved |"
    assert rows[1].split(" | ")[-1] == "pass |"
    assert rows[1].startswith("| three-phase chain |")
    assert "1 pass, 0 fail, 1 unresolved of 2 checks." in text
    missing = text.split("**Not checked by this run:** ")[1].split(".")[0].split(", ")
    assert set(missing) == set(OUTPUT_PATHS) - {"forward engine", "NumPy engine",
                                                "three-phase chain"}


def test_agreement_check_forward_vs_numpy_on_the_reduced_dome():
    from radtree.verify.checks import BackwardPlan, agreement_checks

    plans = {"numpy": BackwardPlan(points=8, rays=64)}
    checks = agreement_checks(photons=1_000_000, backward=["numpy"], plans=plans)
    assert len(checks) == 1
    c = checks[0]
    assert "louvers dome A 12:30" in c.check and c.check.endswith("forward vs numpy")
    assert 850.0 < c.expected < 1050.0          # ≈ 945 lx converged (verify's quick table)
    assert c.status != "fail", c
    assert c.tolerance >= 0.02 * c.expected
    assert c.claim == pytest.approx(0.02 * c.expected)
    assert c.passed is (c.tolerance <= c.claim)


def test_agreement_plan_hours_skip_the_engine_and_the_forward_trace():
    from radtree.verify.checks import BackwardPlan, agreement_checks

    plans = {"numpy": BackwardPlan(points=2, rays=4, hours=("10:30",))}
    assert agreement_checks(hours=("12:30",), photons=0, backward=["numpy"], plans=plans) == []


def test_group_runs_merge_into_one_page(monkeypatch, tmp_path):
    from radtree.cli import main

    _fake_suite(monkeypatch, [Check("a check", "forward", 1.0, 1.01, 0.02, 0.02, "ref")])
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    assert CliRunner().invoke(main, ["verify", "--group", "layers", "-o", str(a)]).exit_code == 0
    monkeypatch.setattr("radtree.verify.suite.transmission_checks", lambda **_k: [
        Check("another", "numpy", 2.0, 2.5, 0.1, 0.1, "")])
    assert CliRunner().invoke(main, ["verify", "--group", "layers", "-o", str(b)]).exit_code == 1
    page = tmp_path / "validation.md"
    res = CliRunner().invoke(main, ["verify", "--merge", str(a), "--merge", str(b), "--page",
                                    str(page)])
    assert res.exit_code == 1, res.output       # the merged table holds a failure
    text = page.read_text()
    assert "2 row groups run side by side" in text
    assert "1 pass, 1 fail, 0 unresolved of 2 checks." in text
    assert "| a check | ref |" in text and "| another | — |" in text


def test_cli_groups_are_the_suites_groups():
    from radtree.cli.verify import GROUP_NAMES
    from radtree.verify.suite import GROUPS

    assert GROUP_NAMES == tuple(GROUPS)


def test_stratified_patch_points_put_two_points_in_every_cell():
    from radtree.scene import SensorGrid
    from radtree.verify.compare import patch_points, stratified_cells

    assert stratified_cells(128) == 8
    with pytest.raises(ValueError):
        stratified_cells(64)
    g = SensorGrid("g", np.array([[0.0, 0.0, 0.0]]), np.array([[0.0, 0.0, 1.0]]))
    p = patch_points(g, 0.5, 32, np.random.default_rng(3), stratified=True).points
    cell = np.floor((p[:, :2] + 0.25) / 0.125).astype(int)          # 4 × 4 cells of 0.125 m
    assert (cell[0::2] == cell[1::2]).all()                          # pairs share their cell
    assert len({tuple(c) for c in cell}) == 16                       # every cell is sampled


def test_the_quick_leaf_layer_plan_is_the_old_scene():
    from radtree.verify.checks import LayerPlan

    quick, full = LayerPlan(), LayerPlan(detectors=14)
    assert (quick.extent, quick.beam) == (10.0, 9.0)     # 6 × 6 detectors, as before
    assert (full.extent, full.beam) == (18.0, 20.0)      # the beam holds every 1 m patch


def test_forward_target_leaves_the_backward_error_room_within_the_claim():
    from radtree.verify.checks import forward_target

    # 3 combined SE = 90 % of the 2 % claim: combined 0.6 %; NumPy at 0.2 % leaves √(0.6² − 0.2²)
    assert forward_target([0.002]) == pytest.approx(math.sqrt(0.006 ** 2 - 0.002 ** 2))
    assert forward_target([0.002, 0.0051]) == pytest.approx(math.sqrt(0.006 ** 2 - 0.0051 ** 2))
    assert forward_target([0.01]) == 0.002                 # no room: the floor


# --------------------------------------------------------------------------- output paths


def test_every_output_path_has_a_group_of_its_own():
    from radtree.verify.page import ENGINE_PATHS, OUTPUT_PATHS
    from radtree.verify.suite import GROUPS

    others = set(OUTPUT_PATHS) - set(ENGINE_PATHS) - {"three-phase chain", "crown BSDF"}
    assert {"annual", "honeybee", "energyplus", "gltf", "photo", "diagnose"} <= set(GROUPS)
    assert len(others) == 6



def assert_all_pass(checks, path: str) -> None:
    """Every check passes and is filed under the output path ``path`` on the page."""
    from radtree.verify.page import path_of

    for c in checks:
        print(c)
        assert c.status == "pass", c
        assert path_of(c) == [path]

def test_gltf_read_back_without_trimesh():
    from radtree.verify.gltf import gltf_checks

    checks = gltf_checks()
    assert_all_pass(checks, "glTF export")
    count, area, box = checks
    assert count.expected == count.got > 5000                # every triangle, mesh by mesh
    assert area.expected == pytest.approx(316.78, abs=0.01)  # the louvers dome's leaf area
    assert abs(area.got - area.expected) < 1e-5 * area.expected
    assert box.got < 1e-5


def test_idf_read_back_by_a_plain_parser():
    from radtree.verify.energyplus import idf_checks, idf_objects

    assert idf_objects("A,\n 1, ! one\n 2;\nB, x;") == [["A", "1", "2"], ["B", "x"]]
    checks = idf_checks(rays=4)
    assert_all_pass(checks, "EnergyPlus schedules")
    values, shadow, shades = checks
    assert values.got <= 5e-7 and shadow.got == 2.0 and shades.got == shades.expected > 100


def test_synthetic_fisheye_openness_and_lai():
    from radtree.verify.page import path_of
    from radtree.verify.photo import hemi_checks, poisson_openness

    assert poisson_openness(0.0) == pytest.approx(1.0, abs=1e-6)
    openness, lai = hemi_checks(size=1000)
    print(openness, lai)
    assert openness.expected == pytest.approx(0.1485, abs=1e-4)
    assert openness.status == lai.status == "pass"
    assert path_of(lai) == ["photo round trip"]


def test_diagnose_fit_recovers_the_injected_strength():
    from radtree.verify.diagnose import fit_checks
    from radtree.verify.page import path_of

    (c,) = fit_checks()
    print(c)
    assert c.status == "pass" and c.got != c.expected      # noisy, yet within 3 SE
    assert c.tolerance == pytest.approx(3 * 12000 * 20 / np.linalg.norm(
        [200, 210, 190, 180, 190, 200, 215]))
    assert path_of(c) == ["diagnose self-test"]


def test_a_missing_extra_is_unresolved_not_passed():
    from radtree.verify.suite import missing_extra

    c = missing_extra("Honeybee export", "honeybee")
    assert c.status == "unresolved" and "pip install 'radtree[honeybee]'" in c.check


def test_honeybee_export_traced_by_honeybee_radiance():
    pytest.importorskip("honeybee_radiance")
    from radtree.engines.radiance.binaries import find_radiance
    from radtree.verify.honeybee import honeybee_checks

    if find_radiance() is None:
        pytest.skip("Radiance not installed")
    checks = honeybee_checks()
    assert_all_pass(checks, "Honeybee export")
    count, direct, lit = checks
    assert count.got == count.expected > 1000
    assert direct.got < 0.005 and "3 sunlit sensors" in direct.check and lit.got == 0
