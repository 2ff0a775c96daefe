"""Statistics against hand-computed values, results-table reductions and properties."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from radtree.errors import RadtreeError
from radtree.measurements import load_measured, load_measured_rows
from radtree.stats import (
    STATS_COLUMNS,
    bootstrap_rmse_interval,
    compare,
    hourly_means,
    mbe,
    mean_stderr,
    nmbe,
    nrmse,
    nrmse_stderr,
    pearson_r,
    r2,
    rmse,
    row_hourly_between_models,
    row_hourly_means,
    row_means,
)

DATA = Path(__file__).resolve().parents[1] / "examples" / "mendoza-street" / "data"
HOURS = ["10:30", "11:30", "12:30", "13:30", "14:30", "15:30", "16:30"]
MEASURED = [1157.0, 1504.0, 1621.0, 1592.0, 1504.0, 1311.0, 1099.0]
# 8 façade sensors: rows higher (3), intermediate (2), lower (3); offsets sum to zero so the
# hourly grid mean equals the hourly base value exactly.
SENSOR_ROWS = ["higher"] * 3 + ["intermediate"] * 2 + ["lower"] * 3
OFFSETS = [30.0, 20.0, 10.0, -5.0, 5.0, -10.0, -20.0, -30.0]


def results_table(hourly: dict[str, list[float]], models: dict[str, str] | None = None,
                  hours: list[str] | None = None, stderr: float | None = None,
                  extra_grid: bool = True) -> pd.DataFrame:
    """A tidy results table whose façade hourly means are exactly ``hourly[scenario]``."""
    hours = hours or HOURS
    rows = []
    for scenario, values in hourly.items():
        model = (models or {}).get(scenario, "louvers")
        for t, base in zip(hours, values):
            for sensor, (row, off) in enumerate(zip(SENSOR_ROWS, OFFSETS)):
                rows.append({
                    "scenario": scenario, "model": model, "datetime": f"2024-12-22T{t}:00-03:00",
                    "time": t, "grid": "facade", "sensor": sensor, "row": row, "x": 0.0,
                    "y": 0.0, "z": 5.0, "lux": base + off,
                    "lux_stderr": math.nan if stderr is None else stderr,
                    "engine": "numpy", "params_hash": "abc",
                })
            if extra_grid:
                rows.append({"scenario": scenario, "model": model, "datetime": "", "time": t,
                             "grid": "workplane", "sensor": 0, "row": None, "x": 0.0, "y": 0.0,
                             "z": 0.8, "lux": 1e6, "lux_stderr": math.nan, "engine": "numpy",
                             "params_hash": "abc"})
    return pd.DataFrame(rows)


@pytest.fixture
def measured() -> pd.DataFrame:
    return load_measured(DATA / "measured_vertical_illuminance.csv")[0]


# --------------------------------------------------------------------------- hand-computed


def test_statistics_by_hand():
    m, s = [100.0, 200.0, 300.0], [110.0, 190.0, 330.0]
    # differences E_m − E_s = −10, 10, −30; mean measured = 200
    assert rmse(m, s) == pytest.approx(math.sqrt((100 + 100 + 900) / 3))
    assert nrmse(m, s) == pytest.approx(math.sqrt(1100 / 3) / 200)  # 0.09574
    assert mbe(m, s) == pytest.approx(-30 / 3)
    assert nmbe(m, s) == pytest.approx(-10 / 200)  # over-prediction → negative
    # deviations: measured −100, 0, 100; simulated (mean 210) −100, −20, 120
    sxy, sxx, syy = 100 * 100 + 0 + 100 * 120, 100**2 * 2, 100**2 + 20**2 + 120**2
    assert pearson_r(m, s) == pytest.approx(sxy / math.sqrt(sxx * syy))  # 0.98783
    assert r2(m, s) == pytest.approx(1 - 1100 / 20000)  # 0.945


def test_under_prediction_gives_positive_mbe_and_r2_can_be_negative():
    m, s = [100.0, 200.0, 300.0], [50.0, 100.0, 150.0]
    assert nmbe(m, s) == pytest.approx(100 / 200)
    assert nrmse(m, s) == pytest.approx(math.sqrt((50**2 + 100**2 + 150**2) / 3) / 200)
    assert pearson_r(m, s) == pytest.approx(1.0)
    assert r2(m, s) == pytest.approx(1 - (50**2 + 100**2 + 150**2) / 20000)
    assert r2(m, [300.0, 200.0, 100.0]) == pytest.approx(1 - (200**2 * 2) / 20000)  # −3


def test_undefined_correlation_is_nan():
    assert math.isnan(pearson_r([1.0, 2.0], [5.0, 5.0]))
    assert math.isnan(pearson_r([1.0], [2.0]))
    assert math.isnan(r2([5.0, 5.0], [4.0, 6.0]))


@pytest.mark.parametrize(
    ("m", "s", "pattern"),
    [([1.0, 2.0], [1.0], "2 values but simulated has 1"), ([], [], "no values"),
     ([1.0, math.nan], [1.0, 2.0], "finite"), ([0.0, 0.0], [1.0, 2.0], "need it > 0")],
)
def test_bad_inputs(m, s, pattern):
    with pytest.raises(RadtreeError, match=pattern):
        nrmse(m, s)


# --------------------------------------------------------------------------- bootstrap


def test_bootstrap_contains_estimate_and_is_deterministic():
    s = [1300.0, 1350.0, 1500.0, 1700.0, 1400.0, 1200.0, 1250.0]
    point = nrmse(MEASURED, s)
    low, high = bootstrap_rmse_interval(MEASURED, s, n_boot=2000, level=0.95, seed=0)
    assert low <= point <= high
    assert low > 0
    assert bootstrap_rmse_interval(MEASURED, s, seed=0) == (low, high)
    assert bootstrap_rmse_interval(MEASURED, s, seed=1) != (low, high)
    narrow = bootstrap_rmse_interval(MEASURED, s, level=0.5, seed=0)
    assert low <= narrow[0] <= narrow[1] <= high
    lux_low, lux_high = bootstrap_rmse_interval(MEASURED, s, normalised=False)
    assert lux_low <= rmse(MEASURED, s) <= lux_high


def test_bootstrap_single_hour_and_bad_arguments():
    assert bootstrap_rmse_interval([100.0], [90.0]) == pytest.approx((0.1, 0.1))
    with pytest.raises(RadtreeError, match="level"):
        bootstrap_rmse_interval([1.0, 2.0], [1.0, 2.0], level=1.0)
    with pytest.raises(RadtreeError, match="n_boot"):
        bootstrap_rmse_interval([1.0, 2.0], [1.0, 2.0], n_boot=0)


# --------------------------------------------------------------------------- Monte Carlo error


def test_mean_stderr():
    assert mean_stderr([10.0] * 8) == pytest.approx(10 / math.sqrt(8))
    assert mean_stderr([3.0, 4.0]) == pytest.approx(5.0 / 2)
    assert math.isnan(mean_stderr([1.0, math.nan]))
    with pytest.raises(RadtreeError):
        mean_stderr([-1.0])


def test_nrmse_stderr_delta_by_hand_and_perturbation_agrees():
    m, s, se = [100.0, 200.0, 300.0], [110.0, 190.0, 330.0], [2.0, 4.0, 1.0]
    d = [-10.0, 10.0, -30.0]
    err = math.sqrt(1100 / 3)
    expected = math.sqrt(sum((di * si) ** 2 for di, si in zip(d, se))) / (3 * err * 200)
    assert nrmse_stderr(m, s, se) == pytest.approx(expected)
    pert = nrmse_stderr(m, s, se, method="perturbation", n_draws=20000, seed=3)
    assert pert == pytest.approx(expected, rel=0.05)
    assert nrmse_stderr(m, s, se, method="perturbation", seed=3) == nrmse_stderr(
        m, s, se, method="perturbation", seed=3)
    assert math.isnan(nrmse_stderr(m, s, [1.0, math.nan, 1.0]))
    assert math.isnan(nrmse_stderr(m, m, se))  # delta method undefined at RMSE = 0
    assert nrmse_stderr(m, m, se, method="perturbation") > 0
    with pytest.raises(RadtreeError, match="method"):
        nrmse_stderr(m, s, se, method="bogus")  # type: ignore[arg-type]


# --------------------------------------------------------------------------- results tables


def test_hourly_means_mean_and_stderr():
    res = results_table({"A": MEASURED}, stderr=8.0)
    out = hourly_means(res)
    assert list(out.columns) == ["scenario", "model", "time", "lux", "lux_stderr", "n_sensors"]
    assert list(out["time"]) == HOURS
    assert list(out["lux"]) == pytest.approx(MEASURED)  # work-plane rows are ignored
    assert list(out["lux_stderr"]) == pytest.approx([8.0 / math.sqrt(8)] * 7)
    assert set(out["n_sensors"]) == {8}
    assert hourly_means(results_table({"A": MEASURED}))["lux_stderr"].isna().all()


def test_hourly_means_rejects_incomplete_or_repeated_sensors():
    res = results_table({"A": MEASURED})
    short = res.drop(res[(res["time"] == "12:30") & (res["sensor"] == 4)].index)
    with pytest.raises(RadtreeError, match=r"scenario A.*12:30 \(missing 4\)"):
        hourly_means(short)
    with pytest.raises(RadtreeError, match="repeats scenario A"):
        hourly_means(pd.concat([res, res.iloc[:1]]))
    with pytest.raises(RadtreeError, match="lacks column.*lux"):
        hourly_means(res.drop(columns=["lux"]))
    with pytest.raises(RadtreeError, match="no rows for grid 'facade'"):
        hourly_means(res[res["grid"] != "facade"])


def test_compare_against_mendoza(measured):
    sim_a = [0.9 * v for v in MEASURED]  # 10 % under-prediction every hour
    sim_b = [v + 100.0 for v in MEASURED]
    res = results_table({"B": sim_b, "A": sim_a}, models={"A": "louvers", "B": "perforated"},
                        stderr=8.0)
    stats, hourly, notes = compare(res, measured, reflection={"A": "calculated"})
    assert list(stats.columns[:10]) == ["scenario", "model", "reflection", "rmse", "rmse_low",
                                        "rmse_high", "mbe", "r", "r2", "n_hours"]
    assert list(stats.columns) == STATS_COLUMNS
    a = stats.set_index("scenario").loc["A"]
    assert a["model"] == "louvers" and a["reflection"] == "calculated"
    # errors 0.1·E_m → nRMSE = 0.1·sqrt(mean E_m²)/mean E_m (not 0.1: hours weigh by size)
    rms_m = math.sqrt(sum(v * v for v in MEASURED) / 7)
    assert a["rmse"] == pytest.approx(0.1 * rms_m / (9788 / 7))
    assert a["mbe"] == pytest.approx(0.1)
    assert a["r"] == pytest.approx(1.0)
    ss_tot = float(np.sum((np.array(MEASURED) - np.mean(MEASURED)) ** 2))
    assert a["r2"] == pytest.approx(1 - sum((0.1 * v) ** 2 for v in MEASURED) / ss_tot)
    assert a["n_hours"] == 7
    assert a["rmse_low"] <= a["rmse"] <= a["rmse_high"]
    assert a["mbe_lux"] == pytest.approx(0.1 * np.mean(MEASURED))
    assert a["rmse_mc_se"] > 0
    b = stats.set_index("scenario").loc["B"]
    assert b["reflection"] == ""
    assert b["rmse"] == pytest.approx(100 / (9788 / 7))
    assert b["mbe"] == pytest.approx(-100 / (9788 / 7))
    assert b["rmse_lux"] == pytest.approx(100.0)
    assert list(hourly.columns) == ["time", "measured_lux", "A", "B"]
    assert list(hourly["time"]) == HOURS
    assert list(hourly["A"]) == pytest.approx(sim_a)
    assert notes == []


def test_compare_reflection_from_results_column(measured):
    res = results_table({"A": MEASURED, "B": MEASURED})
    res["reflection"] = res["scenario"].map({"A": "calculated", "B": "simulated"})
    stats = compare(res, measured).stats.set_index("scenario")
    assert stats.loc["A", "reflection"] == "calculated"
    assert stats.loc["B", "reflection"] == "simulated"
    assert stats.loc["A", "rmse"] == 0.0
    assert math.isnan(stats.loc["A", "rmse_mc_se"])  # no stderr from the engine


def test_compare_missing_measured_hour_is_an_error(measured):
    res = results_table({"A": MEASURED, "C": MEASURED[:5]}, hours=None)
    res = res[~((res["scenario"] == "C") & res["time"].isin(["15:30", "16:30"]))]
    with pytest.raises(RadtreeError, match="scenario C: 15:30, 16:30") as info:
        compare(res, measured)
    assert "scenario A" not in str(info.value)


def test_compare_notes_simulated_hours_without_measurement(measured):
    hours = ["09:30", *HOURS]
    res = results_table({"A": [1000.0, *MEASURED]}, hours=hours)
    stats, hourly, notes = compare(res, measured)
    assert stats.loc[0, "rmse"] == 0.0 and stats.loc[0, "n_hours"] == 7
    assert list(hourly["time"]) == HOURS
    assert len(notes) == 1 and "scenario A" in notes[0] and "09:30" in notes[0]


def test_compare_accepts_per_row_and_per_sensor_measurements():
    res = results_table({"A": MEASURED})
    # per-row measured means equal the simulated row means → weighted grid mean matches
    row_mean = {r: np.mean([o for rr, o in zip(SENSOR_ROWS, OFFSETS) if rr == r])
                for r in ("higher", "intermediate", "lower")}
    per_row = pd.DataFrame([{"time": t, "row": r, "measured_lux": v + row_mean[r]}
                            for t, v in zip(HOURS, MEASURED) for r in row_mean])
    assert compare(res, per_row).stats.loc[0, "rmse"] == pytest.approx(0.0, abs=1e-12)
    per_sensor = pd.DataFrame([{"time": t, "sensor": i, "measured_lux": v + o}
                               for t, v in zip(HOURS, MEASURED) for i, o in enumerate(OFFSETS)])
    assert compare(res, per_sensor).stats.loc[0, "rmse"] == pytest.approx(0.0, abs=1e-12)


def test_row_means_against_mendoza_rows():
    rows = load_measured_rows(DATA / "measured_rows.csv")
    res = results_table({"A": MEASURED}, stderr=4.0)
    out = row_means(res, rows).set_index("row")
    day = np.mean(MEASURED)
    assert out.loc["higher", "simulated_mean_lux"] == pytest.approx(day + 20.0)
    assert out.loc["intermediate", "simulated_mean_lux"] == pytest.approx(day)
    assert out.loc["lower", "simulated_mean_lux"] == pytest.approx(day - 20.0)
    assert out.loc["higher", "measured_mean_lux"] == 1407.0
    assert out.loc["higher", "ratio"] == pytest.approx((day + 20.0) / 1407.0)
    assert out.loc["lower", "difference_lux"] == pytest.approx(day - 20.0 - 1409.0)
    assert out.loc["higher", "simulated_sensors"] == 3
    assert out.loc["intermediate", "measured_sensors"] == 2
    assert out.loc["higher", "simulated_stderr"] == pytest.approx(4.0 / math.sqrt(21))
    sub = row_means(res, rows, times=["10:30"]).set_index("row")
    assert sub.loc["intermediate", "simulated_mean_lux"] == pytest.approx(MEASURED[0])
    no_lower = res[res["row"] != "lower"]
    with pytest.raises(RadtreeError, match="scenario A: row lower"):
        row_means(no_lower, rows)


def test_row_hourly_between_models():
    res = results_table({"A": MEASURED, "B": [1.1 * v for v in MEASURED]})
    per_row = row_hourly_means(res)
    assert len(per_row) == 2 * 3 * 7
    out = row_hourly_between_models(res)
    assert set(out["reference"]) == {"A"} and set(out["scenario"]) == {"B"}
    inter = out.set_index("row").loc["intermediate"]
    rms_m = math.sqrt(sum(v * v for v in MEASURED) / 7)
    assert inter["nrmse"] == pytest.approx(0.1 * rms_m / (9788 / 7))
    assert inter["nmbe"] == pytest.approx(-0.1)
    assert inter["r"] == pytest.approx(1.0)
    assert inter["n_hours"] == 7
    back = row_hourly_between_models(res, reference="B")
    assert back.set_index("row").loc["intermediate", "nmbe"] == pytest.approx(1 - 1 / 1.1)
    with pytest.raises(RadtreeError, match="reference scenario Z"):
        row_hourly_between_models(res, reference="Z")


# --------------------------------------------------------------------------- properties

lux = st.floats(min_value=1.0, max_value=1e5, allow_nan=False, allow_infinity=False)


@st.composite
def paired(draw, min_size: int = 1):
    n = draw(st.integers(min_value=min_size, max_value=24))
    m = draw(st.lists(lux, min_size=n, max_size=n))
    s = draw(st.lists(st.floats(min_value=0.0, max_value=1e5), min_size=n, max_size=n))
    return np.array(m), np.array(s)


@given(paired())
def test_nrmse_bounds_nmbe(pair):
    m, s = pair
    assert nrmse(m, s) >= abs(nmbe(m, s)) * (1 - 1e-12) - 1e-15


@given(paired())
def test_nrmse_zero_iff_equal(pair):
    m, s = pair
    assert nrmse(m, m) == 0.0
    if np.array_equal(m, s):
        assert nrmse(m, s) == 0.0
    else:
        assert nrmse(m, s) > 0.0


@settings(max_examples=60)
@given(paired(min_size=3), st.floats(min_value=1e-3, max_value=1e3))
def test_normalised_statistics_are_scale_invariant(pair, k):
    m, s = pair
    assert nrmse(k * m, k * s) == pytest.approx(nrmse(m, s), rel=1e-9, abs=1e-12)
    assert nmbe(k * m, k * s) == pytest.approx(nmbe(m, s), rel=1e-9, abs=1e-12)
    assume(np.std(m) > 1e-6 * np.mean(m) and np.std(s) > 1e-6 * max(np.mean(s), 1.0))
    assert pearson_r(k * m, k * s) == pytest.approx(pearson_r(m, s), rel=1e-6, abs=1e-9)
    assert r2(k * m, k * s) == pytest.approx(r2(m, s), rel=1e-6, abs=1e-9)


@settings(max_examples=30)
@given(paired(min_size=2), st.integers(min_value=0, max_value=2**32 - 1))
def test_bootstrap_is_ordered_and_seeded(pair, seed):
    m, s = pair
    low, high = bootstrap_rmse_interval(m, s, n_boot=200, seed=seed)
    assert 0.0 <= low <= high
    assert bootstrap_rmse_interval(m, s, n_boot=200, seed=seed) == (low, high)
