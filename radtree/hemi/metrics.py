"""Gap fraction per zenith ring × azimuth segment and the canopy metrics derived from it.

Angles in degrees; θ is the zenith angle (the angle from the lens axis for horizontal photos).
The analysed range [θs, θe] is split into ``rings`` equal zenith bands and ``segments`` equal
azimuth sectors starting at azimuth 0 (north) and running clockwise.

Definitions (T_ij: gap fraction of ring i, segment j; T_i: mean of T_ij over the segments that
have pixels; cells without pixels are left out and the weights renormalised):

* cell gap fraction T_ij = sky share of the cell's solid angle: each sky pixel counts with the
  solid angle it subtends (sinθ / (R²·rho·drho/dθ) sr), so the lens projection is accounted for.
* ``gap_fraction`` = plain share of sky pixels among the valid pixels of the analysed range
  (an image-plane quantity: it depends on the lens projection).
* ``openness`` = Σ Ω_ij T_ij / Σ Ω_ij with Ω_ij = Δφ (cos θa − cos θb): the sky fraction of the
  analysed solid angle. Over 0–90° it is the canopy openness of the hemisphere; for a shorter
  range it is normalised over the analysed solid angle (no extrapolation beyond θe).
* ``svf`` (sky view factor) = Σ C_ij Tc_ij / Σ C_ij with C_ij = Δφ (sin²θb − sin²θa) / 2 and
  Tc_ij the cosine-weighted sky share of the cell (pixels weighted by solid angle × cosθ), i.e.
  ∫gap·cosθ·sinθ / ∫cosθ·sinθ evaluated pixel by pixel, so it does not depend on the number of
  rings. Over 0–90° it is the share of a horizontal surface's irradiance from a uniform sky
  that is not blocked (for a horizontal-axis photo: of the vertical façade's). For a shorter
  range it is normalised by the cosine-weighted integral of the analysed range (a fully open
  sky gives 1 for any range).
* ``difn`` (diffuse non-interceptance, %, LAI-2000/2200 convention) = 100 · Σ W'_i T_i / Σ W'_i,
  T_i the ring gap fraction and W'_i = ∫ sinθ cosθ dθ over ring i (the LAI-2200 weights, which
  sum to 1/2 over the hemisphere, are these cosine weights for its five rings; DIFN =
  2 Σ W'_i T_i). It is the ring-quadrature version of 100 · svf: equal for a sky that is uniform
  within each ring, different by the within-ring cosine weighting otherwise (< 1 % relative for
  10° rings).
* ``lai_eff`` (Miller 1967) = 2 Σ W_i K_i with contact numbers K_i = −ln(max(T_i, floor)) cosθ_i
  (θ_i the ring centre) and W_i = (cos θa − cos θb) / Σ (cos θa − cos θb): Miller's integral
  2∫−ln T cosθ sinθ dθ, normalised over the analysed rings (LAI-2000 practice: missing rings
  are assumed to have the mean contact number).
* ``lai`` (Lang & Xiang 1986 log-averaging) = the same with K_i = −mean_j ln(max(T_ij, floor)) ·
  cosθ_i: averaging logarithms per segment accounts for clumping at the segment scale.
* ``clumping_lx`` = lai_eff / lai (≤ 1 by Jensen's inequality unless the floor binds in a
  segment; NaN when lai = 0).
* ``floor``: gap fractions are floored at ``gap_floor`` (default 0.001) before taking logarithms,
  so a ring or segment without sky contributes −ln(0.001) ≈ 6.9 instead of infinity.
* ``ellipsoid_x``: Campbell's (1986, 1990) ellipsoidal leaf-angle parameter fitted by least
  squares to the ring contact numbers, K_i ≈ L·G(θ_i, x) with G(θ, x) = cosθ·√(x² + tan²θ) /
  (x + 1.774 (x + 1.182)^−0.733), x searched in [0.05, 20] (x = 1 spherical, x < 1 erectophile,
  x > 1 planophile); ``ellipsoid_lai`` is the fitted L.
* ``mean_tilt_deg`` = Campbell's (1990) approximation θ̄ = 9.65 (3 + x)^−1.65 rad.

The canopy-structure quantities (lai_eff, lai, clumping_lx, ellipsoid_*, mean_tilt_deg) assume
an upward view of a horizontally extended canopy and are NaN for horizontal-axis photos.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from radtree.errors import ConfigError

DEFAULT_GAP_FLOOR = 0.001
X_RANGE = (0.05, 20.0)


@dataclass(frozen=True)
class RingGrid:
    """Analysis grid: ``rings`` zenith bands over [zenith_start, zenith_end] × ``segments``."""

    rings: int = 9
    segments: int = 8
    zenith_start: float = 0.0
    zenith_end: float = 90.0

    def __post_init__(self) -> None:
        if not isinstance(self.rings, (int, np.integer)) or not 1 <= self.rings <= 900:
            raise ConfigError(f"rings must be an integer from 1 to 900, got {self.rings}", field="rings")
        if not isinstance(self.segments, (int, np.integer)) or not 1 <= self.segments <= 720:
            raise ConfigError(
                f"segments must be an integer from 1 to 720, got {self.segments}", field="segments"
            )
        s, e = float(self.zenith_start), float(self.zenith_end)
        if not (math.isfinite(s) and math.isfinite(e) and 0.0 <= s < e <= 90.0):
            raise ConfigError(
                f"zenith range must satisfy 0 <= start < end <= 90 degrees, got {s:g},{e:g}",
                field="zenith",
            )
        object.__setattr__(self, "zenith_start", s)
        object.__setattr__(self, "zenith_end", e)

    @property
    def ring_edges(self) -> NDArray[np.float64]:
        return np.linspace(self.zenith_start, self.zenith_end, self.rings + 1)

    @property
    def segment_edges(self) -> NDArray[np.float64]:
        return np.linspace(0.0, 360.0, self.segments + 1)

    @property
    def ring_centres(self) -> NDArray[np.float64]:
        e = self.ring_edges
        return 0.5 * (e[:-1] + e[1:])

    def ring_solid_angle_weights(self) -> NDArray[np.float64]:
        """∫ sinθ dθ over each ring (cos θa − cos θb)."""
        c = np.cos(np.radians(self.ring_edges))
        return c[:-1] - c[1:]

    def ring_cosine_weights(self) -> NDArray[np.float64]:
        """∫ sinθ cosθ dθ over each ring ((sin²θb − sin²θa) / 2)."""
        s2 = np.sin(np.radians(self.ring_edges)) ** 2
        return 0.5 * (s2[1:] - s2[:-1])

    def cell_solid_angle(self) -> NDArray[np.float64]:
        """Exact solid angle (sr) of each ring × segment cell."""
        dphi = 2.0 * math.pi / self.segments
        return np.repeat(self.ring_solid_angle_weights()[:, None] * dphi, self.segments, axis=1)

    def cell_cosine_weight(self) -> NDArray[np.float64]:
        """Exact cosine-weighted solid angle ∫cosθ dΩ (sr) of each cell."""
        dphi = 2.0 * math.pi / self.segments
        return np.repeat(self.ring_cosine_weights()[:, None] * dphi, self.segments, axis=1)

    def locate(
        self, zenith: NDArray[np.float64], azimuth: NDArray[np.float64]
    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.bool_]]:
        """Ring and segment index of directions, and whether they are in the analysed range."""
        z = np.nan_to_num(zenith, nan=-1.0)
        inside = (z >= self.zenith_start) & (z <= self.zenith_end)
        width = (self.zenith_end - self.zenith_start) / self.rings
        ring = np.clip(((z - self.zenith_start) / width).astype(np.intp), 0, self.rings - 1)
        seg = (np.mod(np.nan_to_num(azimuth), 360.0) / (360.0 / self.segments)).astype(np.intp)
        return ring, np.clip(seg, 0, self.segments - 1), inside


@dataclass(frozen=True)
class GapTable:
    """Gap fraction per ring × segment (NaN where a cell has no pixels) and sampling counts.

    ``gap`` weights pixels by solid angle, ``gap_cos`` by solid angle × cosθ (for the SVF).
    """

    grid: RingGrid
    gap: NDArray[np.float64]
    gap_cos: NDArray[np.float64]
    pixels: NDArray[np.int64]
    sky_pixels: NDArray[np.int64]
    sampled_solid_angle: NDArray[np.float64]

    @property
    def ring_gap(self) -> NDArray[np.float64]:
        """Mean gap fraction of each ring over the segments with pixels (NaN if none)."""
        has = ~np.isnan(self.gap)
        total = np.where(has, self.gap, 0.0).sum(axis=1)
        n = has.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(n > 0, total / np.maximum(n, 1), np.nan)

    @property
    def gap_fraction(self) -> float:
        """Plain share of sky pixels among the pixels of the analysed range."""
        n = int(self.pixels.sum())
        return float(self.sky_pixels.sum()) / n if n else math.nan


def gap_table(
    sky: NDArray[np.bool_],
    valid: NDArray[np.bool_],
    zenith: NDArray[np.floating],
    azimuth: NDArray[np.floating],
    weight: NDArray[np.float64],
    grid: RingGrid,
) -> GapTable:
    """Tabulate the solid-angle-weighted gap fraction of each cell of ``grid``."""
    z = np.asarray(zenith[valid], dtype=np.float64)
    ring, seg, inside = grid.locate(z, np.asarray(azimuth[valid], dtype=np.float64))
    idx = (ring * grid.segments + seg)[inside]
    z = z[inside]
    w = weight[valid][inside]
    wc = w * np.cos(np.radians(z))
    s = sky[valid][inside]
    n = grid.rings * grid.segments
    w_all = np.bincount(idx, weights=w, minlength=n)
    w_sky = np.bincount(idx[s], weights=w[s], minlength=n)
    wc_all = np.bincount(idx, weights=wc, minlength=n)
    wc_sky = np.bincount(idx[s], weights=wc[s], minlength=n)
    count = np.bincount(idx, minlength=n)
    count_sky = np.bincount(idx[s], minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        gap = np.where(count > 0, w_sky / np.where(w_all > 0, w_all, 1.0), np.nan)
        gap_cos = np.where(wc_all > 0, wc_sky / np.where(wc_all > 0, wc_all, 1.0), gap)
    shape = (grid.rings, grid.segments)
    return GapTable(
        grid,
        gap.reshape(shape),
        gap_cos.reshape(shape),
        count.reshape(shape).astype(np.int64),
        count_sky.reshape(shape).astype(np.int64),
        np.asarray(w_all, dtype=np.float64).reshape(shape),
    )


# -- metrics from a gap table ---------------------------------------------------------------
def _weighted_mean(values: NDArray[np.float64], weights: NDArray[np.float64]) -> float:
    has = ~np.isnan(values)
    wsum = float(weights[has].sum())
    return float((values[has] * weights[has]).sum() / wsum) if wsum > 0 else math.nan


def openness(table: GapTable) -> float:
    """Solid-angle-weighted sky fraction of the analysed range (0–1)."""
    return _weighted_mean(table.gap, table.grid.cell_solid_angle())


def sky_view_factor(table: GapTable) -> float:
    """Cosine-weighted sky fraction ∫gap cosθ dΩ / ∫cosθ dΩ over the analysed range (0–1)."""
    return _weighted_mean(table.gap_cos, table.grid.cell_cosine_weight())


def difn(table: GapTable) -> float:
    """Diffuse non-interceptance in percent (LAI-2000/2200 cosine ring weights)."""
    return 100.0 * _weighted_mean(table.ring_gap, table.grid.ring_cosine_weights())


def contact_numbers(
    table: GapTable, gap_floor: float = DEFAULT_GAP_FLOOR, *, log_average: bool = False
) -> NDArray[np.float64]:
    """K_i = −ln T_i · cosθ_i per ring (``log_average``: −mean_j ln T_ij, Lang & Xiang)."""
    cos_c = np.cos(np.radians(table.grid.ring_centres))
    if log_average:
        logs = np.log(np.maximum(table.gap, gap_floor))
        has = ~np.isnan(logs)
        n = has.sum(axis=1)
        mean_log = np.where(n > 0, np.where(has, logs, 0.0).sum(axis=1) / np.maximum(n, 1), np.nan)
        return -mean_log * cos_c
    return -np.log(np.maximum(table.ring_gap, gap_floor)) * cos_c


def _lai_from_contacts(table: GapTable, k: NDArray[np.float64]) -> float:
    w = table.grid.ring_solid_angle_weights()
    has = ~np.isnan(k)
    if not has.any():
        return math.nan
    return float(2.0 * (k[has] * w[has]).sum() / w[has].sum())


def lai_miller(table: GapTable, gap_floor: float = DEFAULT_GAP_FLOOR) -> float:
    """Effective LAI by Miller's formula on ring-mean gap fractions."""
    return _lai_from_contacts(table, contact_numbers(table, gap_floor))


def lai_lang_xiang(table: GapTable, gap_floor: float = DEFAULT_GAP_FLOOR) -> float:
    """Clumping-corrected LAI: Miller's formula on log-averaged (per segment) gap fractions."""
    return _lai_from_contacts(table, contact_numbers(table, gap_floor, log_average=True))


def ellipsoid_g(zenith_deg: ArrayLike, x: float) -> NDArray[np.float64]:
    """Campbell's ellipsoidal projection function G(θ, x) (mean leaf projection, 0.5 for x=1)."""
    t = np.radians(np.asarray(zenith_deg, dtype=np.float64))
    return np.cos(t) * ellipsoid_extinction(zenith_deg, x)


def ellipsoid_extinction(zenith_deg: ArrayLike, x: float) -> NDArray[np.float64]:
    """Extinction coefficient K(θ, x) = √(x² + tan²θ) / (x + 1.774 (x + 1.182)^−0.733)."""
    t = np.radians(np.asarray(zenith_deg, dtype=np.float64))
    return np.sqrt(x * x + np.tan(t) ** 2) / (x + 1.774 * (x + 1.182) ** -0.733)


def mean_tilt_deg(x: float) -> float:
    """Mean leaf tilt angle (degrees from horizontal) from x, Campbell (1990) approximation."""
    return math.degrees(9.65 * (3.0 + x) ** -1.65) if math.isfinite(x) else math.nan


def x_from_mean_tilt(tilt_deg: float) -> float:
    """Inverse of :func:`mean_tilt_deg`."""
    return (math.radians(tilt_deg) / 9.65) ** (-1.0 / 1.65) - 3.0


def fit_ellipsoid(
    zenith_deg: ArrayLike, contacts: ArrayLike
) -> tuple[float, float]:
    """Least-squares fit of K_i ≈ L·G(θ_i, x); returns (x, L). NaN when under-determined."""
    z = np.asarray(zenith_deg, dtype=np.float64)
    k = np.asarray(contacts, dtype=np.float64)
    ok = np.isfinite(k)
    z, k = z[ok], k[ok]
    if z.size < 2 or not np.any(k > 0) or np.ptp(z) < 5.0:
        return math.nan, math.nan

    def sse(log_x: float) -> float:
        g = ellipsoid_g(z, math.exp(log_x))
        lai = float(k @ g / (g @ g))
        r = k - lai * g
        return float(r @ r)

    lo, hi = math.log(X_RANGE[0]), math.log(X_RANGE[1])
    grid = np.linspace(lo, hi, 121)
    values = [sse(u) for u in grid]
    i = int(np.argmin(values))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    from scipy.optimize import minimize_scalar  # here: ~0.2 s to import

    best = minimize_scalar(sse, bounds=(a, b), method="bounded", options={"xatol": 1e-6})
    u = float(best.x) if best.fun <= values[i] else float(grid[i])
    x = math.exp(u)
    g = ellipsoid_g(z, x)
    return x, float(k @ g / (g @ g))


@dataclass(frozen=True)
class CanopyMetrics:
    """Summary metrics of one photo (see the module docstring for definitions)."""

    gap_fraction: float
    openness: float
    svf: float
    difn: float
    lai_eff: float
    lai: float
    clumping_lx: float
    ellipsoid_x: float
    ellipsoid_lai: float
    mean_tilt_deg: float

    def as_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in self.__dataclass_fields__}


def canopy_metrics(
    table: GapTable, *, gap_floor: float = DEFAULT_GAP_FLOOR, upward: bool = True
) -> CanopyMetrics:
    """All metrics of a gap table; structure metrics are NaN unless ``upward``."""
    if not (0.0 < gap_floor < 1.0):
        raise ConfigError(f"gap floor must be between 0 and 1, got {gap_floor}", field="gap_floor")
    nan = math.nan
    lai_eff = lai_lx = clump = x = x_lai = tilt = nan
    if upward:
        lai_eff = lai_miller(table, gap_floor)
        lai_lx = lai_lang_xiang(table, gap_floor)
        clump = lai_eff / lai_lx if lai_lx > 0 else nan
        k = contact_numbers(table, gap_floor)
        x, x_lai = fit_ellipsoid(table.grid.ring_centres, k)
        tilt = mean_tilt_deg(x)
    return CanopyMetrics(
        gap_fraction=table.gap_fraction,
        openness=openness(table),
        svf=sky_view_factor(table),
        difn=difn(table),
        lai_eff=lai_eff,
        lai=lai_lx,
        clumping_lx=clump,
        ellipsoid_x=x,
        ellipsoid_lai=x_lai,
        mean_tilt_deg=tilt,
    )
