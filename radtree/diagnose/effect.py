"""An effect of the diagnosis: a named, documented switch on a scenario, with its strength.

:class:`Effect` is the base of every entry of the catalogue (:mod:`radtree.diagnose.effects`);
:class:`EffectContext` is what an effect needs besides the scenario (the project; effects know
no engine); :class:`Strength` the bounds and kind (linear / search) of a fitted strength.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from typing import Any

from radtree.config import Louvers, Project, Scenario, effective_project
from radtree.errors import RadtreeError

#: The "few bounces" (``engine.ab``) that ``ambient_bounces`` switches off to.
LOW_BOUNCES = 2


@dataclass(frozen=True)
class EffectContext:
    """What an effect needs besides the scenario: the project (effects know no engine)."""

    project: Project
    _ab_cache: dict[str, int] = field(default_factory=dict, compare=False, repr=False)

    def louvers(self, sc: Scenario) -> Louvers:
        """The scenario's louvers parameters after its switches."""
        from radtree.trees.build import apply_switches

        tree, _ = apply_switches(self.project.tree, sc.switches, source=str(self.project.source),
                                 root=self.project.root)
        return tree.louvers

    def default_ab(self, sc: Scenario) -> int:
        """Diffuse bounces (``-ab``; every engine traces as many) the scenario uses without an
        ``engine.ab`` switch: the scene's -ab rule (:func:`radtree.pipeline.assemble.scene_ab`:
        the project's ``engine.ab``, else the crown's recommendation)."""
        from radtree.pipeline.assemble import facade_frame, scene_ab

        base = replace(sc, switches={k: v for k, v in sc.switches.items() if k != "engine.ab"})
        proj = effective_project(self.project, base)
        if proj.engine.ab is not None or sc.model == "none":
            return scene_ab(proj, None)
        key = repr((sc.model, sc.form, sorted((k, repr(v)) for k, v in base.switches.items()
                                              if not k.startswith(("light.", "reflection.")))))
        if key not in self._ab_cache:
            from radtree.trees.build import build_tree

            tree = build_tree(proj, base, facade_frame(proj))
            self._ab_cache[key] = scene_ab(proj, int(tree.recommended_ab))
        return self._ab_cache[key]


@dataclass(frozen=True)
class Strength:
    """A strength parameter: what it is, its bounds and how it acts.

    ``mode`` is ``"linear"`` (change ∝ strength; fitted as a non-negative amplitude of the
    signature at ``reference``) or ``"search"`` (re-simulated at ``grid``; 1-D search).
    ``decimals``: the strength written to a project file is rounded to this many decimals
    (negative: to tens, hundreds…).
    """

    label: str
    unit: str
    lo: float
    hi: float
    reference: float
    mode: str = "linear"
    grid: tuple[float, ...] = ()
    integer: bool = False
    decimals: int = 3

    def __post_init__(self) -> None:
        if self.mode not in ("linear", "search"):
            raise ValueError(f"strength mode must be linear or search, got {self.mode!r}")
        if not self.lo <= self.reference <= self.hi:
            raise ValueError(f"reference strength {self.reference} outside [{self.lo}, {self.hi}]")

    def clip(self, value: float) -> float:
        return float(min(self.hi, max(self.lo, value)))

    def round(self, value: float) -> float | int:
        v = self.clip(value)
        if self.integer:
            return int(round(v))
        r = round(v, self.decimals)
        return float(r) if self.decimals > 0 else float(int(r))

    def search_points(self) -> tuple[float, ...]:
        """Strengths at which the change is simulated (within the bounds)."""
        if self.mode == "linear":
            return (self.reference,)
        pts = sorted({self.clip(g) for g in self.grid} | {self.reference})
        return tuple(p for p in pts if p > self.lo or self.integer)

    def text(self, value: float | None) -> str:
        if value is None:
            return "on"
        if self.integer:
            return f"{int(round(value))} {self.unit}".strip()
        if abs(value) >= 100:
            return f"{value:,.0f} {self.unit}".strip()
        return f"{value:.3g} {self.unit}".strip()


class Effect:
    """One physical effect that can be switched on or off in a scenario.

    Subclasses set ``name`` (identifier), ``title``, ``physics`` (one line), ``switch`` (what
    it changes in the project's words) and implement the methods, and declare their
    capabilities (the registry's rows, :func:`radtree.diagnose.registry.effect_rows`):
    ``strength_mode`` (``linear``: the change scales with the strength; ``search``: re-simulated
    at a few strengths; ``on/off``: no strength), ``crowns`` (the crown models it applies to;
    empty: any) and ``needs`` (project data it needs, in words; empty: none).
    """

    name: str = ""
    title: str = ""
    physics: str = ""
    switch: str = ""
    strength_mode: str = "on/off"
    crowns: tuple[str, ...] = ()
    needs: str = ""

    def strength(self, ctx: EffectContext, sc: Scenario) -> Strength | None:
        """The strength parameter (bounds may depend on the scenario), None if on/off only."""
        return None

    def applies(self, ctx: EffectContext, sc: Scenario) -> str | None:
        """None if the effect can be switched in this scenario, else why not."""
        return None

    def is_on(self, ctx: EffectContext, sc: Scenario) -> bool:
        raise NotImplementedError

    def current(self, ctx: EffectContext, sc: Scenario) -> float | None:
        """The strength in the scenario (None for on/off effects)."""
        return None

    def switch_on(self, ctx: EffectContext, sc: Scenario, strength: float | None = None) -> Scenario:
        """The scenario with the effect on (at ``strength``, default the reference)."""
        raise NotImplementedError

    def switch_off(self, ctx: EffectContext, sc: Scenario) -> Scenario:
        raise NotImplementedError

    # helpers ----------------------------------------------------------------------------
    def reference(self, ctx: EffectContext, sc: Scenario) -> float | None:
        st = self.strength(ctx, sc)
        return None if st is None else st.reference

    def _value(self, ctx: EffectContext, sc: Scenario, strength: float | None) -> float | int:
        st = self.strength(ctx, sc)
        if st is None:
            raise RadtreeError(f"effect {self.name} has no strength")
        return st.round(st.reference if strength is None else strength)

    def describe(self, ctx: EffectContext, sc: Scenario, strength: float | None) -> str:
        """What switching on at ``strength`` writes into the scenario, as text."""
        on = self.switch_on(ctx, sc, strength)
        parts = []
        for k in ("reflection", "sky"):
            if getattr(on, k) != getattr(sc, k):
                parts.append(f"{k} = {getattr(on, k)!r}")
        for k, v in on.switches.items():
            if sc.switches.get(k, _MISSING) != v:
                parts.append(f"{k} = {v!r}")
        for k in sc.switches:
            if k not in on.switches:
                parts.append(f"{k} removed")
        return ", ".join(parts) or "(no change)"

    def __repr__(self) -> str:
        return f"<effect {self.name}>"


_MISSING = object()


def with_switches(sc: Scenario, set_: dict[str, Any] | None = None,
                  drop: Iterable[str] = (), **fields_: Any) -> Scenario:
    """A copy of ``sc`` with switches set/dropped and scenario fields replaced."""
    sw = {k: v for k, v in sc.switches.items() if k not in set(drop)}
    sw.update(set_ or {})
    return replace(sc, switches=sw, **fields_)


def _louvers_only(sc: Scenario) -> str | None:
    return None if sc.model == "louvers" else f"needs the louvers model (scenario has {sc.model})"


class _ZeroIsOff(Effect):
    """An effect set by one numeric switch ``key`` whose value 0 means off."""

    key: str

    def is_on(self, ctx: EffectContext, sc: Scenario) -> bool:
        return (self.current(ctx, sc) or 0.0) > 0.0

    def switch_on(self, ctx: EffectContext, sc: Scenario, strength: float | None = None) -> Scenario:
        return with_switches(sc, {self.key: float(self._value(ctx, sc, strength))})

    def switch_off(self, ctx: EffectContext, sc: Scenario) -> Scenario:
        return with_switches(sc, {self.key: 0.0})


