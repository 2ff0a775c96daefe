"""Simulating a measurement campaign: every day, hour and sensor group of a
:class:`~radtree.diagnose.campaign.Campaign` as one vector of observations.

:class:`CampaignSimulator` is a :class:`~radtree.diagnose.simulate.Simulator` whose
:class:`~radtree.diagnose.simulate.Run` holds one value per observation (``Run.times`` are
the observation labels ``DAY HH:MM GROUP[:SENSOR]``) instead of one per hour, so the
attribution, the loop and the self-test work on any campaign unchanged. The scene is built
once per scenario (:func:`radtree.pipeline.assemble.make_scene`) with one extra sensor grid
per campaign geometry (:mod:`radtree.sensor_grid`); each day is traced through
:func:`radtree.pipeline.trace.trace_hours` with the project's site on that date (the scene
does not depend on the day), and the calculated ground terms are added per grid.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario
from radtree.diagnose.campaign import Campaign, Layout, SensorGroup
from radtree.diagnose.identify import noise_sigma
from radtree.diagnose.measured import Measured
from radtree.diagnose.simulate import FACADE, Run, Simulator
from radtree.fileio import write_text
from radtree.light.ground import ground_terms
from radtree.light.hours import hour_states
from radtree.light.tables import direct_normal_table
from radtree.pipeline.assemble import facade_frame
from radtree.pipeline.trace import trace_hours
from radtree.scene import SensorGrid
from radtree.sensor_grid import facade_circle, point_grid
from radtree.stats import mean_stderr


def group_grid(project: Project, group: SensorGroup, name: str) -> SensorGrid:
    """The sensor grid of a campaign group, named ``name`` (façade frame → world)."""
    frame = facade_frame(project)
    if group.grid == "facade":
        sensors = project.sensors if group.height_m is None else replace(
            project.sensors, height_m=float(group.height_m))
        return facade_circle(sensors, frame, name)
    return point_grid(group.points, group.orientation, frame, name, group.name)


def day_projects(project: Project, campaign: Campaign, folder: Path
                 ) -> tuple[dict[str, Project], list[str]]:
    """The project on each campaign day at the campaign's hours, and notes on assumed DNI.

    With a DNI table, an hour the day's table lacks takes the value of the nearest hour it has
    (written to a table in ``folder``)."""
    out: dict[str, Project] = {}
    notes: list[str] = []
    for day in campaign.days:
        light = project.light
        if light.direct_normal_table is not None:
            src = Path(campaign.dni_file(day) or light.direct_normal_table)
            table = direct_normal_table(src)
            have = sorted(table)
            rows = []
            for h in campaign.hours:
                if h in table:
                    rows.append((h, table[h]))
                    continue
                near = min(have, key=lambda t: abs(_minutes(t) - _minutes(h)))
                rows.append((h, table[near]))
                notes.append(f"{day} {h}: no DNI in {src.name}; the value at {near} "
                             f"({table[near]:,.0f} lx) is assumed")
            path = folder / f"dni_{day}.csv"
            write_text(path, "# DNI of the campaign hours (assumed where noted). Units: lux\n"
                       "time,direct_normal_lux\n" + "".join(f"{h},{v:.1f}\n" for h, v in rows))
            light = replace(light, direct_normal_table=path)
        site = replace(project.site, date=day, hours=tuple(campaign.hours))
        out[day] = replace(project, site=site, light=light)
    return out, notes


def _minutes(t: str) -> int:
    h, m = t.split(":")
    return int(h) * 60 + int(m)


@dataclass
class CampaignSimulator(Simulator):
    """A :class:`Simulator` on every observation of ``campaign`` (see the module doc)."""

    campaign: Campaign | None = None
    notes: list[str] = field(default_factory=list)
    _days: dict[str, Project] = field(default_factory=dict, repr=False)
    _grid_names: dict[str, str] = field(default_factory=dict, repr=False)
    _ctraced: dict[str, dict[str, np.ndarray]] = field(default_factory=dict,
                                                                repr=False)
    _tmp: Any = field(default=None, repr=False)
    _origin: Any = field(default=None, repr=False)
    _grids: dict[str, dict[str, SensorGrid]] = field(default_factory=dict, repr=False)
    layout: Layout | None = field(default=None, repr=False)
    #: per-observation factors applied to every run (:meth:`set_weights`); None: plain lux
    weights: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.campaign is None:
            raise ValueError("CampaignSimulator needs a campaign")
        c = self.campaign
        self._origin = self.project
        if self.rays is None and c.rays is not None:
            self.rays = c.rays
        self._tmp = tempfile.TemporaryDirectory(prefix="radtree-campaign-")
        self._days, self.notes = day_projects(self.project, c, Path(self._tmp.name))
        self.project = self._days[c.days[0]]
        self.hours = tuple(c.hours)
        super().__post_init__()
        self._days = {d: replace(p, sensors=self.project.sensors) for d, p in self._days.items()}
        for g in c.groups:
            if g.geometry not in self._grid_names:
                self._grid_names[g.geometry] = (FACADE if g.geometry == "facade" else
                                                f"campaign{len(self._grid_names)}")
        sizes = {geo: len(group_grid(self.project, c.groups[[x.geometry for x in c.groups]
                                                             .index(geo)], name))
                 for geo, name in self._grid_names.items()}
        self.layout = Layout(c, sizes)

    # ------------------------------------------------------------------ public
    def set_weights(self, sc: Scenario, noise: float, noise_lux: float = 0.0) -> np.ndarray:
        """Weight every observation by mean(σ)/σ_i, σ_i its noise in the run of ``sc``
        (:func:`~radtree.diagnose.identify.noise_sigma`): later runs are in *noise-weighted
        lux*, so that a least-squares fit, an RMS and an uncentred correlation over values
        of very different size (a façade reading under the crown, an open-street horizontal
        one ~100 × larger) count each value by its information, not its magnitude."""
        self.weights = None
        raw = self.run(sc)
        sigma = np.maximum(noise_sigma(raw.lux, raw.stderr, noise, noise_lux), 1e-9)
        self.weights = float(np.mean(sigma)) / sigma
        return self.weights

    def run(self, sc: Scenario) -> Run:
        raw = super().run(sc)
        if self.weights is None:
            return raw
        w = self.weights
        lux = raw.lux * w
        return replace(raw, lux=lux, stderr=raw.stderr * w, sensors=lux[None, :],
                       rows=pd.DataFrame({"campaign": lux}, index=raw.rows.index))

    @property
    def labels(self) -> list[str]:
        assert self.layout is not None
        return self.layout.labels

    def sun_positions(self, sc: Scenario) -> tuple[np.ndarray, np.ndarray]:
        """Sun altitude and azimuth (degrees) of every observation."""
        assert self.campaign is not None and self.layout is not None
        pos = {}
        for day, proj in self._days.items():
            for st in hour_states(proj, sc, list(self.hours)):
                pos[(day, st.time)] = (st.sun.altitude_deg, st.sun.azimuth_deg)
        alt = np.array([pos[(o.day, o.time)][0] for o in self.layout.observations])
        az = np.array([pos[(o.day, o.time)][1] for o in self.layout.observations])
        return alt, az

    # ------------------------------------------------------------------ tracing
    def _scene(self, sc: Scenario):
        built = super()._scene(sc)
        assert self.campaign is not None
        for g in self.campaign.groups:
            name = self._grid_names[g.geometry]
            if name not in built.scene.grids:
                built.scene.grids[name] = group_grid(self.project, g, name)
        return built

    def spec(self) -> tuple[type, tuple[Any, ...], dict[str, Any]]:
        return type(self), (self._origin, (), self.engine, self.rays, self.seed), {
            "campaign": self.campaign}

    def traced_cache(self) -> dict[str, Any]:
        return self._ctraced

    def key_project(self) -> Project:
        # the day projects point at DNI tables in this simulator's own temporary folder: hash
        # the project the simulator was made from (its campaign fixes the days and hours)
        return self._origin

    def has_traced(self, sc: Scenario) -> bool:
        return self._traced_key(sc) in self._ctraced

    def trace_payload(self, sc: Scenario) -> Any:
        assert self.campaign is not None
        names = list(dict.fromkeys(self._grid_names.values()))
        traced = {}
        built = self._scene(sc)
        for day, proj in self._days.items():
            out = trace_hours(proj, sc, self._engine, hours=list(self.hours), grids=names,
                              rays=int(self.rays or 1), seed=int(self.seed or 0),
                              built=built)
            for name in names:
                got = [res[name] for res in out.results]
                traced[f"{day}|{name}|lux"] = np.array([x.lux for x in got])
                traced[f"{day}|{name}|se"] = np.array(
                    [x.stderr if x.stderr is not None else np.full(len(x.lux), np.nan)
                     for x in got])
        return traced

    def store_traced(self, sc: Scenario, payload: Any, seconds: float) -> None:
        self._ctraced[self._traced_key(sc)] = payload
        self.traced_runs += 1
        self.trace_seconds += seconds

    def _traced_run(self, sc: Scenario) -> Run:
        assert self.campaign is not None and self.layout is not None
        tkey = self._traced_key(sc)
        names = list(dict.fromkeys(self._grid_names.values()))
        traced = self._ctraced.get(tkey)
        if traced is not None:
            self.cache_hits += 1
        else:
            t0 = time.perf_counter()
            traced = self.trace_payload(sc)
            self.store_traced(sc, traced, time.perf_counter() - t0)
        gkey = repr(sorted((k, v) for k, v in sc.switches.items() if k.startswith("sensors.")))
        grids = self._grids.get(gkey)
        if grids is None:   # the sensor grids do not depend on the crown: one scene's will do
            grids = self._grids[gkey] = dict(self._scene(sc).scene.grids)
        values: dict[tuple[str, str], np.ndarray] = {}
        errors: dict[tuple[str, str], np.ndarray] = {}
        for day, proj in self._days.items():
            states = hour_states(proj, sc, list(self.hours))
            for name in names:
                lux = traced[f"{day}|{name}|lux"].copy()
                for i, st in enumerate(states):
                    lux[i] += ground_terms(proj, sc, st, grids[name])
                values[(day, name)] = lux
                errors[(day, name)] = traced[f"{day}|{name}|se"]
        hour_i = {h: i for i, h in enumerate(self.hours)}
        obs, se = [], []
        for o in self.layout.observations:
            grp = self.campaign.group(o.group)
            key = (o.day, self._grid_names[grp.geometry])
            row, err = values[key][hour_i[o.time]], errors[key][hour_i[o.time]]
            if o.sensor is None:
                obs.append(float(row.mean()))
                se.append(mean_stderr(err))
            else:
                obs.append(float(row[o.sensor]))
                se.append(float(err[o.sensor]))
        labels = self.labels
        lux_v = np.array(obs)
        rows = pd.DataFrame({"campaign": lux_v}, index=pd.Index(labels, name="observation"))
        return Run(tuple(labels), lux_v, np.array(se), rows, lux_v[None, :])


def campaign_synthetic(sim: CampaignSimulator, truth: Scenario, run: Run, noise: float,
                       noise_lux: float, rng: np.random.Generator, path: Path | None,
                       what: str) -> Measured:
    """Synthetic readings of the campaign: the truth's observations × (1 + noise · N(0, 1))
    + noise_lux · N(0, 1) (seeded ``rng``), written to ``path`` when given
    (``day,time,group,sensor,measured_lux``)."""
    assert sim.layout is not None
    n = len(run.lux)
    raw = run.lux / sim.weights if sim.weights is not None else run.lux
    values = raw * (1.0 + noise * rng.standard_normal(n)) + noise_lux * rng.standard_normal(n)
    values = np.maximum(values, 0.0)
    source = f"synthetic ({what})"
    if path is not None:
        write_text(path, f"# Synthetic campaign readings: {what}, noise {noise:.1%}"
                   + (f" + {noise_lux:g} lx" if noise_lux else "") + "\n# Units: lux\n"
                   "day,time,group,sensor,measured_lux\n" + "".join(
                       f"{o.day},{o.time},{o.group},{'' if o.sensor is None else o.sensor},"
                       f"{v:.1f}\n" for o, v in zip(sim.layout.observations, values)))
        source = str(path)
    w = sim.weights if sim.weights is not None else np.ones(n)
    return Measured(tuple(sim.labels), values * w, source,
                    "lux" if sim.weights is None else "noise-weighted lux", "campaign",
                    sun=sim.sun_positions(truth), noise=noise, noise_lux=noise_lux)


def campaign_readings(sim: CampaignSimulator) -> np.ndarray:
    """The campaign's measured value of every observation (lux, unweighted), read from each
    group's ``measured`` files (:func:`radtree.measurements.load_measured`: a mean group takes
    a mean- or sensor-shaped file, a per-sensor group a sensor-shaped one with ids 0…n−1)."""
    from radtree.errors import RadtreeError
    from radtree.measurements import grid_mean, load_measured

    assert sim.campaign is not None and sim.layout is not None
    c = sim.campaign
    have: dict[tuple[str, str, str, int | None], float] = {}
    for g in c.groups:
        for day in c.days:
            path = g.measured_file(day)
            if path is None:
                raise RadtreeError(f"campaign {c.name!r}: group {g.name} has no measured file "
                                   f"for {day} (measured = {{ \"{day}\" = \"file.csv\" }})")
            frame, shape = load_measured(path)
            if g.report == "mean":
                if shape.kind == "row":
                    raise RadtreeError(f"{path}: a per-row file cannot give group {g.name}'s mean")
                gm = grid_mean(frame)
                for t, v in zip(gm["time"], gm["measured_lux"]):
                    have[(day, str(t), g.name, None)] = float(v)
            else:
                if shape.kind != "sensor":
                    raise RadtreeError(f"{path}: group {g.name} reports per sensor: the file "
                                       "needs the time,sensor,lux shape")
                for t, s, v in zip(frame["time"], frame["sensor"], frame["measured_lux"]):
                    have[(day, str(t), g.name, int(s))] = float(v)
    missing = [o.label for o in sim.layout.observations
               if (o.day, o.time, o.group, o.sensor) not in have]
    if missing:
        raise RadtreeError(f"campaign {c.name!r}: {len(missing)} observation(s) have no "
                           f"measured value, e.g. {', '.join(missing[:3])}")
    return np.array([have[(o.day, o.time, o.group, o.sensor)]
                     for o in sim.layout.observations])
