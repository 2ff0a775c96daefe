"""Plan a sweep: read the project and its ``[sweep]`` table, check the fields, make the design
and one :class:`~radtree.sweep.cases.CaseSpec` per case (nothing is run)."""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from radtree.config import set_dotted
from radtree.errors import ConfigError
from radtree.pipeline.executor import scheduler_problem
from radtree.sweep.cases import CaseSpec, absolutise_paths, case_hash, case_header
from radtree.sweep.design import Design, Parameter, make_design, parse_param
from radtree.sweep.settings import check_names, load_base, resolve_parameters
from radtree.tomlout import dumps


@dataclass
class SweepPlan:
    """A sweep resolved to case specs (nothing run yet)."""

    project_file: Path
    out_dir: Path
    design: Design
    specs: list[CaseSpec]
    engine: str
    scenarios: list[str] | None
    hours: list[str] | None
    scheduler: str
    workers: int | None
    measured: Path | None
    notes: list[str]
    fixed: dict[str, Any] = field(default_factory=dict)


def plan_sweep(project: str | Path, params: Sequence[str | Parameter] | None = None, *,
               design: str | None = None, samples: int | None = None,
               seed: int | None = None, scenarios: list[str] | None = None,
               hours: list[str] | None = None, engine: str | None = None,
               scheduler: str | None = None, workers: int | None = None,
               out: str | Path | None = None, fixed: dict[str, Any] | None = None
               ) -> SweepPlan:
    """Read the project (and its ``[sweep]`` table), check the fields, make the design and the
    case specs. Arguments given here win over the table; ``params`` replaces its parameters."""
    from radtree.engines.registry import get_engine

    path, base, settings, project0 = load_base(project)
    root = path.parent
    parameters, fixed_all = _parameters(path, settings, params, fixed)
    kind = design or settings.design or "full"
    seed_v = seed if seed is not None else (settings.seed if settings.seed is not None else 1)
    d = make_design(parameters, kind, samples if samples is not None else settings.samples,
                    seed_v)
    scen, hrs = _scenarios_hours(path, project0, scenarios or settings.scenarios,
                                 hours or settings.hours, [*fixed_all, *d.names])
    eng = get_engine(engine or settings.engine or project0.engine.name).name
    out_dir = Path(out) if out is not None else (
        root / settings.out if settings.out else root / "sweep")
    out_dir = out_dir if out_dir.is_absolute() else (Path.cwd() / out_dir)
    sched = scheduler or settings.scheduler or "local"
    if scheduler_problem(sched):
        raise ConfigError(scheduler_problem(sched))
    nworkers = workers or settings.workers
    notes = list(d.notes)
    if nworkers and sched not in ("local", "sequential"):
        notes.append(f"workers = {nworkers} is not used with an existing scheduler ({sched})")
    specs = _case_specs(path, base, d, fixed_all, (eng, scen, hrs), out_dir, notes)
    return SweepPlan(path, out_dir, d, specs, eng, scen, hrs, sched, nworkers,
                     project0.measured, notes, fixed_all)


def _parameters(path: Path, settings: Any, params: Sequence[str | Parameter] | None,
                fixed: dict[str, Any] | None) -> tuple[list[Parameter], dict[str, Any]]:
    """The swept parameters (given, else the table's; checked and resolved) and the fields
    set in every case (the table's ``[sweep.set]`` and ``fixed``)."""
    if params:
        parameters = [p if isinstance(p, Parameter) else parse_param(p) for p in params]
    else:
        parameters = list(settings.params)
    if not parameters:
        raise ConfigError("no sweep parameters: give --param FIELD=VALUES (e.g. "
                          "--param tree.crown.trunk_distance_m=2:6:5) or a [sweep.params] table",
                          source=str(path))
    fixed_all = dict(settings.fixed)
    fixed_all.update(fixed or {})
    clash = sorted(set(fixed_all) & {p.name for p in parameters})
    if clash:
        raise ConfigError(f"{', '.join(clash)} both swept and fixed (sweep.set / --set)")
    check_names([p.name for p in parameters], list(fixed_all), path)
    return resolve_parameters(parameters), fixed_all


def _scenarios_hours(path: Path, project0: Any, scen: list[str] | None, hrs: list[str] | None,
                     changed: list[str]) -> tuple[list[str] | None, list[str] | None]:
    """The scenarios and hours of every case, checked against the project (an hour not among
    its hours is allowed when the sweep sets or sweeps ``site.hours``: in ``changed``)."""
    if scen:
        for name in scen:
            project0.scenario(name)  # raises with the list of known names
        scen = list(dict.fromkeys(scen))
    if hrs:
        unknown = [h for h in hrs if h not in project0.site.hours]
        if unknown and "site.hours" not in changed:
            raise ConfigError(f"hour(s) {', '.join(unknown)} not among the project's hours "
                              f"({', '.join(project0.site.hours)})", source=str(path),
                              field="site.hours")
        hrs = list(dict.fromkeys(hrs))
    return scen, hrs


def _case_specs(path: Path, base: dict[str, Any], d: Design, fixed_all: dict[str, Any],
                run: tuple[str, list[str] | None, list[str] | None], out_dir: Path,
                notes: list[str]) -> list[CaseSpec]:
    """One spec per case of the design: its project text (overrides applied, data paths
    absolute) and the hash naming its folder; ``run``: engine, scenarios, hours. A case that
    repeats another (same project after overrides) shares its folder (noted)."""
    eng, scen, hrs = run
    root = path.parent
    specs: list[CaseSpec] = []
    seen: dict[str, str] = {}
    width = max(3, len(str(len(d))))
    for i, params_i in enumerate(d.cases, start=1):
        data = copy.deepcopy(base)
        for key, value in list(fixed_all.items()) + list(params_i.items()):
            set_dotted(data, key, value)
        absolutise_paths(data, root)
        h = case_hash(data, eng, scen, hrs)
        cid = f"c{i:0{width}d}"
        if h in seen:
            notes.append(f"{cid} repeats {seen[h]} (same project after overrides): shared folder")
        seen.setdefault(h, cid)
        text = dumps(data, header=case_header(path, cid, params_i))
        specs.append(CaseSpec(cid, h, dict(params_i), str(out_dir / "cases" / h), text, eng,
                              tuple(scen) if scen else None, tuple(hrs) if hrs else None))
    return specs
