"""The annual run by either method: ``dc`` (:func:`radtree.annual.run.compute_annual`) or
``3phase`` (:func:`radtree.annual.threephase_run.compute_annual_3phase`), as
``AnnualOptions.method`` says (the command's ``--method``). Both talk through :mod:`logging`.
"""

from __future__ import annotations

from radtree.annual.publish import AnnualOutcome, write_annual
from radtree.annual.run import AnnualOptions, AnnualResult, compute_annual
from radtree.annual.threephase_run import compute_annual_3phase
from radtree.config import Project


def compute(project: Project, *, options: AnnualOptions | None = None) -> AnnualResult:
    """8760 hours of illuminance by ``options.method``."""
    options = options or AnnualOptions()
    if options.method == "3phase":
        return compute_annual_3phase(project, options=options)
    return compute_annual(project, options=options)


def run(project: Project, *, options: AnnualOptions | None = None,
        figures: bool = True) -> AnnualOutcome:
    """Compute and write the annual results by ``options.method``."""
    return write_annual(compute(project, options=options), figures=figures)
