"""Measurement campaigns as data: what is (or could be) measured, read from a TOML file.

A campaign lists **sensor groups** (the project's façade circle, at its height or another, or
points in the street), the **hours** and **days** of the measurement, whether each group
reports one **mean** per hour or a reading per **sensor**, and the instrument **noise**.
Every (day, hour, group[, sensor]) is one *observation*; the diagnosis and the
identifiability work on the vector of observations. Example (the Mendoza study)::

    [campaign]
    name = "Mendoza, 22 December (the study)"
    days = ["2024-12-22"]          # default: the project's site.date
    hours = ["10:30", "11:30"]     # default: the project's site.hours
    noise = 0.03                   # relative noise (1 σ) of each reported value
    noise_lux = 0.0                # absolute noise floor (1 σ), lux

    [[group]]
    name = "facade"
    grid = "facade"                # the project's [sensors] circle (height_m = … moves it)
    report = "mean"                # one grid mean per hour; "sensor": every sensor's reading
    measured = { "2024-12-22" = "data/measured_vertical_illuminance.csv" }

    [[group]]
    name = "street_open"
    orientation = "horizontal"     # "facade" (vertical, looking out of the façade),
                                   # "horizontal" (looking up), "facing_crown" (vertical,
                                   # looking back at the façade and the crown),
                                   # "ground" (looking down at the street)
    points = [[0.0, 12.0, 1.0]]    # (u along the façade, d out from the façade, z up), m
    report = "sensor"

Coordinates are the studied façade's frame: u along the façade (x east for a north-looking
façade), d the distance out of the façade along its normal, z up; metres. ``measured`` maps a
day to a measured file of :func:`radtree.measurements.load_measured` (mean or sensor shape).
A day may name its own DNI table in ``[campaign] direct_normal = { "DAY" = "file.csv" }``;
otherwise the project's table serves every day, and an hour it lacks takes the DNI of the
nearest hour it has (stated in the notes).
"""

from __future__ import annotations

import datetime as dt
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import tomllib

from radtree.config import Project
from radtree.errors import ConfigError
from radtree.measurements import normalise_time

ORIENTATIONS = ("facade", "horizontal", "facing_crown", "ground")
REPORTS = ("mean", "sensor")
DEFAULT_CAMPAIGN_NOISE = 0.03


@dataclass(frozen=True)
class SensorGroup:
    """One group of sensors (see the module doc). ``grid = "facade"``: the project's circle
    (``height_m`` moves its centre); else ``points`` (u, d, z) m with ``orientation``."""

    name: str
    report: str = "mean"
    grid: str | None = None
    height_m: float | None = None
    orientation: str = "facade"
    points: tuple[tuple[float, float, float], ...] = ()
    measured: tuple[tuple[str, str], ...] = ()
    description: str = ""

    def __post_init__(self) -> None:
        where = f"group {self.name!r}"
        if not self.name or any(c in self.name for c in " :;,"):
            raise ConfigError(f"{where}: a name without spaces, ':', ';' or ','")
        if self.report not in REPORTS:
            raise ConfigError(f"{where}: report must be one of {', '.join(REPORTS)}, got "
                              f"{self.report!r}")
        if self.orientation not in ORIENTATIONS:
            raise ConfigError(f"{where}: orientation must be one of {', '.join(ORIENTATIONS)}, "
                              f"got {self.orientation!r}")
        if self.grid is not None and self.grid != "facade":
            raise ConfigError(f"{where}: grid must be 'facade' (the project's circle), got "
                              f"{self.grid!r}")
        if (self.grid is None) == (not self.points):
            raise ConfigError(f"{where}: give either grid = 'facade' or points = [[u, d, z]]")
        for p in self.points:
            if len(p) != 3 or p[2] <= 0 or p[1] < 0:
                raise ConfigError(f"{where}: point {list(p)} must be [u, d ≥ 0, z > 0] (m)")
        if self.height_m is not None and self.height_m <= 0:
            raise ConfigError(f"{where}: height_m must be > 0, got {self.height_m}")

    @property
    def geometry(self) -> str:
        """Name of the traced sensor grid (groups with the same geometry share it)."""
        if self.grid == "facade":
            return "facade" if self.height_m is None else f"facade_h{self.height_m:g}"
        pts = "_".join(f"{u:g},{d:g},{z:g}" for u, d, z in self.points)
        return f"{self.orientation}@{pts}"

    def measured_file(self, day: str) -> str | None:
        return dict(self.measured).get(day)


@dataclass(frozen=True)
class Campaign:
    """What is (or could be) measured: days × hours × sensor groups, and the noise.

    ``noise``: relative 1-σ noise of every reported value; ``noise_lux``: absolute floor (lux);
    ``rays``: rays per sensor for a seeded engine tracing the campaign (None: the default);
    ``synthetic``: the readings were generated, not measured (said in every output).
    """

    name: str
    days: tuple[str, ...]
    hours: tuple[str, ...]
    groups: tuple[SensorGroup, ...]
    noise: float = DEFAULT_CAMPAIGN_NOISE
    noise_lux: float = 0.0
    rays: int | None = None
    synthetic: bool = False
    description: str = ""
    direct_normal: tuple[tuple[str, str], ...] = ()
    source: Path | None = None

    def __post_init__(self) -> None:
        src = str(self.source) if self.source else None
        if not self.days or not self.hours or not self.groups:
            raise ConfigError("a campaign needs at least one day, one hour and one group",
                              source=src)
        for d in self.days:
            try:
                dt.date.fromisoformat(d)
            except ValueError:
                raise ConfigError(f"day {d!r} is not a date YYYY-MM-DD", source=src,
                                  field="campaign.days") from None
        names = [g.name for g in self.groups]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ConfigError(f"repeated group name(s) {', '.join(dupes)}", source=src)
        if len(set(self.days)) != len(self.days) or len(set(self.hours)) != len(self.hours):
            raise ConfigError("repeated day or hour", source=src)
        if not 0 <= self.noise < 1 or self.noise_lux < 0:
            raise ConfigError(f"noise must be in [0, 1) and noise_lux ≥ 0 (got {self.noise}, "
                              f"{self.noise_lux})", source=src, field="campaign.noise")
        if self.noise == 0 and self.noise_lux == 0:
            raise ConfigError("a campaign needs some noise (noise or noise_lux > 0)", source=src)

    def group(self, name: str) -> SensorGroup:
        for g in self.groups:
            if g.name == name:
                return g
        raise ConfigError(f"campaign {self.name!r} has no group {name!r}")

    def dni_file(self, day: str) -> str | None:
        return dict(self.direct_normal).get(day)

    def summary(self) -> str:
        parts = [f"{g.name} ({g.report})" for g in self.groups]
        return (f"{self.name}: {len(self.days)} day(s) × {len(self.hours)} hour(s); groups "
                f"{', '.join(parts)}; noise {self.noise:.1%}"
                + (f" + {self.noise_lux:g} lx" if self.noise_lux else "")
                + ("; SYNTHETIC readings" if self.synthetic else ""))


def project_campaign(project: Project, noise: float = DEFAULT_CAMPAIGN_NOISE) -> Campaign:
    """The project's own measurement as a campaign: the façade circle's hourly mean on
    ``site.date`` at ``site.hours`` (the measured file when the project names one)."""
    measured = ((project.site.date, str(project.measured)),) if project.measured else ()
    return Campaign(f"{project.name}: façade grid mean", (project.site.date,),
                    tuple(project.site.hours),
                    (SensorGroup("facade", "mean", grid="facade", measured=measured),),
                    noise=noise, source=None)


def _get(table: dict[str, Any], key: str, kind: type | tuple[type, ...], src: str, where: str,
         default: Any = None) -> Any:
    if key not in table:
        return default
    v = table[key]
    if not isinstance(v, kind) or isinstance(v, bool) and kind is not bool:
        raise ConfigError(f"{key} = {v!r} has the wrong type", source=src, field=f"{where}.{key}")
    return v


def load_campaign(path: str | os.PathLike, project: Project | None = None) -> Campaign:
    """Read a campaign TOML file (relative data paths are relative to the file)."""
    p = Path(path)
    src = str(p)
    head, group_tables = _campaign_tables(p)
    days, hours = _days_hours(head, src=src, project=project)
    base = p.parent
    groups = [_sensor_group(g, where=f"group[{i}]", src=src, base=base)
              for i, g in enumerate(group_tables)]
    dn = _get(head, "direct_normal", dict, src, "campaign", {})
    rays = _get(head, "rays", int, src, "campaign")
    return Campaign(
        name=str(_get(head, "name", str, src, "campaign", p.stem)),
        days=tuple(str(d) for d in days), hours=tuple(hours), groups=tuple(groups),
        noise=float(_get(head, "noise", (int, float), src, "campaign", DEFAULT_CAMPAIGN_NOISE)),
        noise_lux=float(_get(head, "noise_lux", (int, float), src, "campaign", 0.0)),
        rays=rays, synthetic=bool(_get(head, "synthetic", bool, src, "campaign", False)),
        description=str(_get(head, "description", str, src, "campaign", "")),
        direct_normal=tuple((str(k), _relative(str(v), base=base)) for k, v in dn.items()),
        source=p)


def _campaign_tables(p: Path) -> tuple[dict[str, Any], Any]:
    """The file's ``[campaign]`` table (its keys checked) and its ``[[group]]`` entries."""
    src = str(p)
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError("campaign file not found", source=src) from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"not valid TOML ({exc})", source=src) from None
    head = data.get("campaign")
    if not isinstance(head, dict):
        raise ConfigError("no [campaign] table", source=src)
    known = {"name", "days", "hours", "noise", "noise_lux", "rays", "synthetic", "description",
             "direct_normal"}
    extra = sorted(set(head) - known)
    if extra:
        raise ConfigError(f"unknown key(s) {', '.join(extra)} (known: {', '.join(sorted(known))})",
                          source=src, field="campaign")
    return head, data.get("group", []) or []


def _days_hours(head: dict[str, Any], *, src: str,
                project: Project | None) -> tuple[list[Any], list[str]]:
    """The campaign's days and hours (HH:MM), defaulting to the project's date and hours."""
    days = _get(head, "days", list, src, "campaign",
                [project.site.date] if project is not None else None)
    hours = _get(head, "hours", list, src, "campaign",
                 list(project.site.hours) if project is not None else None)
    if days is None or hours is None:
        raise ConfigError("days and hours are required (no project to default them from)",
                          source=src, field="campaign")
    try:
        hours = [normalise_time(str(h)) for h in hours]
    except Exception as exc:
        raise ConfigError(str(exc), source=src, field="campaign.hours") from None
    return days, hours


def _relative(v: str, *, base: Path) -> str:
    """``v`` resolved, relative to ``base`` (the campaign file's folder) unless absolute."""
    q = Path(v)
    return str((q if q.is_absolute() else (base / q)).resolve())


def _sensor_group(g: Any, *, where: str, src: str, base: Path) -> SensorGroup:
    """One ``[[group]]`` table (``where``: ``group[i]``) as a checked SensorGroup."""
    if not isinstance(g, dict):
        raise ConfigError("each [[group]] must be a table", source=src, field=where)
    gknown = {"name", "report", "grid", "height_m", "orientation", "points", "measured",
              "description"}
    gextra = sorted(set(g) - gknown)
    if gextra:
        raise ConfigError(f"unknown key(s) {', '.join(gextra)} (known: "
                          f"{', '.join(sorted(gknown))})", source=src, field=where)
    meas = _get(g, "measured", dict, src, where, {})
    pts = _get(g, "points", list, src, where, [])
    bad = [pt for pt in pts if not isinstance(pt, list) or len(pt) != 3]
    if bad:
        raise ConfigError(f"points must be [u, d, z] lists of three numbers (m), got "
                          f"{bad[0]!r}", source=src, field=f"{where}.points")
    try:
        return SensorGroup(
            name=str(_get(g, "name", str, src, where, "")), report=_get(g, "report", str, src,
                                                                       where, "mean"),
            grid=_get(g, "grid", str, src, where),
            height_m=_get(g, "height_m", (int, float), src, where),
            orientation=_get(g, "orientation", str, src, where, "facade"),
            points=tuple((float(pt[0]), float(pt[1]), float(pt[2])) for pt in pts),
            measured=tuple((str(k), _relative(str(v), base=base)) for k, v in meas.items()),
            description=str(_get(g, "description", str, src, where, "")))
    except ConfigError as exc:
        raise ConfigError(str(exc), source=src, field=where) from None
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"points must be lists of three numbers ({exc})", source=src,
                          field=where) from None


def campaign_table(c: Campaign, relative_to: Path | None = None) -> dict[str, Any]:
    """The campaign as TOML data (:func:`radtree.tomlout.dumps`); paths relative to
    ``relative_to`` when given."""

    def path(v: str) -> str:
        return os.path.relpath(v, relative_to) if relative_to is not None else v

    head: dict[str, Any] = {"name": c.name, "days": list(c.days), "hours": list(c.hours),
                            "noise": c.noise}
    if c.noise_lux:
        head["noise_lux"] = c.noise_lux
    if c.rays is not None:
        head["rays"] = c.rays
    if c.synthetic:
        head["synthetic"] = True
    if c.description:
        head["description"] = c.description
    if c.direct_normal:
        head["direct_normal"] = {k: path(v) for k, v in c.direct_normal}
    groups = []
    for g in c.groups:
        t: dict[str, Any] = {"name": g.name, "report": g.report}
        if g.grid is not None:
            t["grid"] = g.grid
            if g.height_m is not None:
                t["height_m"] = g.height_m
        else:
            t["orientation"] = g.orientation
            t["points"] = [list(pt) for pt in g.points]
        if g.measured:
            t["measured"] = {k: path(v) for k, v in g.measured}
        if g.description:
            t["description"] = g.description
        groups.append(t)
    return {"campaign": head, "group": groups}


def merge(base: Campaign, *more: Campaign, name: str | None = None) -> Campaign:
    """The union of campaigns: every day, hour and group (a group named twice keeps the
    first definition, unless a later one reports per sensor)."""
    days = list(base.days)
    hours = list(base.hours)
    groups = {g.name: g for g in base.groups}
    dn = dict(base.direct_normal)
    for c in more:
        days += [d for d in c.days if d not in days]
        hours += [h for h in c.hours if h not in hours]
        for g in c.groups:
            if g.name not in groups or g.report == "sensor":
                groups[g.name] = g
        dn.update(dict(c.direct_normal))
    return replace(base, name=name or base.name, days=tuple(days), hours=tuple(sorted(hours)),
                   groups=tuple(groups.values()), direct_normal=tuple(dn.items()))


@dataclass(frozen=True)
class Observation:
    """One measured value: a group's mean or one sensor's reading at a day and hour."""

    day: str
    time: str
    group: str
    sensor: int | None = None

    @property
    def label(self) -> str:
        return f"{self.day} {self.time} {self.group}" + (
            "" if self.sensor is None else f":{self.sensor}")


@dataclass
class Layout:
    """The observations of a campaign in order (days, hours, groups, sensors) and how many
    sensors each group's geometry has."""

    campaign: Campaign
    sizes: dict[str, int]
    observations: list[Observation] = field(default_factory=list)

    def __post_init__(self) -> None:
        c = self.campaign
        self.observations = [
            Observation(d, h, g.name, s)
            for d in c.days for h in c.hours for g in c.groups
            for s in ([None] if g.report == "mean" else range(self.sizes[g.geometry]))]

    @property
    def labels(self) -> list[str]:
        return [o.label for o in self.observations]
