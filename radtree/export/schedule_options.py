"""What a year of crown transmittances is traced with (:mod:`radtree.export.transmittance`):
:class:`ScheduleOptions` and the two :data:`DEFINITIONS` — light to import (the command line
offers them before anything is traced)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from radtree.config.spec import Checked, meta

#: the schedule's transmittance: ``total`` (beam + forward-scattered light, the default) or
#: ``beam`` (undeviated only); see :mod:`radtree.export.transmittance`
DEFINITIONS: tuple[str, ...] = ("total", "beam")


@dataclass(frozen=True)
class ScheduleOptions(Checked):
    """How the year of transmittances is traced: ``rays`` per hour and crown (about that many
    bundle rays over the crown's shadow), the leaf season (``leaf_on`` / ``leaf_off`` MM-DD,
    None: the project's, see
    :func:`radtree.export.transmittance.default_leaf_schedule`; ``seasons=False``: leafed all
    year) and the ``definition`` (one of :data:`DEFINITIONS`)."""

    TABLE: ClassVar[str] = "export"
    rays: int = field(default=128, metadata=meta(1))
    leaf_on: str | None = None
    leaf_off: str | None = None
    seasons: bool = True
    definition: str = field(default=DEFINITIONS[0], metadata=meta(choices=DEFINITIONS))
