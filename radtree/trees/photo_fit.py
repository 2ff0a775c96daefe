"""Free crowns fitted to upward photos taken under them (``photo_direction = "upward"``).

The free louvers crowns of the volume arrangement are a turbid medium: slat centres uniform
in the clipped crown spheroids, leaf (slat) area density u = ρ·s² (m²/m³), normals from a
leaf-inclination distribution with random azimuths. Seen from the camera point c, a direction
Ω crossing the crowns over a path L(Ω) is sky with probability

    P(Ω) = exp(−u · G(|Ω_z|) · L(Ω))        (0 where Ω meets a trunk)

(Beer–Lambert; G from the slats' own distribution, :func:`radtree.trees.leaf_angles.
mean_projection`). The photo's gap fraction per zenith ring (:mod:`radtree.hemi`, 9 rings over
0–``photo_zenith_deg``, T_i the mean of its ring × segment cells T_ij) is matched by least
squares on the contact-number scale, Σ_i w_i (ln P̄_i(u, x) − ln T_i)² (floored at hemi's
gap floor; w_i the ring's share of the analysed solid angle, so the small rings near the lens
axis, crossed by few leaves, do not dominate) — the scale hemi's LAI is computed on, so the fitted crown reproduces the photo's LAI
and its ring gap fractions; P̄_ij is the solid-angle mean of P over a cell
(:data:`CELL_SAMPLES` directions per cell, L from the ray's intersections with the clipped
spheroids, :func:`crown_paths`).
The fit scans log u × log x (61 × 15 points) and refines the best point with L-BFGS-B;
hemi's own ellipsoidal x / mean tilt and LAI of the photo are reported beside it. With ``louvers.inclination_distribution = "fixed"``
only u is fitted (the inclination stays ``inclination_deg``, e.g. the study's 30°).

Clumping (:mod:`radtree.trees.clumping`): with ``louvers.clumping`` Ω < 1 the crown's slats
are grouped in clusters and the model's gap is exp(−u·G·Ω·L) (Ω per direction,
:func:`~radtree.trees.clumping.clumped_g`), so the fitted u is the *true* density (LAI_true =
LAI_eff / Ω). With ``louvers.clumping_fit`` Ω is estimated from the photo(s)
(:func:`fit_omega`): the photos' Lang & Xiang clumping index — the between-segment variance of
their log gaps, on a finer grid (:data:`CLUMPING_SEGMENTS` segments, the photos sampled at
:data:`CAST_SAMPLES` directions per cell) — is matched by that of crowns drawn like the
generator's and ray-cast along the same directions, at each Ω of :data:`OMEGA_GRID` (u and x
refitted at every Ω, so the model keeps reproducing the ring gap fractions); Ω is solved on a
quadratic through that curve, then u and x fitted at it. At the defaults (Ω = 1, no fit) the
slats are placed at random and hemi's ``clumping_lx`` of the photo is only reported beside
the fit.

Several photos (``photo`` names a folder, all taken at the same camera point): one fit to
their mean ring × segment gaps (:func:`pooled`: the expected gaps the model predicts — fitting
each photo's own logarithms biases a clumped crown's fit), plus one fit per photo whose
spread (s.d.) is reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.optimize import minimize

from radtree.config import Louvers, Sensors
from radtree.errors import ConfigError
from radtree.hemi import HemiResult
from radtree.hemi.directions import up_to_world
from radtree.hemi.metrics import DEFAULT_GAP_FLOOR, RingGrid
from radtree.site.frame import FacadeFrame
from radtree.trees.clumping import cast_slats, clumped_g, lx_clumping
from radtree.trees.crown_fit import U_BOUNDS, X_BOUNDS, CrownFit
from radtree.trees.envelope import CrownRowSpec
from radtree.trees.leaf_angles import mean_projection
from radtree.trees.photo import PhotoSource, analyse_photo, provenance, with_source

CELL_SAMPLES = (6, 10)    # zenith × azimuth directions per ring × segment cell
#: the clumping indices at which the model's Lang & Xiang clumping is computed (fit_omega)
OMEGA_GRID = (1.0, 0.85, 0.7, 0.55, 0.4, 0.25)
CLUSTER_REALISATIONS = 6   # crowns drawn per Ω (seeds 1001–1006) whose clumping_lx is averaged
CAST_SAMPLES = (10, 6)     # ray-cast directions per cell of those crowns (fit_omega)
CLUMPING_SEGMENTS = 32     # azimuth segments of the grid the clumping is compared on (finer
#   than hemi's 8: the Lang & Xiang index separates Ω ≈ 2× better per photo on crowns of 0.2 m
#   clusters, measured on synthetic photos)


@dataclass
class CellPaths:
    """Per ring × segment cell: the sample directions' path lengths through the crowns,
    |Ω_z|, trunk blocking and solid-angle weights (all (cells, samples))."""

    length: np.ndarray
    mu: np.ndarray
    blocked: np.ndarray
    weight: np.ndarray
    shape: tuple[int, int]
    ring_weight: np.ndarray   # each ring's share of the analysed solid angle
    direction: np.ndarray | None = None   # (cells, samples, 3) local unit vectors
    camera: np.ndarray | None = None      # the rays' origin (local, m)
    zenith: np.ndarray | None = None      # (cells, samples) the photo's angles, degrees
    azimuth: np.ndarray | None = None
    grid: RingGrid | None = None


def cell_paths(result: HemiResult, camera: np.ndarray, spec: CrownRowSpec,
               frame: FacadeFrame, samples: tuple[int, int] = CELL_SAMPLES,
               grid: RingGrid | None = None) -> CellPaths:
    """March the sample rays (``samples``: zenith × azimuth per cell) of every cell of
    ``result``'s grid (or ``grid``) from ``camera`` (local)."""
    grid = result.table.grid if grid is None else grid
    ze, ae = grid.ring_edges, grid.segment_edges
    nz, na = samples
    fz = (np.arange(nz) + 0.5) / nz
    fa = (np.arange(na) + 0.5) / na
    zs, az = [], []
    for i in range(grid.rings):
        for j in range(grid.segments):
            z = ze[i] + fz * (ze[i + 1] - ze[i])
            a = ae[j] + fa * (ae[j + 1] - ae[j])
            Z, A = np.meshgrid(z, a, indexing="ij")
            zs.append(Z.ravel())
            az.append(A.ravel())
    Z, A = np.array(zs), np.array(az)
    world = up_to_world(Z.ravel(), A.ravel())
    d = world @ frame.matrix           # world → local (u, n, z) directions
    length, blocked = crown_paths(spec, camera, d)
    shape = (grid.rings, grid.segments)
    ring_w = -np.diff(np.cos(np.radians(ze)))
    return CellPaths(length.reshape(Z.shape), np.abs(d[:, 2]).reshape(Z.shape),
                     blocked.reshape(Z.shape), np.sin(np.radians(Z)), shape,
                     ring_w / ring_w.sum(), d.reshape(*Z.shape, 3), np.asarray(camera, float),
                     Z, A, grid)


def slat_projection(paths: CellPaths, x: float | None, fixed_deg: float) -> np.ndarray:
    """G of every sample direction for distribution x (None: the fixed angle)."""
    if x is None:
        from radtree.trees.volume import projection_g

        return np.asarray(projection_g(paths.mu, fixed_deg))
    return np.asarray(mean_projection(paths.mu.ravel(), x)).reshape(paths.mu.shape)


def _slab(o: np.ndarray, d: np.ndarray, lo: float, hi: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """Ray parameters [t0, t1] inside lo ≤ o + t·d ≤ hi (one coordinate)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = (lo - o) / d, (hi - o) / d
    t0, t1 = np.minimum(a, b), np.maximum(a, b)
    flat = d == 0.0
    inside = (o >= lo) & (o <= hi)
    t0 = np.where(flat, np.where(inside, -np.inf, np.inf), t0)
    t1 = np.where(flat, np.where(inside, np.inf, -np.inf), t1)
    return t0, t1


def crown_paths(spec: CrownRowSpec, camera: np.ndarray, d: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Path length (m) of rays from ``camera`` along unit ``d`` (local) through the clipped
    crowns (each spheroid ∩ n ≥ n_clip ∩ its strip of u: disjoint, so lengths add), and
    whether each ray meets a trunk (vertical cylinder from the street to ``trunk_top``)."""
    o = np.asarray(camera, float)
    length = np.zeros(len(d))
    blocked = np.zeros(len(d), bool)
    for c, (lo, hi) in zip(spec.centres, spec.strips):
        q = (o - c) / np.array([spec.a, spec.a, spec.b])
        v = d / np.array([spec.a, spec.a, spec.b])
        A = np.einsum("ij,ij->i", v, v)
        B = 2.0 * v @ q
        C = float(q @ q) - 1.0
        disc = B * B - 4.0 * A * C
        ok = disc > 0
        r = np.sqrt(np.where(ok, disc, 0.0))
        t0 = np.where(ok, (-B - r) / (2 * A), np.inf)
        t1 = np.where(ok, (-B + r) / (2 * A), -np.inf)
        for axis, lo_v, hi_v in ((1, spec.n_clip, np.inf), (0, lo, hi)):
            s0, s1 = _slab(np.full(len(d), o[axis]), d[:, axis], lo_v, hi_v)
            t0, t1 = np.maximum(t0, s0), np.minimum(t1, s1)
        t0 = np.maximum(t0, 0.0)
        length += np.clip(t1 - t0, 0.0, None)
        # trunk: |(o + t d) − c| < r in plan, 0 ≤ z ≤ top
        qx, qy = o[0] - c[0], o[1] - c[1]
        a2 = d[:, 0] ** 2 + d[:, 1] ** 2
        b2 = 2.0 * (d[:, 0] * qx + d[:, 1] * qy)
        c2 = qx * qx + qy * qy - spec.trunk_radius ** 2
        disc2 = b2 * b2 - 4.0 * a2 * c2
        hit = (disc2 > 0) & (a2 > 1e-12)
        r2 = np.sqrt(np.where(hit, disc2, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            u0 = np.where(hit, (-b2 - r2) / (2 * a2), np.inf)
            u1 = np.where(hit, (-b2 + r2) / (2 * a2), -np.inf)
        z0, z1 = _slab(np.full(len(d), o[2]), d[:, 2], 0.0, spec.trunk_top)
        lo_t, hi_t = np.maximum(np.maximum(u0, z0), 0.0), np.minimum(u1, z1)
        blocked |= hi_t > lo_t
    return length, blocked


def predicted_gaps(paths: CellPaths, lad: float, x: float | None, fixed_deg: float,
                   g: np.ndarray | None = None, omega: float = 1.0,
                   cluster: tuple[float, float] = (0.5, 0.3)) -> np.ndarray:
    """P̄_ij (rings × segments) for density ``lad``, distribution x (None: fixed angle) and
    clumping ``omega`` of clusters ``cluster`` = (radius, slat side) m (``g``: the effective
    G·Ω already)."""
    g = (clumped_g(slat_projection(paths, x, fixed_deg), omega, *cluster) if g is None
         else g)
    p = np.where(paths.blocked, 0.0, np.exp(-lad * g * paths.length))
    return ((p * paths.weight).sum(axis=1) / paths.weight.sum(axis=1)).reshape(paths.shape)


def _ring_log(gaps: np.ndarray) -> np.ndarray:
    """ln of the ring means of a rings × segments gap table (floored at hemi's gap floor)."""
    with np.errstate(invalid="ignore"):
        return np.log(np.maximum(np.nanmean(gaps, axis=1), DEFAULT_GAP_FLOOR))


def _fit(targets: list[np.ndarray], paths: list[CellPaths], fixed_deg: float | None,
         omega: float = 1.0, start: tuple[float, float | None] | None = None,
         cluster: tuple[float, float] = (0.5, 0.3)) -> tuple[float, float | None, float]:
    """Least squares over all cells of all photos → (lad, x or None, RMS) at clumping
    ``omega``: a scan over log u × log x (skipped from ``start``), then L-BFGS-B from the
    best point."""
    rings = [_ring_log(t) for t in targets]
    ok = [np.isfinite(r) for r in rings]
    weights = [p.ring_weight for p in paths]
    fixed = fixed_deg or 0.0

    def sse_g(lad: float, gs: list[np.ndarray]) -> float:
        total = 0.0
        for t, pth, m, g, w in zip(rings, paths, ok, gs, weights):
            r = _ring_log(predicted_gaps(pth, lad, None, fixed, g))[m] - t[m]
            total += float(w[m] @ (r * r))
        return total

    def gs_of(x: float | None) -> list[np.ndarray]:
        return [clumped_g(slat_projection(p, x, fixed), omega, *cluster) for p in paths]

    us = np.exp(np.linspace(math.log(U_BOUNDS[0]), math.log(U_BOUNDS[1]), 61))
    xs: list[float | None] = ([None] if fixed_deg is not None else
                              list(np.exp(np.linspace(math.log(X_BOUNDS[0]),
                                                      math.log(X_BOUNDS[1]), 15))))
    best: tuple[float, float, float | None] = (math.inf, 1.0, None)
    if start is not None:
        us, xs = np.array([start[0]]), [start[1]]
    for x in xs:
        gs = gs_of(x)
        for u in us:
            e = sse_g(float(u), gs)
            if e < best[0]:
                best = (e, float(u), x)

    def sse(v: np.ndarray) -> float:
        x = None if fixed_deg is not None else float(np.exp(v[1]))
        return sse_g(float(np.exp(v[0])), gs_of(x))

    v0 = [math.log(best[1])] + ([] if best[2] is None else [math.log(best[2])])
    bounds = [(math.log(U_BOUNDS[0]), math.log(U_BOUNDS[1]))] + (
        [] if fixed_deg is not None else [(math.log(X_BOUNDS[0]), math.log(X_BOUNDS[1]))])
    res = minimize(sse, np.array(v0), method="L-BFGS-B", bounds=bounds)
    v = res.x if res.fun <= best[0] else np.array(v0)
    lad = float(np.exp(v[0]))
    x = None if fixed_deg is not None else float(np.exp(v[1]))
    cells = [predicted_gaps(p, lad, x, fixed, omega=omega, cluster=cluster) - t
             for p, t in zip(paths, targets)]
    return lad, x, float(np.sqrt(np.nanmean(np.concatenate([c.ravel() for c in cells]) ** 2)))


def pooled(targets: list[np.ndarray], paths: list[CellPaths]
           ) -> tuple[list[np.ndarray], list[CellPaths]]:
    """The photos taken from one camera on one grid (one :class:`CellPaths`) pooled: their
    mean ring × segment gaps, the expected gaps the model predicts (fitting each photo's own
    noisy logarithms would bias a clumped crown's fit)."""
    groups: dict[int, tuple[CellPaths, list[np.ndarray]]] = {}
    for t, p in zip(targets, paths):
        groups.setdefault(id(p), (p, []))[1].append(t)
    return ([np.nanmean(np.array(ts), axis=0) if len(ts) > 1 else ts[0]
             for _, ts in groups.values()], [p for p, _ in groups.values()])


def sampled_gaps(result: HemiResult, paths: CellPaths) -> np.ndarray:
    """The photo's ring × segment gaps sampled at ``paths``'s directions (sky or not)."""
    assert paths.zenith is not None and paths.azimuth is not None
    sky = np.asarray(result.sky_predicate(outside=False)(paths.zenith.ravel(),
                                                         paths.azimuth.ravel()), float)
    p = sky.reshape(paths.weight.shape)
    return ((p * paths.weight).sum(axis=1) / paths.weight.sum(axis=1)).reshape(paths.shape)


def fit_omega(targets: list[np.ndarray], paths: list[CellPaths], dense: CellPaths,
              photos: list[HemiResult], fixed_deg: float | None, spec: CrownRowSpec,
              lv: Louvers
              ) -> tuple[float, tuple[float, float | None], tuple[tuple[float, float], ...],
                         float]:
    """Ω from the photos' Lang & Xiang clumping index: (Ω, the (u, x) fitted nearest to it,
    the curve (Ω, model clumping_lx) over :data:`OMEGA_GRID`, stopped two points past the
    photos' value, and that value on ``dense``'s grid). At every Ω the crown is refitted
    (u, x) and the model's clumping_lx is the mean over :data:`CLUSTER_REALISATIONS` crowns drawn
    like the generator's (:func:`~radtree.trees.volume.draw_crown_slats`) and ray-cast along
    ``dense``'s sample directions (:func:`~radtree.trees.clumping.cast_slats`); the photos'
    clumping_lx is taken at the same directions (:func:`sampled_gaps`), so both share the
    sampling. A quadratic least-squares fit through the curve (made monotone) is solved for
    the photos' value: Ω = 1 when the photos show no more clumping than random slats, the
    grid's end when more than its last point."""
    assert dense.grid is not None
    grid = dense.grid
    target = float(np.nanmean([lx_clumping(sampled_gaps(r, dense), grid) for r in photos]))
    cluster = (lv.cluster_radius_m, lv.slat_size_m)
    curve: list[tuple[float, float]] = []
    fits: list[tuple[float, float | None]] = []
    start: tuple[float, float | None] | None = None
    mean_t, mean_p = pooled(targets, paths)
    for omega in OMEGA_GRID:
        lad, x, _ = _fit(mean_t, mean_p, fixed_deg, omega, start, cluster)
        start = (lad, x)
        fits.append(start)
        lxs = [lx_clumping(cast_gaps(dense, spec, _fitted_table(lv, spec, lad, x, omega),
                                     1001 + k), grid)
               for k in range(CLUSTER_REALISATIONS)]
        curve.append((omega, float(np.nanmean(lxs))))
        if len(curve) >= 4 and sum(c[1] < target for c in curve) >= 2:
            break                       # two points past the photos' value: enough
    om = np.array([c[0] for c in curve])
    lx = np.array([c[1] for c in curve])
    ok = np.isfinite(lx)
    if not math.isfinite(target) or ok.sum() < 3:
        return 1.0, fits[0], tuple(curve), target
    # a quadratic through the noisy curve, made monotone, solved for the photos' value
    fine = np.linspace(om.min(), 1.0, 751)
    smooth = np.maximum.accumulate(np.polyval(np.polyfit(om[ok], lx[ok], 2), fine))
    if target >= smooth[-1]:
        omega_hat = 1.0
    elif target <= smooth[0]:
        omega_hat = float(fine[0])
    else:
        omega_hat = float(np.interp(target, smooth, fine))
    return omega_hat, fits[int(np.argmin(np.abs(om - omega_hat)))], tuple(curve), target


def _fitted_table(lv: Louvers, spec: CrownRowSpec, lad: float, x: float | None,
                  omega: float) -> Louvers:
    """The louvers table of density ``lad``, distribution x (None: fixed) and clumping."""
    from radtree.trees.volume import mean_cos

    new = replace(lv, arrangement="volume", clumping=omega,
                  inclination_distribution="ellipsoidal" if x is not None else "fixed",
                  ellipsoid_x=x if x is not None else lv.ellipsoid_x)
    return replace(new, crossings=float(np.clip(
        lad * mean_cos(new) * 2.0 * spec.b / lv.cover_fraction, 0.01, 60.0)))


def cast_gaps(paths: CellPaths, spec: CrownRowSpec, lv: Louvers, seed: int) -> np.ndarray:
    """Ring × segment gaps of one crown drawn like the generator's (seed ``seed``; slats
    whose centre lies in the crown's share of the row), ray-cast along ``paths``'s sample
    directions (0 where a trunk blocks)."""
    from radtree.trees.volume import draw_crown_slats, slat_edges, slats_per_crown

    assert paths.direction is not None and paths.camera is not None
    d = paths.direction.reshape(-1, 3)
    hit = paths.blocked.ravel().copy()
    per = slats_per_crown(spec, lv)
    lv = replace(lv, seed=seed)
    for ti, child in enumerate(np.random.SeedSequence(seed).spawn(spec.count)):
        c, phi, tilt, _ = draw_crown_slats(np.random.default_rng(child), spec, lv, ti, per)
        lo, hi = spec.strips[ti]
        own = (c[:, 1] >= spec.n_clip) & (c[:, 0] >= lo) & (c[:, 0] <= hi)
        e1, e2 = slat_edges(phi, tilt)
        hit |= cast_slats(d, paths.camera, c[own], e1[own], e2[own], lv.slat_size_m)
    p = (~hit).reshape(paths.weight.shape).astype(float)
    return ((p * paths.weight).sum(axis=1) / paths.weight.sum(axis=1)).reshape(paths.shape)


_CACHE: dict[Any, tuple[CrownFit, list[HemiResult]]] = {}


def fit_crown(src: PhotoSource, camera: np.ndarray, spec: CrownRowSpec, lv: Louvers,
              frame: FacadeFrame) -> tuple[CrownFit, list[HemiResult]]:
    """Fit u (and x) to the upward photo(s) of ``src`` from ``camera`` (local, m)."""
    images = src.images
    key = (tuple((str(p), p.stat().st_mtime) for p in images), src.lens, src.mask,
           src.zenith_deg, tuple(camera.round(6)), spec.a, spec.b, spec.n_clip,
           tuple(spec.centres.ravel().round(6)), lv.inclination_distribution,
           lv.inclination_deg, frame.azimuth_deg, lv.clumping, lv.cluster_radius_m,
           lv.clumping_fit)
    if key in _CACHE:
        return _CACHE[key]
    results = [analyse_photo(p, src) for p in images]
    shared = cell_paths(results[0], camera, spec, frame)   # same grid and camera for all
    paths = [shared if r.table.grid == results[0].table.grid else
             cell_paths(r, camera, spec, frame) for r in results]
    targets = [r.table.gap for r in results]
    fixed = None if lv.inclination_distribution == "ellipsoidal" else lv.inclination_deg
    if not any(np.any(p.length > 0) for p in paths):
        raise ConfigError(f"no line of sight from the camera point {camera.round(2).tolist()} m "
                          "crosses a crown within the analysed zenith range: check "
                          "tree.photo_x_m, photo_distance_m, photo_height_m and the crown "
                          "table", field="tree.photo_height_m")
    omega = lv.clumping
    curve: tuple[tuple[float, float], ...] = ()
    lx_target = math.nan
    cluster = (lv.cluster_radius_m, lv.slat_size_m)
    start: tuple[float, float | None] | None = None
    if lv.clumping_fit:
        g0 = results[0].table.grid
        dense = cell_paths(results[0], camera, spec, frame, CAST_SAMPLES,
                           RingGrid(g0.rings, CLUMPING_SEGMENTS, g0.zenith_start,
                                    g0.zenith_end))
        omega, start, curve, lx_target = fit_omega(targets, paths, dense, results, fixed,
                                                   spec, lv)
    mean_t, mean_p = pooled(targets, paths)
    lad, x, _ = _fit(mean_t, mean_p, fixed, omega, start, cluster)
    rms = float(np.sqrt(np.nanmean(np.concatenate([
        (predicted_gaps(p, lad, x, fixed or 0.0, omega=omega, cluster=cluster) - t).ravel()
        for p, t in zip(paths, targets)]) ** 2)))
    per = tuple(_fit([t], [p], fixed, omega, (lad, x), cluster)[:2]   # from the joint fit
                for t, p in zip(targets, paths)) if len(results) > 1 else ((lad, x),)
    model = [predicted_gaps(p, lad, x, fixed or 0.0, omega=omega, cluster=cluster)
             for p in paths]
    ring_d = [np.nanmean(mg, axis=1) - np.nanmean(t, axis=1) for mg, t in zip(model, targets)]
    ring_rms = float(np.sqrt(np.nanmean(np.concatenate(ring_d) ** 2)))
    edges = results[0].table.grid.ring_edges
    ring_rows = tuple((float(edges[k]), float(edges[k + 1]),
                       float(np.nanmean([np.nanmean(t[k]) for t in targets])),
                       float(np.nanmean([np.nanmean(mg[k]) for mg in model])))
                      for k in range(len(edges) - 1))
    fitted_lv = replace(lv, inclination_distribution="ellipsoidal" if x is not None
                        else "fixed", ellipsoid_x=x if x is not None else lv.ellipsoid_x)
    from radtree.trees.volume import mean_cos

    crossings = lad * mean_cos(fitted_lv) * 2.0 * spec.b / lv.cover_fraction
    fit = CrownFit(lad, x, crossings, rms, ring_rms,
                   float(np.nanmean([r.metrics.lai_eff for r in results])),
                   float(np.nanmean([r.metrics.clumping_lx for r in results])), per,
                   omega, lv.clumping_fit, _model_lx(curve, omega), curve, lx_target,
                   ring_rows)
    _CACHE[key] = (fit, results)
    return fit, results


def _model_lx(curve: tuple[tuple[float, float], ...], omega: float) -> float:
    """The model's clumping_lx at ``omega``, interpolated on the fit's curve (NaN without)."""
    if not curve:
        return math.nan
    om = np.array([c[0] for c in curve])[::-1]
    return float(np.interp(omega, om, np.array([c[1] for c in curve])[::-1]))


def fitted_louvers(lv: Louvers, src: PhotoSource, spec: CrownRowSpec, camera: np.ndarray,
                   frame: FacadeFrame, source: str | None = None,
                   accept_poor_fit: bool = False) -> tuple[Louvers, CrownFit, dict[str, Any]]:
    """The louvers table with the fitted density (``crossings``) and distribution, the fit
    and its provenance."""
    try:
        fit, results = fit_crown(src, camera, spec, lv, frame)
    except ConfigError as exc:
        raise with_source(exc, source) from None
    problems = fit.problems()
    if problems and not accept_poor_fit:
        raise ConfigError(
            f"the crown fitted to the photo {src.path.name} does not describe it: "
            + "; ".join(problems) + ". Rings (photo vs fitted crown):\n" + fit.ring_table()
            + "\nCheck the photo's lens, mask and camera point (tree.photo_x_m, "
            "photo_distance_m, photo_height_m) and the crown table; or set [tree] "
            "accept_poor_fit = true to build it anyway (the report then says so)",
            source=source, field="tree.photo")
    new = replace(lv, arrangement="volume", crossings=float(np.clip(fit.crossings, 0.01, 60.0)),
                  clumping=float(np.clip(fit.clumping, 0.1, 1.0)),
                  inclination_distribution="ellipsoidal" if fit.x is not None else "fixed",
                  ellipsoid_x=fit.x if fit.x is not None else lv.ellipsoid_x)
    return new, fit, provenance(src, results, {**fit.as_dict(),
                                               "camera_local_m": camera.tolist(),
                                               "poor_fit_accepted": problems})


def camera_point(tree: Any, sensors: Sensors) -> np.ndarray:
    """The upward photo's camera point in the façade frame (u, n, z), m."""
    return np.array([sensors.x_m + tree.photo_x_m, tree.photo_distance_m, tree.photo_height_m])
