"""``[limits]``: how big a project radtree builds and traces before refusing it up front.

``max_triangles``: most triangles one scenario's scene may have (street + crown + extra
geometry); ``max_memory_fraction``: share of the machine's available memory
(``MemAvailable`` of ``/proc/meminfo``) a run may be estimated to need. A project over
either is refused before tracing with the estimate and the knob to turn.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from radtree.config.spec import Checked, meta


@dataclass(frozen=True)
class Limits(Checked):
    """Refusal thresholds (a count of triangles; a fraction 0–1 of available memory)."""

    TABLE: ClassVar[str] = "limits"
    max_triangles: int = field(default=5_000_000, metadata=meta(1))
    max_memory_fraction: float = field(default=0.8, metadata=meta(0.0, 1.0, lo_open=True))
