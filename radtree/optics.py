"""Materials as small typed classes (plain data; their Radiance text is written by
:mod:`radtree.engines.radiance.materials`, the NumPy and forward engines read the coefficients).

All optical values are photopic (visible) fractions in [0, 1]; colours are grey (R = G = B), so
the photopic value Radiance computes (0.265 R + 0.670 G + 0.065 B) equals the stated value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

# Transmittance → transmissivity converter for Radiance ``glass`` (normal incidence).
_A, _B, _C, _D = 0.8402528435, 0.0072522239, 0.9166530661, 0.0036261119
MAX_GLASS_TRANSMITTANCE = 0.9183


def fmt(x: float) -> str:
    """Format an optical coefficient the way radtree writes it: up to 4 decimals, no trailing 0."""
    s = f"{x:.4f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _check_fraction(name: str, value: float, what: str) -> None:
    if not isinstance(value, int | float) or math.isnan(value):
        raise ValueError(f"material '{name}': {what} must be a number, got {value!r}")
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"material '{name}': {what} must be between 0 and 1, got {value}")


def transmissivity_from_transmittance(tn: float) -> float:
    """Radiance ``glass`` transmissivity from a measured normal transmittance Tn.

    tn = (sqrt(0.8402528435 + 0.0072522239·Tn²) − 0.9166530661) / 0.0036261119 / Tn,
    valid for 0 < Tn ≤ 0.9183 (above that the transmissivity would exceed 1).
    """
    if not isinstance(tn, int | float) or math.isnan(tn):
        raise ValueError(f"transmittance must be a number, got {tn!r}")
    if tn <= 0.0:
        raise ValueError(f"transmittance must be > 0 for the glass converter, got {tn}")
    if tn > MAX_GLASS_TRANSMITTANCE:
        raise ValueError(
            f"transmittance {tn} is above {MAX_GLASS_TRANSMITTANCE}, where the glass "
            "transmissivity would exceed 1"
        )
    # (√(A + B·Tn²) − C) written as (A + B·Tn² − C²)/(√(A + B·Tn²) + C), with A = C² as the
    # derivation (Fresnel at n = 1.52) has it — the published 10-digit A and C differ by 5e-11,
    # which made the textbook form negative for Tn < 1e-4. Same values elsewhere (< 1e-9).
    root = math.sqrt(_A + _B * tn * tn)
    return _B * tn / (root + _C) / _D


@dataclass(frozen=True)
class Plastic:
    """Lambertian (optionally glossy) opaque material: ``void plastic NAME 0 0 5 ρ ρ ρ spec rough``."""

    name: str
    reflectance: float
    specularity: float = 0.0
    roughness: float = 0.0

    def __post_init__(self) -> None:
        _check_fraction(self.name, self.reflectance, "reflectance")
        _check_fraction(self.name, self.specularity, "specularity")
        _check_fraction(self.name, self.roughness, "roughness")

    @property
    def transmittance(self) -> float:
        return 0.0


@dataclass(frozen=True)
class Trans:
    """Translucent material (Radiance ``trans``), e.g. a leaf or a translucent crown shell.

    Built from the hemispherical reflectance R (diffuse), the diffuse transmittance T_d and the
    specular (direct, undeviated) transmittance T_s. With spec = 0:
    C = R + T_d + T_s, trans = (T_d + T_s)/C, tspec = T_s/(T_d + T_s).
    """

    name: str
    reflectance: float
    diffuse_transmittance: float
    specular_transmittance: float = 0.0

    def __post_init__(self) -> None:
        _check_fraction(self.name, self.reflectance, "reflectance")
        _check_fraction(self.name, self.diffuse_transmittance, "diffuse transmittance")
        _check_fraction(self.name, self.specular_transmittance, "specular transmittance")
        total = self.reflectance + self.diffuse_transmittance + self.specular_transmittance
        if total > 1.0 + 1e-9:
            raise ValueError(
                f"material '{self.name}': reflectance + transmittance = {total:.4f} exceeds 1"
            )
        if total <= 0.0:
            raise ValueError(f"material '{self.name}': reflectance + transmittance must be > 0")

    @property
    def transmittance(self) -> float:
        return self.diffuse_transmittance + self.specular_transmittance

    @property
    def coefficients(self) -> tuple[float, float, float]:
        """(C, trans, tspec) as Radiance expects them."""
        t = self.transmittance
        c = self.reflectance + t
        trans = t / c
        tspec = self.specular_transmittance / t if t > 0 else 0.0
        return c, trans, tspec


@dataclass(frozen=True)
class Glass:
    """Radiance ``glass``: specular transmission, Fresnel reflection (~8 %), no diffuse reflectance.

    Use :meth:`from_transmittance` to build it from a measured normal transmittance.
    """

    name: str
    transmissivity: float

    def __post_init__(self) -> None:
        _check_fraction(self.name, self.transmissivity, "transmissivity")

    @classmethod
    def from_transmittance(cls, name: str, transmittance: float) -> Glass:
        return cls(name, transmissivity_from_transmittance(transmittance))

    @property
    def reflectance(self) -> float:
        return 0.0

    @property
    def transmittance(self) -> float:
        """Normal-incidence transmittance of this transmissivity (inverse of the converter)."""
        tn = self.transmissivity
        # Radiance glass: T = tn (1-r)^2 / (1 - r^2 tn^2), r = 0.04 at n = 1.52 (normal incidence)
        r = ((1.52 - 1.0) / (1.52 + 1.0)) ** 2
        return tn * (1 - r) ** 2 / (1 - (r * tn) ** 2)


@dataclass(frozen=True)
class Hole:
    """Fully open: rays pass undisturbed (an opening in a perforated shell).

    Radiance geometry with this material is simply not written; the NumPy engine ignores it.
    """

    name: str

    @property
    def reflectance(self) -> float:
        return 0.0

    @property
    def transmittance(self) -> float:
        return 1.0


@dataclass(frozen=True)
class Bsdf:
    """A surface scattering by a measured or computed BSDF (LBNL/WINDOW XML, Klems or tensor
    tree): ``void BSDF NAME 6 thickness xml ux uy uz . 0 0``. The surface normal points to the
    XML's *back* side (genBSDF's +z, the room); ``up`` is the world direction of the XML's +y
    (Radiance keeps it in the plane of the normal and ``up``). ``peak``: Radiance's ``aBSDF``
    instead (``void aBSDF NAME 5 xml ux uy uz . 0 0``, no thickness): the XML's
    straight-through peak, when it has one, passes shadow and view rays unscattered, so a
    light source is seen through it directly (Radiance ``src/rt/m_bsdf.c``,
    ``compute_through``: the BTDF at 29 directions round the straight line, the values not
    below ⅛ of the peak's mean taken as the through component). Radiance only: the in-process engines refuse it."""

    name: str
    xml: str
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    thickness: float = 0.0
    peak: bool = False

    def __post_init__(self) -> None:
        if not self.xml.endswith(".xml"):
            raise ValueError(f"material '{self.name}': BSDF data must be an .xml file, "
                             f"got {self.xml!r}")
        if not math.isfinite(self.thickness) or self.thickness < 0:
            raise ValueError(f"material '{self.name}': thickness must be ≥ 0 m")
        if self.peak and self.thickness:
            raise ValueError(f"material '{self.name}': aBSDF (peak) has no thickness")


#: The Klems full basis (LBNL/WINDOW "LBNL/Klems Full"): per θ ring (lower, upper, centre
#: polar angle in degrees, number of azimuth patches); 145 patches in this order.
KLEMS_FULL_RINGS: tuple[tuple[float, float, float, int], ...] = (
    (0.0, 5.0, 0.0, 1), (5.0, 15.0, 10.0, 8), (15.0, 25.0, 20.0, 16), (25.0, 35.0, 30.0, 20),
    (35.0, 45.0, 40.0, 24), (45.0, 55.0, 50.0, 24), (55.0, 65.0, 60.0, 24),
    (65.0, 75.0, 70.0, 16), (75.0, 90.0, 82.5, 12))


Material = Plastic | Trans | Glass | Hole | Bsdf


def with_reflectance(material: Plastic, reflectance: float) -> Plastic:
    """The same Lambertian material with another reflectance (per-hour ground reflectance)."""
    return Plastic(material.name, reflectance, material.specularity, material.roughness)
