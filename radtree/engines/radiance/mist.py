"""Turbid-medium crowns (:mod:`radtree.media`) in Radiance as ``mist`` volumes.

Radiance's ``mist`` (reference manual ``ray.html``, "Mist"; ``src/rt/m_mist.c``,
``src/rt/raytrace.c:rayparticipate``, ``src/rt/source.c:srcscatter``) marks a closed,
outward-facing surface as the boundary of a uniform participating medium::

    mod mist id
    N src1 .. srcN          light sources tested for in-scattering in the volume
    0
    7 σ σ σ  ω ω ω  g       extinction (1/world unit, absorption + scattering), scattering
                            albedo, Henyey–Greenstein eccentricity

What Radiance does with it, read in its source (NREL/Radiance 2fcca99, 2021):

* every ray segment inside is attenuated by exp(−σ·L) (``rayparticipate``) — *except shadow
  rays towards light sources*, which see only the absorbed part, exp(−σ(1 − ω)·L) ("no
  scattering for sources": the scattered share is taken to go on towards the point);
* in-scattering is single scattering of the *listed light sources* only (``srcscatter``: one
  sample per source per segment at ``-ms 0``, the HG phase with g), plus ω·``-av``·(1 − e^{−σL})
  of the constant ambient value (radtree: ``-av 0``); the glow sky and the ground glow are
  distant ``glow`` sources Radiance skips (``SSKIP`` in ``marksources``), so the sky reaches
  a sensor through a crown only attenuated (ambient rays crossing it), never scattered.

So a mist crown cannot hold both the exact uncollided sun and leaf scattering: with ω > 0 the
sun's shadow rays through a crown are too bright by exp(σωL). The same rule gives the sun a
σ of its own, though: with no source listed there is no in-scattering at all, and an albedo
ω = 1 − σ_sun/σ (negative when σ_sun > σ: Radiance does not bound it) makes the shadow rays
see σ(1 − ω) = σ_sun while every other ray sees σ (tests/test_radiance_mist.py checks both
with real ``rtrace``). radtree writes (per crown, per hour, :func:`crown_mist`):

* extinction σ = u · G(μ)·Ω_c · (1 − T_s) per metre — the rate of leaves that deflect a ray,
  the same law as the NumPy engine (:mod:`radtree.engines.common.turbid`); mist is isotropic,
  so one μ (``engine.mist_extinction``): ``"horizontal"`` (default) μ = 0, the paths that
  reach a façade or a window through a street crown run near-horizontally and G(0) is the
  smallest G of leaves tilted less than ~55°, so the light that meets no leaf is at least
  kept; ``"sun"`` μ of the hour's sun; ``"mean"`` the mean over all directions (∫₀¹ G dμ =
  ½ without clumping, Ross 1981 ch. 2); ``"vertical"`` the cosine-weighted mean over the
  directions a vertical surface receives (:func:`vertical_g`);
* the sun (``engine.mist_sun``): ``"beam"`` (default) ω = 1 − σ_sun/σ, no sources, g = 0:
  the sun's uncollided beam through each crown is exactly the NumPy engine's Beer–Lambert
  transmittance, no leaf-scattered light; ``"scatter"`` ω = (R + T_d)/(1 − T_s) and g
  (:func:`leaf_asymmetry`) with the sun listed as the scattered source — Radiance then
  single-scatters the sun into rays crossing a crown but lets its shadow rays through with
  exp(−σ(1 − ω)L); ``"mist"`` ω = 0: the sun sees the mist's σ.
  Radiance applies the HG phase only for g > 0 (``srcscatter``: g ≤ 0 scatters
  isotropically); leaves that reflect more than they transmit diffusely scatter backwards
  (g < 0), so g is written as max(g, 0).

What the form leaves out — the light the leaves scatter (sun and sky, every order) — was
measured against the NumPy engine in ``benchmarks/turbid_radiance.py`` (its docstring holds
the figures, every hour): the default mist reads the reference street's façade (scenario F)
−9.5 ± 0.5 % of the NumPy turbid crowns' light (hours −16 … −4 %), the office example's
façade −31.9 ± 0.2 % and work plane −38.8 ± 0.4 %; the leaves scatter 34 %, 47 % and 55 % of
that light, and the horizontal σ passes +29 … +37 % more than the NumPy engine's uncollided
light. σ at the sun (the first choice one would make) reads −78 … −84 %.

The envelope: each crown's spheroid cut by its half-spaces, as the convex hull
(:class:`scipy.spatial.ConvexHull`) of points on the spheroid (:data:`RINGS` × :data:`SEGMENTS`
latitude–longitude grid), on each cut's ellipse (:data:`SEGMENTS` points) and on the lines
where two cuts meet — a closed, convex, outward-facing triangle mesh (a spheroid and its
half-spaces are convex), written as polygons modified by ``crown_mist.<i>``. Memory: a few
hundred triangles per crown, whatever the leaf count. Overlapping crowns (an inventory) add
their extinctions correctly, but Radiance wants overlapping mists to share albedo and g and
to list disjoint sources (``m_mist.c``): a ray carries one albedo, the last entered mist's.
With ``"beam"`` the albedo 1 − G(μ_sun)/G(μ) depends on the leaf kind only, so crowns of one
species agree; where two species overlap the sun's σ inside the overlap is off, and with
``"scatter"`` leaving the inner of two overlapping crowns drops the sun from the outer's list
for the rest of that segment.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import cache

import numpy as np
from scipy.spatial import ConvexHull

from radtree.config.engine import MIST_EXTINCTION, MIST_SUN, EngineParams
from radtree.engines.radiance.materials import mist_text
from radtree.engines.radiance.meshes import mesh_to_radiance
from radtree.errors import EngineError
from radtree.light.sky import SkyState
from radtree.media import LeafKind, TurbidCrowns
from radtree.optics import Material, Trans
from radtree.scene import Mesh

RINGS = 24        # latitude rings of the envelope (pole to pole)
SEGMENTS = 48     # longitude segments (and points on each cut's ellipse)
EXTINCTION_CHOICES = MIST_EXTINCTION
SUN_CHOICES = MIST_SUN
BEAM_FLOOR = 1e-3   # "beam": σ ≥ 10⁻³ σ_sun (horizontal leaves have G(0) = 0)
SUN_SOURCE = "sun"   # the source's name in the hour's sky (radtree's and gendaylit's)


def mist_name(crown: int) -> str:
    """The mist modifier of crown ``crown``."""
    return f"crown_mist.{crown}"


def _unit_points() -> np.ndarray:
    """The latitude–longitude points of the unit sphere (poles once)."""
    th = np.linspace(0.0, math.pi, RINGS + 1)
    ph = np.linspace(0.0, 2.0 * math.pi, SEGMENTS, endpoint=False)
    st, ct = np.sin(th)[:, None], np.cos(th)[:, None]
    pts = np.stack([st * np.cos(ph), st * np.sin(ph), ct * np.ones_like(ph)], -1)
    return np.unique(pts.reshape(-1, 3).round(12), axis=0)


@cache
def volume_scale() -> float:
    """k = (V_sphere / V_hull)^(1/3) of the unit sphere's inscribed hull: the envelope's
    axes are k·a, k·b so that the polyhedron holds the spheroid's volume (and, a convex body's
    mean chord being 4V/S, nearly its mean path length); at 24 × 48 k − 1 = 2.4·10⁻³ and the
    chords lie within ±0.3 % of the spheroid's."""
    return float((4.0 / 3.0 * math.pi / ConvexHull(_unit_points()).volume) ** (1.0 / 3.0))


def _basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to unit ``n`` and to each other."""
    t = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(n, t)
    u /= np.linalg.norm(u)
    return u, np.cross(n, u)


def _cut_points(centre: np.ndarray, *, a: float, b: float, plane: np.ndarray) -> np.ndarray:
    """Points on the ellipse where the plane n·x = c meets the spheroid (empty: it misses).
    In the spheroid's unit-sphere coordinates the plane is m·q = d, its circle of radius
    √(1 − d²/|m|²) about d·m/|m|²."""
    s = np.array([a, a, b])
    m = plane[:3] * s
    d = plane[3] - plane[:3] @ centre
    mm = float(m @ m)
    r2 = 1.0 - d * d / mm
    if r2 <= 0:
        return np.zeros((0, 3))
    mh = m / math.sqrt(mm)
    u, v = _basis(mh)
    ph = np.linspace(0.0, 2.0 * math.pi, SEGMENTS, endpoint=False)[:, None]
    q = d * m / mm + math.sqrt(r2) * (np.cos(ph) * u + np.sin(ph) * v)
    return centre + q * s


def _edge_points(centre: np.ndarray, *, a: float, b: float, p1: np.ndarray, p2: np.ndarray
                 ) -> np.ndarray:
    """Points along the line where two cut planes meet, inside the spheroid."""
    n = np.cross(p1[:3], p2[:3])
    if np.linalg.norm(n) < 1e-9:
        return np.zeros((0, 3))
    a_mat = np.stack([p1[:3], p2[:3], n])
    x0 = np.linalg.solve(a_mat, np.array([p1[3], p2[3], n @ centre]))
    s = np.array([a, a, b])
    o, e = (x0 - centre) / s, n / s
    qa, qb, qc = e @ e, o @ e, o @ o - 1.0
    disc = qb * qb - qa * qc
    if disc <= 0:
        return np.zeros((0, 3))
    t = np.linspace((-qb - math.sqrt(disc)) / qa, (-qb + math.sqrt(disc)) / qa, RINGS + 1)
    return x0 + t[:, None] * n


def envelope(centre: np.ndarray, *, a: float, b: float, planes: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (k, 3), triangles (m, 3)) of one crown's closed envelope, the triangles
    counter-clockwise seen from outside (outward normals by the right-hand rule, as Radiance
    polygons). ``planes`` (p, 4): keep n·x ≥ c; all-zero rows keep everything."""
    centre = np.asarray(centre, float)
    a, b = a * volume_scale(), b * volume_scale()
    cuts = [pl for pl in np.asarray(planes, float).reshape(-1, 4) if np.any(pl[:3] != 0)]
    pts = [centre + _unit_points() * [a, a, b]]
    pts += [_cut_points(centre, a=a, b=b, plane=pl) for pl in cuts]
    pts += [_edge_points(centre, a=a, b=b, p1=p1, p2=p2) for i, p1 in enumerate(cuts)
            for p2 in cuts[i + 1:]]
    p = np.vstack(pts)
    keep = np.ones(len(p), bool)
    for pl in cuts:
        keep &= p @ pl[:3] >= pl[3] - 1e-9 * max(a, b)
    hull = ConvexHull(p[keep])
    verts = hull.points
    tri = hull.simplices.copy()
    e0, e1 = verts[tri[:, 1]] - verts[tri[:, 0]], verts[tri[:, 2]] - verts[tri[:, 0]]
    flip = np.einsum("ij,ij->i", np.cross(e0, e1), hull.equations[:, :3]) < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    used = np.unique(tri)
    index = np.full(len(verts), -1)
    index[used] = np.arange(len(used))
    return verts[used], index[tri]


def leaf_asymmetry(kind: LeafKind, *, leaf: Trans, mu: float, nodes: int = 400) -> float:
    """g = mean cosine of the scattering angle of a bi-Lambertian leaf canopy for light along
    a direction of |Ω_z| = ``mu``: leaves met with normals of the leaf angle distribution
    weighted by |n·Ω'| (the area scattering phase function, Ross 1981 ch. 6; Shultis & Myneni
    1988, JQSRT 39, 115–129), each scattering R/π·|n·Ω| into the lit side and T_d/π·|n·Ω|
    through; a Lambertian lobe's mean direction is ⅔ of its normal, so per leaf the mean
    scattered cosine is −⅔·|n·Ω'|·(R − T_d)/(R + T_d) and over the leaves met
    g = −⅔ (R − T_d)/(R + T_d) · E[|n·Ω'|²]/E[|n·Ω'|] (inclinations from the kind's CDF,
    azimuths uniform, on ``nodes`` × ``nodes`` midpoints)."""
    r, td = leaf.reflectance, leaf.diffuse_transmittance
    if r + td <= 0:
        return 0.0
    q = (np.arange(nodes) + 0.5) / nodes
    theta = np.interp(q, kind.incl_cdf, kind.incl_edges)[:, None]
    phi = 2.0 * math.pi * q[None, :]
    mu = min(max(float(mu), 0.0), 1.0)
    cos_nw = np.abs(np.cos(theta) * mu + np.sin(theta) * math.sqrt(1.0 - mu * mu) * np.cos(phi))
    ratio = float(np.mean(cos_nw ** 2) / np.mean(cos_nw))
    return -2.0 / 3.0 * (r - td) / (r + td) * ratio


def mean_g(kind: LeafKind, *, nodes: int = 2000) -> float:
    """∫₀¹ G(μ)·Ω_c dμ: the mean effective projection over all directions (½ without
    clumping, Ross 1981 ch. 2)."""
    mu = (np.arange(nodes) + 0.5) / nodes
    return float(np.mean(kind.g(mu)))


def vertical_g(kind: LeafKind, *, nodes: int = 2000) -> float:
    """(4/π) ∫₀¹ G(μ)·Ω_c √(1 − μ²) dμ: G·Ω_c averaged over the directions a vertical
    surface receives light from, cosine-weighted (direction at zenith angle θ, azimuth φ from
    the surface normal: weight sin θ cos φ · sin θ dθ dφ, so μ = |cos θ| has the density
    (2/π)√(1 − μ²) on [−1, 1]) — the paths that light a façade through a crown."""
    mu = (np.arange(nodes) + 0.5) / nodes
    w = np.sqrt(1.0 - mu * mu)
    return float(np.sum(kind.g(mu) * w) / np.sum(w))


def _g_eff(kind: LeafKind, *, extinction: str, sun_mu: float | None) -> float:
    """G·Ω_c of the mist's one extinction (module text)."""
    if extinction == "sun" and sun_mu is not None:
        return float(kind.g(np.array([sun_mu]))[0])
    if extinction == "vertical":
        return vertical_g(kind)
    if extinction == "horizontal":
        return float(kind.g(np.array([0.0]))[0])
    return mean_g(kind)


def crown_mist(media: TurbidCrowns, *, crown: int, leaf: Trans, sun_mu: float | None,
               extinction: str, sun: str) -> tuple[float, float, float]:
    """(σ per metre, albedo ω, HG g) of crown ``crown`` (module text). ``sun_mu``: |Ω_z| of
    the hour's sun (None: no sun — no scattering, and ``"sun"`` takes the mean)."""
    if extinction not in EXTINCTION_CHOICES or sun not in SUN_CHOICES:
        raise ValueError(f"mist extinction must be one of {EXTINCTION_CHOICES} and sun one of "
                         f"{SUN_CHOICES}, got {extinction!r}, {sun!r}")
    kind = media.kinds[int(media.kind[crown])]
    pass_ = 1.0 - leaf.specular_transmittance
    u = float(media.lad[crown])
    sigma = u * _g_eff(kind, extinction=extinction, sun_mu=sun_mu) * pass_
    if sun_mu is None or pass_ <= 0 or sun == "mist":
        return sigma, 0.0, 0.0
    if sun == "beam":     # shadow rays: σ(1 − ω) = σ at the sun's μ
        at_sun = u * float(kind.g(np.array([sun_mu]))[0]) * pass_
        sigma = max(sigma, BEAM_FLOOR * at_sun)
        return sigma, 1.0 - at_sun / sigma, 0.0
    albedo = (leaf.reflectance + leaf.diffuse_transmittance) / pass_
    return sigma, albedo, max(0.0, leaf_asymmetry(kind, leaf=leaf, mu=sun_mu))


def mist_geometry_text(media: TurbidCrowns) -> str:
    """``geometry/crowns_mist.rad``: every crown's envelope (:func:`envelope`) as polygons
    modified by its mist (:func:`mist_name`)."""
    out = [f"# {len(media)} turbid crown(s) as mist volumes: closed convex envelopes "
           f"({RINGS} rings x {SEGMENTS} segments), outward normals\n"]
    for i in range(len(media)):
        verts, tri = envelope(media.centres[i], a=float(media.a[i]), b=float(media.b[i]),
                              planes=media.planes[i])
        out.append(mesh_to_radiance(Mesh(f"crown_envelope.{i}", mist_name(i), verts, tri)))
    return "\n".join(out)


def hour_mist_text(media: TurbidCrowns, *, materials: Mapping[str, Material], state: SkyState,
                   extinction: str, sun: str) -> str:
    """``skies/<HHMM>_mist.rad``: each crown's mist (:func:`crown_mist`) at this hour."""
    lit = state.direct_normal_lux > 0 and state.sun.above_horizon
    sun_mu = abs(float(state.sun.vector[2])) if lit else None
    out = [f"# turbid crowns as mist at {state.time}: extinction {extinction!r}, "
           f"sun {sun!r}\n"]
    for i in range(len(media)):
        leaf = materials[media.kinds[int(media.kind[i])].material]
        if not isinstance(leaf, Trans):
            raise EngineError(f"turbid crowns: leaf material '{leaf.name}' must be a trans "
                              f"material, got {type(leaf).__name__}")
        sigma, albedo, g = crown_mist(media, crown=i, leaf=leaf, sun_mu=sun_mu,
                                      extinction=extinction, sun=sun)
        sources = (SUN_SOURCE,) if sun == "scatter" and albedo > 0 else ()
        out.append(mist_text(mist_name(i), extinction=sigma, albedo=albedo, eccentricity=g,
                             sources=sources))
    return "\n".join(out)


def max_optical_depth(media: TurbidCrowns, materials: Mapping[str, Material], *,
                      extinction: str) -> float:
    """An upper bound of σ·L across one crown for the mists ``extinction`` writes: u · G·Ω_c
    of that choice (``"sun"``: the largest over μ) · (1 − T_s) · 2·max(a, b)."""
    tau = 0.0
    for i in range(len(media)):
        kind = media.kinds[int(media.kind[i])]
        leaf = materials.get(kind.material)
        ts = leaf.specular_transmittance if isinstance(leaf, Trans) else 0.0
        g = (float(np.max(kind.g_eff)) if extinction == "sun"
             else _g_eff(kind, extinction=extinction, sun_mu=None))
        tau = max(tau, float(media.lad[i]) * g * (1.0 - ts) * 2.0 * float(max(media.a[i],
                                                                               media.b[i])))
    return tau


def mist_params(params: EngineParams, media: TurbidCrowns | None,
                materials: Mapping[str, Material]) -> EngineParams:
    """``params`` with ``-lw`` (and the dense maps' ``-lw``) times exp(−τ_max)
    (:func:`max_optical_depth`) when the scene has mist crowns. Radiance gives the ray that
    leaves a mist volume the weight of its parent times exp(−σL) and drops it below ``-lw``
    with no Russian roulette (``rayorigin`` with no coefficient, ``m_mist.c``): at ``-lw
    0.001`` an ambient sample of ``-ad 2048`` (weight ≈ 1/800) lost every path that crossed
    more than τ ≈ 0.2 of a crown — the reference street's façade read 95 % low. Scaled, a ray
    alive before a crown is alive after it (after two crowns in a row it may still be cut);
    the roulette elsewhere keeps its expectation."""
    if media is None or not len(media):
        return params
    f = math.exp(-max_optical_depth(media, materials,
                                    extinction=params.radiance.mist_extinction))
    r = params.radiance
    return params.changed(lw=r.lw * f, dense_lw=None if r.dense_lw is None else r.dense_lw * f)
