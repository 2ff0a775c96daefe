"""Effects on the light reaching the façade from the sky and the street: unfiltered and
calculated ground reflection, the sky's diffuse light, the opposite façade, a per-hour ground
reflectance (each registered in :mod:`radtree.diagnose.registry`)."""

from __future__ import annotations

from dataclasses import replace

from radtree.config import Scenario, effective_project
from radtree.diagnose.effect import Effect, EffectContext, Strength, _ZeroIsOff, with_switches


class UnfilteredGround(_ZeroIsOff):
    name = "unfiltered_ground"
    title = "Ground-reflected light arriving unfiltered below the crown"
    physics = ("street-lit concrete reflects ρ(α)·E_open onto the façade from below the crown "
               "without crossing the leaf layers (the dome form makes it cross them)")
    switch = "switches.reflection.unfiltered = s (0–1): adds s·ρ(α)·E_open·F to vertical sensors"
    key = "reflection.unfiltered"
    strength_mode = "linear"

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
    strength_mode = "linear"

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
    strength_mode = "linear"

    def strength(self, ctx: EffectContext, sc: Scenario) -> Strength:
        ref = ctx.project.street.opposite_reflectance
        ref = ref if 0.0 < ref <= 0.9 else 0.35
        return Strength("opposite façade reflectance", "", 0.0, 0.9, ref, "linear", decimals=3)

    def current(self, ctx: EffectContext, sc: Scenario) -> float:
        return float(effective_project(ctx.project, sc).street.opposite_reflectance)


class HourlyGroundReflectance(Effect):
    name = "hourly_ground_reflectance"
    title = "Per-hour (sun-angle dependent) concrete reflectance"
    physics = ("the concrete reflects more at higher sun (table ρ(α)), instead of one constant "
               "reflectance for the whole day")
    switch = ("the project's street.ground_reflectance table (off: switches."
              "street.ground_reflectance = the table's mean over the hours, a constant)")
    key = "street.ground_reflectance"
    needs = "a street.ground_reflectance table"

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
