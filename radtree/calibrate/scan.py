"""How a scenario's fit depends on the crown's global permeability — a scan, not a fit.

The measured canopy permeability (5–6 %, reference case §1) bounds how much light a crown model may
pass. This scan varies one crown field (default: the louvers' slat transmittance, continuous and
free of sunflecks), and for each value reports

* ``permeability_street``: Σ_h façade illuminance with the crown / Σ_h in the open street (the
  same canyon), light as the project sets it — what ``radtree calibrate --global`` matches;
* ``permeability_unobstructed``: the same numerator under sun **and** the stated clear sky, over
  an *unobstructed* vertical reference (no canyon: a flat ground to the horizon, sun + sky) —
  the reference case's literal definition "vertical illuminance under the crown / unobstructed vertical global
  illuminance";
* the scenario's normalised RMSE, MBE and r against the measured hourly means.

So one reads off which nRMSE the measured permeability band allows, and which permeability a
target nRMSE would need. No value is chosen here: the scan reports, the user decides. NumPy
engine (Monte Carlo standard errors in the table); Radiance would give the same within ~1 %.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario, check_key
from radtree.engines.registry import seeded_engine
from radtree.errors import ConfigError, RadtreeError
from radtree.figures import new_figure, save_png
from radtree.fileio import atomic_path
from radtree.measurements import hourly_grid_means
from radtree.pipeline.processes import spawned_map, usable_cores, with_threads
from radtree.pipeline.trace import facade_total, trace_scenario
from radtree.stats import nmbe, nrmse, pearson_r

log = logging.getLogger(__name__)

MEASURED_BAND = (0.05, 0.06)   # reference case §1: canopy permeability 5–6 %
TARGET_NRMSE = 0.10            # the reference study's scenario A reached 0.09
UNOBSTRUCTED_WIDTH_M = 2000.0  # a flat ground this wide is "to the horizon" for a 5 m sensor


@dataclass
class PermeabilityScan:
    scenario: str
    field: str
    table: pd.DataFrame            # value, permeability_street(_se), permeability_unobstructed(_se),
    #                                nrmse, nmbe, r, one column per hour (façade mean, lux)
    hours: list[str]

    def band_nrmse(self, column: str = "permeability_unobstructed") -> tuple[float, float] | None:
        """nRMSE range over the scanned values whose permeability lies in the measured band,
        interpolated at the band's edges (None when the scan does not span the band)."""
        p, e = self.table[column].to_numpy(), self.table["nrmse"].to_numpy()
        order = np.argsort(p)
        p, e = p[order], e[order]
        lo, hi = MEASURED_BAND
        if p[0] > lo or p[-1] < hi:
            return None
        inside = [float(np.interp(lo, p, e)), float(np.interp(hi, p, e))]
        inside += [float(x) for x, q in zip(e, p, strict=True) if lo <= q <= hi]
        return min(inside), max(inside)

    def summary(self) -> list[str]:
        lines = []
        for col, label in (("permeability_street", "street reference, project light"),
                           ("permeability_unobstructed", "the reference case's unobstructed global reference")):
            band = self.band_nrmse(col)
            if band is None:
                lines.append(f"{label}: the scan does not span the measured band "
                             f"{100 * MEASURED_BAND[0]:.0f}–{100 * MEASURED_BAND[1]:.0f} %.")
            else:
                lines.append(f"{label}: within the measured permeability band "
                             f"{100 * MEASURED_BAND[0]:.0f}–{100 * MEASURED_BAND[1]:.0f} %, "
                             f"scenario {self.scenario} reaches nRMSE {band[0]:.3f}–{band[1]:.3f}.")
        ok = self.table[self.table["nrmse"] <= TARGET_NRMSE]
        if len(ok):
            lines.append(f"nRMSE ≤ {TARGET_NRMSE:g} needs {self.field} "
                         f"{ok['value'].min():g}–{ok['value'].max():g}, i.e. a permeability of "
                         f"{100 * ok['permeability_street'].min():.1f}–"
                         f"{100 * ok['permeability_street'].max():.1f} % (street reference) / "
                         f"{100 * ok['permeability_unobstructed'].min():.1f}–"
                         f"{100 * ok['permeability_unobstructed'].max():.1f} % (unobstructed).")
        else:
            lines.append(f"No scanned value reaches nRMSE ≤ {TARGET_NRMSE:g} "
                         f"(best {self.table['nrmse'].min():.3f}).")
        return lines


def unobstructed_project(project: Project) -> Project:
    """The reference case's reference for the permeability: a vertical sensor with nothing in front of it —
    no opposite building, a flat ground of the project's reflectance to the horizon — lit by
    the sun and the stated clear sky (``light.sky = "perez"``: *global* illuminance)."""
    st = replace(project.street, width_m=UNOBSTRUCTED_WIDTH_M,
                 length_m=2 * UNOBSTRUCTED_WIDTH_M, opposite_building_height_m=0.01)
    return replace(project, street=st, light=replace(project.light, sky="perez"))


def _sum(project: Project, sc: Scenario, rays: int, seed: int) -> tuple[float, float]:
    """Σ over hours of the façade sensors' mean traced illuminance, and its standard error."""
    return facade_total(project, sc, seeded_engine(), rays, seed)


#: one trace of the scan: "sum" (Σ over hours of the façade mean, its s.e.) or "hourly" (the
#: scenario's façade mean per hour, as simulated: calculated ground terms included)
_Job = tuple[str, Project, Scenario]


def _run_job(job: tuple[str, Project, Scenario, int, int]) -> Any:
    kind, project, sc, rays, seed = job
    if kind == "sum":
        return _sum(project, sc, rays, seed)
    sim = trace_scenario(project, sc, seeded_engine(), rays, seed, grids=["facade"])
    return sim.groupby("time")["lux"].mean()


def _ratio(num: tuple[float, float], den: tuple[float, float]) -> tuple[float, float]:
    p = num[0] / den[0]
    return p, p * math.hypot(num[1] / num[0], den[1] / den[0])


def scan_permeability(project: Project, scenario: str = "A",
                      field: str = "louvers.transmittance",
                      values: Sequence[float] = (0.45, 0.5, 0.55, 0.6, 0.65),
                      rays: int = 2048, seed: int = 1) -> PermeabilityScan:
    """Scan ``field`` (a crown switch such as ``louvers.transmittance``) over ``values`` for
    ``scenario`` of ``project``; see the module docstring for the columns.

    Plan (checks, measured hourly means, the traces) → execute (worker processes) → publish
    (one row per value)."""
    sc0, m = _checked_inputs(project, scenario=scenario, field=field, values=values)
    jobs = _scan_jobs(project, sc0=sc0, scenario=scenario, field=field, values=values)
    workers = min(usable_cores(), len(jobs))
    threads = max(1, usable_cores() // workers)
    log.info("%d traces (%d values × 3 + 2 references, %d rays/sensor) in %d process%s",
             len(jobs), len(values), rays, workers, "es" if workers > 1 else "")
    out = spawned_map(_run_job, [(kind, with_threads(p, threads), sc, rays, seed)
                                 for kind, p, sc in jobs], workers)
    open_street, unob = out[0], out[1]
    log.info("open street: Σ façade %.0f lx; unobstructed reference (sun + %g lx sky): "
             "Σ %.0f lx", open_street[0], project.light.diffuse_horizontal_lux, unob[0])
    hours: list[str] = list(m.index)
    rows = [_scan_row(v, out=out[2 + 3 * k: 5 + 3 * k], open_street=open_street, unob=unob,
                      measured=m, hours=hours, field=field, scenario=scenario)
            for k, v in enumerate(values)]
    return PermeabilityScan(scenario, field, pd.DataFrame(rows), hours)


def _checked_inputs(project: Project, *, scenario: str, field: str,   # type: ignore[no-untyped-def]
                    values: Sequence[float]):
    """The scanned scenario and the measured hourly façade means at the project's hours, or
    the error naming what is missing (values typed and bounded, a crown, measured data)."""
    for v in values:  # a switch of the one registry, each value typed and bounded
        check_key(field, v, source=str(project.source), where=f"switches.{field}")
    sc0 = next((s for s in project.scenarios if s.name == scenario), None)
    if sc0 is None:
        raise ConfigError(f"no scenario {scenario!r} in {project.source} (scenarios: "
                          f"{', '.join(s.name for s in project.scenarios)})")
    if sc0.model in ("none",):
        raise ConfigError(f"scenario {scenario!r} has no crown to scan")
    if project.measured is None:
        raise RadtreeError(f"{project.source}: no measured data ([project] measured) to "
                           "compare the scan with")
    m = hourly_grid_means(project.measured)
    if m is None:
        raise RadtreeError(f"{project.measured}: the scan needs hourly façade means (or per-sensor "
                           "values), not per-row values")
    unmeasured = [h for h in project.site.hours if h not in m.index]
    if unmeasured:
        raise RadtreeError(f"{project.measured}: no measured value at {', '.join(unmeasured)} "
                           "(the scan compares every project hour)")
    outside = [t for t in m.index if t not in project.site.hours]
    if outside:
        log.info("measured hour(s) %s are not among the project's hours: not compared",
                 ", ".join(outside))
    m = m.reindex(list(project.site.hours))
    if not values:
        raise ConfigError("no values to scan", field=field)
    return sc0, m


def _scan_jobs(project: Project, *, sc0: Scenario, scenario: str, field: str,
               values: Sequence[float]) -> list[_Job]:
    """Every trace, each independent: the open street and the unobstructed reference, then per
    value the crown's façade sum (project light, Perez sky) and its hourly fit."""
    sky_project = replace(project, light=replace(project.light, sky="perez"))
    open_sc = Scenario("open", "none", "traced", switches=dict(sc0.switches))
    crowns, fits = [], []
    for v in values:
        sw = {**sc0.switches, field: v}
        crowns.append(Scenario(f"{scenario}:{field}={v}", sc0.model, "traced", form=sc0.form,
                               switches=sw))
        fits.append(replace(sc0, switches=sw))
    # every trace is independent: 2 + 3 per value, in worker processes sharing the cores
    jobs: list[_Job] = [("sum", project, open_sc), ("sum", unobstructed_project(project), open_sc)]
    for crown, fit in zip(crowns, fits, strict=True):
        jobs += [("sum", project, crown), ("sum", sky_project, crown), ("hourly", project, fit)]
    return jobs


def _scan_row(v: float, *, out: Sequence[Any], open_street: Any, unob: Any,
              measured: pd.Series, hours: list[str], field: str,
              scenario: str) -> dict[str, float]:
    """The table row of one scanned value (logged): permeabilities with their standard errors,
    the fit statistics against ``measured`` and the hourly façade means."""
    street, sky, hourly = out
    p_street = _ratio(street, open_street)
    p_unob = _ratio(sky, unob)
    m = measured
    s = hourly.reindex(m.index).to_numpy()
    row = {"value": float(v), "permeability_street": p_street[0],
           "permeability_street_se": p_street[1], "permeability_unobstructed": p_unob[0],
           "permeability_unobstructed_se": p_unob[1], "nrmse": nrmse(m.to_numpy(), s),
           "nmbe": nmbe(m.to_numpy(), s), "r": pearson_r(m.to_numpy(), s)}
    row.update({t: float(x) for t, x in zip(hours, s, strict=True)})
    log.info("  %s = %g: permeability %.2f %% (street) / %.2f %% (unobstructed); %s nRMSE "
             "%.3f, nMBE %+.3f", field, v, 100 * p_street[0], 100 * p_unob[0], scenario,
             row["nrmse"], row["nmbe"])
    return row


def write_scan(scan: PermeabilityScan, folder: Path) -> tuple[Path, Path]:
    """``permeability_scan.csv`` and ``permeability_scan.png`` in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    csv = folder / "permeability_scan.csv"
    table = scan.table.assign(scenario=scan.scenario, field=scan.field)
    with atomic_path(csv) as tmp:
        table.to_csv(tmp, index=False, float_format="%.5g")
    fig = new_figure(6.4, 3.8, 150)
    ax = fig.add_subplot(1, 1, 1)
    t = scan.table.sort_values("value")
    ax.axvspan(100 * MEASURED_BAND[0], 100 * MEASURED_BAND[1], color="0.85",
               label="measured permeability 5–6 %")
    ax.axhline(TARGET_NRMSE, color="k", ls=":", lw=1, label=f"target nRMSE {TARGET_NRMSE:g}")
    ax.plot(100 * t["permeability_unobstructed"], t["nrmse"], "o-", color="tab:green",
            label="vs unobstructed global reference (reference case)")
    ax.plot(100 * t["permeability_street"], t["nrmse"], "s--", color="tab:blue",
            label="vs open street, project light")
    for _, r in t.iterrows():
        ax.annotate(f"{r['value']:g}", (100 * r["permeability_unobstructed"], r["nrmse"]),
                    textcoords="offset points", xytext=(4, 4), fontsize=7, color="tab:green")
    ax.set_xlabel("crown global permeability (%)")
    ax.set_ylabel(f"scenario {scan.scenario} normalised RMSE")
    ax.set_title(f"Scenario {scan.scenario}: fit against the crown's permeability "
                 f"(scanning {scan.field})", fontsize=9)
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=7)
    png = save_png(fig, folder / "permeability_scan.png", 150)
    return csv, png


def read_scan(project: Project) -> PermeabilityScan | None:
    """The scan ``radtree permeability`` wrote in ``results/`` (None when none was run)."""
    csv = project.results_dir / "permeability_scan.csv"
    if not csv.exists():
        return None
    t = pd.read_csv(csv)
    return PermeabilityScan(str(t["scenario"].iloc[0]), str(t["field"].iloc[0]),
                            t.drop(columns=["scenario", "field"]), [])


def scan_section_data(project: Project, out: Path) -> dict[str, Any] | None:
    """The report section on ``results/permeability_scan.csv`` (None when no scan was run), as
    the data ``templates/sections/permeability_scan.html.j2`` and ``.md.j2`` render:
    permeabilities in %, nRMSE / nMBE as fractions. Copies the figure into the report folder
    ``out``."""
    import shutil

    png = project.results_dir / "permeability_scan.png"
    scan = read_scan(project)
    if scan is None:
        return None
    figure = None
    if png.exists():
        shutil.copyfile(png, out / "permeability_scan.png")
        figure = "permeability_scan.png"
    rows = [[f"{r['value']:g}", f"{100 * r['permeability_street']:.2f}",
             f"{100 * r['permeability_unobstructed']:.2f}", f"{r['nrmse']:.3f}",
             f"{r['nmbe']:+.3f}", f"{r['r']:.3f}"] for _, r in scan.table.iterrows()]
    return {"scenario": scan.scenario, "field": scan.field, "summary": scan.summary(),
            "figure": figure, "rows": rows}
