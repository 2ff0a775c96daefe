"""Effects inside a louvers crown: specular transmission through the slats, gaps in the
crown, fewer or more filtration stages (registered in :mod:`radtree.diagnose.registry`)."""

from __future__ import annotations

from radtree.config import Scenario
from radtree.diagnose.effect import (
    Effect,
    EffectContext,
    Strength,
    _louvers_only,
    _ZeroIsOff,
    with_switches,
)


class SpecularTransmission(_ZeroIsOff):
    name = "specular_transmission"
    title = "Specular (direct) transmission through the slats"
    physics = ("part of each slat layer's transmission passes undeviated (sun through leaf "
               "gaps and edges), so direct sun crosses the layers as a beam instead of diffusely")
    switch = "switches.louvers.specular_fraction = f (off: 0)"
    key = "louvers.specular_fraction"
    strength_mode = "search"
    crowns = ("louvers",)

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
    strength_mode = "search"
    crowns = ("louvers",)

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

    strength_mode = "search"
    crowns = ("louvers",)

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
