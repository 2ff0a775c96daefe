"""Parameter sweeps over the unknowns of a project (reference case §1), run on dask.distributed.

    from radtree.pipeline.options import RunOptions
    from radtree.sweep import SweepOptions, run_sweep
    out = run_sweep("my-street", sweep=SweepOptions(params=("tree.crown.trunk_distance_m=2:6:5",
                                                            "tree.louvers.layers=3,4,5")),
                    run=RunOptions(scenarios=("A",)))
    out.table        # every case's tidy rows + case_id, case_hash and parameter columns
    out.sensitivity  # per scenario × parameter × metric: main-effect range, Spearman ρ

Modules: :mod:`~radtree.sweep.design` (parameters, full factorial, Latin hypercube),
:mod:`~radtree.sweep.settings` (the ``[sweep]`` table, field checks), :mod:`~radtree.sweep.plan`
(the case specs), :mod:`~radtree.sweep.cases` (one case: folder, hash, the worker function),
:mod:`~radtree.sweep.scheduler` (the cases on an executor: dask or sequential), :mod:`~radtree.sweep.run`
(the whole sweep: resume, merged table, case and failure tables), :mod:`~radtree.sweep.sensitivity`
(metrics, effect ranges, tornado plot, report fragment); the command is :mod:`radtree.cli.sweep`.
"""

from __future__ import annotations

import importlib
from typing import Any

# Lazy exports (PEP 562): importing radtree.sweep stays light for ``radtree --help``.
_EXPORTS = {
    "Design": "design", "Parameter": "design", "full_factorial": "design",
    "latin_hypercube": "design", "make_design": "design", "parse_param": "design",
    "parse_spec": "design",
    "CaseResult": "cases", "CaseSpec": "cases", "run_case": "cases",
    "SweepPlan": "plan", "plan_sweep": "plan", "execute": "scheduler",
    "SweepOutcome": "run", "SweepOptions": "run", "merge_results": "run", "run_sweep": "run",
    "case_metrics": "sensitivity", "sensitivity_table": "sensitivity",
    "sweep_section_data": "sensitivity", "tornado_plot": "sensitivity",
    "write_sensitivity": "sensitivity",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        module = importlib.import_module(f"radtree.sweep.{_EXPORTS[name]}")
        return getattr(module, name)
    raise AttributeError(f"module 'radtree.sweep' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(list(globals()) + __all__)
