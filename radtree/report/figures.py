"""The report's figures: matplotlib (Agg, no pyplot state), 150 dpi PNG, labelled with units.

Every function draws one figure from :class:`radtree.report.data.ReportData`, saves it and
returns its caption (what is plotted, in which units).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import LogNorm, Normalize
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, FuncFormatter, LogLocator, NullFormatter

from radtree.figures import new_figure, save_png
from radtree.report.data import (
    MAP_GRID,
    TIMING_PARTS,
    ReportData,
    ScenarioInfo,
    facade_coordinates,
)
from radtree.stats import FACADE_GRID

DPI = 150
MEASURED_STYLE: dict[str, Any] = {"color": "black", "marker": "o", "linewidth": 2.2, "markersize": 6,
                  "zorder": 5}
FORM_LINESTYLES = {"dome": "-", "free": "--"}
LUX_LABEL = "vertical illuminance on the façade (lx)"
MAP_CMAP = "viridis"


def _new_figure(width: float, height: float) -> Figure:
    return new_figure(width, height, DPI)


def _save(fig: Figure, path: Path) -> None:
    save_png(fig, path, DPI)


def scenario_colours(names: list[str]) -> dict[str, tuple[float, ...]]:
    cmap = colormaps["tab10" if len(names) <= 10 else "tab20"]
    return {n: tuple(cmap(i % cmap.N)) for i, n in enumerate(names)}


def decimal_hour(t: str) -> float:
    h, m = str(t).split(":")
    return int(h) + int(m) / 60.0


def _utc_label(offset: float) -> str:
    if offset == 0:
        return "UTC"
    sign = "+" if offset > 0 else "−"
    hours = abs(offset)
    text = f"{hours:g}" if hours != int(hours) else f"{int(hours)}"
    return f"UTC{sign}{text}"


def clock_offset_hours(site: Any) -> float:
    """The site's civil UTC offset (h) at noon on its date: daylight saving included (an IANA
    ``time_zone``), unlike ``utc_offset_hours`` (standard time, the EPW time base)."""
    from datetime import datetime

    noon = datetime.fromisoformat(f"{site.date}T12:00").replace(tzinfo=site.tzinfo)
    delta = noon.utcoffset()
    return site.utc_offset_hours if delta is None else delta.total_seconds() / 3600.0


def _time_axis(ax: Axes, times: list[str], site: Any) -> None:
    ticks = [decimal_hour(t) for t in times]
    ax.xaxis.set_major_locator(FixedLocator(ticks))
    ax.set_xticklabels(times, rotation=45 if len(times) > 8 else 0,
                       ha="right" if len(times) > 8 else "center")
    zone = site.time_zone if "/" in str(site.time_zone) else ""
    label = _utc_label(clock_offset_hours(site))
    ax.set_xlabel(f"local clock time ({zone + ', ' if zone else ''}{label})")


def _plain_log_axis(axis) -> None:
    """Ticks of a logarithmic axis as plain numbers (1000, 2000, 5000) instead of powers of 10."""
    axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}".replace(",", "\u2009")))
    axis.set_minor_formatter(NullFormatter())


def _measured_first(ax: Axes) -> tuple[list, list[str]]:
    """Legend handles and labels with "measured" first."""
    handles, labels = ax.get_legend_handles_labels()
    order = sorted(range(len(labels)), key=lambda i: labels[i] != "measured")
    return [handles[i] for i in order], [labels[i] for i in order]


def _style(info: ScenarioInfo) -> str:
    return FORM_LINESTYLES.get(info.form, ":")


# --------------------------------------------------------------------------- hourly


def hourly_plot(data: ReportData, path: Path) -> str:
    """Measured and simulated façade grid mean per hour, with Monte Carlo error bars."""
    fig = _new_figure(9.0, 4.6)
    ax = fig.add_subplot()
    colours = scenario_colours(data.names)
    times = sorted(set(data.hourly["time"]))
    with_bars: list[str] = []
    without: list[str] = []
    scale: list[float] = []          # the values that set the y axis (no stand-in)
    for info in data.scenarios:
        h = data.hourly_sim[data.hourly_sim["scenario"] == info.name].sort_values("time")
        x = [decimal_hour(t) for t in h["time"]]
        se = h["lux_stderr"].to_numpy(dtype=float)
        have_se = bool(np.isfinite(se).all() and len(se))
        (with_bars if have_se else without).append(info.name)
        y = h["lux"].to_numpy(dtype=float)
        if not info.stand_in:
            scale.extend(y + (np.nan_to_num(se) if have_se else 0.0))
        ax.errorbar(x, y, yerr=se if have_se else None,
                    color=colours[info.name], linestyle=":" if info.stand_in else _style(info),
                    marker="s", markersize=4, linewidth=1.0 if info.stand_in else 1.4,
                    capsize=3, label=info.label + (" (stand-in)" if info.stand_in else ""))
    if data.measured is not None:
        m = data.measured.sort_values("time")
        ax.plot([decimal_hour(t) for t in m["time"]], m["measured_lux"], label="measured",
                **MEASURED_STYLE)
        scale.extend(m["measured_lux"].to_numpy(dtype=float))
    _time_axis(ax, times, data.project.site)
    ax.set_ylabel(LUX_LABEL)
    finite = [v for v in scale if np.isfinite(v)]
    stand_ins = [s.name for s in data.scenarios if s.stand_in]
    if stand_ins and finite:
        ax.set_ylim(0, 1.1 * max(finite))   # a stand-in does not set the scale
    else:
        ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    fig.legend(*_measured_first(ax), fontsize=7.5, loc="outside right upper", frameon=False)
    ax.set_title(f"{data.project.site.name}, {data.project.site.date}", fontsize=10)
    _save(fig, path)
    n = int(data.hourly_sim["n_sensors"].max()) if len(data.hourly_sim) else 0
    caption = (f"Hourly mean vertical illuminance (lx) of the {n} façade sensors, measured "
               "(black) and simulated per scenario (colours; line style by crown form: "
               "solid = sensor dome, dashed = free-standing crown).")
    if with_bars:
        caption += (" Error bars: ±1 Monte Carlo standard error of the simulated hourly mean "
                    f"(scenario(s) {', '.join(with_bars)}).")
    if without:
        caption += (f" No Monte Carlo standard error for scenario(s) {', '.join(without)} "
                    "(the engine gives none).")
    if data.measured is None:
        caption += " No measurements in this project."
    if stand_ins:
        caption += (f" Dotted: stand-in scenario(s) {', '.join(stand_ins)} (a crown from a "
                    "stand-in input, not the studied tree); they do not set the vertical scale "
                    "and may run off it.")
    return caption


# --------------------------------------------------------------------------- scatter


def scatter_plot(data: ReportData, path: Path) -> str:
    """Measured against simulated hourly means, with the 1:1 line and a ±10 % band."""
    if data.measured is None or data.comparison is None:
        raise ValueError("scatter plot needs measurements")
    fig = _new_figure(5.6, 5.6 + 0.18 * math.ceil((len(data.names) + 2) / 2))
    ax = fig.add_subplot()
    colours = scenario_colours(data.names)
    hourly = data.comparison.hourly
    m = hourly["measured_lux"].to_numpy(dtype=float)
    values = [m]
    for info in data.scenarios:
        s = hourly[info.name].to_numpy(dtype=float)
        values.append(s)
        ax.scatter(m, s, color=colours[info.name], s=28, label=info.label, zorder=3,
                   marker="os^vD<>ph*"[data.names.index(info.name) % 10], edgecolors="none")
    allv = np.concatenate(values)
    allv = allv[np.isfinite(allv) & (allv > 0)]
    lo, hi = float(allv.min()), float(allv.max())
    log = hi / lo > 8.0
    if log:
        lo, hi = lo / 1.3, hi * 1.3
        ax.set_xscale("log")
        ax.set_yscale("log")
        _plain_log_axis(ax.xaxis)
        _plain_log_axis(ax.yaxis)
    else:
        lo, hi = 0.0, hi * 1.08
    line = np.geomspace(max(lo, 1e-3), hi, 200) if log else np.linspace(lo, hi, 200)
    ax.fill_between(line, 0.9 * line, 1.1 * line, color="0.85", label="±10 %", zorder=1)
    ax.plot(line, line, color="black", linewidth=1, label="1:1", zorder=2)
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_aspect("equal")
    ax.set_xlabel("measured hourly mean illuminance (lx)")
    ax.set_ylabel("simulated hourly mean illuminance (lx)")
    ax.grid(True, alpha=0.3, which="both")
    fig.legend(*ax.get_legend_handles_labels(), fontsize=7, loc="outside lower center",
               ncols=2, frameon=False)
    _save(fig, path)
    return ("Simulated against measured hourly mean façade illuminance (lx), one point per "
            "scenario and hour; the line is 1:1 and the grey band ±10 % of the measured value"
            + (" (logarithmic axes: the values span more than a factor 8)." if log else "."))


# --------------------------------------------------------------------------- façade maps


MapKey = tuple[str, str]  # (scenario, time)
MapArrays = tuple[np.ndarray, np.ndarray, np.ndarray]  # along-façade u (m), height z (m), lux


@dataclass
class FacadeMapData:
    """Dense-grid and sensor points per (scenario, time), projected on the façade plane."""

    maps: dict[MapKey, MapArrays]
    sensors: dict[MapKey, MapArrays]
    times: list[str]


def map_data(data: ReportData) -> FacadeMapData:
    """Group the dense grid and the sensors once; u from the dense grid's principal axis."""
    r = data.results
    grid = r["grid"].astype(str)
    maps_df = r[grid == MAP_GRID]
    if maps_df.empty:
        raise ValueError("no dense façade grid in the results")
    first = maps_df[(maps_df["scenario"] == maps_df["scenario"].iloc[0])
                    & (maps_df["time"] == maps_df["time"].iloc[0])]
    _, axis = facade_coordinates(first["x"].to_numpy(float), first["y"].to_numpy(float),
                                 data.project.street.facade_azimuth_deg)

    def group(df: pd.DataFrame) -> dict[MapKey, MapArrays]:
        out: dict[MapKey, MapArrays] = {}
        for (scenario, time), g in df.groupby(["scenario", "time"], sort=False):
            out[(str(scenario), str(time))] = (g[["x", "y"]].to_numpy(float) @ axis,
                                               g["z"].to_numpy(float), g["lux"].to_numpy(float))
        return out

    return FacadeMapData(group(maps_df), group(r[grid == FACADE_GRID]),
                         sorted(set(maps_df["time"].astype(str))))


def _norm(values: list[np.ndarray]) -> Normalize:
    finite = [v[np.isfinite(v)] for v in values]
    allv = np.concatenate(finite) if finite else np.array([])
    lo, hi = (float(allv.min()), float(allv.max())) if allv.size else (0.0, 1.0)
    if lo > 0 and hi / lo > 10:
        return LogNorm(vmin=lo, vmax=hi)
    if hi <= lo:
        hi = lo + 1.0
    return Normalize(vmin=lo, vmax=hi)


def _draw_map(ax: Axes, u: np.ndarray, z: np.ndarray, lux: np.ndarray, norm: Normalize):
    """Draw one façade map; a regular grid as cells, anything else as a triangulation."""
    ur, zr = np.round(u, 4), np.round(z, 4)
    us, zs = np.unique(ur), np.unique(zr)
    if len(us) >= 2 and len(zs) >= 2 and len(us) * len(zs) == len(u) and \
            len(set(zip(ur, zr))) == len(u):
        img = np.full((len(zs), len(us)), np.nan)
        img[np.searchsorted(zs, zr), np.searchsorted(us, ur)] = lux

        def edges(c: np.ndarray) -> np.ndarray:
            mid = (c[1:] + c[:-1]) / 2
            return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])

        return ax.pcolormesh(edges(us), edges(zs), img, cmap=MAP_CMAP, norm=norm,
                             shading="flat")
    try:
        return ax.tripcolor(u, z, lux, cmap=MAP_CMAP, norm=norm, shading="gouraud")
    except (ValueError, RuntimeError):
        return ax.scatter(u, z, c=lux, cmap=MAP_CMAP, norm=norm, s=60, marker="s")


def _panel(md: FacadeMapData, ax: Axes, key: MapKey, norm: Normalize, title: str,
           small: bool = False):
    ax.set_title(title, fontsize=7 if small else 9, pad=2 if small else 4)
    if key not in md.maps:
        ax.text(0.5, 0.5, "no dense-grid values", ha="center", va="center",
                transform=ax.transAxes, fontsize=6 if small else 8)
        return None
    u, z, lux = md.maps[key]
    mappable = _draw_map(ax, u, z, lux, norm)
    if key in md.sensors:
        su, sz, _ = md.sensors[key]
        ax.scatter(su, sz, s=5 if small else 16, facecolors="white", edgecolors="black",
                   linewidths=0.5, zorder=4)
    ax.set_aspect("equal")
    return mappable


def _colorbar(fig: Figure, mappable, norm: Normalize, small: bool = False, **kw) -> None:
    cb = fig.colorbar(mappable, **kw)
    cb.set_label("vertical illuminance (lx)", fontsize=8 if small else 10)
    if isinstance(norm, LogNorm):
        _plain_log_axis(cb.ax.yaxis)
    if small:
        cb.ax.tick_params(labelsize=7)


def facade_maps(data: ReportData, path: Path) -> str:
    """One false-colour panel per scenario at ``data.map_time``, shared lux scale."""
    if data.map_time is None:
        raise ValueError("no dense façade grid in the results")
    md = map_data(data)
    time = data.map_time
    names = data.names
    ncols = min(3, len(names))
    nrows = math.ceil(len(names) / ncols)
    fig = _new_figure(3.0 * ncols + 1.2, 3.0 * nrows + 0.4)
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True, sharey=True)
    norm = _norm([md.maps[(n, time)][2] for n in names if (n, time) in md.maps])
    mappable = None
    for i, info in enumerate(data.scenarios):
        ax = axes[i // ncols][i % ncols]
        m = _panel(md, ax, (info.name, time), norm,
                   f"{info.name}: {info.model_label}, {info.reflection}")
        mappable = mappable or m
        if i % ncols == 0:
            ax.set_ylabel("height above street (m)")
        if i + ncols >= len(names):  # nothing below this panel
            ax.set_xlabel("along the façade (m)")
            ax.xaxis.set_tick_params(labelbottom=True)
    for j in range(len(names), nrows * ncols):
        axes[j // ncols][j % ncols].set_visible(False)
    if mappable is not None:
        _colorbar(fig, mappable, norm, ax=axes.ravel().tolist(), shrink=0.8, aspect=30)
    fig.suptitle(f"Façade illuminance at {time}", fontsize=10)
    _save(fig, path)
    scale = "logarithmic" if isinstance(norm, LogNorm) else "linear"
    return ("False-colour vertical illuminance (lx) on the dense façade grid at "
            f"{data.map_time_reason}; one panel per scenario, one common colour scale "
            f"({scale}); white dots mark the façade sensors. Horizontal axis: distance along "
            "the façade (m, to the right seen from the street); vertical: height above the "
            "street (m).")


def facade_maps_all_hours(data: ReportData, path: Path) -> str:
    """Small multiples: scenarios (rows) × hours (columns), shared lux scale.

    Laid out by hand (no constrained layout: with dozens of panels it dominates the run time);
    tick labels only on the left column and the bottom row.
    """
    md = map_data(data)
    times, names = md.times, data.names
    nrows, ncols = len(names), len(times)
    width, height = 1.45 * ncols + 1.5, 1.5 * nrows + 0.7
    fig = Figure(figsize=(width, height), dpi=DPI)
    FigureCanvasAgg(fig)
    gs = fig.add_gridspec(nrows, ncols, left=0.55 / width, right=1 - 1.05 / width,
                          bottom=0.5 / height, top=1 - 0.25 / height, wspace=0.12, hspace=0.3)
    norm = _norm(list(v[2] for v in md.maps.values()))
    mappable = None
    first: Axes | None = None
    for i, name in enumerate(names):
        for j, t in enumerate(times):
            ax = fig.add_subplot(gs[i, j], sharex=first, sharey=first)
            first = first or ax
            m = _panel(md, ax, (name, t), norm, f"{name} {t}", small=True)
            mappable = mappable or m
            ax.tick_params(labelsize=6, length=2, labelleft=j == 0,
                           labelbottom=i == nrows - 1)
            if j == 0:
                ax.set_ylabel("height (m)", fontsize=6)
            if i == nrows - 1:
                ax.set_xlabel("along façade (m)", fontsize=6)
    if mappable is not None:
        cax = fig.add_axes((1 - 0.85 / width, 0.2, 0.12 / width, 0.6))
        _colorbar(fig, mappable, norm, small=True, cax=cax)
    _save(fig, path)
    scale = "logarithmic" if isinstance(norm, LogNorm) else "linear"
    return ("Small multiples of the dense façade grid: vertical illuminance (lx) for every "
            f"scenario (rows) and hour (columns), one common {scale} colour scale; white dots "
            "are the sensors.")


# --------------------------------------------------------------------------- timing


def timing_plot(data: ReportData, path: Path) -> str:
    """Stacked horizontal bars: preparation, geometry, tracing seconds per scenario."""
    if data.timing is None:
        raise ValueError("no timing table")
    t = data.timing.set_index("scenario")
    names = [n for n in data.names if n in t.index]
    fig = _new_figure(6.5, 0.45 * len(names) + 1.4)
    ax = fig.add_subplot()
    left = np.zeros(len(names))
    labels = {"preparation_s": "scene/property preparation", "geometry_s": "geometry preparation",
              "tracing_s": "ray tracing"}
    colours = {"preparation_s": "#9ecae1", "geometry_s": "#4292c6", "tracing_s": "#08306b"}
    for part in TIMING_PARTS:
        v = np.array([float(t.loc[n, part]) if np.isfinite(float(t.loc[n, part])) else 0.0
                      for n in names])
        ax.barh(names, v, left=left, color=colours[part], label=labels[part])
        left += v
    ax.invert_yaxis()
    ax.set_xlabel("wall-clock time (s)")
    ax.set_ylabel("scenario")
    ax.legend(fontsize=7.5, loc="lower right")
    ax.grid(True, axis="x", alpha=0.3)
    _save(fig, path)
    return ("Wall-clock time per scenario (s), split into scene/property preparation, geometry "
            "preparation and ray tracing (tracing summed over hours; with parallel workers the "
            "elapsed time is shorter).")


# --------------------------------------------------------------------------- convergence


def convergence_plot(data: ReportData, path: Path) -> str:
    """Façade mean against -ab per scenario (and hour)."""
    if data.convergence is None:
        raise ValueError("no convergence table")
    c = data.convergence
    fig = _new_figure(6.0, 4.0)
    ax = fig.add_subplot()
    names = list(dict.fromkeys([*data.names, *map(str, c["scenario"].unique())]))
    colours = scenario_colours(names)
    keys = ["scenario"] + (["time"] if "time" in c.columns else [])
    for key, g in c.groupby(keys, sort=True):
        key = key if isinstance(key, tuple) else (key,)
        g = g.sort_values("ab")
        label = " ".join(str(k) for k in key)
        ax.plot(g["ab"], g["facade_mean_lux"], marker="o", color=colours[str(key[0])],
                label=label)
    ax.set_xlabel("ambient bounces -ab")
    ax.set_ylabel("façade sensor mean (lx)")
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7.5)
    _save(fig, path)
    engines = (", ".join(sorted(map(str, c["engine"].dropna().unique())))
               if "engine" in c.columns else "")
    return ("Ambient-bounce convergence: façade sensor mean illuminance (lx) against the "
            "number of ambient bounces (-ab; every engine counts them like rtrace), per scenario "
            "(and hour)" + (f"; traced with {engines}" if engines else "") + ".")
