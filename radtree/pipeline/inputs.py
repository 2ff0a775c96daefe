"""The project's inputs checked once, the same way whichever command reads them.

:func:`check_inputs` is what ``radtree new`` runs on the file it writes and what ``radtree
build`` runs before it writes anything: the weather of every hour (an EPW checked against
``[site]``, the clear sky, or the DNI table; the sun above the horizon at each hour), the tree
inventory and building footprints (every feature read, its numbers checked, the geographic
sanity of :func:`radtree.site.inventory.check_spread`), the Honeybee model. Each failure is one
:class:`~radtree.errors.ConfigError` naming the file, the field or feature, the value as written
and the fix.
"""

from __future__ import annotations

from radtree.config import Project
from radtree.light.hours import hour_states
from radtree.site.district import load_district


def check_inputs(project: Project) -> None:
    """Raise ConfigError for the first input the project cannot be built from."""
    hour_states(project)
    for sc in project.scenarios:
        if sc.sky:   # a scenario's own sky reads the same weather
            hour_states(project, sc)
    if project.district is not None:
        load_district(project)
    if project.honeybee is not None:
        from radtree.site.honeybee_model import load_model

        load_model(project.honeybee.model)
