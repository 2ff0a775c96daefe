"""Annual climate-based daylight with deciduous street trees (``radtree annual``).

* the weather (the EPW a run uses, the generated clear-sky year) is in :mod:`radtree.light`
  (:mod:`~radtree.light.weather`, :mod:`~radtree.light.clearsky`);
* :mod:`~radtree.annual.skymatrix` — ``epw2wea``, ``gendaymtx`` sky matrix and hourly suns,
  Reinhart patches;
* :mod:`~radtree.annual.coefficients` — ``rcontrib`` daylight coefficients (sky patches,
  exact hourly suns for the direct sun, sun patches for reflected sunlight);
* :mod:`~radtree.annual.schedule` — leaf-on/leaf-off dates, occupancy;
* :mod:`~radtree.annual.branches` — the leaf-off crown (opaque branches at 40°);
* :mod:`~radtree.annual.metrics` — UDI, DA, sDA, ASE;
* :mod:`~radtree.annual.run` — the run's steps (plan, coefficients, result:
  :func:`compute_annual`); :mod:`~radtree.annual.publish` writes its tables
  (:func:`run_annual`);
* :mod:`~radtree.annual.threephase` — the three-phase method (view matrix · crown BSDF ·
  daylight matrix · sky), run by :mod:`~radtree.annual.threephase_run` (``--method
  3phase``); :mod:`~radtree.annual.methods` picks the method;
* :mod:`~radtree.annual.report` — figures and :func:`annual_section_data`.

The command is :mod:`radtree.cli.annual`.
"""

from __future__ import annotations

from radtree.annual.publish import run_annual
from radtree.annual.run import AnnualOptions, AnnualResult, compute_annual
from radtree.annual.schedule import LeafSchedule


def annual_section_data(project) -> dict:
    """The report section's data of the annual results (see :mod:`radtree.annual.report`)."""
    from radtree.annual.report import annual_section_data as _section

    return _section(project)


__all__ = ["AnnualOptions", "AnnualResult", "LeafSchedule", "annual_section_data",
           "compute_annual", "run_annual"]
