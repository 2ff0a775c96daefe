"""Effects of the light transport itself: extra diffuse (ambient) bounces (registered in
:mod:`radtree.diagnose.registry`)."""

from __future__ import annotations

from radtree.config import Scenario
from radtree.diagnose.effect import LOW_BOUNCES, Effect, EffectContext, with_switches


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
