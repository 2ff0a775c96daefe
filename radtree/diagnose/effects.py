"""The catalogue of physical effects the diagnosis can add to a scenario.

Each effect is a named, documented switch on a :class:`radtree.config.Scenario`: it returns a new
scenario (``switches`` and/or the fields ``reflection``, ``sky``) with the effect on at a given
strength, or off; it says whether it is already on, and it carries one line of physics. Where
the effect has a strength (a number with bounds) the attribution fits it to the residual:

* ``linear`` strengths change the façade illuminance in proportion to the strength (exactly for
  ``unfiltered_ground``; within ~2 % for ``sky_diffuse`` — checked on Mendoza at 6, 12 and
  20 klx diffuse — and approximately for ``opposite_facade``), so one signature at a reference
  strength, scaled by a non-negative amplitude, is fitted;
* ``search`` strengths are non-linear (slat optics through several layers, random crown gaps,
  whole filtration stages): the change is re-simulated at a few strengths and the fit is a 1-D
  search over them (piecewise-linear between the simulated strengths; integer strengths only
  at the simulated whole numbers);
* effects without a strength are on/off: the change is fixed (no amplitude is fitted).

``off`` is the model without the effect; the candidates of a diagnosis step are the effects
that apply to the scenario (crown model, project data) and are off in it.

Effects (``EFFECTS``, in the order of :data:`radtree.diagnose.registry.EFFECT_REGISTRY`, which
names each effect's class in :mod:`radtree.diagnose.catalogue`): ``unfiltered_ground``,
``calculated_reflection``, ``sky_diffuse``, ``opposite_facade``, ``ambient_bounces``,
``specular_transmission``, ``crown_gaps``, ``fewer_stages``, ``more_stages``,
``hourly_ground_reflectance``. This module holds the catalogue's instances and the helpers that
choose among them.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from radtree.config import Scenario, lookup_key
from radtree.diagnose.effect import Effect, EffectContext, Strength
from radtree.diagnose.registry import EFFECT_REGISTRY, effect_class
from radtree.errors import RadtreeError

__all__ = ["EFFECTS", "EFFECT_NAMES", "Effect", "EffectContext", "Strength", "candidates",
           "catalogue_lines", "check_effect_keys", "get_effect", "parse_effects"]

EFFECTS: tuple[Effect, ...] = tuple(effect_class(name)() for name in EFFECT_REGISTRY)
EFFECT_NAMES: tuple[str, ...] = tuple(EFFECT_REGISTRY)


def check_effect_keys(catalogue: Iterable[Effect] = EFFECTS) -> None:
    """Every switch an effect writes is a key of the one registry (ConfigError naming it and
    listing the known switches otherwise); the values are checked when a scenario is made."""
    for e in catalogue:
        key = getattr(e, "key", None)
        if key is not None:
            lookup_key(key, where=f"effect {e.name}: switches.{key}")


check_effect_keys()


def get_effect(name: str) -> Effect:
    """The catalogue's effect called ``name`` (RadtreeError listing the names otherwise)."""
    for e in EFFECTS:
        if e.name == name:
            return e
    raise RadtreeError(f"unknown effect {name!r}; the catalogue has: {', '.join(EFFECT_NAMES)}")


def parse_effects(text: str | Iterable[str] | None) -> tuple[Effect, ...]:
    """Effects from a comma-separated list (or names); None/empty → the whole catalogue."""
    if text is None:
        return EFFECTS
    names = [n.strip() for n in (text.split(",") if isinstance(text, str) else text)]
    names = [n for n in names if n]
    if not names:
        return EFFECTS
    seen: list[Effect] = []
    for n in names:
        e = get_effect(n)
        if e not in seen:
            seen.append(e)
    return tuple(seen)


def candidates(ctx: EffectContext, sc: Scenario, catalogue: Iterable[Effect] = EFFECTS
               ) -> tuple[list[Effect], dict[str, str]]:
    """Effects that apply to ``sc`` and are off in it, and why each other one is not a
    candidate (``{name: reason}``)."""
    out: list[Effect] = []
    why: dict[str, str] = {}
    for e in catalogue:
        reason = e.applies(ctx, sc)
        if reason:
            why[e.name] = f"not applicable: {reason}"
        elif e.is_on(ctx, sc):
            cur = e.current(ctx, sc)
            st = e.strength(ctx, sc)
            why[e.name] = "already on" + (f" ({st.text(cur)})" if st is not None
                                          and cur is not None else "")
        else:
            out.append(e)
    return out, why


def catalogue_lines(ctx: EffectContext | None = None, scenario: Scenario | None = None) -> list[str]:
    """One entry per effect: name, title, one line of physics, the switch and its strength
    (with a project: also whether it is on in ``scenario``, default the first)."""
    lines = []
    status: dict[str, str] = {}
    if ctx is not None:
        scenario = scenario or ctx.project.scenarios[0]
        cands, why = candidates(ctx, scenario)
        status = {e.name: "off: a candidate" for e in cands} | why
    for e in EFFECTS:
        lines.append(f"{e.name}: {e.title}")
        lines.append(f"    physics:  {e.physics}")
        lines.append(f"    switch:   {e.switch}")
        if ctx is not None and scenario is not None:
            st = e.strength(ctx, scenario)
        else:
            st = _static_strength(e)
        if st is not None:
            lines.append(f"    strength: {st.label}, {st.mode}, bounds [{st.text(st.lo)}, "
                         f"{st.text(st.hi)}], reference {st.text(st.reference)}")
        else:
            lines.append("    strength: none (on/off)")
        if e.name in status and scenario is not None:
            lines.append(f"    in {scenario.name}: {status[e.name]}")
    return lines


def _static_strength(e: Effect) -> Strength | None:
    """The strength of an effect without a project (documented defaults)."""
    from radtree.config import Light, Street, Tree

    class _P:  # the few project fields the strengths read
        light = Light(direct_normal_table=None)
        street = Street()
        tree = Tree()

    try:
        return e.strength(_FakeContext(_P()), Scenario("x", "louvers"))  # type: ignore[arg-type]
    except (AttributeError, RadtreeError, ValueError):
        return None


@dataclass(frozen=True)
class _FakeContext:
    project: Any
