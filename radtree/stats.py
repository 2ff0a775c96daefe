"""Statistics between simulated and measured façade illuminance (reference case §3).

With E_m the measured and E_s the simulated hourly mean of the façade grid over n hours:

* nRMSE = sqrt(Σ (E_m − E_s)² / n) / (Σ E_m / n)   (with the square root; the study's numbers
  include it even though its printed formula does not);
* nMBE  = (Σ (E_m − E_s) / n) / (Σ E_m / n)          (positive = the model under-predicts);
* Pearson r, and R² = 1 − SS_res / SS_tot with SS_tot taken about the measured mean;
* a percentile bootstrap over hours on (n)RMSE, and the Monte Carlo standard error of the
  simulated values carried through to the hourly grid mean and to nRMSE.

Every table function reads the tidy results table (``results/illuminance.csv``) with columns
``scenario, model, datetime, time, grid, sensor, row, x, y, z, lux, lux_stderr, engine,
params_hash``. Illuminances are lux; normalised statistics are dimensionless fractions.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Literal, NamedTuple

import numpy as np
import numpy.typing as npt
import pandas as pd

from radtree.errors import RadtreeError
from radtree.measurements import grid_mean, normalise_time
from radtree.results_schema import REQUIRED_COLUMNS

FloatArray = npt.NDArray[np.float64]

FACADE_GRID = "facade"
STATS_COLUMNS = ["scenario", "model", "reflection", "rmse", "rmse_low", "rmse_high", "mbe", "r",
                 "r2", "n_hours", "rmse_lux", "mbe_lux", "rmse_mc_se"]


# --------------------------------------------------------------------------- scalar statistics


def _pair(measured: npt.ArrayLike, simulated: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Validate and return two equal-length, finite 1-D float arrays."""
    m = np.asarray(measured, dtype=float).ravel()
    s = np.asarray(simulated, dtype=float).ravel()
    if m.size != s.size:
        raise RadtreeError(f"measured has {m.size} values but simulated has {s.size}")
    if m.size == 0:
        raise RadtreeError("no values to compare")
    if not (np.isfinite(m).all() and np.isfinite(s).all()):
        raise RadtreeError("measured and simulated values must be finite (no NaN/inf)")
    return m, s


def _mean_measured(m: FloatArray) -> float:
    mean = float(m.mean())
    if mean <= 0:
        raise RadtreeError(f"mean measured value is {mean:g}; normalised statistics need it > 0")
    return mean


def rmse(measured: npt.ArrayLike, simulated: npt.ArrayLike) -> float:
    """Root-mean-square error sqrt(Σ(E_m − E_s)²/n), in the inputs' units (lux)."""
    m, s = _pair(measured, simulated)
    return float(np.sqrt(np.mean((m - s) ** 2)))


def mbe(measured: npt.ArrayLike, simulated: npt.ArrayLike) -> float:
    """Mean bias error Σ(E_m − E_s)/n in the inputs' units (lux); positive = under-prediction."""
    m, s = _pair(measured, simulated)
    return float(np.mean(m - s))


def nrmse(measured: npt.ArrayLike, simulated: npt.ArrayLike) -> float:
    """Normalised RMSE: RMSE divided by the mean measured value (dimensionless)."""
    m, s = _pair(measured, simulated)
    return float(np.sqrt(np.mean((m - s) ** 2))) / _mean_measured(m)


def nmbe(measured: npt.ArrayLike, simulated: npt.ArrayLike) -> float:
    """Normalised MBE: MBE divided by the mean measured value; positive = under-prediction."""
    m, s = _pair(measured, simulated)
    return float(np.mean(m - s)) / _mean_measured(m)


def pearson_r(measured: npt.ArrayLike, simulated: npt.ArrayLike) -> float:
    """Pearson correlation coefficient; NaN if fewer than 2 values or either series is constant."""
    m, s = _pair(measured, simulated)
    if m.size < 2:
        return math.nan
    dm, ds = m - m.mean(), s - s.mean()
    denom = math.sqrt(float(np.sum(dm * dm)) * float(np.sum(ds * ds)))
    if denom == 0.0:
        return math.nan
    return float(np.clip(np.sum(dm * ds) / denom, -1.0, 1.0))


def r2(measured: npt.ArrayLike, simulated: npt.ArrayLike) -> float:
    """Coefficient of determination 1 − SS_res/SS_tot (can be < 0); NaN if measured is constant.

    SS_res = Σ(E_m − E_s)², SS_tot = Σ(E_m − mean E_m)². This is not r² unless the simulation
    is an unbiased least-squares fit of the measurement.
    """
    m, s = _pair(measured, simulated)
    ss_tot = float(np.sum((m - m.mean()) ** 2))
    if ss_tot == 0.0:
        return math.nan
    return 1.0 - float(np.sum((m - s) ** 2)) / ss_tot


def bootstrap_rmse_interval(measured: npt.ArrayLike, simulated: npt.ArrayLike, n_boot: int = 2000,
                            level: float = 0.95, seed: int = 0, normalised: bool = True
                            ) -> tuple[float, float]:
    """Percentile bootstrap interval on (n)RMSE, resampling hours with replacement.

    Each resample of n hours recomputes RMSE (and, if ``normalised``, divides by that
    resample's mean measured value). Returns (low, high) at ``level``; deterministic for a seed.
    With 7 hours the interval is wide and only indicative.
    """
    m, s = _pair(measured, simulated)
    if n_boot < 1:
        raise RadtreeError(f"n_boot must be ≥ 1, got {n_boot}")
    if not 0.0 < level < 1.0:
        raise RadtreeError(f"level must be between 0 and 1 (exclusive), got {level}")
    if normalised:
        _mean_measured(m)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, m.size, size=(n_boot, m.size))
    mb, sb = m[idx], s[idx]
    values = np.sqrt(np.mean((mb - sb) ** 2, axis=1))
    if normalised:
        values = values / mb.mean(axis=1)
    alpha = (1.0 - level) / 2.0
    low, high = np.quantile(values, [alpha, 1.0 - alpha])
    return float(low), float(high)


# --------------------------------------------------------------------------- Monte Carlo error


def mean_stderr(stderrs: npt.ArrayLike) -> float:
    """Standard error of the mean of N independent Monte Carlo estimates: sqrt(Σ se_i²)/N (lux).

    Used for the hourly mean of the 8 façade sensors. NaN if any se_i is NaN (engine gave none).
    Sensors traced with independent random streams are independent; if an engine shares rays
    between sensors this underestimates the error.
    """
    se = np.asarray(stderrs, dtype=float).ravel()
    if se.size == 0:
        raise RadtreeError("no standard errors to combine")
    if np.isnan(se).any():
        return math.nan
    if (se < 0).any():
        raise RadtreeError("standard errors must be ≥ 0")
    return float(np.sqrt(np.sum(se**2)) / se.size)


def nrmse_stderr(measured: npt.ArrayLike, simulated: npt.ArrayLike,
                 simulated_stderr: npt.ArrayLike,
                 method: Literal["delta", "perturbation"] = "delta",
                 n_draws: int = 2000, seed: int = 0) -> float:
    """Standard error of nRMSE due to Monte Carlo noise in the simulated hourly values.

    ``"delta"`` (default): first-order propagation, with d_i = E_m,i − E_s,i,
    ∂nRMSE/∂E_s,i = −d_i / (n · RMSE · mean E_m), so
    SE = sqrt(Σ (d_i · se_i)²) / (n · RMSE · mean E_m). It is undefined at RMSE = 0 (returns
    NaN); use ``"perturbation"`` there. ``"perturbation"``: redraw E_s,i + se_i · N(0, 1)
    ``n_draws`` times (seeded) and take the standard deviation of nRMSE. Both ignore the
    upward bias Monte Carlo noise adds to RMSE (E[RMSE²] grows by mean se²).
    NaN if any standard error is NaN.
    """
    m, s = _pair(measured, simulated)
    se = np.asarray(simulated_stderr, dtype=float).ravel()
    if se.size != m.size:
        raise RadtreeError(f"{se.size} standard errors for {m.size} simulated values")
    if np.isnan(se).any():
        return math.nan
    if (se < 0).any() or not np.isfinite(se).all():
        raise RadtreeError("standard errors must be finite and ≥ 0")
    mean_m = _mean_measured(m)
    if method == "delta":
        d = m - s
        err = float(np.sqrt(np.mean(d**2)))
        if err == 0.0:
            return math.nan
        return float(np.sqrt(np.sum((d * se) ** 2))) / (m.size * err * mean_m)
    if method == "perturbation":
        if n_draws < 2:
            raise RadtreeError(f"n_draws must be ≥ 2, got {n_draws}")
        rng = np.random.default_rng(seed)
        draws = s + se * rng.standard_normal((n_draws, m.size))
        values = np.sqrt(np.mean((m - draws) ** 2, axis=1)) / mean_m
        return float(np.std(values, ddof=1))
    raise RadtreeError(f"method must be 'delta' or 'perturbation', got {method!r}")


# --------------------------------------------------------------------------- results tables


def _check_results(results: pd.DataFrame, grid: str) -> pd.DataFrame:
    """Return the rows of ``grid`` with normalised times; raise on missing columns or bad data."""
    missing = [c for c in REQUIRED_COLUMNS if c not in results.columns]
    if missing:
        raise RadtreeError(f"results table lacks column(s) {', '.join(missing)} "
                           f"(has {', '.join(map(str, results.columns))})")
    df = results[results["grid"].astype(str) == grid].copy()
    if df.empty:
        grids = ", ".join(sorted(map(str, results["grid"].unique())))
        raise RadtreeError(f"results table has no rows for grid '{grid}' (grids: {grids or 'none'})")
    try:
        df["time"] = [normalise_time(str(t)) for t in df["time"]]
    except RadtreeError as exc:
        raise RadtreeError(f"results table: {exc}") from None
    df["scenario"] = df["scenario"].astype(str)
    if "lux_stderr" not in df.columns:
        df["lux_stderr"] = np.nan
    bad = df[~np.isfinite(df["lux"].astype(float))]
    if not bad.empty:
        first = bad.iloc[0]
        raise RadtreeError(f"results table: {len(bad)} non-finite lux value(s) on grid '{grid}', "
                           f"first at scenario {first['scenario']} {first['time']} sensor "
                           f"{first['sensor']}")
    dup = df.duplicated(["scenario", "time", "sensor"], keep=False)
    if dup.any():
        first = df[dup].iloc[0]
        raise RadtreeError(
            f"results table repeats scenario {first['scenario']} {first['time']} sensor "
            f"{first['sensor']} on grid '{grid}' (mixed runs? filter by engine/params_hash first)")
    models = df.groupby("scenario")["model"].nunique()
    if (models > 1).any():
        raise RadtreeError("results table gives several models for scenario(s) "
                           + ", ".join(models[models > 1].index))
    return df


def _scenario_model(df: pd.DataFrame) -> dict[str, str]:
    return {str(k): str(v) for k, v in df.groupby("scenario")["model"].first().items()}


def hourly_means(results: pd.DataFrame, grid: str = FACADE_GRID) -> pd.DataFrame:
    """Per scenario × time: mean lux over the grid's sensors and its Monte Carlo standard error.

    Returns columns ``scenario, model, time, lux, lux_stderr, n_sensors`` (lux; stderr from
    :func:`mean_stderr`, NaN where the engine gives none). Every hour of a scenario must have the
    same sensors, otherwise the means would not be comparable and a RadtreeError is raised.
    """
    df = _check_results(results, grid)
    for scenario, group in df.groupby("scenario"):
        sets = group.groupby("time")["sensor"].apply(frozenset)
        if sets.nunique() > 1:
            full = frozenset().union(*sets)
            short = [f"{t} (missing {', '.join(map(str, sorted(full - s, key=str)))})"
                     for t, s in sets.items() if s != full]
            raise RadtreeError(f"scenario {scenario}: hours lack sensors on grid '{grid}': "
                               + "; ".join(short))
    rows = []
    for (scenario, time), group in df.groupby(["scenario", "time"], sort=True):
        rows.append({"scenario": scenario, "model": group["model"].iloc[0], "time": time,
                     "lux": float(group["lux"].astype(float).mean()),
                     "lux_stderr": mean_stderr(group["lux_stderr"].astype(float)),
                     "n_sensors": len(group)})
    return pd.DataFrame(rows, columns=["scenario", "model", "time", "lux", "lux_stderr",
                                       "n_sensors"])


def _reflection_modes(df: pd.DataFrame, scenarios: Sequence[str],
                      reflection: Mapping[str, str] | None) -> dict[str, str]:
    if reflection is not None:
        return {s: str(reflection.get(s, "")) for s in scenarios}
    if "reflection" in df.columns:
        modes = df.groupby("scenario")["reflection"].unique()
        out = {}
        for s in scenarios:
            values = [str(v) for v in modes[s] if not pd.isna(v)]
            if len(values) > 1:
                raise RadtreeError(f"scenario {s} has several reflection modes: {', '.join(values)}")
            out[s] = values[0] if values else ""
        return out
    return dict.fromkeys(scenarios, "")


class Comparison(NamedTuple):
    """Result of :func:`compare`: statistics table, hourly table, and notes on ignored data."""

    stats: pd.DataFrame
    hourly: pd.DataFrame
    notes: list[str]


def compare(results: pd.DataFrame, measured: pd.DataFrame,
            reflection: Mapping[str, str] | None = None, grid: str = FACADE_GRID,
            n_boot: int = 2000, level: float = 0.95, seed: int = 0) -> Comparison:
    """Compare each scenario's hourly grid mean with the measured hourly mean.

    ``measured`` is a tidy frame from :func:`radtree.measurements.load_measured` (any shape; a
    per-row frame is weighted by the results' sensors per row). ``reflection`` maps scenario →
    ground-reflection mode; otherwise a ``reflection`` column of ``results`` is used, else "".

    ``stats`` columns: ``scenario, model, reflection, rmse`` (nRMSE), ``rmse_low, rmse_high``
    (bootstrap interval on nRMSE at ``level``), ``mbe`` (nMBE), ``r, r2, n_hours``, then
    ``rmse_lux, mbe_lux`` (lux) and ``rmse_mc_se`` (delta-method Monte Carlo SE of nRMSE,
    NaN where the engine gives no stderr). ``hourly`` columns: ``time, measured_lux`` and one
    column of simulated mean lux per scenario.

    Every measured hour must be simulated in every scenario, else RadtreeError naming the
    scenario(s) and hour(s). Simulated hours without a measurement are left out and listed in
    ``notes``.
    """
    df = _check_results(results, grid)
    labelled = df.dropna(subset=["row"])
    sensors_per_row = (labelled.groupby(labelled["row"].astype(str).str.lower())["sensor"]
                       .nunique().to_dict())
    meas = grid_mean(measured, sensors_per_row if "row" in measured.columns else None)
    hourly_sim = hourly_means(results, grid)
    times = list(meas["time"])
    scenarios = sorted(hourly_sim["scenario"].unique())

    missing, notes = [], []
    for scenario in scenarios:
        have = set(hourly_sim.loc[hourly_sim["scenario"] == scenario, "time"])
        lacking = [t for t in times if t not in have]
        if lacking:
            missing.append(f"scenario {scenario}: {', '.join(lacking)}")
        extra = sorted(have - set(times))
        if extra:
            notes.append(f"scenario {scenario}: simulated hour(s) {', '.join(extra)} have no "
                         "measurement and were left out of the statistics")
    if missing:
        raise RadtreeError("measured hour(s) without a simulated value on grid "
                           f"'{grid}' — " + "; ".join(missing))

    models = _scenario_model(df)
    modes = _reflection_modes(df, scenarios, reflection)
    hourly = meas[["time", "measured_lux"]].copy()
    m = hourly["measured_lux"].to_numpy(dtype=float)
    stats_rows = []
    for scenario in scenarios:
        sim = (hourly_sim[hourly_sim["scenario"] == scenario].set_index("time")
               .loc[times])
        s = sim["lux"].to_numpy(dtype=float)
        hourly[scenario] = s
        low, high = bootstrap_rmse_interval(m, s, n_boot=n_boot, level=level, seed=seed)
        stats_rows.append({
            "scenario": scenario, "model": models[scenario], "reflection": modes[scenario],
            "rmse": nrmse(m, s), "rmse_low": low, "rmse_high": high, "mbe": nmbe(m, s),
            "r": pearson_r(m, s), "r2": r2(m, s), "n_hours": len(times),
            "rmse_lux": rmse(m, s), "mbe_lux": mbe(m, s),
            "rmse_mc_se": nrmse_stderr(m, s, sim["lux_stderr"].to_numpy(dtype=float)),
        })
    return Comparison(pd.DataFrame(stats_rows, columns=STATS_COLUMNS),
                      hourly.reset_index(drop=True), notes)


def row_hourly_means(results: pd.DataFrame, grid: str = FACADE_GRID) -> pd.DataFrame:
    """Per scenario × row × time: mean lux of the row's sensors and its Monte Carlo SE.

    Returns columns ``scenario, model, row, time, lux, lux_stderr, n_sensors``; sensors without a
    row label are left out.
    """
    df = _check_results(results, grid).dropna(subset=["row"])
    if df.empty:
        raise RadtreeError(f"results table has no row labels on grid '{grid}'")
    df["row"] = df["row"].astype(str).str.lower()
    out = (df.groupby(["scenario", "row", "time"], sort=True)
           .agg(model=("model", "first"), lux=("lux", "mean"),
                lux_stderr=("lux_stderr", lambda v: mean_stderr(v.astype(float))),
                n_sensors=("sensor", "size"))
           .reset_index())
    return out[["scenario", "model", "row", "time", "lux", "lux_stderr", "n_sensors"]]


def row_means(results: pd.DataFrame, measured_rows: pd.DataFrame, grid: str = FACADE_GRID,
              times: Sequence[str] | None = None) -> pd.DataFrame:
    """Per scenario × row: simulated daily mean against the measured daily mean (lux).

    The simulated daily mean is the mean over the chosen hours (``times``, default all simulated
    hours) and the row's sensors. Returns ``scenario, model, row, simulated_mean_lux,
    simulated_stderr, measured_mean_lux, ratio`` (simulated/measured), ``difference_lux``
    (simulated − measured), ``simulated_sensors, measured_sensors``. A measured row missing from
    a scenario raises RadtreeError; a simulated row without measurement gets NaN.
    """
    for col in ("row", "measured_mean_lux"):
        if col not in measured_rows.columns:
            raise RadtreeError(f"measured rows table lacks column '{col}'")
    df = _check_results(results, grid).dropna(subset=["row"])
    df["row"] = df["row"].astype(str).str.lower()
    if times is not None:
        wanted = [normalise_time(t) for t in times]
        absent = sorted(set(wanted) - set(df["time"]))
        if absent:
            raise RadtreeError(f"no simulated values at hour(s) {', '.join(absent)}")
        df = df[df["time"].isin(wanted)]
    meas = measured_rows.assign(row=measured_rows["row"].astype(str).str.lower()).set_index("row")
    out = []
    missing = []
    for scenario, group in df.groupby("scenario", sort=True):
        for row in meas.index:
            if row not in set(group["row"]):
                missing.append(f"scenario {scenario}: row {row}")
        for row, rg in group.groupby("row", sort=True):
            sim = float(rg["lux"].astype(float).mean())
            measured = float(meas.loc[row, "measured_mean_lux"]) if row in meas.index else math.nan
            out.append({
                "scenario": scenario, "model": rg["model"].iloc[0], "row": row,
                "simulated_mean_lux": sim,
                "simulated_stderr": mean_stderr(rg["lux_stderr"].astype(float)),
                "measured_mean_lux": measured,
                "ratio": sim / measured if measured > 0 else math.nan,
                "difference_lux": sim - measured,
                "simulated_sensors": int(rg["sensor"].nunique()),
                "measured_sensors": (int(meas.loc[row, "sensors"])
                                     if row in meas.index and "sensors" in meas.columns else None),
            })
    if missing:
        raise RadtreeError("measured row(s) without simulated sensors on grid "
                           f"'{grid}' — " + "; ".join(missing))
    return pd.DataFrame(out)


def row_hourly_between_models(results: pd.DataFrame, reference: str | None = None,
                              grid: str = FACADE_GRID) -> pd.DataFrame:
    """Per row: hourly statistics of each scenario against a reference scenario.

    Only daily means were measured per row, so per-row hourly comparisons are between models.
    The reference (default: the first scenario in sorted order) takes the role of E_m:
    ``nrmse`` is normalised by the reference's mean and ``nmbe`` > 0 means the scenario is
    below the reference. Returns ``reference, scenario, model, row, nrmse, nmbe, r, r2,
    n_hours``. Scenario and reference must cover the same hours.
    """
    per_row = row_hourly_means(results, grid)
    scenarios = sorted(per_row["scenario"].unique())
    ref = scenarios[0] if reference is None else str(reference)
    if ref not in scenarios:
        raise RadtreeError(f"reference scenario {ref} not in results ({', '.join(scenarios)})")
    ref_df = per_row[per_row["scenario"] == ref].set_index(["row", "time"])["lux"]
    out = []
    for scenario in scenarios:
        if scenario == ref:
            continue
        sc = per_row[per_row["scenario"] == scenario]
        for row, rg in sc.groupby("row", sort=True):
            sim = rg.set_index("time")["lux"]
            if row not in ref_df.index.get_level_values("row"):
                raise RadtreeError(f"reference scenario {ref} has no sensors in row {row}")
            base = ref_df.loc[row]
            if set(base.index) != set(sim.index):
                diff = sorted(set(base.index) ^ set(sim.index))
                raise RadtreeError(f"scenarios {scenario} and {ref} differ in hours for row {row}: "
                                   + ", ".join(diff))
            m = base.sort_index().to_numpy(dtype=float)
            s = sim.sort_index().to_numpy(dtype=float)
            out.append({"reference": ref, "scenario": scenario, "model": rg["model"].iloc[0],
                        "row": row, "nrmse": nrmse(m, s), "nmbe": nmbe(m, s),
                        "r": pearson_r(m, s), "r2": r2(m, s), "n_hours": len(m)})
    return pd.DataFrame(out, columns=["reference", "scenario", "model", "row", "nrmse", "nmbe",
                                      "r", "r2", "n_hours"])
