"""The Perez all-weather sky, computed exactly as Radiance's ``gendaylit`` + ``perezlum.cal`` do.

Both engines must see the same sky. The Radiance engine runs ``gendaylit -ang ALT AZ -L DNI DHI
-O 0`` and lights the scene with ``skyfunc`` (``perezlum.cal``); the NumPy engine evaluates the
same function from the same ten parameters, computed here in Python by the algorithm of
``gendaylit.c`` (Radiance 6, version 2.6 of the program, Delaunay 1994 / Wienold 2021):

1. illuminances → irradiances and the Perez indices (sky clearness ε, sky brightness Δ) by the
   fixed-point iteration of ``illu_to_irra_index`` (Perez 1990 luminous-efficacy models,
   precipitable water 2 cm, 9 iterations, indices clamped to ε ∈ [1, 12.01], Δ ∈ [0.01, 0.6]);
   Δ needs the extraterrestrial irradiance, i.e. the day of year: with ``-ang`` gendaylit never
   sets its day number, which stays **0** (eccentricity factor 1.0350, early January) — we use
   the same by default so that both engines agree;
2. the five coefficients a..e of the Perez 1993 all-weather model for (ε, Δ, sun zenith Z);
3. the diffuse normalisation A1 = DHI / (2π/145 · Σ lv(θᵢ, φᵢ) cos θᵢ) over gendaylit's 145 fixed
   directions — a coarse quadrature, so the horizontal illuminance of the *continuous* sky
   differs from DHI by a few per cent (:func:`horizontal_illuminance` gives the exact value);
4. the ground brightness A2 = ρ_g · (L_zenith · normsc(alt)/F2/π + 6.8e-5/π · L_sun · sin alt);
5. ``perezlum.cal``: ``skybright = wmean((Dz+1.01)^10, intersky, (Dz+1.01)^-10, A2)`` — the sky
   blends smoothly into the ground brightness near the horizon; below the horizon the value is
   ≈ A2, which Radiance uses for the ground glow when one is attached to ``skyfunc``.

gendaylit also lowers a sun higher than 87° to 87° (sun and sky). Luminances here are in cd/m²
(gendaylit ``-O 0`` visible radiance × ``WHITE_EFFICACY``, :mod:`radtree.light.units`); the
gendaylit command and the parsing of its output are in :mod:`radtree.engines.radiance.sky`.

:func:`perez_efficacy` is the same Perez (1990) luminous-efficacy model in a vectorised,
non-iterated form (irradiances in, as for the generated clear-sky year of
:mod:`radtree.light.clearsky`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radtree.light.sun import SUN_SOLID_ANGLE_SR

SOLAR_CONSTANT_E = 1367.0  # W/m²
SOLAR_CONSTANT_L = 127500.0  # lux
MAX_ALTITUDE_DEG = 87.0
SKYCLEAR_INF, SKYCLEAR_SUP = 1.0, 12.01
SKYBRIG_INF, SKYBRIG_SUP = 0.01, 0.6
GENDAYLIT_ANG_DAY_NUMBER = 0  # gendaylit -ang leaves its day number at 0
DEW_POINT_DEFAULT = 10.97353115  # gendaylit's default dew point → 2 cm precipitable water
PRECIPITABLE_WATER_CM = 2.0  # the same 2 cm, as the vectorised efficacy takes it

# Perez et al. 1993, all-weather sky luminance model: 8 clearness bins × (a, b, c, d, e) × 4.
# Stored as float32 as in gendaylit.c.
_COEFF_PEREZ = np.array([
    1.3525, -0.2576, -0.2690, -1.4366, -0.7670, 0.0007, 1.2734, -0.1233, 2.8000, 0.6004,
    1.2375, 1.000, 1.8734, 0.6297, 0.9738, 0.2809, 0.0356, -0.1246, -0.5718, 0.9938,
    -1.2219, -0.7730, 1.4148, 1.1016, -0.2054, 0.0367, -3.9128, 0.9156, 6.9750, 0.1774,
    6.4477, -0.1239, -1.5798, -0.5081, -1.7812, 0.1080, 0.2624, 0.0672, -0.2190, -0.4285,
    -1.1000, -0.2515, 0.8952, 0.0156, 0.2782, -0.1812, -4.5000, 1.1766, 24.7219, -13.0812,
    -37.7000, 34.8438, -5.0000, 1.5218, 3.9229, -2.6204, -0.0156, 0.1597, 0.4199, -0.5562,
    -0.5484, -0.6654, -0.2672, 0.7117, 0.7234, -0.6219, -5.6812, 2.6297, 33.3389, -18.3000,
    -62.2500, 52.0781, -3.5000, 0.0016, 1.1477, 0.1062, 0.4659, -0.3296, -0.0876, -0.0329,
    -0.6000, -0.3566, -2.5000, 2.3250, 0.2937, 0.0496, -5.6812, 1.8415, 21.0000, -4.7656,
    -21.5906, 7.2492, -3.5000, -0.1554, 1.4062, 0.3988, 0.0032, 0.0766, -0.0656, -0.1294,
    -1.0156, -0.3670, 1.0078, 1.4051, 0.2875, -0.5328, -3.8500, 3.3750, 14.0000, -0.9999,
    -7.1406, 7.5469, -3.4000, -0.1078, -1.0750, 1.5702, -0.0672, 0.4016, 0.3017, -0.4844,
    -1.0000, 0.0211, 0.5025, -0.5119, -0.3000, 0.1922, 0.7023, -1.6317, 19.0000, -5.0000,
    1.2438, -1.9094, -4.0000, 0.0250, 0.3844, 0.2656, 1.0468, -0.3788, -2.4517, 1.4656,
    -1.0500, 0.0289, 0.4260, 0.3590, -0.3250, 0.1156, 0.7781, 0.0025, 31.0625, -14.5000,
    -46.1148, 55.3750, -7.2312, 0.4050, 13.3500, 0.6234, 1.5000, -0.6426, 1.8564, 0.5636,
], dtype=np.float32).reshape(8, 5, 4)

# gendaylit's 145 integration directions (zenith angle θ, azimuth φ from the sun, degrees).
_DEFANGLE_THETA = np.repeat([84, 72, 60, 48, 36, 24, 12, 0], [30, 30, 24, 24, 18, 12, 6, 1])
_DEFANGLE_PHI = np.concatenate([
    np.arange(0, 360, 12), np.arange(0, 360, 12), np.arange(0, 360, 15), np.arange(0, 360, 15),
    np.arange(0, 360, 20), np.arange(0, 360, 30), np.arange(0, 360, 60), [0],
]).astype(float)

# Perez 1990 luminous efficacy models: bin bounds and (a, b, c, d) per clearness bin — the one
# table of radtree (gendaylit's iteration below and the generated clear-sky year both use it).
_EFFI_BOUNDS = np.array([1.0, 1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200])
_DIFFUSE_EFFI = np.array([
    [97.24, -0.46, 12.00, -8.91], [107.22, 1.15, 0.59, -3.95], [104.97, 2.96, -5.53, -8.77],
    [102.39, 5.59, -13.95, -13.90], [100.71, 5.94, -22.75, -23.74],
    [106.42, 3.83, -36.15, -28.83], [141.88, 1.90, -53.24, -14.03], [152.23, 0.35, -45.27, -7.98],
])
_DIRECT_EFFI = np.array([
    [57.20, -4.55, -2.98, 117.12], [98.99, -3.46, -1.21, 12.38], [109.83, -4.90, -1.71, -8.81],
    [110.34, -5.84, -1.99, -4.56], [106.36, -3.97, -1.75, -6.16], [107.19, -1.25, -1.51, -26.73],
    [105.75, 0.77, -1.26, -34.44], [101.18, 1.58, -1.10, -8.29],
])


@dataclass(frozen=True)
class PerezSky:
    """The ten ``perezlum.cal`` arguments of one hour, luminances in cd/m².

    ``diffuse_norm`` (A1), ``ground_brightness`` (A2), ``coefficients`` (A3..A7 = a..e),
    ``sun_direction`` (A8..A10, unit vector towards the sun, x east, y north, z up — after
    gendaylit's 87° cap). ``epsilon``/``delta``: the Perez clearness and brightness used.
    """

    diffuse_norm: float
    ground_brightness: float
    coefficients: tuple[float, float, float, float, float]
    sun_direction: tuple[float, float, float]
    epsilon: float = float("nan")
    delta: float = float("nan")

    @property
    def arguments(self) -> tuple[float, ...]:
        """The ten real arguments as gendaylit ``-O 2`` (luminance) would print them."""
        return (self.diffuse_norm, self.ground_brightness, *self.coefficients,
                *self.sun_direction)

    def luminance(self, directions: np.ndarray) -> np.ndarray:
        """``perezlum.cal`` ``skybright`` (cd/m²) for unit direction vectors (..., 3).

        Defined for all directions: below the horizon it tends to the ground brightness A2.
        """
        d = np.asarray(directions, float)
        dz = d[..., 2]
        a, b, c, dd, e = self.coefficients
        sx, sy, sz = self.sun_direction
        cosg = d[..., 0] * sx + d[..., 1] * sy + dz * sz
        gamma = np.arccos(np.clip(cosg, -1.0, 1.0))
        dzc = np.where(dz > 0.01, dz, 0.01)
        with np.errstate(over="ignore", under="ignore"):
            grad = 1.0 + a * np.exp(b / dzc)
            indic = 1.0 + c * np.exp(dd * gamma) + e * cosg * cosg
        intersky = self.diffuse_norm * grad * indic
        wa = (dz + 1.01) ** 10
        wb = (dz + 1.01) ** -10
        return (wa * intersky + wb * self.ground_brightness) / (wa + wb)

    def horizontal_illuminance(self, n: int = 400) -> float:
        """Illuminance (lux) of the upper hemisphere of this sky on a horizontal plane, by
        quadrature — the light the engines actually receive (≈ DHI within gendaylit's
        normalisation error)."""
        return horizontal_illuminance(self, n)


def horizontal_illuminance(sky: PerezSky, n: int = 400) -> float:
    """∫ L cos θ dω over the upper hemisphere (midpoint rule in cos θ and φ, n × 2n cells)."""
    mu = (np.arange(n) + 0.5) / n  # cos θ
    phi = (np.arange(2 * n) + 0.5) * math.pi / n
    M, P = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1.0 - M * M)
    dirs = np.stack([s * np.cos(P), s * np.sin(P), M], axis=-1)
    L = sky.luminance(dirs)
    return float((L * M).sum() * (1.0 / n) * (math.pi / n))


def eccentricity(day_number: float) -> float:
    """Earth–sun distance correction (R0/R)² of gendaylit (Spencer's series)."""
    g = 2.0 * math.pi * (day_number - 1.0) / 365.0
    return (1.00011 + 0.034221 * math.cos(g) + 0.00128 * math.sin(g)
            + 0.000719 * math.cos(2 * g) + 0.000077 * math.sin(2 * g))


def air_mass(sun_zenith_deg: float) -> float:
    """Relative optical air mass (Kasten–Young form used by gendaylit)."""
    z = min(sun_zenith_deg, 90.0)
    return 1.0 / (math.cos(math.radians(z)) + 0.15 * math.exp(math.log(93.885 - z) * -1.253))


def _bin(eps: float, bounds: np.ndarray) -> int:
    return int(np.searchsorted(bounds, eps, side="right") - 1)


def _clamp_indices(eps: float, delta: float) -> tuple[float, float]:
    """gendaylit's check_parametrization: clamp ε and Δ into the model's range."""
    if eps < SKYCLEAR_INF:
        eps = SKYCLEAR_INF
    if eps > SKYCLEAR_SUP:
        eps = SKYCLEAR_SUP - 0.001
    if delta < SKYBRIG_INF:
        delta = SKYBRIG_INF
    if delta > SKYBRIG_SUP:
        delta = SKYBRIG_SUP
    return eps, delta


def _diffuse_efficacy(eps: float, delta: float, zenith_deg: float, water: float) -> float:
    a, b, c, d = _DIFFUSE_EFFI[max(_bin(eps, _EFFI_BOUNDS), 0)]
    return a + b * water + c * math.cos(math.radians(zenith_deg)) + d * math.log(delta)


def _direct_efficacy(eps: float, delta: float, zenith_deg: float, water: float) -> float:
    a, b, c, d = _DIRECT_EFFI[max(_bin(eps, _EFFI_BOUNDS), 0)]
    v = a + b * water + c * math.exp(5.73 * math.radians(zenith_deg) - 5.0) + d * delta
    return max(v, 0.0)


def perez_indices(dni_lux: float, dhi_lux: float, altitude_deg: float,
                  day_number: float = GENDAYLIT_ANG_DAY_NUMBER,
                  dew_point: float = DEW_POINT_DEFAULT) -> tuple[float, float]:
    """Perez sky clearness ε and brightness Δ from illuminances, as gendaylit ``-L`` does."""
    alt = min(altitude_deg, MAX_ALTITUDE_DEG)
    zen = 90.0 - alt
    z3 = 1.041 * math.radians(zen) ** 3
    water = math.exp(0.07 * dew_point - 0.075)
    e0 = eccentricity(day_number)
    m = air_mass(zen)

    def clearness(dif: float, dirn: float) -> float:
        if dif <= 0.0:
            return math.inf
        return ((dif + dirn) / dif + z3) / (1.0 + z3)

    def brightness(dif: float) -> float:
        return dif * m / (SOLAR_CONSTANT_E * e0)

    dif = dhi_lux * SOLAR_CONSTANT_E / SOLAR_CONSTANT_L
    dirn = dni_lux * SOLAR_CONSTANT_E / SOLAR_CONSTANT_L
    eps, delta = _clamp_indices(clearness(dif, dirn), brightness(dif))
    for _ in range(9):  # gendaylit's loop always runs its 9 iterations
        dif = dhi_lux / _diffuse_efficacy(eps, delta, zen, water)
        d_eff = _direct_efficacy(eps, delta, zen, water)
        dirn = 0.0 if d_eff < 0.1 else dni_lux / d_eff
        eps, delta = _clamp_indices(clearness(dif, dirn), brightness(dif))
    return eps, delta


def perez_coefficients(eps: float, delta: float, sun_zenith_rad: float) -> np.ndarray:
    """The five Perez 1993 coefficients a..e for clearness ε, brightness Δ, sun zenith Z."""
    if 1.065 < eps < 2.8 and delta < 0.2:
        delta = 0.2
    k = _bin(float(np.float32(eps)), _EFFI_BOUNDS)
    x = _COEFF_PEREZ[max(k, 0)].astype(float)
    Z = sun_zenith_rad
    c = x[:, 0] + x[:, 1] * Z + delta * (x[:, 2] + x[:, 3] * Z)
    if k <= 0:
        c[2] = math.exp((delta * (x[2, 0] + x[2, 1] * Z)) ** x[2, 2]) - x[2, 3]
        c[3] = -math.exp(delta * (x[3, 0] + x[3, 1] * Z)) + x[3, 2] + delta * x[3, 3]
    return c


def _relative_luminance(c: np.ndarray, zeta: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    return (1.0 + c[0] * np.exp(c[1] / np.cos(zeta))) * (
        1.0 + c[2] * np.exp(c[3] * gamma) + c[4] * np.cos(gamma) ** 2)


def _normsc(altitude_rad: float, intermediate: bool) -> float:
    nf = ([3.5556, -2.7152, -1.3081, 1.0660, 0.60227] if intermediate
          else [2.766521, 0.547665, -0.369832, 0.009237, 0.059229])
    x = (altitude_rad - math.pi / 4.0) / (math.pi / 4.0)
    v = nf[4]
    for i in (3, 2, 1, 0):
        v = v * x + nf[i]
    return v


def perez_parameters(dni_lux: float, dhi_lux: float, altitude_deg: float,
                     radiance_azimuth_deg: float, ground_reflectance: float = 0.2,
                     sun: bool = True, day_number: float = GENDAYLIT_ANG_DAY_NUMBER
                     ) -> PerezSky:
    """The sky of ``gendaylit -ang ALT AZ -L DNI DHI -g RHO [-s]``, luminances in cd/m².

    ``radiance_azimuth_deg`` is degrees west of south (gendaylit's convention); ``sun=False``
    is gendaylit's ``-s`` (it only removes the sun's share of the ground brightness).
    ``day_number`` 0 reproduces ``-ang`` (see the module notes); pass the day of year to get
    the value gendaylit computes when called with month/day/hour instead.
    """
    if dni_lux < 0 or dhi_lux < 0:
        raise ValueError("illuminances must be ≥ 0")
    alt_deg = min(altitude_deg, MAX_ALTITUDE_DEG)
    alt = math.radians(alt_deg)
    azi = math.radians(radiance_azimuth_deg)
    sundir = (-math.sin(azi) * math.cos(alt), -math.cos(azi) * math.cos(alt), math.sin(alt))
    zero = PerezSky(0.0, 0.0, (0.0, 0.0, 0.0, 0.0, 0.0), sundir)
    if dni_lux + dhi_lux == 0:
        return zero  # gendaylit prints its "error sky" (all zeros) when there is no light
    zen = 90.0 - alt_deg
    Z = math.radians(zen)
    eps, delta = perez_indices(dni_lux, dhi_lux, alt_deg, day_number)
    c = perez_coefficients(eps, delta, Z)
    if c[1] > 0:  # gendaylit: "positive Perez parameter B, printing error sky"
        return zero

    theta = np.radians(_DEFANGLE_THETA.astype(float))
    phi = np.radians(_DEFANGLE_PHI)
    cosg = math.cos(Z) * np.cos(theta) + math.sin(Z) * np.sin(theta) * np.cos(phi)
    gamma = np.arccos(np.clip(cosg, -1.0, 1.0))
    lv = _relative_luminance(c, theta, gamma).astype(np.float32).astype(float)
    integral = float((lv * np.cos(theta)).sum() * (2.0 * math.pi / 145.0))
    diffnorm = dhi_lux / integral  # cd/m² (gendaylit -O 2 units); 0 without diffuse light

    sun_luminance = dni_lux / SUN_SOLID_ANGLE_SR
    zenith = float(_relative_luminance(c, np.array(0.0), np.array(Z))) * diffnorm
    if eps == 1.0:
        normfactor = 0.777778
    elif eps >= 6.0:
        f2 = 0.274 * (0.91 + 10.0 * math.exp(-3.0 * (math.pi / 2.0 - alt)) + 0.45 * sundir[2] ** 2)
        normfactor = _normsc(alt, False) / f2 / math.pi
    else:
        f2 = (2.739 + 0.9891 * math.sin(0.3119 + 2.6 * alt)) * math.exp(
            -(math.pi / 2.0 - alt) * (0.4441 + 1.48 * alt))
        normfactor = _normsc(alt, True) / f2 / math.pi
    ground = zenith * normfactor
    if sun and eps > 1.0:
        ground += 6.8e-5 / math.pi * sun_luminance * sundir[2]
    ground *= ground_reflectance
    return PerezSky(diffnorm, ground, (float(c[0]), float(c[1]), float(c[2]), float(c[3]),
                                       float(c[4])), sundir, eps, delta)


def perez_sky(state) -> PerezSky:
    """The Perez sky of a :class:`radtree.light.sky.SkyState` exactly as the Radiance engine
    writes it (``radtree.engines.radiance.sky.gendaylit_command``: ``-ang``, ``-L``, ``-g ρ``,
    ``-s`` without sun)."""
    return perez_parameters(state.direct_normal_lux, state.diffuse_horizontal_lux,
                            state.sun.altitude_deg, state.sun.radiance_azimuth_deg,
                            ground_reflectance=state.ground_reflectance, sun=state.sun_on)


def perez_efficacy(dni: np.ndarray, dhi: np.ndarray, zenith_deg: np.ndarray,
                   day_of_year: np.ndarray, water_cm: float = PRECIPITABLE_WATER_CM
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Direct and diffuse luminous efficacy (lm/W) of Perez et al. (1990) per hour.

    Irradiances ``dni``, ``dhi`` in W/m², ``zenith_deg`` the sun zenith in degrees. Unlike
    :func:`perez_indices` (gendaylit's illuminance → irradiance iteration) the indices come
    straight from the irradiances: ε with the 1.041 Z³ term, Δ with the Kasten–Young (1989)
    air mass and the eccentricity 1 + 0.033 cos(2π·day/365), clamped to Δ ∈ [0.01, 0.6].
    """
    dni = np.asarray(dni, float)
    dhi = np.asarray(dhi, float)
    z = np.radians(np.clip(zenith_deg, 0.0, 90.0))
    k = 1.041 * z**3
    with np.errstate(divide="ignore", invalid="ignore"):
        eps = np.where(dhi > 0, ((dhi + dni) / np.where(dhi > 0, dhi, 1.0) + k) / (1.0 + k), 1.0)
    e0 = SOLAR_CONSTANT_E * (1.0 + 0.033 * np.cos(2.0 * np.pi * np.asarray(day_of_year) / 365.0))
    zd = np.minimum(np.degrees(z), 89.9)
    am = 1.0 / (np.cos(np.radians(zd)) + 0.50572 * (96.07995 - zd) ** -1.6364)
    delta = np.clip(dhi * am / e0, 0.01, 0.6)
    b = np.clip(np.searchsorted(_EFFI_BOUNDS, np.clip(eps, 1.0, 12.0), side="right") - 1, 0, 7)
    d = _DIFFUSE_EFFI[b]
    eff_dif = d[:, 0] + d[:, 1] * water_cm + d[:, 2] * np.cos(z) + d[:, 3] * np.log(delta)
    s = _DIRECT_EFFI[b]
    eff_dir = np.maximum(s[:, 0] + s[:, 1] * water_cm + s[:, 2] * np.exp(5.73 * z - 5.0)
                         + s[:, 3] * delta, 0.0)
    return eff_dir, eff_dif
