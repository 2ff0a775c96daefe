"""The report's sections: Python builds each section's data (tables and lists of formatted
cells), ``templates/sections/<name>.html.j2`` / ``<name>.md.j2`` render it.

The page templates (``report.html.j2``, ``report.md.j2``) include every section; the optional
studies (office block, sweep, crown realisations, permeability scan, diagnosis, annual) come as
:class:`Section` entries, ``name`` naming the template and ``data`` what it renders as ``s``.

* :mod:`~radtree.report.sections.results` — scenarios, hourly, statistics, rows, timing,
  reflection, convergence tables;
* :mod:`~radtree.report.sections.provenance` — provenance, parameters, crown-model pictures;
* :mod:`~radtree.report.sections.extras` — the optional studies' sections.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from jinja2 import Environment

from radtree.resources import template_environment

#: The optional sections, in page order (each has ``sections/<name>.html.j2``; the ones the
#: Markdown report shows also ``.md.j2``).
OPTIONAL = ("office", "sweep", "realisations", "permeability_scan", "diagnose", "annual",
            "direct_sun", "photo_check", "method", "facades")
OPTIONAL += ("honeybee", "view3d")  # type: ignore[assignment]  # issue 19 (own line: merges)
OPTIONAL += ("points_crown",)  # type: ignore[assignment]  # issue 41 (own line: merges)
#: issue 38: the tree impact (first), the light traced, and the core sections by name (their
#: templates read the page context ``c``; ``data`` is then empty)
OPTIONAL += ("impact", "light", "scenarios", "hourly", "statistics", "rows", "maps",  # type: ignore[assignment]
             "models", "reflection", "convergence", "timing", "provenance")


@dataclass(frozen=True)
class Section:
    """An optional section: ``templates/sections/<name>.html.j2`` (and ``.md.j2``) with
    ``data`` as ``s``."""

    name: str
    data: dict[str, Any]
    title: str = ""          # the contents' entry (default: from the name)
    appendix: bool = False   # research sections after the results

    def __post_init__(self) -> None:
        if self.name not in OPTIONAL:
            raise ValueError(f"unknown report section {self.name!r} (known: "
                             f"{', '.join(OPTIONAL)})")
        if not isinstance(self.data, dict):
            raise TypeError(f"section {self.name}: data must be a dict, got "
                            f"{type(self.data).__name__}")


def environment(html: bool) -> Environment:
    """The report's Jinja environment: autoescaped for HTML, verbatim for Markdown."""
    return template_environment(autoescape=html, keep_trailing_newline=True, trim_blocks=True,
                                lstrip_blocks=True)


def render_section(section: Section, html: bool = True) -> str:
    """One optional section alone (as the page includes it)."""
    suffix = "html" if html else "md"
    return environment(html).get_template(f"sections/{section.name}.{suffix}.j2").render(
        s=section.data)
