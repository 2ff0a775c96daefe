"""What the in-process engines (NumPy backward, forward) share behind the engine interface."""

from __future__ import annotations

from radtree.engines.base import Engine
from radtree.engines.common.raycast import embree_available


class InProcessEngine(Engine):
    """An engine that traces in this Python process with the NumPy/Embree ray caster: always
    available, versioned by NumPy (and Embree when it is used)."""

    missing_hint = "it failed to load"

    @classmethod
    def available(cls) -> bool:
        return True

    def version(self) -> str | None:
        import numpy

        return f"numpy {numpy.__version__}" + (", embree" if embree_available() else "")
