"""The annual run by either method: ``dc`` (:func:`radtree.annual.run.compute_annual`) or
``3phase`` (:func:`radtree.annual.threephase.compute_annual_3phase`), as
``AnnualOptions.method`` says (the command's ``--method``)."""

from __future__ import annotations

from collections.abc import Callable

from radtree.annual.run import (
    AnnualOptions,
    AnnualOutcome,
    AnnualResult,
    compute_annual,
    write_annual,
)
from radtree.annual.threephase import compute_annual_3phase
from radtree.config import Project


def compute(project: Project, options: AnnualOptions | None = None,
            echo: Callable[[str], None] = print, progress: bool = False) -> AnnualResult:
    """8760 hours of illuminance by ``options.method``."""
    options = options or AnnualOptions()
    if options.method == "3phase":
        return compute_annual_3phase(project, options, echo)
    return compute_annual(project, options, echo, progress)


def run(project: Project, options: AnnualOptions | None = None,
        echo: Callable[[str], None] = print, progress: bool = False,
        figures: bool = True) -> AnnualOutcome:
    """Compute and write the annual results by ``options.method``."""
    return write_annual(compute(project, options, echo, progress), figures=figures)
