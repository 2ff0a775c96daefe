"""radtree diagnose: catalogue, measurements, residual rules, attribution, loop, self-test."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from radtree.cli.diagnose import diagnose_command
from radtree.config import Scenario, load_project
from radtree.config.step_project import write_step_project
from radtree.diagnose.attribution import Signature, cosine, fit_candidate
from radtree.diagnose.effects import (
    EFFECT_NAMES,
    EFFECTS,
    EffectContext,
    candidates,
    get_effect,
    parse_effects,
)
from radtree.diagnose.measured import load_measurements
from radtree.diagnose.registry import EFFECT_REGISTRY, effect_class, effect_rows
from radtree.diagnose.residuals import disagreement_map
from radtree.errors import RadtreeError
from radtree.measurements import MeasurementError
from tests.conftest import MENDOZA, copy_project

HOURS = ["10:30", "11:30", "12:30", "13:30", "14:30", "15:30", "16:30"]


@pytest.fixture(scope="module")
def mendoza():
    return load_project(MENDOZA)


@pytest.fixture(scope="module")
def reduced(tmp_path_factory) -> Path:
    """Mendoza, 7 hours, no dense grid, few rays (for the simulation tests)."""
    p = copy_project(tmp_path_factory.mktemp("diag") / "proj",
                     {r"^rays = \d+": "rays = 128",
                      r"^dense_hours = .*$": "dense_grid = false"})
    return p


# --------------------------------------------------------------------------- catalogue
def test_catalogue_complete_and_documented():
    must = {"unfiltered_ground", "calculated_reflection", "sky_diffuse", "opposite_facade",
            "ambient_bounces", "specular_transmission", "crown_gaps", "fewer_stages",
            "more_stages", "hourly_ground_reflectance"}
    assert must <= set(EFFECT_NAMES)
    for e in EFFECTS:
        assert e.title and e.physics and e.switch
        assert "\n" not in e.physics


@pytest.mark.parametrize("name", EFFECT_NAMES)
def test_effects_switch_on_and_off(mendoza, name):
    ctx = EffectContext(mendoza)
    e = get_effect(name)
    for sc in mendoza.scenarios:
        if e.applies(ctx, sc):
            continue
        on = e.switch_on(ctx, sc)
        off = e.switch_off(ctx, sc)
        assert e.is_on(ctx, on), (name, sc.name, on)
        assert not e.is_on(ctx, off), (name, sc.name, off)
        assert e.is_on(ctx, e.switch_on(ctx, off)), (name, sc.name)
        st = e.strength(ctx, sc)
        if st is not None:
            assert st.lo <= st.reference <= st.hi
            # strengths are clipped to the bounds
            assert st.round(st.hi * 10 + 1) == st.round(st.hi)
        # the switched scenario builds a valid project view
        from radtree.config import effective_project

        effective_project(mendoza, on)


def test_effect_status_in_mendoza(mendoza):
    ctx = EffectContext(mendoza)
    a, b = mendoza.scenario("A"), mendoza.scenario("B")
    cands_a = {e.name for e in candidates(ctx, a)[0]}
    cands_b = {e.name for e in candidates(ctx, b)[0]}
    # already in the Mendoza model: opposite façade 0.35, 8 bounces, specular 0.9, ρ(α) table
    for on in ("opposite_facade", "ambient_bounces", "specular_transmission",
               "hourly_ground_reflectance"):
        assert on not in cands_a and on not in cands_b
    assert "calculated_reflection" in cands_b and "calculated_reflection" not in cands_a
    assert {"sky_diffuse", "unfiltered_ground", "crown_gaps", "fewer_stages"} <= cands_a
    assert "sky_diffuse" not in {e.name for e in candidates(ctx, mendoza.scenario("A-sky"))[0]}
    # specific switches
    sky = get_effect("sky_diffuse").switch_on(ctx, b, 8000)
    assert sky.sky == "perez" and sky.switches["light.diffuse_horizontal_lux"] == 8000.0
    assert get_effect("fewer_stages").switch_on(ctx, b, 2).switches["louvers.layers"] == 3
    assert get_effect("crown_gaps").switch_on(ctx, b, 0.1).switches[
        "louvers.cover_fraction"] == pytest.approx(0.9)
    assert get_effect("ambient_bounces").switch_off(ctx, b).switches["engine.ab"] == 2
    assert ctx.default_ab(b) == 7  # louvers, 5 layers: the crown recommends -ab 7
    const = get_effect("hourly_ground_reflectance").switch_off(ctx, b)
    assert 0.151 <= const.switches["street.ground_reflectance"] <= 0.157


def test_parse_effects_errors():
    assert parse_effects(None) == EFFECTS
    assert [e.name for e in parse_effects("sky_diffuse, crown_gaps")] == ["sky_diffuse",
                                                                         "crown_gaps"]
    with pytest.raises(RadtreeError, match="unknown effect 'sky'.*sky_diffuse"):
        parse_effects("sky")


def test_list_effects_cli(mendoza):
    r = CliRunner().invoke(diagnose_command, ["list-effects"])
    assert r.exit_code == 0, r.output
    for name in EFFECT_NAMES:
        assert name in r.output
    assert r.output.count("physics:") == len(EFFECTS)
    listed = [line.split(":")[0] for line in r.output.splitlines() if not line.startswith(" ")]
    assert listed == list(EFFECT_REGISTRY)


def test_effect_registry_is_the_catalogue():
    """The registry names the catalogue, the CLI's --effects help and list-effects; each
    class's declared capabilities match what it does."""
    from radtree.diagnose.effects import _static_strength

    assert EFFECT_NAMES == tuple(EFFECT_REGISTRY)
    assert [e.name for e in EFFECTS] == list(EFFECT_REGISTRY)
    rows = effect_rows()
    assert [r[0] for r in rows] == list(EFFECT_REGISTRY)
    help_text = CliRunner().invoke(diagnose_command, ["run", "--help"],
                                   terminal_width=400).output
    assert ", ".join(EFFECT_REGISTRY) in " ".join(help_text.split())
    ctx = EffectContext(load_project(MENDOZA))
    homogeneous = Scenario("h", "homogeneous")
    for e, (name, summary, caps) in zip(EFFECTS, rows):
        assert summary == e.title
        st = _static_strength(e)
        assert caps.startswith(f"strength: {'on/off' if st is None else st.mode}; "), name
        louvers_only = e.applies(ctx, homogeneous) is not None and "louvers" in str(
            e.applies(ctx, homogeneous))
        assert ("crowns: louvers" in caps) == louvers_only, name
    assert rows[-1] == ("hourly_ground_reflectance", EFFECTS[-1].title,
                        "strength: on/off; crowns: any; needs a street.ground_reflectance table")
    with pytest.raises(RadtreeError, match="unknown effect 'sky'.*sky_diffuse"):
        effect_class("sky")


# --------------------------------------------------------------------------- measurements
def _write(p: Path, text: str) -> Path:
    p.write_text(text)
    return p


def test_measurements_bad_files_name_the_line(tmp_path, mendoza):
    bad = _write(tmp_path / "m.csv", "# Units: lux\ntime,measured_lux\n10:30,1157\n11:30,abc\n")
    with pytest.raises(MeasurementError, match=r"line 4.*'abc'.*not a number"):
        load_measurements(mendoza, bad)
    nounits = _write(tmp_path / "n.csv", "time,measured_lux\n10:30,1157\n")
    with pytest.raises(MeasurementError, match="units not stated"):
        load_measurements(mendoza, nounits)
    shape = _write(tmp_path / "s.csv", "# Units: lux\nwhen,value\n10:30,1\n")
    with pytest.raises(MeasurementError, match="line 2.*fit none of the accepted shapes"):
        load_measurements(mendoza, shape)
    few = _write(tmp_path / "f.csv", "# Units: lux\ntime,measured_lux\n10:30,1157\n18:30,900\n")
    with pytest.raises(RadtreeError, match="only 1 measured hour.*at least 3"):
        load_measurements(mendoza, few)


def test_measurements_hours_without_counterpart_are_listed(tmp_path, mendoza):
    text = "# Units: klux\ntime,measured_lux\n" + "".join(
        f"{h},{v}\n" for h, v in [("09:30", 0.9), ("11:30", 1.504), ("12:30", 1.621),
                                  ("13:30", 1.592), ("14:30", 1.504), ("17:30", 0.8)])
    m = load_measurements(mendoza, _write(tmp_path / "m.csv", text))
    assert m.times == ("11:30", "12:30", "13:30", "14:30")
    assert m.left_out == ["09:30", "17:30"]
    assert m.unmeasured == ["10:30", "15:30", "16:30"]
    assert m.hourly[0] == pytest.approx(1504.0)
    notes = " ".join(m.notes())
    assert "09:30, 17:30" in notes and "10:30, 15:30, 16:30" in notes


def test_measurements_per_row_shape(tmp_path, mendoza):
    rows = {"higher": 3, "intermediate": 2, "lower": 3}
    text = "# Units: lux\ntime,row,lux\n" + "".join(
        f"{h},{r},{1000 + 10 * i + (50 if r == 'lower' else 0)}\n"
        for i, h in enumerate(HOURS) for r in rows)
    m = load_measurements(mendoza, _write(tmp_path / "r.csv", text), sensors_per_row=rows)
    assert m.shape == "row" and m.rows_hourly is not None
    assert m.hourly[0] == pytest.approx((1000 * 3 + 1000 * 2 + 1050 * 3) / 8)


# --------------------------------------------------------------------------- residual rules
def test_disagreement_map_words():
    times = HOURS
    alt = np.array([48.7, 61.2, 73.0, 80.5, 74.5, 62.9, 50.4])
    az = np.array([89.0, 78.9, 60.3, 5.8, 304.1, 283.0, 272.2])
    meas = np.full(7, 1400.0)
    sim = meas - (600 - 6 * alt)  # under-predicts most at low sun
    rows_sim = pd.DataFrame({"higher": meas, "intermediate": meas + 10, "lower": meas - 200},
                            index=pd.Index(times, name="time"))
    rows_meas = pd.DataFrame({"row": ["higher", "intermediate", "lower"],
                              "measured_mean_lux": [1400.0, 1400.0, 1400.0]})
    dm = disagreement_map(times, measured=meas, simulated=sim, simulated_se=np.full(7, 5.0),
                          sun_altitude=alt, sun_azimuth=az, simulated_rows=rows_sim,
                          measured_rows=rows_meas)
    text = " ".join(dm.findings)
    assert "under-predicts at 7 of 7 hours" in text
    assert "grows towards low sun" in text
    assert "lower row departs" in text and "lower row only" in text
    assert list(dm.hourly["period"]) == ["morning"] * 3 + ["noon"] + ["afternoon"] * 3
    # morning only
    sim2 = meas - np.array([300, 300, 300, 0, 0, 0, 0.0])
    dm2 = disagreement_map(times, measured=meas, simulated=sim2, simulated_se=np.full(7, 5.0),
                           sun_altitude=alt, sun_azimuth=az)
    assert "morning only" in " ".join(dm2.findings)
    assert dm2.stats["nmbe"] == pytest.approx(900 / 7 / 1400)


# --------------------------------------------------------------------------- attribution maths
def _sig(effect: str, kind: str, strengths, hourly, ref=None) -> Signature:
    e = get_effect(effect)
    hourly = np.atleast_2d(np.asarray(hourly, float))
    st = None if kind == "binary" else replace(
        e.strength(EffectContext(load_project(MENDOZA)), Scenario("x", "louvers")),
        mode=kind, grid=tuple(strengths), reference=float(ref or strengths[0]))
    return Signature(e, kind, st, np.asarray(strengths, float), hourly,
                     np.zeros((len(hourly), 3)), ["higher", "intermediate", "lower"],
                     [], None if st is None else st.reference)


def test_linear_fit_recovers_strength_and_cv(mendoza):
    ctx = EffectContext(mendoza)
    x = np.array([200.0, 210, 190, 180, 190, 200, 215])
    r = 1.5 * x
    f = fit_candidate(_sig("sky_diffuse", "linear", [12000.0], x), r, ctx,
                      mendoza.scenario("A"), None)
    assert f.strength == pytest.approx(18000.0)
    assert f.explained_fraction == pytest.approx(1.0)
    assert f.cv_rmse_lux == pytest.approx(0.0, abs=1e-9)
    # a negative residual cannot be fitted by a non-negative amplitude
    g = fit_candidate(_sig("sky_diffuse", "linear", [12000.0], x), -r, ctx,
                      mendoza.scenario("A"), None)
    assert g.strength == 0.0 and g.cv_rmse_lux == pytest.approx(np.sqrt(np.mean(r ** 2)))


def test_cross_validation_penalises_flexible_signature(mendoza):
    """A 1-D search over many differently shaped signatures bends through seven noisy points
    in-sample, but loses to a one-amplitude signature once cross-validated."""
    ctx = EffectContext(mendoza)
    rng = np.random.default_rng(1)
    r = 100 + 20 * rng.standard_normal(7)
    grid = list(np.round(np.linspace(0.01, 0.2, 20), 3))
    shapes = 100 + 40 * rng.standard_normal((20, 7))
    simple = fit_candidate(_sig("sky_diffuse", "linear", [12000.0], np.full(7, 100.0)), r, ctx,
                           mendoza.scenario("A"), None)
    flexible = fit_candidate(_sig("crown_gaps", "search", grid, shapes, ref=0.05), r, ctx,
                             mendoza.scenario("B"), None)
    assert flexible.rmse_fit_lux < simple.rmse_fit_lux  # in-sample the flexible one wins …
    assert simple.cv_rmse_lux < flexible.cv_rmse_lux  # … cross-validated it does not
    assert cosine(np.ones(3), 2 * np.ones(3)) == pytest.approx(1.0)


def test_search_fit_interpolates(mendoza):
    ctx = EffectContext(mendoza)
    base = np.array([100.0, 150, 200, 250, 200, 150, 100])
    sig = _sig("crown_gaps", "search", [0.02, 0.05, 0.1], [base * 0.3, base, base * 1.5],
               ref=0.05)
    f = fit_candidate(sig, 0.65 * base, ctx, mendoza.scenario("B"), None)
    # 0.65 lies between 0.3 (g=0.02) and 1.0 (g=0.05): g = 0.02 + 0.5·0.03 = 0.035
    assert f.strength == pytest.approx(0.035, abs=0.001)
    assert f.change == "louvers.cover_fraction = 0.965"


# --------------------------------------------------------------------------- project files
def test_step_project_file_round_trip(tmp_path):
    proj = load_project(copy_project(tmp_path / "p"))
    ctx = EffectContext(proj)
    sc = get_effect("sky_diffuse").switch_on(ctx, proj.scenario("B"), 9000)
    sc = replace(sc, name="B-diag1", description="test")
    out = proj.root / "diagnose" / "radtree.step1.toml"
    before = (proj.root / "radtree.toml").read_text()
    loaded = write_step_project(proj, sc, out)
    assert loaded.switches == sc.switches and loaded.sky == "perez"
    text = out.read_text()
    assert '"../data/direct_normal_illuminance.csv"' in text
    again = load_project(out)
    assert again.light.direct_normal_table == proj.light.direct_normal_table
    assert [s.name for s in again.scenarios][-1] == "B-diag1"
    assert (proj.root / "radtree.toml").read_text() == before     # the project file untouched


# --------------------------------------------------------------------------- simulations
def test_selftest_names_hidden_effects(reduced):
    """Hidden-effect self-test on a reduced Mendoza (128 rays, 7 hours, no dense grid): three
    effects hidden in scenario B, candidates from the whole catalogue."""
    from radtree.diagnose import DiagnoseOptions, selftest

    effects = parse_effects("more_stages,sky_diffuse,unfiltered_ground")
    res = selftest(reduced, noise=0.03,
                   options=DiagnoseOptions(scenario="B", effects=effects, max_steps=2))
    table = res.table()
    assert list(table.columns[:5]) == ["hidden_effect", "distinguishable", "named_effect",
                                       "rmse_before", "rmse_after"]
    assert list(table["hidden_effect"]) == ["more_stages", "sky_diffuse", "unfiltered_ground"]
    assert res.passed, table.to_string()
    t = table.set_index("hidden_effect")
    flags = t["distinguishable"]
    # one layer more darkens every hour: nothing else in the catalogue does in B
    assert flags["more_stages"] and t.loc["more_stages", "separation_snr"] >= 3
    # sky and unfiltered ground light both brighten every hour (signatures correlate > 0.9):
    # the sky at 12 klx lies within 3 σ (over the 7 hours) of another candidate's best fit
    sky = t.loc["sky_diffuse"]
    assert sky["max_correlation"] > 0.9
    assert not sky["distinguishable"] and sky["separation_snr"] < 3
    assert sky["nearest_candidate"] in {"unfiltered_ground", "fewer_stages"}
    # the unfiltered share 0.1: the verdict is its separation's (a larger signal than the
    # sky's, so at a like correlation more of it is left beyond the others' best fits)
    ug = t.loc["unfiltered_ground"]
    assert flags["unfiltered_ground"] == (ug["separation_snr"] >= 3 and ug["snr"] >= 0.33)
    assert ug["combined_snr"] > t.loc["sky_diffuse", "combined_snr"]
    # 7 values cannot separate anything from the span of all the other candidates together
    assert (t["joint_snr"] <= t["separation_snr"] + 1e-9).all()
    assert (t["separation_snr"] <= t["combined_snr"] + 1e-9).all()
    for c in res.cases:
        assert c.gap_shrinks
        assert c.loop is not None and c.loop.steps, c.effect
        assert c.loop.final_map.stats["nrmse"] < c.loop.start_map.stats["nrmse"]
        # named outright or, where not distinguishable, at least within the declared tie
        assert c.named == c.effect or c.effect in c.loop.steps[0].tie_with
    fitted = table.set_index("hidden_effect").loc["more_stages", "strength_fitted"]
    assert fitted == 1
    out = reduced / "diagnose"
    assert (out / "selftest.csv").exists() and (out / "selftest.html").exists()
    assert (out / "selftest" / "more_stages.csv").exists()


def test_diagnose_cli_on_mendoza(reduced):
    r = CliRunner().invoke(diagnose_command, [str(reduced), "--scenario", "A", "--rays", "128",
                                              "--max-steps", "2"])
    assert r.exit_code == 0, (r.output, r.exception)
    out = reduced / "diagnose"
    steps = pd.read_csv(out / "steps.csv")
    assert list(steps.columns[:8]) == ["step", "effect", "explained_fraction", "strength",
                                       "rmse_before", "rmse_after", "cv_rmse_before",
                                       "cv_rmse_after"]
    assert len(steps) >= 1
    assert (steps["rmse_after"] < steps["rmse_before"]).all()
    assert (steps["cv_rmse_after"] < steps["cv_rmse_before"]).all()
    # scenario A misses light at every hour: the first step adds light
    assert steps["effect"].iloc[0] in ("sky_diffuse", "unfiltered_ground")
    html = (out / "index.html").read_text()
    assert "Disagreement map" in html and "under-predicts" in html
    assert (out / "residual_steps.png").stat().st_size > 1000
    step1 = load_project(out / "radtree.step1.toml")
    assert step1.scenarios[-1].name == "A-diag1"
    assert not math.isnan(steps["strength"].iloc[0]) or steps["effect"].iloc[0] == ""


def test_diagnose_cli_errors(reduced, tmp_path):
    bad = _write(tmp_path / "bad.csv", "# Units: lux\ntime,measured_lux\n10:30,-5\n")
    r = CliRunner().invoke(diagnose_command, [str(reduced), "--measured", str(bad)])
    assert isinstance(r.exception, RadtreeError)
    assert "line 3" in str(r.exception) and "negative" in str(r.exception)
    r = CliRunner().invoke(diagnose_command, ["run"])
    assert r.exit_code == 2 and "Missing argument 'PROJECT'" in r.output
    # the modes are subcommands: an option of another mode is refused by click, not by hand
    r = CliRunner().invoke(diagnose_command, ["selftest", str(reduced), "--measured", "x.csv"])
    assert r.exit_code == 2 and "No such option: --measured" in r.output
    r = CliRunner().invoke(diagnose_command, [str(reduced), "--selftest", "--effects", "nope"])
    assert isinstance(r.exception, RadtreeError) and "unknown effect" in str(r.exception)


def test_selftest_cli_exit_code(reduced, monkeypatch):
    """The self-test exits non-zero when a distinguishable effect was misnamed."""
    import radtree.diagnose.hidden as hidden

    class Fake:
        passed = False
        seconds = 1.0
        cases = [type("C", (), {"distinguishable": True, "effect": "more_stages",
                                "named": "sky_diffuse"})()]
        misnamed = cases

        def table(self):
            return pd.DataFrame([{"hidden_effect": "more_stages", "distinguishable": True,
                                  "named_effect": "sky_diffuse", "rmse_before": 0.5,
                                  "rmse_after": 0.1, "gap_shrinks": True}])

    monkeypatch.setattr(hidden, "selftest", lambda *a, **k: Fake())
    r = CliRunner().invoke(diagnose_command, [str(reduced), "--selftest"])
    assert r.exit_code == 1
    assert "more_stages → sky_diffuse" in r.output


def test_simulator_matches_simulate_project(tmp_path):
    """The diagnosis runs give the numbers `radtree simulate` writes (same seed and rays)."""
    from radtree.diagnose.simulate import Simulator
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project

    p = copy_project(tmp_path / "p", {r"^rays = \d+": "rays = 64",
                                      r"^dense_hours = .*$": "dense_grid = false"},
                     hours=["10:30", "13:30"])
    proj = load_project(p)
    sc = replace(proj.scenario("A"), switches={"reflection.unfiltered": 0.05})
    proj = replace(proj, scenarios=(sc,))
    out = simulate_project(proj, options=RunOptions(engine="numpy"))
    assert out is not None
    table = out.table[out.table["grid"] == "facade"]
    sim = Simulator(proj, ("10:30", "13:30"), "numpy", rays=64, seed=proj.engine.seed)
    run = sim.run(sc)
    expected = table.groupby("time")["lux"].mean().reindex(["10:30", "13:30"]).to_numpy()
    np.testing.assert_allclose(run.lux, expected, rtol=1e-9)
    # cached: the same scenario under another name costs no tracing
    sim.run(replace(sc, name="other", description="x"))
    assert sim.traced_runs == 1 and sim.cache_hits == 1
    # the analytic term alone changes: the traced part is reused
    more = sim.run(replace(sc, switches={"reflection.unfiltered": 0.1}))
    assert sim.traced_runs == 1 and np.all(more.lux > run.lux)
    # under calculated reflection the street's reflectance is not traced either: reused, and
    # the same numbers a fresh simulator traces for that scenario
    rho = replace(sc, switches={**sc.switches, "street.ground_reflectance": 0.35})
    reused = sim.run(rho)
    assert sim.traced_runs == 1
    fresh = Simulator(proj, ("10:30", "13:30"), "numpy", rays=64, seed=proj.engine.seed).run(rho)
    np.testing.assert_allclose(reused.lux, fresh.lux, rtol=1e-12)
    assert not np.allclose(reused.lux, run.lux)
