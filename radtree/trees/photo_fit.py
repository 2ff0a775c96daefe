"""Free crowns fitted to upward photos taken under them (``photo_direction = "upward"``).

The free louvers crowns of the volume arrangement are a turbid medium: slat centres uniform
in the clipped crown spheroids, leaf (slat) area density u = ρ·s² (m²/m³), normals from a
leaf-inclination distribution with random azimuths. Seen from the camera point c, a direction
Ω crossing the crowns over a path L(Ω) is sky with probability

    P(Ω) = exp(−u · G(|Ω_z|) · L(Ω))        (0 where Ω meets a trunk)

(Beer–Lambert; G from the slats' own distribution, :func:`radtree.trees.leaf_angles.
mean_projection`). The photo's gap fraction per zenith ring (:mod:`radtree.hemi`, 9 rings over
0–``photo_zenith_deg``, T_i the mean of its ring × segment cells T_ij) is matched by least
squares on the contact-number scale, Σ_i (ln P̄_i(u, x) − ln T_i)² (floored at hemi's gap
floor) — the scale hemi's LAI is computed on, so the fitted crown reproduces the photo's LAI
and its ring gap fractions; P̄_ij is the solid-angle mean of P over a cell
(:data:`CELL_SAMPLES` directions per cell, L by marching the ray in :data:`STEP_M` steps).
The fit scans log u × log x (61 × 15 points) and refines the best point with L-BFGS-B;
hemi's own ellipsoidal x / mean tilt and LAI of the photo are reported beside it. With ``louvers.inclination_distribution = "fixed"``
only u is fitted (the inclination stays ``inclination_deg``, e.g. the study's 30°).

Clumping: the model's slats are placed at random (no clumping); hemi's clumping index
``clumping_lx`` of the photo is reported beside the fit, the fitted u is an *effective*
density (it reproduces the photo's gaps, not the true leaf area of a clumped crown).

Several photos (``photo`` names a folder, all taken at the same camera point): one joint fit
over all their cells, plus one fit per photo whose spread (s.d.) is reported.
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
from radtree.hemi.metrics import DEFAULT_GAP_FLOOR
from radtree.site.frame import FacadeFrame
from radtree.trees.envelope import CrownRowSpec
from radtree.trees.leaf_angles import mean_projection, mean_tilt
from radtree.trees.photo import PhotoSource, analyse_photo, provenance, with_source

CELL_SAMPLES = (6, 10)    # zenith × azimuth directions per ring × segment cell
STEP_M = 0.05             # ray marching step through the crowns
X_BOUNDS = (0.1, 10.0)
U_BOUNDS = (1e-3, 20.0)


@dataclass(frozen=True)
class CrownFit:
    """The fitted crown: leaf area density ``lad`` (m²/m³), ellipsoidal ``x`` (None: fixed
    inclination), the vertical ``crossings`` through a crown centre, fit residuals and the
    per-photo spread."""

    lad: float
    x: float | None
    crossings: float
    rms: float
    ring_rms: float
    lai_photo: float
    clumping_photo: float
    per_photo: tuple[tuple[float, float | None], ...]

    @property
    def mean_tilt_deg(self) -> float | None:
        return None if self.x is None else mean_tilt(self.x)

    def spread(self) -> dict[str, float]:
        lads = [p[0] for p in self.per_photo]
        xs = [p[1] for p in self.per_photo if p[1] is not None]
        out = {"photos": float(len(lads))}
        if len(lads) > 1:
            out["lad_sd"] = float(np.std(lads, ddof=1))
            if len(xs) > 1:
                out["x_sd"] = float(np.std(xs, ddof=1))
        return out

    def as_dict(self) -> dict[str, Any]:
        return {"leaf_area_density_m2_m3": self.lad, "ellipsoid_x": self.x,
                "mean_tilt_deg": self.mean_tilt_deg, "crossings": self.crossings,
                "gap_rms_cells": self.rms, "gap_rms_rings": self.ring_rms,
                "lai_eff_photo": self.lai_photo, "clumping_lx_photo": self.clumping_photo,
                **self.spread()}


@dataclass
class CellPaths:
    """Per ring × segment cell: the sample directions' path lengths through the crowns,
    |Ω_z|, trunk blocking and solid-angle weights (all (cells, samples))."""

    length: np.ndarray
    mu: np.ndarray
    blocked: np.ndarray
    weight: np.ndarray
    shape: tuple[int, int]


def cell_paths(result: HemiResult, camera: np.ndarray, spec: CrownRowSpec,
               frame: FacadeFrame) -> CellPaths:
    """March the sample rays of every cell of ``result``'s grid from ``camera`` (local)."""
    grid = result.table.grid
    ze, ae = grid.ring_edges, grid.segment_edges
    nz, na = CELL_SAMPLES
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
    top = float(spec.centres[:, 2].max() + spec.b)
    reach = float(np.max(np.abs(spec.centres[:, :2] - camera[:2]))
                  + 2 * spec.a) / max(1e-3, 1.0)
    t_max = min(200.0, math.hypot(reach, top - camera[2]) * 2.0)
    steps = np.arange(STEP_M / 2, t_max, STEP_M)
    length = np.zeros(len(d))
    blocked = np.zeros(len(d), bool)
    for k in range(0, len(d), 512):
        dk = d[k:k + 512]
        pts = camera[None, None, :] + steps[None, :, None] * dk[:, None, :]
        flat = pts.reshape(-1, 3)
        inside = spec.inside(flat).reshape(pts.shape[:2])
        length[k:k + 512] = inside.sum(axis=1) * STEP_M
        trunk = np.zeros(len(flat), bool)
        for c in spec.centres:
            trunk |= ((np.hypot(flat[:, 0] - c[0], flat[:, 1] - c[1]) < spec.trunk_radius)
                      & (flat[:, 2] < spec.trunk_top) & (flat[:, 2] >= 0.0))
        blocked[k:k + 512] = trunk.reshape(pts.shape[:2]).any(axis=1)
    shape = (grid.rings, grid.segments)
    return CellPaths(length.reshape(Z.shape), np.abs(d[:, 2]).reshape(Z.shape),
                     blocked.reshape(Z.shape), np.sin(np.radians(Z)), shape)


def slat_projection(paths: CellPaths, x: float | None, fixed_deg: float) -> np.ndarray:
    """G of every sample direction for distribution x (None: the fixed angle)."""
    if x is None:
        from radtree.trees.volume import projection_g

        return np.asarray(projection_g(paths.mu, fixed_deg))
    return np.asarray(mean_projection(paths.mu.ravel(), x)).reshape(paths.mu.shape)


def predicted_gaps(paths: CellPaths, lad: float, x: float | None, fixed_deg: float,
                   g: np.ndarray | None = None) -> np.ndarray:
    """P̄_ij (rings × segments) for density ``lad`` and distribution x (None: fixed angle)."""
    g = slat_projection(paths, x, fixed_deg) if g is None else g
    p = np.where(paths.blocked, 0.0, np.exp(-lad * g * paths.length))
    return ((p * paths.weight).sum(axis=1) / paths.weight.sum(axis=1)).reshape(paths.shape)


def _ring_log(gaps: np.ndarray) -> np.ndarray:
    """ln of the ring means of a rings × segments gap table (floored at hemi's gap floor)."""
    with np.errstate(invalid="ignore"):
        return np.log(np.maximum(np.nanmean(gaps, axis=1), DEFAULT_GAP_FLOOR))


def _fit(targets: list[np.ndarray], paths: list[CellPaths], fixed_deg: float | None
         ) -> tuple[float, float | None, float]:
    """Least squares over all cells of all photos → (lad, x or None, RMS): a scan over
    log u × log x, then L-BFGS-B from the best point."""
    rings = [_ring_log(t) for t in targets]
    ok = [np.isfinite(r) for r in rings]
    fixed = fixed_deg or 0.0

    def sse_g(lad: float, gs: list[np.ndarray]) -> float:
        total = 0.0
        for t, pth, m, g in zip(rings, paths, ok, gs):
            r = _ring_log(predicted_gaps(pth, lad, None, fixed, g))[m] - t[m]
            total += float(r @ r)
        return total

    def gs_of(x: float | None) -> list[np.ndarray]:
        return [slat_projection(p, x, fixed) for p in paths]

    us = np.exp(np.linspace(math.log(U_BOUNDS[0]), math.log(U_BOUNDS[1]), 61))
    xs: list[float | None] = ([None] if fixed_deg is not None else
                              list(np.exp(np.linspace(math.log(X_BOUNDS[0]),
                                                      math.log(X_BOUNDS[1]), 15))))
    best: tuple[float, float, float | None] = (math.inf, 1.0, None)
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
    cells = [predicted_gaps(p, lad, x, fixed) - t for p, t in zip(paths, targets)]
    return lad, x, float(np.sqrt(np.nanmean(np.concatenate([c.ravel() for c in cells]) ** 2)))


_CACHE: dict[Any, tuple[CrownFit, list[HemiResult]]] = {}


def fit_crown(src: PhotoSource, camera: np.ndarray, spec: CrownRowSpec, lv: Louvers,
              frame: FacadeFrame) -> tuple[CrownFit, list[HemiResult]]:
    """Fit u (and x) to the upward photo(s) of ``src`` from ``camera`` (local, m)."""
    images = src.images
    key = (tuple((str(p), p.stat().st_mtime) for p in images), src.lens, src.mask,
           src.zenith_deg, tuple(camera.round(6)), spec.a, spec.b, spec.n_clip,
           tuple(spec.centres.ravel().round(6)), lv.inclination_distribution,
           lv.inclination_deg, frame.azimuth_deg)
    if key in _CACHE:
        return _CACHE[key]
    results = [analyse_photo(p, src) for p in images]
    paths = [cell_paths(r, camera, spec, frame) for r in results]
    targets = [r.table.gap for r in results]
    fixed = None if lv.inclination_distribution == "ellipsoidal" else lv.inclination_deg
    if not any(np.any(p.length > 0) for p in paths):
        raise ConfigError(f"no line of sight from the camera point {camera.round(2).tolist()} m "
                          "crosses a crown within the analysed zenith range: check "
                          "tree.photo_x_m, photo_distance_m, photo_height_m and the crown "
                          "table", field="tree.photo_height_m")
    lad, x, rms = _fit(targets, paths, fixed)
    per = tuple(_fit([t], [p], fixed)[:2] for t, p in zip(targets, paths)
                ) if len(results) > 1 else ((lad, x),)
    model = [predicted_gaps(p, lad, x, fixed or 0.0) for p in paths]
    ring_d = [np.nanmean(mg, axis=1) - np.nanmean(t, axis=1) for mg, t in zip(model, targets)]
    ring_rms = float(np.sqrt(np.nanmean(np.concatenate(ring_d) ** 2)))
    fitted_lv = replace(lv, inclination_distribution="ellipsoidal" if x is not None
                        else "fixed", ellipsoid_x=x if x is not None else lv.ellipsoid_x)
    from radtree.trees.volume import mean_cos

    crossings = lad * mean_cos(fitted_lv) * 2.0 * spec.b / lv.cover_fraction
    fit = CrownFit(lad, x, crossings, rms, ring_rms,
                   float(np.nanmean([r.metrics.lai_eff for r in results])),
                   float(np.nanmean([r.metrics.clumping_lx for r in results])), per)
    _CACHE[key] = (fit, results)
    return fit, results


def fitted_louvers(lv: Louvers, src: PhotoSource, spec: CrownRowSpec, camera: np.ndarray,
                   frame: FacadeFrame, source: str | None = None
                   ) -> tuple[Louvers, CrownFit, dict[str, Any]]:
    """The louvers table with the fitted density (``crossings``) and distribution, the fit
    and its provenance."""
    try:
        fit, results = fit_crown(src, camera, spec, lv, frame)
    except ConfigError as exc:
        raise with_source(exc, source) from None
    new = replace(lv, arrangement="volume", crossings=float(np.clip(fit.crossings, 0.01, 60.0)),
                  inclination_distribution="ellipsoidal" if fit.x is not None else "fixed",
                  ellipsoid_x=fit.x if fit.x is not None else lv.ellipsoid_x)
    return new, fit, provenance(src, results, {**fit.as_dict(),
                                               "camera_local_m": camera.tolist()})


def camera_point(tree: Any, sensors: Sensors) -> np.ndarray:
    """The upward photo's camera point in the façade frame (u, n, z), m."""
    return np.array([sensors.x_m + tree.photo_x_m, tree.photo_distance_m, tree.photo_height_m])
