"""Run a sweep: one ordinary project per case, executed on ``dask.distributed``, resumable.

Layout (``OUT`` = ``PROJECT/sweep`` unless told otherwise)::

    OUT/design.json                   parameters, design kind, seed, engine, scenarios, hours
    OUT/cases/<case_hash>/radtree.toml   the project file with the case's overrides applied
    OUT/cases/<case_hash>/result.csv     the case's tidy results (written atomically, last)
    OUT/cases/<case_hash>/case.json      parameters, status, error, seconds, host
    OUT/cases.csv                     one line per case of the design (status, seconds)
    OUT/results.csv                   every finished case's rows + case_id, case_hash, parameters
    OUT/failures.csv                  failed cases: parameters and error
    OUT/sensitivity.csv, OUT/metrics.csv, OUT/tornado.png   (see :mod:`radtree.sweep.sensitivity`)

A case's folder is named by the hash of everything that changes its numbers (the project data
with the overrides applied, the engine, the scenarios and hours), so a rerun — or another
design that shares cases — skips every case whose ``result.csv`` exists. A case interrupted
midway has no ``result.csv`` and is recomputed (its finished hours are reused from the case's
own ``results/parts/``).

Execution: a :class:`dask.distributed.LocalCluster` by default (one single-threaded worker
process per core, loopback only, no dashboard), or ``scheduler="tcp://host:port"`` for an
existing cluster (its workers must have radtree installed and see the output folder), or
``scheduler="sequential"`` to run the same case function in this process. Every path submits
:func:`run_case` once per case and collects results as they complete; a failing case is
recorded and the others go on.
"""

from __future__ import annotations

import copy
import hashlib
import json
import os
import socket
import time
import traceback
import uuid
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.config import PATH_FIELDS, set_dotted
from radtree.errors import ConfigError, RadtreeError
from radtree.fileio import atomic_path, write_text
from radtree.sweep.design import Design, Parameter, Value, make_design, parse_param
from radtree.sweep.settings import check_names, load_base, resolve_parameters
from radtree.sweep.tomlout import dumps

CASE_COLUMNS = ["case_id", "case_hash"]


# ---------------------------------------------------------------- case data
@dataclass(frozen=True)
class CaseSpec:
    """Everything a worker needs to run one case (plain, picklable data)."""

    case_id: str
    case_hash: str
    params: dict[str, Value]
    folder: str
    toml_text: str
    engine: str
    scenarios: tuple[str, ...] | None = None
    hours: tuple[str, ...] | None = None


@dataclass
class CaseResult:
    """What :func:`run_case` returns: ``status`` is ``done`` or ``failed``."""

    case_id: str
    case_hash: str
    params: dict[str, Value]
    status: str
    seconds: float = 0.0
    error: str = ""
    error_type: str = ""
    host: str = ""
    pid: int = 0
    table: pd.DataFrame | None = field(default=None, repr=False)


def _absolute(value: Any, root: Path) -> Any:
    if isinstance(value, str) and value and not Path(value).is_absolute():
        return str((root / value).resolve())
    return value


def _looks_like_path(value: str) -> bool:
    return ("/" in value or "\\" in value or Path(value).suffix != "") and "\n" not in value


def absolutise_paths(data: dict[str, Any], root: Path) -> dict[str, Any]:
    """Rewrite the relative data paths of project data to absolute ones (in place; returned).

    The known path fields always; any other relative text value that names an existing file
    of the project folder too (so fields added later keep working from the case folder).
    """
    for name in PATH_FIELDS:
        table: Any = data
        parts = name.split(".")
        for part in parts[:-1]:
            table = table.get(part) if isinstance(table, dict) else None
        if isinstance(table, dict) and isinstance(table.get(parts[-1]), str):
            table[parts[-1]] = _absolute(table[parts[-1]], root)
    for item in data.get("geometry", []) or []:
        if isinstance(item, dict) and isinstance(item.get("file"), str):
            item["file"] = _absolute(item["file"], root)

    def walk(obj: Any) -> Any:
        if isinstance(obj, dict):
            return {k: walk(v) for k, v in obj.items()}
        if isinstance(obj, list):
            return [walk(v) for v in obj]
        if (isinstance(obj, str) and obj and _looks_like_path(obj)
                and not Path(obj).is_absolute()):
            try:
                if (root / obj).is_file():
                    return str((root / obj).resolve())
            except (OSError, ValueError):
                return obj
        return obj

    walked = walk(data)
    data.clear()
    data.update(walked)
    return data


def case_hash(data: dict[str, Any], engine: str, scenarios: Iterable[str] | None,
              hours: Iterable[str] | None) -> str:
    """12-hex hash of the case's project data, engine, scenarios and hours."""
    payload = {"project": data, "engine": engine,
               "scenarios": list(scenarios) if scenarios else None,
               "hours": list(hours) if hours else None}
    text = json.dumps(payload, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def _case_header(source: Path, case_id: str, params: dict[str, Value]) -> str:
    lines = [f"radtree sweep case, generated from {source}",
             "(relative data paths rewritten to absolute ones; [sweep] table removed)",
             "overrides:"]
    lines += [f"  {k} = {v!r}" for k, v in params.items()]
    del case_id  # the case id depends on the design order; the file must not
    return "\n".join(lines)


# ---------------------------------------------------------------- the case function
def _log_writer(path: Path) -> Callable[[str], None]:
    def echo(msg: str) -> None:
        with path.open("a", encoding="utf-8") as fh:
            fh.write(str(msg) + "\n")
    return echo


def run_case(spec: CaseSpec) -> CaseResult:
    """Build and simulate one case as an ordinary project in its folder; never raises.

    Writes ``radtree.toml`` (if it differs), runs :func:`radtree.scenarios.simulate_project`
    (after building with pictures off for Radiance), then ``result.csv`` atomically and
    ``case.json``. Any exception becomes a ``failed`` result carrying its message.
    """
    from radtree.config import load_project
    from radtree.scenarios import build_project, simulate_project

    t0 = time.perf_counter()
    folder = Path(spec.folder)
    result = CaseResult(spec.case_id, spec.case_hash, dict(spec.params), "failed",
                        host=socket.gethostname(), pid=os.getpid())
    try:
        folder.mkdir(parents=True, exist_ok=True)
        toml = folder / "radtree.toml"
        if not toml.exists() or toml.read_text(encoding="utf-8") != spec.toml_text:
            write_text(toml, spec.toml_text)
        log = _log_writer(folder / "case.log")
        log(f"--- case {spec.case_hash} on {result.host} pid {result.pid} at "
            f"{time.strftime('%Y-%m-%d %H:%M:%S')}")
        project = load_project(folder)
        scenarios = list(spec.scenarios) if spec.scenarios else None
        hours = list(spec.hours) if spec.hours else None
        if spec.engine == "radiance":
            build_project(project, scenarios, echo=log, progress=False, pictures=False)
        out = simulate_project(project, spec.engine, scenarios, hours, workers=1, echo=log,
                               progress=False)
        if out is None:  # only on dry runs
            raise RadtreeError("simulation returned no table")
        table = out.table
        if scenarios:
            table = table[table["scenario"].astype(str).isin(scenarios)]
        if hours:
            table = table[table["time"].astype(str).isin(hours)]
        table = table.reset_index(drop=True)
        with atomic_path(folder / "result.csv") as tmp:
            table.to_csv(tmp, index=False)
        result.status = "done"
        result.table = table
    except Exception as exc:  # noqa: BLE001 - a case must fail alone, with its message
        result.error = str(exc) or type(exc).__name__
        result.error_type = type(exc).__name__
        if not isinstance(exc, RadtreeError):
            result.error += "\n" + traceback.format_exc(limit=6)
    result.seconds = time.perf_counter() - t0
    try:
        meta = {k: v for k, v in asdict(result).items() if k != "table"}
        write_text(folder / "case.json", json.dumps(meta, indent=2, default=str))
    except OSError:
        pass
    return result


# ---------------------------------------------------------------- the sweep
@dataclass
class SweepOutcome:
    """What :func:`run_sweep` did and wrote."""

    out_dir: Path
    design: Design
    table: pd.DataFrame
    cases: pd.DataFrame
    failures: pd.DataFrame
    computed: list[str]
    reused: list[str]
    failed: list[str]
    engine: str
    seconds: float
    sensitivity: pd.DataFrame | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def path(self) -> Path:
        return self.out_dir / "results.csv"


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
    from radtree.scenarios import choose_engine

    path, base, settings, project0 = load_base(project)
    root = path.parent
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
    parameters = resolve_parameters(parameters)
    kind = design or settings.design or "full"
    seed_v = seed if seed is not None else (settings.seed if settings.seed is not None else 1)
    d = make_design(parameters, kind, samples if samples is not None else settings.samples,
                    seed_v)

    scen = scenarios or settings.scenarios
    if scen:
        for name in scen:
            project0.scenario(name)  # raises with the list of known names
        scen = list(dict.fromkeys(scen))
    hrs = hours or settings.hours
    if hrs:
        unknown = [h for h in hrs if h not in project0.site.hours]
        if unknown and "site.hours" not in fixed_all and "site.hours" not in d.names:
            raise ConfigError(f"hour(s) {', '.join(unknown)} not among the project's hours "
                              f"({', '.join(project0.site.hours)})", source=str(path),
                              field="site.hours")
        hrs = list(dict.fromkeys(hrs))
    eng_name = engine or settings.engine or project0.engine.name
    eng = choose_engine(eng_name)
    out_dir = Path(out) if out is not None else (
        root / settings.out if settings.out else root / "sweep")
    out_dir = out_dir if out_dir.is_absolute() else (Path.cwd() / out_dir)
    sched = scheduler or settings.scheduler or "local"
    if not (sched in ("local", "sequential") or "://" in sched):
        raise ConfigError(f"scheduler {sched!r}: expected 'local', 'sequential' or a dask "
                          "scheduler address such as tcp://127.0.0.1:8786")
    nworkers = workers or settings.workers
    notes = list(d.notes)
    if nworkers and sched not in ("local", "sequential"):
        notes.append(f"workers = {nworkers} is not used with an existing scheduler ({sched})")

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
        text = dumps(data, header=_case_header(path, cid, params_i))
        specs.append(CaseSpec(cid, h, dict(params_i), str(out_dir / "cases" / h), text, eng,
                              tuple(scen) if scen else None, tuple(hrs) if hrs else None))
    return SweepPlan(path, out_dir, d, specs, eng, scen, hrs, sched, nworkers,
                     project0.measured, notes, fixed_all)


def _default_workers() -> int:
    return max(1, os.cpu_count() or 1)


def execute(specs: list[CaseSpec], scheduler: str = "local", workers: int | None = None,
            on_result: Callable[[CaseResult], None] | None = None) -> list[CaseResult]:
    """Run :func:`run_case` for every spec; return results in completion order.

    ``scheduler``: ``"sequential"`` (this process), ``"local"`` (a LocalCluster of ``workers``
    single-threaded processes on 127.0.0.1, default one per core), or a scheduler address.
    """
    results: list[CaseResult] = []

    def take(res: CaseResult) -> None:
        results.append(res)
        if on_result is not None:
            on_result(res)

    if not specs:
        return results
    if scheduler == "sequential":
        for spec in specs:
            take(run_case(spec))
        return results

    import logging

    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler == "local":
        n = min(workers or _default_workers(), len(specs))
        with warnings.catch_warnings():  # "port 8787 in use": the scheduler picks another
            warnings.simplefilter("ignore", UserWarning)
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=None, host="127.0.0.1",
                                   silence_logs=logging.ERROR)
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout=30)
        except (OSError, TimeoutError) as exc:
            raise RadtreeError(f"cannot connect to the dask scheduler at {scheduler}: {exc}"
                               ) from exc
    token = uuid.uuid4().hex[:8]
    futures = []
    try:
        by_future = {}
        for spec in specs:
            fut = client.submit(run_case, spec, key=f"radtree-case-{spec.case_hash}-{token}",
                                pure=False)
            futures.append(fut)
            by_future[fut.key] = spec
        for fut in as_completed(futures):
            spec = by_future[fut.key]
            try:
                res = fut.result()
            except Exception as exc:  # noqa: BLE001 - a lost worker fails this case only
                res = CaseResult(spec.case_id, spec.case_hash, dict(spec.params), "failed",
                                 error=f"the dask task failed: {type(exc).__name__}: {exc}",
                                 error_type=type(exc).__name__)
            take(res)
    finally:
        for fut in futures:
            if not fut.done():
                fut.cancel()
        client.close()
        if cluster is not None:
            cluster.close()
    return results


def _params_frame(specs: list[CaseSpec], names: list[str]) -> pd.DataFrame:
    return pd.DataFrame([{"case_id": s.case_id, "case_hash": s.case_hash,
                          **{n: s.params[n] for n in names}} for s in specs],
                        columns=CASE_COLUMNS + names)


def merge_results(specs: list[CaseSpec], names: list[str]) -> pd.DataFrame:
    """Every finished case's ``result.csv`` with ``case_id, case_hash`` and parameter columns."""
    frames = []
    for s in specs:
        f = Path(s.folder) / "result.csv"
        if not f.exists():
            continue
        df = pd.read_csv(f)
        front = pd.DataFrame({"case_id": [s.case_id] * len(df), "case_hash": s.case_hash,
                              **{n: [s.params[n]] * len(df) for n in names}})
        frames.append(pd.concat([front, df], axis=1))
    if not frames:
        return pd.DataFrame(columns=CASE_COLUMNS + names)
    return pd.concat(frames, ignore_index=True)


def run_sweep(project: str | Path, params: Sequence[str | Parameter] | None = None, *,
              design: str | None = None, samples: int | None = None, seed: int | None = None,
              scenarios: list[str] | None = None, hours: list[str] | None = None,
              engine: str | None = None, scheduler: str | None = None,
              workers: int | None = None, out: str | Path | None = None,
              fixed: dict[str, Any] | None = None, progress: bool = True,
              echo: Callable[[str], None] = print, sensitivity: bool = True) -> SweepOutcome:
    """Plan, run (skipping finished cases), merge and summarise a sweep. See the module text.

    ``params`` are ``FIELD=VALUES`` strings (``a:b:n`` or ``v1,v2``) or :class:`Parameter`;
    without them the ``[sweep.params]`` table is used. ``fixed`` sets fields in every case.
    Returns a :class:`SweepOutcome`; failures do not raise (they are in ``failures``).
    """
    t0 = time.perf_counter()
    plan = plan_sweep(project, params, design=design, samples=samples, seed=seed,
                      scenarios=scenarios, hours=hours, engine=engine, scheduler=scheduler,
                      workers=workers, out=out, fixed=fixed)
    out_dir = plan.out_dir
    out_dir.mkdir(parents=True, exist_ok=True)
    names = plan.design.names
    for note in plan.notes:
        echo(f"note: {note}")
    write_text(out_dir / "design.json", json.dumps({
        "project": str(plan.project_file), "design": plan.design.kind, "seed": plan.design.seed,
        "cases": len(plan.specs), "engine": plan.engine, "scenarios": plan.scenarios,
        "hours": plan.hours, "fixed": plan.fixed,
        "parameters": [{"name": p.name, "kind": p.kind, "spec": p.text, "integer": p.integer}
                       for p in plan.design.parameters],
    }, indent=2, default=str))

    unique: dict[str, CaseSpec] = {}
    for s in plan.specs:
        unique.setdefault(s.case_hash, s)
    todo = [s for s in unique.values() if not (Path(s.folder) / "result.csv").exists()]
    reused_hashes = {h for h, s in unique.items() if s not in todo}
    echo(f"sweep: {len(plan.specs)} cases ({plan.design.kind}, {len(names)} parameter(s)), "
         f"{len(todo)} to run, {len(reused_hashes)} finished before; engine {plan.engine}; "
         f"scheduler {plan.scheduler}"
         + (f" ({plan.workers or min(_default_workers(), max(1, len(todo)))} workers)"
            if plan.scheduler == "local" else ""))

    bar = None
    if progress and todo:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), desc="sweep", unit="case")
    write = bar.write if bar is not None else echo
    failed: list[CaseResult] = []

    def on_result(res: CaseResult) -> None:
        if res.status == "done":
            f = Path(unique[res.case_hash].folder) / "result.csv"
            if not f.exists() and res.table is not None:  # worker without our file system
                with atomic_path(f) as tmp:
                    res.table.to_csv(tmp, index=False)
        else:
            failed.append(res)
            shown = ", ".join(f"{k}={v!r}" for k, v in res.params.items())
            first = res.error.strip().splitlines()[0] if res.error.strip() else res.error_type
            write(f"case {res.case_id} ({shown}) failed: {first}")
        if bar is not None:
            bar.update(1)

    try:
        results = execute(todo, plan.scheduler, plan.workers, on_result)
    finally:
        if bar is not None:
            bar.close()
    by_hash = {r.case_hash: r for r in results}

    table = merge_results(plan.specs, names)
    with atomic_path(out_dir / "results.csv") as tmp:
        table.to_csv(tmp, index=False)

    rows = []
    for s in plan.specs:
        r = by_hash.get(s.case_hash)
        status = ("reused" if s.case_hash in reused_hashes
                  else (r.status if r is not None else "missing"))
        rows.append({"case_id": s.case_id, "case_hash": s.case_hash, "status": status,
                     "seconds": round(r.seconds, 3) if r is not None else None,
                     "host": r.host if r is not None else "",
                     "pid": r.pid if r is not None else None,
                     **{n: s.params[n] for n in names}})
    cases = pd.DataFrame(rows, columns=CASE_COLUMNS + ["status", "seconds", "host", "pid"]
                         + names)
    with atomic_path(out_dir / "cases.csv") as tmp:
        cases.to_csv(tmp, index=False)

    fail_rows = []
    for s in plan.specs:
        r = by_hash.get(s.case_hash)
        if r is not None and r.status != "done":
            fail_rows.append({"case_id": s.case_id, "case_hash": s.case_hash,
                              **{n: s.params[n] for n in names},
                              "error_type": r.error_type, "error": r.error.strip()})
    failures = pd.DataFrame(fail_rows,
                            columns=CASE_COLUMNS + names + ["error_type", "error"])
    with atomic_path(out_dir / "failures.csv") as tmp:
        failures.to_csv(tmp, index=False)

    notes = list(plan.notes)
    sens = None
    if sensitivity and len(table):
        from radtree.sweep.sensitivity import write_sensitivity

        try:
            sens = write_sensitivity(out_dir, table, plan.design, plan.measured)
        except (RadtreeError, ValueError, KeyError, OSError) as exc:  # results are kept
            notes.append(f"sensitivity summary not written: {exc}")
            echo(f"warning: sensitivity summary not written: {exc}")
    computed = [s.case_id for s in plan.specs
                if s.case_hash in by_hash and by_hash[s.case_hash].status == "done"]
    reused = [s.case_id for s in plan.specs if s.case_hash in reused_hashes]
    failed_ids = [s.case_id for s in plan.specs
                  if s.case_hash in by_hash and by_hash[s.case_hash].status != "done"]
    return SweepOutcome(out_dir, plan.design, table, cases, failures, computed, reused,
                        failed_ids, plan.engine, time.perf_counter() - t0, sens, notes)
