"""The physics suite's checks: each returns :class:`Check` rows (what ``verify.csv`` holds).

* :func:`transmission_checks` — uncollided transmission through horizontally homogeneous
  layers of random discrete black leaves (LAI 1 and 3; spherical, planophile, erectophile;
  sun zenith 0°, 30°, 60°) against exp(−G(θ)·LAI/cos θ), by the forward engine (horizontal
  patch detectors under the layer) and the NumPy engine (direct sun at random points there):
  within 1 % or 3 standard errors (over independent leaf layers).
* :func:`energy_checks` — leaves with r + t = 1 over a white Lambertian floor send all the flux
  back up (≤ 0.5 %); over a black floor reflected + transmitted + absorbed = launched, and the
  floor's detector tiles tally what the floor absorbed.
* :func:`agreement_checks` — forward vs every backward engine available (NumPy, Radiance) on
  the reduced Mendoza louvers dome (:data:`radtree.verify.compare.REDUCED_DOME`), façade
  patch mean within 2 % or 3 combined standard errors.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from radtree.config import EngineParams, Project
from radtree.engines.forward import ForwardSettings, trace_forward
from radtree.engines.forward.interface import ForwardEngine
from radtree.engines.numpy.scenes import sky_state
from radtree.engines.registry import engine_class
from radtree.optics import Plastic, Trans
from radtree.scene import Mesh, Scene, SensorGrid, quad
from radtree.verify.compare import backward_patch_mean, backward_patch_values, reduced_dome_project
from radtree.verify.leaves import LEAF_DISTRIBUTIONS, leaf_layer, uncollided_transmission
from radtree.verify.spheres import place_spheres, sphere_leaves, sphere_transmission

log = logging.getLogger(__name__)

FORWARD = ForwardEngine.name  # the Check rows' engine label
DNI = 100000.0
UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Check:
    """One verified number against an independent ``reference``.

    ``tolerance`` is what |got − expected| is held to (the claim, or 3 standard errors when
    the measurement's noise is wider); ``claim`` (None: ``tolerance``) is what the physics
    claims. :attr:`status`: ``pass`` when the difference is within the tolerance *and* the
    tolerance is no wider than the claim; ``fail`` when the difference exceeds the tolerance;
    ``unresolved`` when it is within a tolerance wider than the claim (the run is too noisy to
    confirm the claim: no pass)."""

    check: str
    engine: str
    expected: float
    got: float
    tolerance: float
    claim: float | None = None
    reference: str = ""

    @property
    def status(self) -> str:
        if not abs(self.got - self.expected) <= self.tolerance:
            return "fail"
        claim = self.tolerance if self.claim is None else self.claim
        return "pass" if self.tolerance <= claim * (1.0 + 1e-12) else "unresolved"

    @property
    def passed(self) -> bool:
        return self.status == "pass"

    def row(self) -> dict:
        return {"check": self.check, "engine": self.engine, "expected": self.expected,
                "got": self.got, "tolerance": self.tolerance,
                "claim": self.tolerance if self.claim is None else self.claim,
                "status": self.status, "passed": self.passed, "reference": self.reference}


def _tolerance(expected: float, se: float, rel: float) -> float:
    return max(rel * abs(expected), 3.0 * se)


def _checked(name: str, engine: str, expected: float, got: float, se: float, rel: float,
             reference: str) -> Check:
    """A check claiming ``rel`` (relative): held to max(claim, 3 SE) (:class:`Check`)."""
    return Check(name, engine, expected, got, _tolerance(expected, se, rel),
                 rel * abs(expected), reference)


def _square(name: str, material: str, half: float, z: float = 0.0) -> Mesh:
    return quad(name, material, np.array([[-half, -half, z], [half, -half, z],
                                          [half, half, z], [-half, half, z]], float))


# ----------------------------------------------------------------- Beer–Lambert


ZENITHS = (0.0, 30.0, 60.0)
LAIS = (1.0, 3.0)


@dataclass(frozen=True)
class LayerPlan:
    """How :func:`transmission_checks` samples the leaf layers: ``detectors`` × ``detectors``
    horizontal 1 m detectors under a layer of side ``detectors`` + 4 m (2 m of layer beyond the
    detectors on every side: the slant path at 60° crosses the layer within 1.82 m), square
    leaves of side ``leaf`` (m); the forward engine's sun beam just holds the detectors. Leaf
    placement noise (the realised layer's own gaps) dominates the spread of the detector
    values, and its variance scales as leaf side² / detector area, so the long run uses smaller
    leaves over a larger area (Beer–Lambert holds for any leaf size in a Poisson layer).
    ``realisations``: the most independent layers; with ``resolve`` (a fraction of the claim)
    layers are added one at a time, after ``min_realisations``, until every zenith's 3 SE is
    within ``resolve`` × claim (sequential stopping: the same rule for every row, stated on the
    page)."""

    detectors: int = 6
    leaf: float = 0.07
    realisations: int = 4
    min_realisations: int = 2
    resolve: float | None = None

    @property
    def extent(self) -> float:
        return self.detectors + 4.0

    @property
    def beam(self) -> float:
        return float(math.ceil(self.detectors * math.sqrt(2.0)))


def _layer_scene(lai: float, distribution: str, seed: int, plan: LayerPlan) -> Scene:
    """Black leaves in a square layer (z 1–2 m, :attr:`LayerPlan.extent`), the plan's 1 m
    detectors (facing up) just below it: no floor, so only uncollided sunlight reaches them."""
    layer = leaf_layer("leaves", "black", lai=lai, distribution=distribution,
                       extent=plan.extent, z_bottom=1.0, z_top=2.0, size=plan.leaf,
                       rng=np.random.default_rng(seed))
    xs = np.arange(plan.detectors) - (plan.detectors - 1) / 2.0
    X, Y = np.meshgrid(xs, xs)
    det = SensorGrid("facade", np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, 0.95)]),
                     np.tile(UP, (X.size, 1)))
    return Scene([layer], {"black": Plastic("black", 0.0)}, {"facade": det})


def _detector_transmission(engine: str, scene: Scene, zenith: float, *, photons: int,
                           points: int, seed: int, beam: float) -> np.ndarray:
    """Uncollided transmission on each detector under the sun at ``zenith``: the forward
    engine launches a ``beam`` m sun beam of ``photons``; a backward engine traces the direct
    sun at ``points`` stratified points per detector (two in each cell, m × m cells)."""
    st = sky_state("none", altitude=90.0 - zenith, azimuth=0.0, dni=DNI, ground_glow=False)
    direct = DNI * math.cos(math.radians(zenith))
    if engine_class(engine).photon_budget:
        res = trace_forward(scene, st, ForwardSettings(
            photons=photons, batches=4, max_bounces=0, beam_diameter_m=beam, patch_m=1.0,
            seed=seed))
        value = res.grids["facade"].lux
    else:
        value = backward_patch_values(engine, scene, st, "facade", 1.0, ab=0, points=points,
                                      rays=1, seed=seed, stratified=True).mean(axis=1)
    return np.asarray(value) / direct


def _mean_se(v: list[float]) -> tuple[float, float]:
    a = np.asarray(v, float)
    return float(a.mean()), (float(a.std(ddof=1) / math.sqrt(len(a))) if len(a) > 1 else 0.0)


def _layer_rows(lai: float, dist: str, engines: tuple[str, ...], zeniths: tuple[float, ...],
                plan: LayerPlan, photons: int, points: int) -> dict[tuple[str, float], list]:
    """Detector transmissions per (engine, zenith) over the plan's leaf layers."""
    got: dict[tuple[str, float], list[float]] = {(e, z): [] for e in engines for z in zeniths}
    for r in range(plan.realisations):
        scene = _layer_scene(lai, dist, 1000 + r, plan)
        for z in zeniths:
            expected = uncollided_transmission(dist, lai, z)
            for e in engines:
                got[e, z].extend(_detector_transmission(
                    e, scene, z, photons=int(photons / max(expected, 0.05)), points=points,
                    seed=r + 1, beam=plan.beam))
        if plan.resolve is not None and r + 1 >= plan.min_realisations and all(
                3.0 * _mean_se(v)[1] <= plan.resolve * 0.01 * uncollided_transmission(
                    dist, lai, z) for (_e, z), v in got.items()):
            log.info(f"LAI {lai:g} {dist}: resolved after {r + 1} layers")
            break
    return got


def transmission_checks(*, realisations: int = 4, photons: int = 20_000, points: int = 72,
                        leaf: float = 0.07, engines: tuple[str, ...] = (FORWARD,),
                        lais: tuple[float, ...] = LAIS,
                        distributions: tuple[str, ...] = LEAF_DISTRIBUTIONS,
                        zeniths: tuple[float, ...] = ZENITHS, plan: LayerPlan | None = None
                        ) -> list[Check]:
    """Uncollided transmission for LAI 1 and 3 × the three leaf-angle distributions × sun
    zenith 0°, 30°, 60°: mean over the detectors of independent layers (``plan``, default
    6 × 6 detectors, ``leaf`` m leaves, ``realisations`` layers), its standard error from the
    spread of those (nearly independent) detector values: photon and leaf-placement noise
    together. The forward engine launches ``photons`` / T photons (T the expected
    transmission, at most 20×) in a beam just holding the detectors; a backward engine (e.g.
    ``numpy``) traces the direct sun at ``points`` stratified points per detector."""
    plan = plan or LayerPlan(leaf=leaf, realisations=realisations)
    out = []
    for lai in lais:
        for dist in distributions:
            got = _layer_rows(lai, dist, engines, zeniths, plan, photons, points)
            for z in zeniths:
                expected = uncollided_transmission(dist, lai, z)
                name = f"uncollided transmission LAI {lai:g} {dist} zenith {z:g}°"
                for e in engines:
                    mean, se = _mean_se(got[e, z])
                    out.append(_checked(name, e, expected, mean, se, 0.01,
                                        "exp(−G(θ)·LAI/cos θ) (Beer–Lambert, Ross G)"))
                    log.info(f"{name}: expected {expected:.5f}, {e} {mean:.5f} ± {se:.5f} "
                             f"({len(got[e, z]) // plan.detectors ** 2} layers)")
    return out


# ----------------------------------------------------------------- floating spheres


def sphere_checks(*, realisations: int = 2, photons: int = 100_000, points: int = 32,
                  engines: tuple[str, ...] = (FORWARD,), zeniths: tuple[float, ...] = ZENITHS
                  ) -> list[Check]:
    """Uncollided transmission under RAMI-HET01-like floating spheres
    (:mod:`radtree.verify.spheres`; black leaves, no floor) on 36 horizontal 1 m detectors
    (6 m × 6 m at the floor) against the numerical integral over each detector of
    exp(−G·u·Σ chords); ``realisations`` independent leaf placements in one sphere layout
    (forward: ``photons`` in a 9 m beam; backward: ``points`` stratified points per detector,
    :func:`_detector_transmission`). Standard error from the spread of (got − expected) over
    detectors and realisations."""
    spheres = place_spheres(np.random.default_rng(5))
    xs = np.arange(-2.5, 3.0, 1.0)
    X, Y = np.meshgrid(xs, xs)
    pts = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, 0.01)])
    det = SensorGrid("facade", pts, np.tile(UP, (X.size, 1)))
    diffs: dict[tuple[str, float], list[np.ndarray]] = {(e, z): [] for e in engines
                                                        for z in zeniths}
    expect: dict[float, np.ndarray] = {}
    for r in range(realisations):
        leaves = sphere_leaves("leaves", "black", spheres, np.random.default_rng(2000 + r))
        scene = Scene([leaves], {"black": Plastic("black", 0.0)}, {"facade": det})
        for z in zeniths:
            if z not in expect:
                sun = sky_state("none", altitude=90.0 - z, azimuth=0.0, dni=DNI,
                                ground_glow=False).sun
                expect[z] = sphere_transmission(pts, 1.0, np.asarray(sun.vector, float), spheres)
            for e in engines:
                diffs[e, z].append(_detector_transmission(
                    e, scene, z, photons=photons, points=points, seed=r + 1, beam=9.0)
                    - expect[z])
    out = []
    for z in zeniths:
        expected = float(expect[z].mean())
        name = f"floating spheres (RAMI HET01 / 10) uncollided transmission zenith {z:g}°"
        for e in engines:
            d = np.concatenate(diffs[e, z])
            se = float(d.std(ddof=1) / math.sqrt(len(d)))
            out.append(_checked(name, e, expected, expected + float(d.mean()), se, 0.01,
                                "numerical integral of the spheres' shadows (RAMI HET01)"))
            log.info(f"{name}: expected {expected:.4f}, {e} "
                     f"{expected + float(d.mean()):.4f} ± {se:.4f}")
    return out


# ----------------------------------------------------------------- energy


def _canopy(material: str, floor: str, floor_half: float) -> list[Mesh]:
    return [leaf_layer("leaves", material, lai=2.0, distribution="spherical", extent=3.0,
                       z_bottom=0.5, z_top=1.5, size=0.15, rng=np.random.default_rng(3)),
            _square("floor", floor, floor_half)]


def energy_checks(photons: int = 40_000) -> list[Check]:
    """Flux conservation of the forward engine (a 2 m sun beam on a 3 m leaf layer)."""
    out = []
    st = sky_state("none", altitude=60.0, azimuth=0.0, dni=DNI, ground_glow=False)
    target = {"facade": SensorGrid("facade", np.array([[0, 0, 0.01]]), UP[None, :])}
    white = Scene(_canopy("leaf", "floor", 500.0),
                  {"leaf": Trans("leaf", 0.45, 0.45, 0.10), "floor": Plastic("floor", 1.0)},
                  target)
    r = trace_forward(white, st, ForwardSettings(photons=photons, max_bounces=200,
                                                 max_specular=200, threshold=0.001,
                                                 beam_diameter_m=2.0))
    led = r.ledger
    out.append(Check("energy: r + t = 1 leaves over a white floor, fraction sent back up",
                     FORWARD, 1.0, led.escaped_up / led.launched, 0.005,
                     reference="energy conservation (r + t = 1, white floor)"))
    xs = np.arange(-11.0, 12.0, 2.0)
    X, Y = np.meshgrid(xs, xs)
    tiles = SensorGrid("floor_tiles", np.column_stack([X.ravel(), Y.ravel(),
                                                       np.full(X.size, 1e-3)]),
                       np.tile(UP, (X.size, 1)))
    black = Scene(_canopy("leaf", "floor", 12.0),
                  {"leaf": Trans("leaf", 0.10, 0.15, 0.30), "floor": Plastic("floor", 0.0)},
                  {**target, "floor_tiles": tiles})
    r = trace_forward(black, st, ForwardSettings(photons=photons, max_bounces=50,
                                                 threshold=0.001, beam_diameter_m=2.0,
                                                 patch_m=2.0))
    led = r.ledger
    floor = led.absorbed_by("floor")
    rta = led.escaped_up + floor + led.escaped_down + led.absorbed_by("leaf")
    out.append(Check("energy: black floor, (reflected + transmitted + absorbed) / launched",
                     FORWARD, 1.0, rta / led.launched, 0.005,
                     reference="energy conservation (photon ledger)"))
    tallied = float(r.grids["floor_tiles"].lux.sum()) * 4.0
    out.append(Check("energy: black floor, detector tiles' flux / flux absorbed by the floor",
                     FORWARD, 1.0, tallied / floor, 1e-4,
                     reference="the floor's absorbed flux (photon ledger)"))
    return out


# ----------------------------------------------------------------- estimator agreement


@dataclass(frozen=True)
class BackwardPlan:
    """How one backward engine is sampled in :func:`agreement_checks`: ``points`` stratified
    points per 0.5 m patch (two in each cell of an m × m grid: ``points`` = 2 m²,
    :func:`radtree.verify.compare.patch_points`), ``rays`` paths per point (NumPy), ``ad``
    (Radiance ``-ad``; None = the project's) and the ``hours`` compared (None = every hour of
    the check)."""

    points: int = 32
    rays: int = 96
    ad: int | None = 256
    hours: tuple[str, ...] | None = None


def agreement_forward(project: Project, ab: int, photons: int, rel_se: float | None,
                      max_photons: int) -> ForwardSettings:
    """The forward estimator of the agreement rows: the project's (focused launch, guided
    diffuse directions, Russian roulette) with the sun's direct beam tallied on the patches
    like every other photon (``direct_sun`` off: the default computes it at the sensor points,
    not the patch mean the backward engines are sampled for), seed 7; rounds of ``photons``
    until the façade mean's relative standard error is ``rel_se`` (None: one round) or
    ``max_photons``."""
    from dataclasses import replace

    return replace(ForwardSettings.from_params(project.engine, ab), photons=photons, seed=7,
                   direct_sun=False, target_rel_se=rel_se,
                   max_photons=max(max_photons, photons))


def _plan_params(project: Project, plan: BackwardPlan) -> EngineParams:
    ad = plan.ad
    return project.engine if ad is None else project.engine.changed(ad=int(ad))


def forward_target(backward_rel_se: list[float], claim: float = 0.02, share: float = 0.9,
                   floor: float = 0.002) -> float:
    """The forward run's relative standard error that brings 3 combined standard errors to
    ``share`` × ``claim`` against the noisiest backward estimate (relative SEs), at least
    ``floor``."""
    room = (share * claim / 3.0) ** 2 - max(backward_rel_se, default=0.0) ** 2
    return max(math.sqrt(room) if room > 0 else 0.0, floor)


def agreement_checks(*, hours: tuple[str, ...] = ("12:30",), scenarios: tuple[str, ...] = ("A",),
                     photons: int = 4_000_000, backward: list[str] | None = None,
                     crown: str = "louvers dome", plans: dict[str, BackwardPlan] | None = None,
                     rel_se: float | None = None, max_photons: int = 0) -> list[Check]:
    """Forward vs backward engines on the reduced Mendoza louvers dome (or another ``crown``
    of :data:`radtree.verify.compare.REDUCED`): the 8 sensors' 0.5 m
    patch mean per scenario and hour (expected = the backward engine's value). Each backward
    engine is sampled by its entry of ``plans`` (default :class:`BackwardPlan`) first; the
    forward engine (:func:`agreement_forward`) then runs ``photons`` once (``rel_se`` None) or
    in rounds to :func:`forward_target` of the backward errors (at least ``rel_se``, at most
    ``max_photons``)."""
    from radtree.engines.registry import available_engines
    from radtree.light.hours import hour_states
    from radtree.pipeline.assemble import make_scene

    names = backward if backward is not None else [
        e.name for e in available_engines() if not e.photon_budget]
    plan_of = {e: (plans or {}).get(e, BackwardPlan()) for e in names}
    out = []
    for hour in hours:
        active = [e for e in names if hour in (plan_of[e].hours or (hour,))]
        if not active:
            continue
        proj = reduced_dome_project(hour, crown=crown)
        for name in scenarios:
            sc = proj.scenario(name)
            built = make_scene(proj, sc, dense_grid=False)
            st = hour_states(proj, sc, [hour])[0]
            bws = {e: backward_patch_mean(
                e, built.scene, st, "facade", 0.5, ab=built.ab, points=plan_of[e].points,
                rays=plan_of[e].rays, stratified=True,
                params=_plan_params(proj, plan_of[e])) for e in active}
            target = None if rel_se is None else max(rel_se, forward_target(
                [b.stderr / max(b.lux, 1e-9) for b in bws.values()]))
            fw = trace_forward(built.scene, st, agreement_forward(
                proj, built.ab, photons, target, max_photons), ["facade"])
            got, se = fw.grid_mean("facade")
            for e, bw in bws.items():
                label = (f"agreement: reduced Mendoza {crown} {name} {hour}, façade patch "
                         f"mean, forward vs {e}")
                out.append(_checked(label, FORWARD, bw.lux, got, math.hypot(se, bw.stderr),
                                    0.02, f"{e} backward engine, same scene"))
                log.info(f"{label}: {e} {bw.lux:.1f} ± {bw.stderr:.1f}, forward "
                         f"{got:.1f} ± {se:.1f} ({fw.photons} photons)")
    return out


def log_checks(checks: list[Check], logger: logging.Logger) -> list[Check]:
    """Log one line per check (expected, got, ok/FAILED) to ``logger``; return ``checks``."""
    for c in checks:
        logger.info(f"{c.check}: expected {c.expected:.4g}, got {c.got:.4g} "
                    f"({'ok' if c.passed else 'FAILED'})")
    return checks
