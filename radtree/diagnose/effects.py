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

Effects (``EFFECTS``, in this order): ``unfiltered_ground``, ``calculated_reflection``,
``sky_diffuse``, ``opposite_facade``, ``ambient_bounces``, ``specular_transmission``,
``crown_gaps``, ``fewer_stages``, ``more_stages``, ``hourly_ground_reflectance``.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import Any

from radtree.config import Scenario, effective_project, lookup_key
from radtree.diagnose.effect import (
    LOW_BOUNCES,
    Effect,
    EffectContext,
    Strength,
    _louvers_only,
    _ZeroIsOff,
    with_switches,
)
from radtree.errors import RadtreeError


class UnfilteredGround(_ZeroIsOff):
    name = "unfiltered_ground"
    title = "Ground-reflected light arriving unfiltered below the crown"
    physics = ("street-lit concrete reflects ρ(α)·E_open onto the façade from below the crown "
               "without crossing the leaf layers (the dome form makes it cross them)")
    switch = "switches.reflection.unfiltered = s (0–1): adds s·ρ(α)·E_open·F to vertical sensors"
    key = "reflection.unfiltered"

    def strength(self, ctx: EffectContext, sc: Scenario) -> Strength:
        return Strength("share s of the open street's reflected light", "", 0.0, 1.0, 0.1,
                        "linear", decimals=3)

    def current(self, ctx: EffectContext, sc: Scenario) -> float:
        return float(sc.switches.get(self.key, 0.0))

    def switch_off(self, ctx: EffectContext, sc: Scenario) -> Scenario:
        return with_switches(sc, drop=[self.key])


class CalculatedReflection(Effect):
    name = "calculated_reflection"
    title = "Ground reflection calculated instead of traced"
    physics = ("the street's reflected light is added analytically, ρ(α)·E_ground·F with the "
               "street under the crown's shade, instead of being traced through the crown filters")
    switch = "scenario reflection = 'calculated' (off: 'traced')"

    def is_on(self, ctx: EffectContext, sc: Scenario) -> bool:
        return sc.reflection == "calculated"

    def switch_on(self, ctx: EffectContext, sc: Scenario, strength: float | None = None) -> Scenario:
        return replace(sc, reflection="calculated")

    def switch_off(self, ctx: EffectContext, sc: Scenario) -> Scenario:
        return replace(sc, reflection="traced")


class SkyDiffuse(Effect):
    name = "sky_diffuse"
    title = "Diffuse light from the sky"
    physics = ("a clear Perez sky adds diffuse light from the whole vault, nearly the same at "
               "every hour, on top of the collimated sun")
    switch = ("scenario sky = 'perez' with switches.light.diffuse_horizontal_lux = strength "
              "(off: sky = 'none')")
    key = "light.diffuse_horizontal_lux"

    def strength(self, ctx: EffectContext, sc: Scenario) -> Strength | None:
        if ctx.project.light.epw is not None:
            return None  # the hour's diffuse comes from the weather file
        ref = ctx.project.light.diffuse_horizontal_lux
        ref = ref if 0 < ref <= 40000 else 12000.0
        return Strength("diffuse horizontal illuminance", "lx", 0.0, 40000.0, ref, "linear",
                        decimals=-1)

    def _sky(self, ctx: EffectContext, sc: Scenario) -> str:
        return sc.sky or ctx.project.light.sky

    def current(self, ctx: EffectContext, sc: Scenario) -> float:
        if self._sky(ctx, sc) != "perez":
            return 0.0
        return float(effective_project(ctx.project, sc).light.diffuse_horizontal_lux)

    def is_on(self, ctx: EffectContext, sc: Scenario) -> bool:
        if self._sky(ctx, sc) != "perez":
            return False
        return ctx.project.light.epw is not None or self.current(ctx, sc) > 0.0

    def switch_on(self, ctx: EffectContext, sc: Scenario, strength: float | None = None) -> Scenario:
        if self.strength(ctx, sc) is None:
            return with_switches(sc, sky="perez")
        return with_switches(sc, {self.key: float(self._value(ctx, sc, strength))}, sky="perez")

    def switch_off(self, ctx: EffectContext, sc: Scenario) -> Scenario:
        return with_switches(sc, drop=[self.key], sky="none")


class OppositeFacade(_ZeroIsOff):
    name = "opposite_facade"
    title = "Interreflection with the opposite façade"
    physics = ("the sunlit façade across the street reflects light back onto the studied "
               "façade; off treats it as black")
    switch = "switches.street.opposite_reflectance = ρ (off: 0)"
    key = "street.opposite_reflectance"

    def strength(self, ctx: EffectContext, sc: Scenario) -> Strength:
        ref = ctx.project.street.opposite_reflectance
        ref = ref if 0.0 < ref <= 0.9 else 0.35
        return Strength("opposite façade reflectance", "", 0.0, 0.9, ref, "linear", decimals=3)

    def current(self, ctx: EffectContext, sc: Scenario) -> float:
        return float(effective_project(ctx.project, sc).street.opposite_reflectance)



class AmbientBounces(Effect):
    name = "ambient_bounces"
    title = "Extra diffuse (ambient) bounces"
    physics = ("light reaches the sensors after several diffuse reflections and transmissions "
               "(slats, wall, street); too few bounces drop that interreflected part")
    switch = (f"switches.engine.ab (every engine traces that many diffuse bounces): off = "
              f"{LOW_BOUNCES}, on = the model's -ab (project engine.ab, else the crown's "
              f"recommendation), at least {LOW_BOUNCES + 2}")
    key = "engine.ab"

    def _on_ab(self, ctx: EffectContext, sc: Scenario) -> int:
        ab = ctx.default_ab(sc)
        return ab if ab > LOW_BOUNCES else LOW_BOUNCES + 2

    def is_on(self, ctx: EffectContext, sc: Scenario) -> bool:
        ab = sc.switches.get(self.key)
        return int(ab if ab is not None else ctx.default_ab(sc)) > LOW_BOUNCES

    def switch_on(self, ctx: EffectContext, sc: Scenario, strength: float | None = None) -> Scenario:
        return with_switches(sc, {self.key: self._on_ab(ctx, sc)})

    def switch_off(self, ctx: EffectContext, sc: Scenario) -> Scenario:
        return with_switches(sc, {self.key: LOW_BOUNCES})


class SpecularTransmission(_ZeroIsOff):
    name = "specular_transmission"
    title = "Specular (direct) transmission through the slats"
    physics = ("part of each slat layer's transmission passes undeviated (sun through leaf "
               "gaps and edges), so direct sun crosses the layers as a beam instead of diffusely")
    switch = "switches.louvers.specular_fraction = f (off: 0)"
    key = "louvers.specular_fraction"

    def applies(self, ctx: EffectContext, sc: Scenario) -> str | None:
        return _louvers_only(sc)

    def strength(self, ctx: EffectContext, sc: Scenario) -> Strength:
        ref = ctx.project.tree.louvers.specular_fraction
        ref = ref if ref > 0 else 0.9
        return Strength("specular share of the slat transmittance", "", 0.0, 1.0, ref, "search",
                        grid=(0.3, 0.6, 0.9), decimals=2)

    def current(self, ctx: EffectContext, sc: Scenario) -> float:
        return float(ctx.louvers(sc).specular_fraction)



class CrownGaps(Effect):
    name = "crown_gaps"
    title = "Direct sun through gaps in the crown"
    physics = ("each slat layer leaves a fraction g of its area open, so some sun reaches the "
               "façade through aligned gaps without any filtering")
    switch = "switches.louvers.cover_fraction = 1 − g (off: 1)"
    key = "louvers.cover_fraction"

    def applies(self, ctx: EffectContext, sc: Scenario) -> str | None:
        return _louvers_only(sc)

    def strength(self, ctx: EffectContext, sc: Scenario) -> Strength:
        return Strength("gap fraction g per layer", "", 0.0, 0.5, 0.05, "search",
                        grid=(0.02, 0.05, 0.1, 0.2), decimals=3)

    def current(self, ctx: EffectContext, sc: Scenario) -> float:
        return 1.0 - float(ctx.louvers(sc).cover_fraction)

    def is_on(self, ctx: EffectContext, sc: Scenario) -> bool:
        return self.current(ctx, sc) > 1e-9

    def switch_on(self, ctx: EffectContext, sc: Scenario, strength: float | None = None) -> Scenario:
        g = float(self._value(ctx, sc, strength))
        return with_switches(sc, {self.key: round(1.0 - g, 6)})

    def switch_off(self, ctx: EffectContext, sc: Scenario) -> Scenario:
        return with_switches(sc, {self.key: 1.0})


class _Stages(Effect):
    """Filtration stages (``louvers.layers``) changed from the project's value."""

    key = "louvers.layers"
    sign = -1

    def applies(self, ctx: EffectContext, sc: Scenario) -> str | None:
        why = _louvers_only(sc)
        if why:
            return why
        layers = ctx.louvers(sc).layers
        base = ctx.project.tree.louvers.layers
        if (layers - base) * self.sign < 0:
            return f"the scenario already has {layers} layers against the project's {base}"
        if self.sign < 0 and base <= 1:
            return "the project's crown has a single layer"
        if self.sign > 0 and base >= 20:
            return "the project's crown already has the maximum of 20 layers"
        return None

    def _bounds(self, ctx: EffectContext) -> tuple[int, int]:
        base = ctx.project.tree.louvers.layers
        return (1, base - 1) if self.sign < 0 else (1, min(3, 20 - base))

    def strength(self, ctx: EffectContext, sc: Scenario) -> Strength:
        lo, hi = self._bounds(ctx)
        hi = max(hi, lo)
        return Strength("layers " + ("removed" if self.sign < 0 else "added"), "layer(s)",
                        float(lo), float(hi), 1.0, "search", grid=(1.0, 2.0), integer=True,
                        decimals=0)

    def current(self, ctx: EffectContext, sc: Scenario) -> float:
        return float(max(0, (ctx.louvers(sc).layers - ctx.project.tree.louvers.layers)
                         * self.sign))

    def is_on(self, ctx: EffectContext, sc: Scenario) -> bool:
        return self.current(ctx, sc) > 0

    def switch_on(self, ctx: EffectContext, sc: Scenario, strength: float | None = None) -> Scenario:
        n = int(self._value(ctx, sc, strength))
        return with_switches(sc, {self.key: int(ctx.project.tree.louvers.layers + self.sign * n)})

    def switch_off(self, ctx: EffectContext, sc: Scenario) -> Scenario:
        return with_switches(sc, {self.key: int(ctx.project.tree.louvers.layers)})


class FewerStages(_Stages):
    name = "fewer_stages"
    title = "Fewer filtration stages (a more permeable crown)"
    physics = ("light crossing the crown meets fewer slat layers, each passing about half of "
               "it, so the crown's permeability rises by about ×2 per stage removed")
    switch = "switches.louvers.layers = project layers − n (off: the project's layers)"
    sign = -1


class MoreStages(_Stages):
    name = "more_stages"
    title = "More filtration stages (a denser crown)"
    physics = ("light crossing the crown meets more slat layers, each passing about half of it, "
               "so the crown's permeability falls by about ×2 per stage added")
    switch = "switches.louvers.layers = project layers + n (off: the project's layers)"
    sign = +1


class HourlyGroundReflectance(Effect):
    name = "hourly_ground_reflectance"
    title = "Per-hour (sun-angle dependent) concrete reflectance"
    physics = ("the concrete reflects more at higher sun (table ρ(α)), instead of one constant "
               "reflectance for the whole day")
    switch = ("the project's street.ground_reflectance table (off: switches."
              "street.ground_reflectance = the table's mean over the hours, a constant)")
    key = "street.ground_reflectance"

    def applies(self, ctx: EffectContext, sc: Scenario) -> str | None:
        if ctx.project.street.ground_reflectance_table is None:
            return "the project gives a constant ground reflectance (no per-hour table)"
        return None

    def is_on(self, ctx: EffectContext, sc: Scenario) -> bool:
        return (ctx.project.street.ground_reflectance_table is not None
                and self.key not in sc.switches)

    def constant(self, ctx: EffectContext) -> float:
        from radtree.light.ground import ground_reflectance_at
        from radtree.light.sun import local_datetime, sun_position

        site = ctx.project.site
        values = []
        for h in site.hours:
            sun = sun_position(local_datetime(site.date, h, site.tzinfo),
                               site.latitude, site.longitude, site.elevation_m)
            values.append(ground_reflectance_at(ctx.project, sun.altitude_deg))
        return round(float(sum(values) / len(values)), 4)

    def switch_on(self, ctx: EffectContext, sc: Scenario, strength: float | None = None) -> Scenario:
        return with_switches(sc, drop=[self.key])

    def switch_off(self, ctx: EffectContext, sc: Scenario) -> Scenario:
        return with_switches(sc, {self.key: self.constant(ctx)})


EFFECTS: tuple[Effect, ...] = (
    UnfilteredGround(), CalculatedReflection(), SkyDiffuse(), OppositeFacade(), AmbientBounces(),
    SpecularTransmission(), CrownGaps(), FewerStages(), MoreStages(), HourlyGroundReflectance(),
)
EFFECT_NAMES: tuple[str, ...] = tuple(e.name for e in EFFECTS)


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
