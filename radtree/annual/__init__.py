"""Annual climate-based daylight with deciduous street trees (``radtree annual``).

* :mod:`~radtree.annual.weather` — a generated clear-sky EPW (labelled GENERATED) and which
  EPW a project uses;
* :mod:`~radtree.annual.skymatrix` — ``epw2wea``, ``gendaymtx`` sky matrix and hourly suns,
  Reinhart patches;
* :mod:`~radtree.annual.coefficients` — ``rcontrib`` daylight coefficients (sky patches,
  exact hourly suns for the direct sun, sun patches for reflected sunlight);
* :mod:`~radtree.annual.schedule` — leaf-on/leaf-off dates, occupancy;
* :mod:`~radtree.annual.branches` — the leaf-off crown (opaque branches at 40°);
* :mod:`~radtree.annual.metrics` — UDI, DA, sDA, ASE;
* :mod:`~radtree.annual.run` — the run (:func:`run_annual`) and its tables;
* :mod:`~radtree.annual.report` — figures and :func:`annual_section_data`;
* :mod:`~radtree.annual.cli` — ``annual_command``.
"""

from __future__ import annotations

from radtree.annual.run import AnnualOptions, AnnualResult, compute_annual, run_annual
from radtree.annual.schedule import LeafSchedule


def annual_section_data(project) -> dict:
    """The report section's data of the annual results (see :mod:`radtree.annual.report`)."""
    from radtree.annual.report import annual_section_data as _section

    return _section(project)


__all__ = ["AnnualOptions", "AnnualResult", "LeafSchedule", "annual_section_data",
           "compute_annual", "run_annual"]
