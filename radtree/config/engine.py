"""The ``[engine]`` table: the settings every engine reads and one parameter group per engine.

The project file's ``[engine]`` table stays flat (``rays = 4096``, ``ad = 2048``,
``photons = 1000000``, …). In code, :class:`EngineParams` holds what every engine reads
(``name``, ``ab``, ``seed``, ``workers``) and one frozen, validated group per engine:

* :class:`RadianceParams` — ``rtrace`` ambient settings and the Radiance photon map
  (``params.radiance.ad``),
* :class:`NumpyParams` — the built-in backward Monte Carlo (``params.numpy.rays``),
* :class:`ForwardParams` — forward light tracing (``params.forward.photons``; the engine turns
  it into its :class:`radtree.engines.forward.settings.ForwardSettings`).

Each engine reads its own group. The groups' fields keep the table's names, bounds and
messages (``engine.rays: got 0, expected ≥ 1``): :func:`radtree.config.spec.table_fields`
lists them in place of the group, so the reader, the switch registry (``"engine.rays"``) and
the reference pages see the flat table. ``EngineParams(rays=512, ad=64)`` and
``dataclasses.replace(params, rays=512)`` take the flat keys as well: each goes to its group.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Any, ClassVar

from radtree.config.spec import Checked, meta

SAMPLING_CHOICES = ("sobol", "random")  # NumPy engine's first directions (engines/numpy/qmc)
MIST_EXTINCTION = ("sun", "mean", "vertical", "horizontal")   # Radiance mist crowns' σ
MIST_SUN = ("beam", "scatter", "mist")   # the sun through Radiance mist crowns


@dataclass(frozen=True)
class RadianceParams(Checked):
    """Radiance ``rtrace`` ambient settings: ``ad``, ``as_`` (written ``as`` in the file),
    ``ar``, ``aa``, ``lw`` (Radiance reference manual, rtrace(1)). The defaults (``-aa 0 -as
    0``: no irradiance cache, no super-sampling) are pure Monte Carlo: behind slat crowns the
    cache and ``-as`` bias ``-I`` low by 4–8 % and the cache makes ``-ab 7`` runs take minutes
    instead of seconds. ``pmap_*``: the photon map (:mod:`radtree.engines.radiance.pmap`)."""

    TABLE: ClassVar[str] = "engine"
    LABEL: ClassVar[str] = "Radiance"   # in the reference pages
    ad: int = field(default=2048, metadata=meta(1))
    as_: int = field(default=0, metadata=meta(0, toml="as"))
    ar: int = field(default=256, metadata=meta(1))
    aa: float = field(default=0.0, metadata=meta(0.0, 1.0))
    lw: float = field(default=0.0001, metadata=meta(0.0, 1.0))
    # the dense façade map (a figure) only: -lw (None = lw)
    dense_lw: float | None = field(default=None, metadata=meta(0.0, 1.0))
    # photon map (radtree.engines.radiance.pmap): global photons per hour (None = no
    # photon map, plain rtrace -I), caustic photons (None = none), photons per density estimate
    pmap_photons: int | None = field(default=None, metadata=meta(1))
    pmap_caustic_photons: int | None = field(default=None, metadata=meta(1))
    pmap_bandwidth: int = field(default=50, metadata=meta(1))
    # turbid crowns as mist (radtree.engines.radiance.mist): σ at the hour's sun direction,
    # the mean over all directions, the vertical receiver's cosine-weighted mean, or horizontal
    mist_extinction: str = field(default="horizontal", metadata=meta(choices=MIST_EXTINCTION))
    # turbid crowns as mist: the sun's shadow rays see σ at the sun (beam, no scattering),
    # the sun scattered by the leaves (scatter; shadow rays see only absorption), or the mist
    mist_sun: str = field(default="beam", metadata=meta(choices=MIST_SUN))


@dataclass(frozen=True)
class NumpyParams(Checked):
    """The built-in NumPy engine: ``rays`` paths per sensor (``dense_rays`` per dense-map
    point), at most ``max_bounces`` diffuse bounces, first directions ``"sobol"``-stratified or
    ``"random"`` (``sampling``)."""

    TABLE: ClassVar[str] = "engine"
    LABEL: ClassVar[str] = "NumPy engine"   # in the reference pages
    rays: int = field(default=4096, metadata=meta(1))
    max_bounces: int = field(default=8, metadata=meta(0))
    sampling: str = field(default="sobol", metadata=meta(choices=SAMPLING_CHOICES))
    # the dense façade map (a figure) only: paths per point (None = rays)
    dense_rays: int | None = field(default=None, metadata=meta(1))


@dataclass(frozen=True)
class ForwardParams(Checked):
    """The forward engine (:mod:`radtree.engines.forward.settings`): photons per hour, flux
    threshold relative to a photon's launched flux, ray splitting (else Russian roulette), sun
    beam diameter aimed at the first grid (None = the whole scene), square detector side,
    batches, focused launch, splitting and guiding near the target grid, a precision target."""

    TABLE: ClassVar[str] = "engine"
    LABEL: ClassVar[str] = "forward engine"   # in the reference pages
    # photons per hour (sun and sky together, allotted ∝ their launched flux)
    photons: int = field(default=1_000_000, metadata=meta(1))
    forward_threshold: float = field(default=0.05, metadata=meta(0.0, 1.0, lo_open=True,
                                                                    hi_open=True))
    forward_splitting: bool = False
    beam_diameter_m: float | None = field(default=None, metadata=meta(0.0, lo_open=True))
    patch_m: float = field(default=0.5, metadata=meta(0.0, lo_open=True))
    forward_batches: int = field(default=32, metadata=meta(2))  # per round (precision.py)
    # focused launch, innermost disc radius (m) around the target grid (None = start points
    # uniform over the launch disc) (default 1 m, with forward_guide 0.8: the variance reduction
    # that makes the precision target affordable — on reference-case A/B at 12:30 10–20× less
    # time to a 2 % *estimated* error than the uniform launch, whose 64 M photons still left
    # 3.5 %: benchmarks/forward.py)
    forward_focus_m: float | None = field(default=1.0, metadata=meta(0.0, lo_open=True))
    # children per diffuse event near the target grid (1 = none), and how near
    forward_split: int = field(default=1, metadata=meta(1))
    forward_split_radius_m: float = field(default=2.0, metadata=meta(0.0, lo_open=True))
    # share of diffuse directions aimed at the target grid (0 = none), sphere (default 0.8
    # towards the sphere just holding the target grid's patches, None = that radius)
    forward_guide: float = field(default=0.8, metadata=meta(0.0, 1.0, hi_open=True))
    forward_guide_radius_m: float | None = field(default=None, metadata=meta(0.0, lo_open=True))
    # rounds of `photons` added until every traced grid's mean has this relative standard
    # error (None = one round of `photons`), at most `max_photons` per hour (then a warning
    # with the error reached): radtree.engines.forward.precision
    target_rel_se: float | None = field(default=0.02, metadata=meta(0.0, 1.0, lo_open=True,
                                                                    hi_open=True))
    max_photons: int = field(default=16_000_000, metadata=meta(1))
    # the sun's direct beam computed at the sensor points (as the backward engines see it), sun
    # photons tallied on the patches only once scattered: radtree.engines.forward.direct
    forward_direct_sun: bool = True
    # weight window: after an hour's first round, photons heavier than this many mean patch
    # crossings (× (d / r)², d from the target grid's centre) split into copies (0 = none):
    # radtree.engines.forward.window
    forward_window: float = field(default=2.0, metadata=meta(0.0))
    # the sky's unscattered light (sky and ground glow through specular transmissions only)
    # estimated at the sensor points, sky photons tallied on the patches only once scattered:
    # radtree.engines.forward.skypoint
    forward_direct_sky: bool = True
    # every round of the focused launch traced in this many stages, its rings allotted again
    # before each from all photons so far (1 = the round at once; default 4: the error's heavy
    # tail of a round allotted from the pilot alone, benchmarks/forward.py; a beam or a
    # uniform launch traces its rounds at once): radtree.engines.forward.strata
    forward_stages: int = field(default=4, metadata=meta(1))


#: the parameter groups of :class:`EngineParams`: attribute → class
GROUPS: dict[str, type] = {"radiance": RadianceParams, "numpy": NumpyParams,
                           "forward": ForwardParams}
#: a group's field (its attribute name: ``as_``) → the group holding it
GROUP_OF: dict[str, str] = {f.name: g for g, cls in GROUPS.items() for f in fields(cls)}


@dataclass(frozen=True)
class _EngineTable(Checked):
    """The fields of :class:`EngineParams` (its constructor routes the flat keys)."""

    TABLE: ClassVar[str] = "engine"
    GROUPS: ClassVar[dict[str, type]] = GROUPS
    name: str = "auto"  # a name of radtree.engines.registry (checked when the engine is chosen)
    # the scene's diffuse bounces, counted by every engine like rtrace -ab (None = from the
    # crown model: radtree.pipeline.assemble.scene_ab)
    ab: int | None = field(default=None, metadata=meta(0, 20))
    radiance: RadianceParams = field(default_factory=RadianceParams)
    numpy: NumpyParams = field(default_factory=NumpyParams)
    seed: int = 1
    workers: int = field(default=2, metadata=meta(1))
    forward: ForwardParams = field(default_factory=ForwardParams)


class EngineParams(_EngineTable):
    """Tracing parameters: the engine ``name``, ``ab`` (None = from the crown model),
    ``seed``, ``workers``, then one group per engine. Radiance (``params.radiance``): ``ad``,
    ``as_`` (written ``as`` in the file), ``ar``, ``aa``, ``lw``, ``dense_lw``, ``pmap_*``; the
    defaults (``-aa 0 -as 0``: no irradiance cache, no super-sampling) are pure Monte Carlo.
    NumPy engine (``params.numpy``): ``rays`` per sensor (``dense_rays`` per dense-map point),
    ``max_bounces``, ``sampling`` (first directions ``"sobol"``-stratified or ``"random"``).
    Forward engine (``params.forward``): ``photons``, ``forward_*``, ``beam_diameter_m``,
    ``patch_m``, ``target_rel_se``, ``max_photons``."""

    def __init__(self, **given: Any) -> None:
        """The fields by name; a group's flat key (``rays=512``) goes into that group, on top
        of the group given (``dataclasses.replace(params, rays=512)`` works so); an unknown
        key is a TypeError, as for any dataclass."""
        changes: dict[str, dict[str, Any]] = {g: {} for g in GROUPS}
        for key in [k for k in given if k in GROUP_OF]:
            changes[GROUP_OF[key]][key] = given.pop(key)
        for g, cls in GROUPS.items():
            group = given.get(g) or cls()
            given[g] = replace(group, **changes[g]) if changes[g] else group
        super().__init__(**given)

    def changed(self, **changes: Any) -> EngineParams:
        """A copy with ``changes`` (flat keys or common fields, as the constructor takes them):
        ``params.changed(rays=512, max_bounces=ab)``; what ``dataclasses.replace`` does, typed
        for the flat keys."""
        return replace(self, **changes)

    def flat(self) -> dict[str, Any]:
        """The table as the project file holds it: ``{attribute: value}`` of the common
        fields and of every group's (``as_`` keeps its attribute name)."""
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in GROUPS}
        for g in GROUPS:
            group = getattr(self, g)
            out.update({f.name: getattr(group, f.name) for f in fields(group)})
        return out
