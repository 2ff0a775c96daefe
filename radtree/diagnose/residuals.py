"""The disagreement map: residuals (measured − simulated) by hour, by sensor row and by sun
altitude, with nRMSE/nMBE, and simple stated rules that put structure into words.

Residual = E_measured − E_simulated (lx): positive means the model under-predicts (as nMBE).
The rules (all thresholds are module constants, printed in the report):

* **bias** — at least ``BIAS_SHARE`` of the hours have the same sign and |nMBE| ≥ ``BIAS_NMBE``;
* **sun altitude** — Pearson r between residual and sun altitude with |r| ≥ ``ALT_R`` and a
  residual range ≥ ``SPREAD`` × the mean measured value: "grows towards low sun" (r < 0) or
  "towards high sun" (r > 0);
* **level** — likewise r between residual and the simulated value (a missing *factor* grows
  with the illuminance, an additive term need not);
  (``ALT_R_WEAK`` ≤ |r| < ``ALT_R``: reported as a weak tendency);
* **morning/afternoon** — hours with the sun within ``NOON_AZ`` degrees of azimuth of the
  meridian are "noon" and left out; of the others, the sun in the eastern half of the sky
  (compass azimuth 0–180°) is morning; when both halves have ≥ 2 hours and their mean
  residuals differ by ≥ ``SPREAD`` × the mean measured value the misfit is asymmetric, and
  "morning only" (afternoon only) when the other half's mean is less than half as large;
* **rows** — per-row daily means (``project.measured_rows``) or hourly per-row measurements:
  a spread of row residuals ≥ ``ROW_SPREAD`` × the mean measured value names the row that
  departs most (e.g. "lower row only" when the other rows are within half of it);
* **noise** — a residual RMS below ``NOISE_FACTOR`` × the RMS Monte Carlo standard error of the
  simulated hourly means is within the simulation's own noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from radtree.stats import nmbe, nrmse, pearson_r

BIAS_SHARE = 0.8
BIAS_NMBE = 0.03
ALT_R = 0.7
ALT_R_WEAK = 0.5
NOON_AZ = 20.0
SPREAD = 0.05
ROW_SPREAD = 0.03
NOISE_FACTOR = 2.0

RULES = [
    f"bias: ≥ {BIAS_SHARE:.0%} of the hours share the residual's sign and |nMBE| ≥ "
    f"{BIAS_NMBE:.0%}",
    f"sun altitude: |r(residual, sun altitude)| ≥ {ALT_R} and residual range ≥ {SPREAD:.0%} of "
    f"the mean measured value ({ALT_R_WEAK} ≤ |r| < {ALT_R}: a weak tendency)",
    f"level: |r(residual, simulated value)| ≥ {ALT_R} and the same range condition",
    f"morning/afternoon: sun within {NOON_AZ:g}° of azimuth of the meridian = noon (left out), "
    "else sun in the eastern half of the sky (azimuth 0–180°) = morning; mean "
    f"residuals of the halves differ by ≥ {SPREAD:.0%} of the mean measured value (each half "
    "≥ 2 hours); 'only' when the other half's mean is less than half as large",
    f"rows: spread of the row residuals ≥ {ROW_SPREAD:.0%} of the mean measured value; 'only' "
    "when the other rows are within half of the departing row's residual",
    f"noise: residual RMS < {NOISE_FACTOR:g} × RMS Monte Carlo standard error → within the "
    "simulation noise",
]


@dataclass
class DisagreementMap:
    """Residual tables and the words that describe their structure."""

    hourly: pd.DataFrame
    rows: pd.DataFrame | None
    stats: dict[str, float]
    findings: list[str] = field(default_factory=list)
    rows_hourly: pd.DataFrame | None = None

    @property
    def residual(self) -> np.ndarray:
        return self.hourly["residual_lux"].to_numpy(float)


def disagreement_map(times: tuple[str, ...] | list[str], *, measured: np.ndarray,
                     simulated: np.ndarray, simulated_se: np.ndarray,
                     sun_altitude: np.ndarray, sun_azimuth: np.ndarray,
                     simulated_rows: pd.DataFrame | None = None,
                     measured_rows: pd.DataFrame | None = None,
                     measured_rows_hourly: pd.DataFrame | None = None) -> DisagreementMap:
    """Residual tables and findings.

    ``simulated_rows``: DataFrame indexed by time, one column per row (lx). ``measured_rows``:
    ``row, measured_mean_lux`` daily means; ``measured_rows_hourly``: ``time, row,
    measured_lux`` (when the file has hourly row or sensor values).
    """
    m = np.asarray(measured, float)
    s = np.asarray(simulated, float)
    se = np.asarray(simulated_se, float)
    res = m - s
    alt = np.asarray(sun_altitude, float)
    az = np.asarray(sun_azimuth, float) % 360.0
    morning = (az > 0) & (az < 180)
    off_meridian = np.minimum.reduce([az, np.abs(az - 180.0), 360.0 - az])
    noon = off_meridian < NOON_AZ
    mean_m = float(m.mean())
    hourly = pd.DataFrame({
        "time": list(times), "sun_altitude_deg": alt, "sun_azimuth_deg": az,
        "period": np.where(noon, "noon", np.where(morning, "morning", "afternoon")),
        "measured_lux": m, "simulated_lux": s, "simulated_se_lux": se,
        "residual_lux": res, "residual_pct": 100.0 * res / m,
    })
    se_ok = se[np.isfinite(se)]
    stats = {
        "nrmse": nrmse(m, s), "nmbe": nmbe(m, s), "rmse_lux": float(np.sqrt(np.mean(res ** 2))),
        "mbe_lux": float(res.mean()), "r": pearson_r(m, s),
        "mc_se_rms_lux": float(np.sqrt(np.mean(se_ok ** 2))) if se_ok.size else math.nan,
        "mean_measured_lux": mean_m,
    }
    rows, rows_hourly = _row_tables(simulated_rows, measured_rows, measured_rows_hourly)
    out = DisagreementMap(hourly, rows, stats, rows_hourly=rows_hourly)
    out.findings = findings(out)
    return out


def _row_tables(simulated_rows: pd.DataFrame | None, measured_rows: pd.DataFrame | None,
                measured_rows_hourly: pd.DataFrame | None
                ) -> tuple[pd.DataFrame | None, pd.DataFrame | None]:
    """Per-row daily residuals (from the daily means, else from the hourly row values) and
    the hourly per-row residuals (lx)."""
    rows = None
    rows_hourly = None
    if simulated_rows is not None and measured_rows is not None and len(measured_rows):
        sim_daily = simulated_rows.mean(axis=0)
        recs = []
        for _, r in measured_rows.iterrows():
            name = str(r["row"]).lower()
            if name not in sim_daily.index:
                continue
            mm = float(r["measured_mean_lux"])
            sm = float(sim_daily[name])
            recs.append({"row": name, "measured_mean_lux": mm, "simulated_mean_lux": sm,
                         "residual_lux": mm - sm, "residual_pct": 100.0 * (mm - sm) / mm})
        rows = pd.DataFrame(recs) if recs else None
    if simulated_rows is not None and measured_rows_hourly is not None:
        recs = []
        for _, r in measured_rows_hourly.iterrows():
            name, t = str(r["row"]).lower(), str(r["time"])
            if name in simulated_rows.columns and t in simulated_rows.index:
                sm = float(simulated_rows.loc[t, name])
                recs.append({"time": t, "row": name, "measured_lux": float(r["measured_lux"]),
                             "simulated_lux": sm, "residual_lux": float(r["measured_lux"]) - sm})
        if recs:
            rows_hourly = pd.DataFrame(recs)
            if rows is None:
                g = rows_hourly.groupby("row", sort=False)
                rows = pd.DataFrame({
                    "row": list(g.groups), "measured_mean_lux": g["measured_lux"].mean().values,
                    "simulated_mean_lux": g["simulated_lux"].mean().values})
                rows["residual_lux"] = rows["measured_mean_lux"] - rows["simulated_mean_lux"]
                rows["residual_pct"] = 100 * rows["residual_lux"] / rows["measured_mean_lux"]
    return rows, rows_hourly


def _r(a: np.ndarray, b: np.ndarray) -> float:
    if len(a) < 3 or np.ptp(a) == 0 or np.ptp(b) == 0:
        return math.nan
    return float(np.corrcoef(a, b)[0, 1])


def findings(dm: DisagreementMap) -> list[str]:
    """The residual's structure in words, by the rules of :data:`RULES` (in their order)."""
    res = dm.hourly["residual_lux"].to_numpy(float)
    out = [_bias(dm, res)]
    out += _altitude_and_level(dm, res)
    out += _morning_afternoon(dm, res)
    out += _rows(dm)
    out += _noise(dm)
    return out


def _bias(dm: DisagreementMap, res: np.ndarray) -> str:
    n = len(res)
    word = "under-predicts" if dm.stats["mbe_lux"] > 0 else "over-predicts"
    same = max(int((res > 0).sum()), int((res < 0).sum()))
    if same >= BIAS_SHARE * n and abs(dm.stats["nmbe"]) >= BIAS_NMBE:
        return (f"Bias: the model {word} at {same} of {n} hours "
                f"(nMBE {dm.stats['nmbe']:+.3f}, mean residual {dm.stats['mbe_lux']:+.0f} lx).")
    return f"No consistent bias: residuals of both signs (nMBE {dm.stats['nmbe']:+.3f})."


def _altitude_and_level(dm: DisagreementMap, res: np.ndarray) -> list[str]:
    h = dm.hourly
    out: list[str] = []
    spread = float(np.ptp(res)) if len(res) else 0.0
    big = spread >= SPREAD * dm.stats["mean_measured_lux"]
    r_alt = _r(res, h["sun_altitude_deg"].to_numpy(float))
    if big and math.isfinite(r_alt) and abs(r_alt) >= ALT_R:
        i_lo = int(np.argmin(h["sun_altitude_deg"].to_numpy(float)))
        if r_alt < 0:
            out.append(f"Sun altitude: the residual grows towards low sun (r = {r_alt:+.2f}); "
                       f"largest at {h['time'].iloc[int(np.argmax(res))]}, "
                       f"{res[i_lo]:+.0f} lx at the lowest sun ({h['time'].iloc[i_lo]}, "
                       f"{h['sun_altitude_deg'].iloc[i_lo]:.0f}°).")
        else:
            out.append(f"Sun altitude: the residual grows towards high sun (r = {r_alt:+.2f}).")
    elif big and math.isfinite(r_alt) and abs(r_alt) >= ALT_R_WEAK:
        out.append(f"Sun altitude: a weak tendency (r = {r_alt:+.2f}, below {ALT_R}) for the "
                   f"residual to grow towards {'low' if r_alt < 0 else 'high'} sun.")
    else:
        out.append("Sun altitude: no clear dependence "
                   f"(r = {r_alt:+.2f}, residual range {spread:.0f} lx).")
    r_lvl = _r(res, h["simulated_lux"].to_numpy(float))
    if big and math.isfinite(r_lvl) and abs(r_lvl) >= ALT_R:
        out.append(f"Level: the residual {'grows' if r_lvl > 0 else 'shrinks'} with the "
                   f"simulated illuminance (r = {r_lvl:+.2f}) — "
                   + ("a missing factor (too much or too little filtering) rather than an "
                      "additive term." if r_lvl * dm.stats['mbe_lux'] > 0 else
                      "largest where the model is darkest."))
    return out


def _morning_afternoon(dm: DisagreementMap, res: np.ndarray) -> list[str]:
    h = dm.hourly
    am = (h["period"] == "morning").to_numpy()
    pm = (h["period"] == "afternoon").to_numpy()
    if am.sum() < 2 or pm.sum() < 2:
        return []
    ma = float(res[am].mean())
    mp = float(res[pm].mean())
    if abs(ma - mp) < SPREAD * dm.stats["mean_measured_lux"]:
        return [f"Morning/afternoon: symmetric about solar noon (mean residual morning "
                f"{ma:+.0f} lx, afternoon {mp:+.0f} lx)."]
    if abs(mp) < 0.5 * abs(ma):
        what = "morning only"
    elif abs(ma) < 0.5 * abs(mp):
        what = "afternoon only"
    elif ma * mp < 0:
        what = "of opposite sign in the morning and the afternoon"
    else:
        what = "larger in the " + ("morning" if abs(ma) > abs(mp) else "afternoon")
    return [f"Morning/afternoon: asymmetric, {what} (mean residual morning "
            f"{ma:+.0f} lx, afternoon {mp:+.0f} lx; noon hours left out)."]


def _rows(dm: DisagreementMap) -> list[str]:
    if dm.rows is None or len(dm.rows) < 2:
        return []
    rr = dm.rows.set_index("row")["residual_lux"]
    rspread = float(rr.max() - rr.min())
    if rspread < ROW_SPREAD * dm.stats["mean_measured_lux"]:
        return ["Rows: the row residuals agree within "
                f"{ROW_SPREAD:.0%} of the mean (" + ", ".join(
                    f"{k} {v:+.0f}" for k, v in rr.items()) + " lx) — no row structure."]
    dev = (rr - rr.median()).abs()
    worst = str(dev.idxmax())
    others = rr.drop(worst)
    only = bool((others.abs() < 0.5 * abs(rr[worst])).all())
    return [f"Rows: the {worst} row departs ({rr[worst]:+.0f} lx against "
            + ", ".join(f"{k} {v:+.0f}" for k, v in others.items()) + " lx)"
            + (f" — {worst} row only." if only else ".")]


def _noise(dm: DisagreementMap) -> list[str]:
    mc = dm.stats["mc_se_rms_lux"]
    if not (math.isfinite(mc) and mc > 0):
        return []
    rmse = dm.stats["rmse_lux"]
    if rmse < NOISE_FACTOR * mc:
        return [f"Noise: the residual RMS {rmse:.0f} lx is within "
                f"{NOISE_FACTOR:g}× the Monte Carlo noise ({mc:.1f} lx)."]
    return [f"Noise: the residual RMS {rmse:.0f} lx is {rmse / mc:.0f}× the Monte Carlo "
            f"standard error ({mc:.1f} lx): a model difference, not simulation noise."]
