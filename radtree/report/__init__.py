"""The project report: statistics, tables, figures → ``PROJECT/report/index.html``.

    from radtree.config import load_project
    from radtree.report import build_report
    build_report(load_project("my-street"))   # → Path to report/index.html

Reads only the results layout (``results/illuminance.csv``, ``timing.csv``, ``manifest.json``,
``convergence.csv``, ``build/<scenario>/manifest.json`` and ``model.png``) and the project's
measurement files. The heavy modules (pandas, matplotlib) load on the first call.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from radtree.config import Project

__all__ = ["build_report"]


def build_report(project: Project) -> Path:
    """Write ``PROJECT/report/`` atomically and return the path of ``index.html``; quiet
    unless ``radtree.log.enable()`` (its messages go to :mod:`logging`).

    See :func:`radtree.report.build.build_report`.
    """
    from radtree.report.build import build_report as _build

    return _build(project)
