"""The volume arrangement of the free-standing louvers crowns (``louvers.arrangement = "volume"``).

Why: the layered free crowns stack ``layers`` lens-shaped slat layers, so every *vertical* line
crosses ``layers`` slats, but a vertical façade sensor looks out near-horizontally, *along* the
layers, and crosses far fewer (the reference case, "first physical check", point 2). A leaf canopy is closer
to a turbid medium: leaves scattered through the crown volume, so the number of leaves met
depends on the path length through the crown and on the projected leaf area along the path,
not on a layer structure.

Geometry. Inside each crown spheroid (horizontal semi-axis a, vertical semi-axis b) slat
centres are drawn uniformly at random (``louvers.seed``); every slat is an s × s square
(``slat_size_m``) with one edge horizontal, its normal m inclined α (``inclination_deg``) from
the vertical at a uniformly random azimuth. The density is

    ρ = crossings · cover_fraction / (s² · cos α · 2b)      slats per m³

(``crossings`` = ``louvers.crossings``, or ``layers`` when it is 0), so that a vertical line
through the crown centre crosses ``crossings · cover_fraction`` slats on average. Each crown
gets round(ρ · V) slats (V = 4/3 π a² b; a crown following its outline, 4/3 b A with
centres uniform in that body, :mod:`radtree.trees.outline`); slats are then treated exactly like the layered free crowns'
(:func:`radtree.trees.crown_clip.touches_share`, :func:`~radtree.trees.crown_clip.cut_to_share`,
:func:`~radtree.trees.crown_clip.trunk_clash`): dropped where they would cut the trunk or lie
wholly outside the crown's share of the row, cut at the wall-side clip plane and at the planes
shared with neighbour crowns. A slat's centre lies in its spheroid; its corners may stand out
by up to s/√2 (the envelope is the centres').

Optics along a path. A slat is crossed by a line of direction Ω when its centre lies in a
prism of cross-section s²·|m·Ω| around the line, so a path of length L through the crown
crosses on average

    λ(Ω) = ρ · s² · G(Ω) · L,      G(Ω) = mean over azimuth of |m·Ω|

slats (Poisson distributed; fixed total count → binomial, indistinguishable at these counts).
G = cos α for vertical Ω and (2/π)·sin α for horizontal Ω (:func:`projection_g`). With slat
specular transmittance T_s the undeviated (direct) transmission is exp(−λ·(1 − T_s)) — the
turbid-medium Beer–Lambert law. For the reference-case crowns (a 5 m, b 4.75 m, s 0.3 m, α 30°) the
horizontal diameter crosses λ_h = 0.387 · crossings slats, the vertical axis ``crossings``.

Clumping (``louvers.clumping`` Ω < 1). The same slats (same count, sizes, inclinations,
azimuths) grouped in spherical clusters of radius ``cluster_radius_m`` scattered uniformly at
random in the crown, each slat uniform in its cluster (:mod:`radtree.trees.clumping`): the
density ρ stays the true one and a path crosses on average Ω·λ(Ω) slats' worth of cover (the
λ figures below are for random slats). Ω = 1 draws exactly the unclumped crown.

Ambient bounces. The light that crosses many slats does so mostly as *specular*
transmission (followed by shadow and specular rays, not ambient bounces); only the diffuse
share (T_d, R) needs ``-ab``. The recommended ``-ab`` therefore does not grow with the
crossing count: min(crossings + 2, :data:`VOLUME_AB_CAP`), measured with
``radtree convergence`` (figures at :data:`VOLUME_AB_CAP`).

Realisations. A façade sensor sees the slats just in front of it at large solid angles, so one
realisation (one ``louvers.seed``) of the reference-case crowns scatters in global permeability by
≈ 10 % (s.d. over 24 seeds at crossings 15; see :func:`radtree.calibrate.permeability.calibrate_crossings`,
which calibrates the mean over seeds). Slats are drawn in fixed blocks, so with one seed a
larger ``crossings`` adds slats to the same crown instead of redrawing it.
"""

from __future__ import annotations

import math

import numpy as np

from radtree.config import Louvers
from radtree.errors import ConfigError
from radtree.trees.clumping import cluster_lad, clustered_slat_centres
from radtree.trees.crown_clip import cut_to_share, touches_share, trunk_clash
from radtree.trees.envelope import CrownRowSpec
from radtree.trees.leaf_angles import draw_inclinations, mean_projection, mean_tilt, projection_g

MAX_VOLUME_SLATS = 200_000
DRAW_BLOCK = 1024  # slats drawn per block (nested realisations, see _draw_nested)
# Radiance -ab for volume crowns: light crossing many slats does so mostly by specular
# transmission, which needs no ambient bounce, so the façade mean converges by -ab 6 (within
# 0.1 % on reference-case F); `radtree convergence examples/mendoza-street -s F` prints the
# ladder, figures in docs/benchmarks.md.
VOLUME_AB_CAP = 6


def crossings_of(lv: Louvers) -> float:
    """Mean slat crossings of a vertical line through the crown centre, before cover."""
    return float(lv.crossings) if lv.crossings > 0 else float(lv.layers)


def mean_cos(lv: Louvers) -> float:
    """Mean |cos| of the slat normals with the vertical: cos α, or over the ellipsoidal
    distribution (:mod:`radtree.trees.leaf_angles`)."""
    if lv.inclination_distribution == "ellipsoidal":
        return float(mean_projection(np.array([1.0]), lv.ellipsoid_x)[0])
    return math.cos(math.radians(lv.inclination_deg))


def slat_g(mu: float, lv: Louvers) -> float:
    """The slats' mean projection G for |Ω_z| = mu."""
    if lv.inclination_distribution == "ellipsoidal":
        return float(mean_projection(np.array([mu]), lv.ellipsoid_x)[0])
    return float(projection_g(mu, lv.inclination_deg))


def volume_density(lv: Louvers, b: float) -> float:
    """Slats per m³: ρ = crossings · cover / (s² cos α · 2b) (cos α: :func:`mean_cos`)."""
    s = lv.slat_size_m
    return crossings_of(lv) * lv.cover_fraction / (s * s * mean_cos(lv) * 2.0 * b)


def volume_slat_bound(spec: CrownRowSpec, lv: Louvers) -> int:
    """Slats drawn (before dropping): count · round(ρ · 4/3 π a² b)."""
    per = volume_density(lv, spec.b) * spec.crown_volume()
    return spec.count * int(round(per))


def recommended_volume_ab(lv: Louvers) -> int:
    """Radiance -ab for volume crowns: ⌈crossings⌉ + 2, capped at :data:`VOLUME_AB_CAP` (6).

    Why the cap suffices: see the comment at :data:`VOLUME_AB_CAP` (figures in the guide's
    Validation page).
    """
    return int(min(math.ceil(crossings_of(lv)) + 2, VOLUME_AB_CAP))


def volume_ab_note(ab: int) -> str:
    """The crown notes' line on ``-ab`` for volume crowns (the reasoning and figures of the
    comment at :data:`VOLUME_AB_CAP`)."""
    return (f"Radiance: -ab {ab} (crossings + 2, capped at 6: light crossing many "
            "slats does so mostly by specular transmission, which needs no ambient "
            "bounce; on reference-case scenario F, crossings 15, the façade mean moved 0.1 % "
            "from -ab 6 to -ab 8 at 13:30 (1457 → 1456 lx) and to -ab 12 at 10:30 "
            "(1089 → 1090 lx), and −1.1 % from -ab 6 to -ab 5 — check with radtree "
            "convergence).")


def clipped_volume(spec: CrownRowSpec, samples: int = 400_000, seed: int = 0
                   ) -> tuple[float, float]:
    """(volume, standard error) in m³ of the union of the clipped crowns, by Monte Carlo."""
    r = spec.max_radius
    lo = spec.centres.min(axis=0) - [r, r, spec.b]
    hi = spec.centres.max(axis=0) + [r, r, spec.b]
    lo[1] = max(lo[1], spec.n_clip)
    box = float(np.prod(hi - lo))
    rng = np.random.default_rng(seed)
    p = lo + rng.random((samples, 3)) * (hi - lo)
    frac = float(np.mean(spec.inside(p)))
    return box * frac, box * math.sqrt(frac * (1.0 - frac) / samples)


def _draw_nested(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The first ``n`` of a stream of (point uniform in the unit ball, azimuth) pairs, drawn in
    blocks of :data:`DRAW_BLOCK`: a larger ``n`` adds slats and keeps the first ones, so with a
    fixed seed the crown's realisation grows with the crossings instead of being redrawn."""
    xs, phis = [], []
    for _ in range(max(1, -(-n // DRAW_BLOCK))):
        d = rng.standard_normal((DRAW_BLOCK, 3))
        d /= np.linalg.norm(d, axis=1)[:, None]
        xs.append(d * rng.random(DRAW_BLOCK)[:, None] ** (1.0 / 3.0))
        phis.append(rng.uniform(0.0, 2.0 * math.pi, DRAW_BLOCK))
    return np.concatenate(xs)[:n], np.concatenate(phis)[:n]


def _slat_corners(centres: np.ndarray, phi: np.ndarray, s: float,
                  alpha: float | np.ndarray) -> np.ndarray:
    """(k, 4, 3) corners of s × s squares, normal inclined ``alpha`` (rad; one or one per
    slat) at azimuth ``phi``, one edge horizontal."""
    e1, e2 = slat_edges(phi, alpha)    # horizontal edge, up the slope
    h1 = np.array([-0.5, 0.5, 0.5, -0.5]) * s
    h2 = np.array([-0.5, -0.5, 0.5, 0.5]) * s
    return (centres[:, None, :] + h1[None, :, None] * e1[:, None, :]
            + h2[None, :, None] * e2[:, None, :])


def slats_per_crown(spec: CrownRowSpec, lv: Louvers) -> int:
    """Slats drawn in each crown: round(ρ · V), V = 4/3 π a² b for the spheroid, 4/3 b A
    for a crown following its outline (:meth:`CrownRowSpec.crown_volume`)."""
    return int(round(volume_density(lv, spec.b) * spec.crown_volume()))


def draw_crown_slats(rng: np.random.Generator, spec: CrownRowSpec, lv: Louvers, ti: int,
                     per: int) -> tuple[np.ndarray, np.ndarray, float | np.ndarray, int]:
    """Crown ``ti``'s ``per`` slats before any clipping: centres (local m; in clusters when
    ``lv.clumping`` < 1, :mod:`radtree.trees.clumping`), normal azimuths φ and inclinations
    (rad; one for a fixed inclination), and the number of clusters (0 unclumped)."""
    c = spec.centres[ti]
    x, phi = _draw_nested(rng, per)
    n_cl = 0
    if lv.clumping < 1.0:   # slats grouped in clusters
        centres, n_cl = clustered_slat_centres(
            np.random.default_rng([lv.seed, ti, 11]), x, c, to_crown=spec.from_ball,
            slat=lv.slat_size_m, omega=lv.clumping, radius=lv.cluster_radius_m)
    else:
        centres = c + spec.from_ball(x)
    tilt: float | np.ndarray = math.radians(lv.inclination_deg)
    if lv.inclination_distribution == "ellipsoidal":
        tilt = draw_inclinations(np.random.default_rng([lv.seed, ti, 7]), per, lv.ellipsoid_x)
    return centres, phi, tilt, n_cl


def slat_edges(phi: np.ndarray, tilt: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit edge vectors (k, 3) of the slats of :func:`_slat_corners`: horizontal, up the
    slope."""
    ca = np.broadcast_to(np.cos(tilt), phi.shape)
    sa = np.broadcast_to(np.sin(tilt), phi.shape)
    cp, sp = np.cos(phi), np.sin(phi)
    e1 = np.stack([-sp, cp, np.zeros_like(phi)], axis=1)
    e2 = np.stack([-ca * cp, -ca * sp, sa], axis=1)
    return e1, e2


def build_volume_louvers(spec: CrownRowSpec, lv: Louvers, source: str | None = None
                         ) -> tuple[list[np.ndarray], dict[str, float]]:
    """Slat polygons (local coordinates) of the volume arrangement and geometry info."""
    s = lv.slat_size_m
    if mean_cos(lv) < 1e-6:
        raise ConfigError("vertical slats (inclination 90°) give no vertical crossings: the "
                          "volume density is undefined", source=source,
                          field="tree.louvers.inclination_deg")
    bound = volume_slat_bound(spec, lv)
    if bound > MAX_VOLUME_SLATS:
        raise ConfigError(f"the volume louvers would need {bound} slats (limit "
                          f"{MAX_VOLUME_SLATS}): use larger slats (tree.louvers.slat_size_m) or "
                          "fewer crossings", source=source, field="tree.louvers.slat_size_m")
    rho = volume_density(lv, spec.b)
    a, b = spec.a, spec.b
    per = slats_per_crown(spec, lv)
    polys: list[np.ndarray] = []
    cut = dropped_trunk = in_crown = clusters = 0
    for ti, child in enumerate(np.random.SeedSequence(lv.seed).spawn(spec.count)):
        rng = np.random.default_rng(child)
        c = spec.centres[ti]
        lo, hi = spec.strips[ti]
        centres, phi, tilt, n_cl = draw_crown_slats(rng, spec, lv, ti, per)
        clusters += n_cl
        corners = _slat_corners(centres, phi, s, tilt)
        rho_plan = np.hypot(centres[:, 0] - c[0], centres[:, 1] - c[1])
        clash = trunk_clash(rho_plan, corners[:, :, 2].min(axis=1), spec, s)
        ok = touches_share(corners, spec, lo, hi) & ~clash
        dropped_trunk += int(np.sum(clash))
        own = ((centres[:, 1] >= spec.n_clip) & (centres[:, 0] >= lo) & (centres[:, 0] <= hi))
        in_crown += int(np.sum(own & ~clash))
        kept, n_cut = cut_to_share(corners[ok], spec, lo, hi)
        polys.extend(kept)
        cut += n_cut
    volume, volume_se = clipped_volume(spec)
    g_v, g_h = slat_g(1.0, lv), slat_g(0.0, lv)
    info = {
        "slat_bound": float(bound), "slats_drawn": float(per * spec.count),
        "slats_cut": float(cut), "slats_dropped": float(dropped_trunk),
        "slats_centre_in_crown": float(in_crown),
        "slat_mean_area_m2": s * s, "density_per_m3": rho,
        "crossings": crossings_of(lv),
        "crown_volume_m3": volume, "crown_volume_se_m3": volume_se,
        "expected_slats_in_crown": rho * volume,
        "g_vertical": g_v, "g_horizontal": g_h,
        "lambda_vertical_per_m": rho * s * s * g_v,
        "lambda_horizontal_per_m": rho * s * s * g_h,
        "lambda_vertical": rho * s * s * g_v * 2.0 * b,
        "lambda_horizontal": rho * s * s * g_h * 2.0 * a,
    }
    if lv.clumping < 1.0:   # λ above are for random slats; clumped ones cross Ω times as many
        info.update({"clumping": lv.clumping, "clusters": float(clusters),
                     "cluster_radius_m": lv.cluster_radius_m,
                     "cluster_lad_m2_m3": cluster_lad(lv.clumping, lv.cluster_radius_m, s)})
    return polys, info


def volume_note(lv: Louvers, info: dict[str, float], slats: int, t_specular: float) -> str:
    """What the volume arrangement built, for the notes."""
    lam_v, lam_h = info["lambda_vertical"], info["lambda_horizontal"]
    return (
        f"Louvers, volume arrangement: {slats} slats of {lv.slat_size_m:g} m × "
        f"{lv.slat_size_m:g} m inclined {_tilt_text(lv)} at random azimuths, centres "
        f"uniform at random in the crowns, density {info['density_per_m3']:.2f} slats/m³ "
        f"(crossings {info['crossings']:g} × cover {lv.cover_fraction:g} on a vertical line "
        f"through a crown centre); clipped crown volume {info['crown_volume_m3']:.0f} m³ "
        f"({int(info['slats_cut'])} slats cut at the wall-side or shared planes, "
        f"{int(info['slats_dropped'])} dropped at the trunks). Mean slats crossed (Poisson): "
        f"λ vertical {info['lambda_vertical_per_m']:.3f}/m, {lam_v:.2f} through the centre "
        f"(2b); λ horizontal {info['lambda_horizontal_per_m']:.3f}/m, {lam_h:.2f} through the "
        f"centre (2a). Direct (specular, T_s {t_specular:.3f}) transmission exp(−λ(1 − T_s)): "
        f"vertical {math.exp(-lam_v * (1 - t_specular)):.3g}, horizontal "
        f"{math.exp(-lam_h * (1 - t_specular)):.3g}." + _clumping_text(info))


def _clumping_text(info: dict[str, float]) -> str:
    """The clusters of clumped slats (louvers.clumping < 1), for the notes."""
    if "clumping" not in info:
        return ""
    return (f" Clumped foliage: the slats grouped in {int(info['clusters'])} spherical "
            f"clusters of radius {info['cluster_radius_m']:g} m (leaf area density "
            f"{info['cluster_lad_m2_m3']:.2f} m²/m³ inside a cluster) at random in the crowns, "
            f"clumping index Ω = {info['clumping']:.3f}: the mean gap along a path is that of "
            f"random slats at Ω times the density (the λ above are for random slats).")


def _tilt_text(lv: Louvers) -> str:
    if lv.inclination_distribution == "ellipsoidal":
        return (f"as drawn from Campbell's ellipsoidal distribution x = {lv.ellipsoid_x:.3g} "
                f"(mean {mean_tilt(lv.ellipsoid_x):.1f}°)")
    return f"{lv.inclination_deg:g}°"
