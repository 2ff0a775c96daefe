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
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.errors import RadtreeError
from radtree.fileio import atomic_path, write_text
from radtree.sweep.cases import CASE_COLUMNS, CaseResult, CaseSpec
from radtree.sweep.design import Design, Parameter
from radtree.sweep.plan import plan_sweep
from radtree.sweep.scheduler import default_workers, execute


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
         + (f" ({plan.workers or min(default_workers(), max(1, len(todo)))} workers)"
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
