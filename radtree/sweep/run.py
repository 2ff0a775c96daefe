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

Modules: :mod:`~radtree.sweep.plan` (the design resolved to case specs),
:mod:`~radtree.sweep.cases` (one case: its folder, hash and the function a worker runs),
:mod:`~radtree.sweep.scheduler` (running the cases on dask or in this process).
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.errors import RadtreeError
from radtree.fileio import atomic_path, write_text
from radtree.log import progress
from radtree.pipeline.options import RunOptions
from radtree.sweep.cases import CASE_COLUMNS, CaseResult, CaseSpec
from radtree.sweep.design import Design, Parameter
from radtree.sweep.plan import SweepPlan, plan_sweep
from radtree.sweep.scheduler import default_workers, execute, make_executor

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SweepOptions:
    """What to sweep (None = the project's ``[sweep]`` table, then the defaults).

    ``params``: ``FIELD=VALUES`` strings (``a:b:n`` or ``v1,v2``) or :class:`Parameter` —
    they replace the table's parameters; ``design`` ``full`` (default) or ``lhs``;
    ``samples``/``seed`` of a Latin hypercube (default 10 per parameter, seed 1); ``out`` the
    output folder (default ``PROJECT/sweep``); ``fixed`` fields set in every case;
    ``sensitivity``: write the sensitivity summary."""

    params: tuple[str | Parameter, ...] | None = None
    design: str | None = None
    samples: int | None = None
    seed: int | None = None
    out: str | Path | None = None
    fixed: Mapping[str, Any] | None = None
    sensitivity: bool = True

    def __post_init__(self) -> None:
        if self.params is not None:
            object.__setattr__(self, "params", tuple(self.params) or None)


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


def run_sweep(project: str | Path, *, sweep: SweepOptions | None = None,
              run: RunOptions | None = None) -> SweepOutcome:
    """Plan, run (skipping finished cases), merge and summarise a sweep. See the module text.

    ``sweep``: what to sweep (:class:`SweepOptions`); ``run``: how each case runs
    (:class:`~radtree.pipeline.options.RunOptions`: ``engine``, ``scenarios``, ``hours``,
    ``scheduler`` — default ``local`` —, ``workers``). Returns a :class:`SweepOutcome`;
    failures do not raise (they are in ``failures``)."""
    t0 = time.perf_counter()
    sweep, run = sweep or SweepOptions(), run or RunOptions()
    plan = plan_sweep(project, list(sweep.params) if sweep.params else None,
                      design=sweep.design, samples=sweep.samples, seed=sweep.seed,
                      scenarios=list(run.scenarios) if run.scenarios else None,
                      hours=list(run.hours) if run.hours else None,
                      engine=run.engine if isinstance(run.engine, str) else
                      getattr(run.engine, "name", None), scheduler=run.scheduler,
                      workers=run.workers, out=sweep.out,
                      fixed=dict(sweep.fixed) if sweep.fixed else None)
    todo, unique, reused = _start(plan)
    results = _run_cases(plan, todo, unique)
    return _publish(plan, results, reused, sweep.sensitivity, time.perf_counter() - t0)


def _start(plan: SweepPlan) -> tuple[list[CaseSpec], dict[str, CaseSpec], set[str]]:
    """Write ``design.json``; the cases to run, every distinct case by hash, and the hashes
    of the cases finished before (their ``result.csv`` is there)."""
    plan.out_dir.mkdir(parents=True, exist_ok=True)
    for note in plan.notes:
        log.info("note: %s", note)
    write_text(plan.out_dir / "design.json", json.dumps({
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
    reused = {h for h, s in unique.items() if s not in todo}
    log.info("sweep: %d cases (%s, %d parameter(s)), %d to run, %d finished before; engine %s; "
             "scheduler %s%s", len(plan.specs), plan.design.kind, len(plan.design.names),
             len(todo), len(reused), plan.engine, plan.scheduler,
             f" ({plan.workers or min(default_workers(), max(1, len(todo)))} workers)"
             if plan.scheduler == "local" else "")
    return todo, unique, reused


def _run_cases(plan: SweepPlan, todo: list[CaseSpec], unique: dict[str, CaseSpec]
               ) -> dict[str, CaseResult]:
    """Run the cases left on the plan's executor; each result by case hash. A case's table
    comes back from a worker without our file system: it is written here."""
    bar = progress(None, desc="sweep", total=len(todo), unit="case")

    def on_result(res: CaseResult) -> None:
        if res.status == "done":
            f = Path(unique[res.case_hash].folder) / "result.csv"
            if not f.exists() and res.table is not None:  # worker without our file system
                with atomic_path(f) as tmp:
                    res.table.to_csv(tmp, index=False)
        else:
            shown = ", ".join(f"{k}={v!r}" for k, v in res.params.items())
            first = res.error.strip().splitlines()[0] if res.error.strip() else res.error_type
            log.warning("case %s (%s) failed: %s", res.case_id, shown, first)
        bar.update(1)

    try:
        results = execute(todo, make_executor(plan.scheduler, plan.workers), on_result)
    finally:
        bar.close()
    return {r.case_hash: r for r in results}


def _publish(plan: SweepPlan, by_hash: dict[str, CaseResult], reused: set[str],
             sensitivity: bool, seconds: float) -> SweepOutcome:
    """Write ``results.csv``, ``cases.csv``, ``failures.csv`` (and the sensitivity summary);
    the outcome."""
    names = plan.design.names
    table = merge_results(plan.specs, names)
    cases = _case_table(plan, by_hash, reused)
    failures = _failure_table(plan, by_hash)
    for name, frame in (("results.csv", table), ("cases.csv", cases),
                        ("failures.csv", failures)):
        with atomic_path(plan.out_dir / name) as tmp:
            frame.to_csv(tmp, index=False)
    notes = list(plan.notes)
    sens = None
    if sensitivity and len(table):
        from radtree.sweep.sensitivity import write_sensitivity

        try:
            sens = write_sensitivity(plan.out_dir, table, plan.design, plan.measured)
        except (RadtreeError, ValueError, KeyError, OSError) as exc:  # results are kept
            notes.append(f"sensitivity summary not written: {exc}")
            log.warning("sensitivity summary not written: %s", exc)
    ok = {h for h, r in by_hash.items() if r.status == "done"}
    ids = {k: [s.case_id for s in plan.specs if s.case_hash in hashes]
           for k, hashes in (("computed", ok), ("reused", reused),
                             ("failed", set(by_hash) - ok))}
    return SweepOutcome(plan.out_dir, plan.design, table, cases, failures, ids["computed"],
                        ids["reused"], ids["failed"], plan.engine, seconds, sens, notes)


def _case_table(plan: SweepPlan, by_hash: dict[str, CaseResult], reused: set[str]
                ) -> pd.DataFrame:
    """One line per case of the design: status (done, failed, reused, missing), seconds,
    host, pid and the parameters."""
    names = plan.design.names
    rows = []
    for s in plan.specs:
        r = by_hash.get(s.case_hash)
        status = "reused" if s.case_hash in reused else (r.status if r is not None
                                                          else "missing")
        rows.append({"case_id": s.case_id, "case_hash": s.case_hash, "status": status,
                     "seconds": round(r.seconds, 3) if r is not None else None,
                     "host": r.host if r is not None else "",
                     "pid": r.pid if r is not None else None,
                     **{n: s.params[n] for n in names}})
    return pd.DataFrame(rows, columns=CASE_COLUMNS + ["status", "seconds", "host", "pid"]
                        + names)


def _failure_table(plan: SweepPlan, by_hash: dict[str, CaseResult]) -> pd.DataFrame:
    """The failed cases: parameters, error type and message."""
    names = plan.design.names
    rows = []
    for s in plan.specs:
        r = by_hash.get(s.case_hash)
        if r is not None and r.status != "done":
            rows.append({"case_id": s.case_id, "case_hash": s.case_hash,
                         **{n: s.params[n] for n in names},
                         "error_type": r.error_type, "error": r.error.strip()})
    return pd.DataFrame(rows, columns=CASE_COLUMNS + names + ["error_type", "error"])
