"""Monte Carlo uncertainty of the annual metrics, from independent replicates of the traces.

The daylight coefficients are Monte Carlo estimates: one sensor's coefficient error is the same
in every hour of the year, so it does not average out over the 8760 hours. A sensor whose DA
sits near 50 % flips in or out of sDA with it, and a grid of 96 sensors moves ≈ 1 pp of sDA
per flip. The size of that noise is measured, not assumed: with ``TraceParams.replicates`` R
each coefficient is traced R times with independent sample sequences
(:class:`radtree.annual.coefficients.TraceParams`); the year is assembled once per replicate,
and the metrics' standard errors are the jackknife's over the replicates (Efron & Tibshirani
1993, *An Introduction to the Bootstrap*, ch. 11 — cited from memory):

    θ̂ = θ(mean of all R),  θ̂₍₋ₖ₎ = θ(mean without replicate k),
    SE = √((R − 1)/R · Σₖ (θ̂₍₋ₖ₎ − mean θ̂₍₋·₎)²)

Illuminance is linear in the coefficients, so the leave-one-out years are
``(R·Ē − E_k)/(R − 1)``. DA and the UDI bands count thousands of sensor-hours and move
smoothly with the coefficients; sDA counts sensors (DA ≥ 50 %) and moves in steps of one
sensor, for which the jackknife fails (it reads 0 when no leave-one-out year flips a
sensor). Its SE is from the sensors instead (:func:`sda_se`): each sensor is in sDA with
probability p = Φ((DA − 50)/SE_DA), SE_DA its DA's jackknife SE, independently of the
others (each sensor has its own samples), so the count of sensors in sDA has variance
Σ p(1 − p). ``benchmarks/annual_precision.py`` checks both against the spread of repeated
runs.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd

import radtree.annual.metrics as m
from radtree.annual.coefficients import CoefficientRunner, TraceParams
from radtree.annual.combine import combine
from radtree.annual.weather_year import YearInputs

#: grid metrics of :func:`grid_metrics` (percent; ``mean_lux`` in lux)
METRICS = ("DA300", "sDA", "UDI<100", "UDI100-3000", "UDI>3000", "mean_lux")
#: columns of ``results/annual/uncertainty.csv`` (:func:`table`)
COLUMNS = ("grid", "tree", "metric", "value", "se")


def grid_metrics(lux: np.ndarray, occupied: np.ndarray) -> dict[str, float]:
    """Metrics of one grid's (sensors, hours) ``lux`` over the ``occupied`` hours: the mean
    DA₃₀₀ and sDA₃₀₀/₅₀ (:mod:`radtree.annual.metrics`), the UDI bands below 100, 100–3000
    (both bounds included) and above 3000 lx as % of sensor-hours, and the mean lux."""
    da = m.daylight_autonomy(lux, occupied)
    bands = m.udi(lux, occupied).mean(axis=0)
    e = np.asarray(lux, float)[:, np.asarray(occupied, bool)]
    return {"DA300": float(da.mean()), "sDA": m.spatial_daylight_autonomy(da),
            "UDI<100": float(bands["udi_below_100"]),
            "UDI100-3000": float(bands["udi_100_300"] + bands["udi_300_3000"]),
            "UDI>3000": float(bands["udi_above_3000"]), "mean_lux": float(e.mean())}


def sda_se(da: np.ndarray, da_se: np.ndarray, fraction: float = m.SDA_FRACTION) -> float:
    """Standard error (percentage points) of sDA over sensors whose DA (%) has standard error
    ``da_se``, the sensors independent: 100/N · √Σ p(1 − p), p = Φ((DA − fraction)/SE_DA)
    (p is 0 or 1 where SE_DA is 0)."""
    from scipy.special import ndtr

    da, da_se = np.asarray(da, float), np.asarray(da_se, float)
    z = np.where(da_se > 0, (da - fraction) / np.where(da_se > 0, da_se, 1.0),
                 np.where(da >= fraction, np.inf, -np.inf))
    p = ndtr(z)
    return float(100.0 / max(len(da), 1) * np.sqrt(np.sum(p * (1 - p))))


def jackknife(replicates: Sequence[np.ndarray], statistic: Callable[[np.ndarray], dict]
              ) -> tuple[dict, dict]:
    """(estimate, standard error) per key of ``statistic`` (floats or arrays) applied to the
    mean of the ``replicates`` (R arrays of the same shape, each an independent estimate of
    one quantity that is linear in the traced coefficients). One replicate: SE NaN."""
    reps = [np.asarray(r, np.float64) for r in replicates]
    n = len(reps)
    if n == 0:
        raise ValueError("no replicates")
    total = np.sum(reps, axis=0)
    estimate = statistic(total / n)
    if n == 1:
        return estimate, {k: np.full(np.shape(v), np.nan) if np.ndim(v) else float("nan")
                          for k, v in estimate.items()}
    leave = [statistic((total - r) / (n - 1)) for r in reps]
    se = {}
    for k, v0 in estimate.items():
        v = np.array([d[k] for d in leave])
        s = np.sqrt((n - 1) / n * np.sum((v - v.mean(axis=0)) ** 2, axis=0))
        se[k] = s if np.ndim(v0) else float(s)
    return estimate, se


def metrics_se(replicates: Sequence[np.ndarray], occupied: np.ndarray
               ) -> tuple[dict[str, float], dict[str, float]]:
    """(metrics, standard errors) of :func:`grid_metrics` for the mean of one grid's
    ``replicates`` ((sensors, hours) lux each): the jackknife's, sDA's by :func:`sda_se`."""
    def stat(e: np.ndarray) -> dict:
        return {**grid_metrics(e, occupied), "da": m.daylight_autonomy(e, occupied)}

    est, se = jackknife(replicates, stat)
    se["sDA"] = sda_se(est.pop("da"), se.pop("da"))
    return est, se


def year_replicates(runner: CoefficientRunner, year: YearInputs, mf: int, sun_mf: int,
                    trace: TraceParams, sun_trace: TraceParams
                    ) -> list[tuple[np.ndarray, np.ndarray]]:
    """(total, direct) lux, each (sensors, hours), of one scene per replicate: the year of
    :func:`radtree.annual.run.scene_year_lux` assembled from each replicate's sky and
    reflected-sun coefficients (the ``-ab 0`` direct sun is exact, the same in all). Their
    mean is ``scene_year_lux``'s year."""
    if trace.replicates != sun_trace.replicates:
        raise ValueError("the sky and the reflected sun need the same number of replicates")
    _, wea, sky, suns, verts, weights, need, patch_dirs = year
    c_sky = runner.sky_replicates(mf, trace)
    c_dir = runner.suns("direct", suns.direction, 0, trace)
    c_n = runner.suns_replicates(f"patch{sun_mf}_ab{trace.ab}", patch_dirs[need], trace.ab,
                                 sun_trace)
    c_0 = runner.suns(f"patch{sun_mf}_ab0", patch_dirs[need], 0, sun_trace)
    out = []
    for k in range(trace.replicates):
        c_ind = np.zeros((runner.n_sensors, len(patch_dirs), 3), np.float32)
        c_ind[:, need] = c_n[k] - c_0
        out.append(combine(c_sky[k], sky, c_dir, suns, c_ind, verts, weights, wea.n_hours))
    return out


def table(replicas: Sequence[dict[str, dict[str, np.ndarray]]], grids: Sequence[str],
          occupied: np.ndarray) -> pd.DataFrame:
    """Grid metrics of the replicates' mean year and their standard errors (:func:`metrics_se`):
    one row per grid, tree ("with" — the seasonal crown —, "without", "leaf_on", "leaf_off")
    and metric of :data:`METRICS` (columns grid, tree, metric, value, se; percent, mean_lux
    in lux). ``replicas``: R dicts tree → grid → (sensors, hours) lux, one per replicate."""
    rows = []
    trees = [t for t in ("with", "without", "leaf_on", "leaf_off") if t in replicas[0]]
    for g in grids:
        for tree in trees:
            est, se = metrics_se([r[tree][g] for r in replicas], occupied)
            rows += [{"grid": g, "tree": tree, "metric": k, "value": est[k], "se": se[k]}
                     for k in METRICS]
    return pd.DataFrame(rows, columns=list(COLUMNS))
