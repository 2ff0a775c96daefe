"""Effects by name: the diagnosis's catalogue of physical effects, each a class imported on
first use, shaped like the engine registry (:mod:`radtree.engines.registry`).

Adding an effect: write its class (a :class:`~radtree.diagnose.effect.Effect` with ``name``,
``title``, ``physics``, ``switch`` and its declared capabilities ``strength_mode``,
``crowns``, ``needs``) in a module of :mod:`radtree.diagnose.catalogue` (or a new one), and
add one line here. The order of :data:`EFFECT_REGISTRY` is the catalogue's order (ties in a
ranking are broken by name, not by this order). The command line's ``--effects`` names,
``radtree diagnose list-effects`` and the reference pages (:func:`effect_rows`) read this.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING

from radtree.errors import RadtreeError

if TYPE_CHECKING:
    from radtree.diagnose.effect import Effect

_CATALOGUE = "radtree.diagnose.catalogue"

#: name → "module:Class" (imported on first use)
EFFECT_REGISTRY: dict[str, str] = {
    "unfiltered_ground": f"{_CATALOGUE}.light:UnfilteredGround",
    "calculated_reflection": f"{_CATALOGUE}.light:CalculatedReflection",
    "sky_diffuse": f"{_CATALOGUE}.light:SkyDiffuse",
    "opposite_facade": f"{_CATALOGUE}.light:OppositeFacade",
    "ambient_bounces": f"{_CATALOGUE}.bounces:AmbientBounces",
    "specular_transmission": f"{_CATALOGUE}.crown:SpecularTransmission",
    "crown_gaps": f"{_CATALOGUE}.crown:CrownGaps",
    "fewer_stages": f"{_CATALOGUE}.crown:FewerStages",
    "more_stages": f"{_CATALOGUE}.crown:MoreStages",
    "hourly_ground_reflectance": f"{_CATALOGUE}.light:HourlyGroundReflectance",
}


def effect_class(name: str) -> type[Effect]:
    """The registered class of effect ``name`` (RadtreeError listing the names otherwise);
    its ``name`` attribute is checked to be the registry's."""
    if name not in EFFECT_REGISTRY:
        raise RadtreeError(f"unknown effect {name!r}; the catalogue has: "
                           f"{', '.join(EFFECT_REGISTRY)}")
    module, _, cls_name = EFFECT_REGISTRY[name].partition(":")
    cls: type[Effect] = getattr(import_module(module), cls_name)
    if cls.name != name:
        raise RadtreeError(f"effect registry: {EFFECT_REGISTRY[name]} is named {cls.name!r}, "
                           f"registered as {name!r}")
    return cls


def capabilities(cls: type[Effect]) -> str:
    """An effect's declared capabilities in words: strength mode, crowns, needs."""
    parts = [f"strength: {cls.strength_mode}",
             "crowns: " + (", ".join(cls.crowns) if cls.crowns else "any")]
    if cls.needs:
        parts.append(f"needs {cls.needs}")
    return "; ".join(parts)


def effect_rows() -> list[tuple[str, str, str]]:
    """``(name, summary, capabilities)`` per registered effect, in the catalogue's order (the
    reference pages' table)."""
    rows = []
    for name in EFFECT_REGISTRY:
        cls = effect_class(name)
        rows.append((name, cls.title, capabilities(cls)))
    return rows
