"""Fisheye lens projections: zenith angle (degrees) <-> normalised image radius.

The normalised radius is ``rho = r / R90`` where ``r`` is the distance of a point from the
image centre and ``R90`` the radius (pixels) of the 90° circle, so ``rho(90°) = 1`` for every
projection. For horizontal-axis photos read "zenith angle" as "angle from the lens axis".

Projections (theta in radians where a formula needs it):

* ``equidistant``   rho = theta / 90°                       (the default; "polar")
* ``equisolid``     rho = sin(theta/2) / sin(45°)
* ``stereographic`` rho = tan(theta/2)
* ``orthographic``  rho = sin(theta)                         (defined up to 90° only)
* ``polynomial``    rho = p(x) / p(1),  p(x) = a1 x + a2 x² + ...,  x = theta / 90°

Polynomial lenses are normalised by ``p(1)`` so that the mask radius is exactly the 90° circle
(for the FC-E8, p(1) = 1.00108: a 0.1 % rescaling). Their inverse is computed numerically
(a monotone lookup table refined by Newton steps), vectorised over arrays.

Lens presets:

* ``FC-E8``: Nikon FC-E8 converter, p(x) = 1.06 x + 0.00498 x² − 0.0639 x³ (as published with
  the hemispheR R package's example photo).
* ``FC-E9``: Nikon FC-E9 converter, r/R = 0.6427 θ + 0.0346 θ² − 0.024491 θ³ with θ in radians
  (Hemisfer's polynomial, as distributed with the caiman/rcaiman R packages, Díaz et al.; rcaiman
  rounds it to 0.643, 0.0346, −0.0245). Stored here in the x = θ/90° form.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from radtree.errors import ConfigError

KINDS = ("equidistant", "equisolid", "stereographic", "orthographic", "polynomial")

FC_E8_COEFFICIENTS = (1.06, 0.00498, -0.0639)
FC_E9_RADIAN_COEFFICIENTS = (0.6427, 0.0346, -0.024491)

_HALF_PI = math.pi / 2.0
_TABLE_SIZE = 4097
NEWTON_STEPS = 1  # after a 4097-point table lookup one step reaches ~1e-12 degrees


def radian_to_x_coefficients(coefficients: tuple[float, ...]) -> tuple[float, ...]:
    """Convert polynomial coefficients in theta (radians) into the x = theta/90° form."""
    return tuple(float(a) * _HALF_PI ** (k + 1) for k, a in enumerate(coefficients))


@dataclass(frozen=True)
class Projection:
    """A lens projection mapping zenith angle (degrees) to normalised radius rho = r/R90.

    ``coefficients`` (polynomial lenses only) are a1, a2, ... of p(x) = Σ a_k x^k with
    x = zenith/90°; there is no constant term (the image centre is the lens axis).
    """

    kind: str = "equidistant"
    coefficients: tuple[float, ...] = ()
    name: str = ""
    _table: tuple[NDArray[np.float64], NDArray[np.float64]] | None = field(
        default=None, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        kind = str(self.kind).lower()
        if kind not in KINDS:
            raise ConfigError(
                f"unknown projection '{self.kind}'; expected one of {', '.join(KINDS)}",
                field="lens",
            )
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "coefficients", tuple(float(c) for c in self.coefficients))
        if not self.name:
            object.__setattr__(self, "name", kind)
        if kind != "polynomial":
            if self.coefficients:
                raise ConfigError(f"projection '{kind}' takes no coefficients", field="lens")
            return
        coeffs = self.coefficients
        if not coeffs or len(coeffs) > 8:
            raise ConfigError(
                "a polynomial lens needs 1 to 8 coefficients a1,a2,... (r/R = a1·x + a2·x² + ..., "
                "x = zenith/90°)",
                field="polynomial",
            )
        if not all(math.isfinite(c) for c in coeffs):
            raise ConfigError(f"polynomial coefficients must be finite, got {coeffs}", field="polynomial")
        x = np.linspace(0.0, 1.0, _TABLE_SIZE)
        raw = _poly(coeffs, x)
        if raw[-1] <= 0 or np.any(np.diff(raw) <= 0):
            raise ConfigError(
                f"polynomial lens {coeffs} is not strictly increasing from 0° to 90°; "
                "r/R must grow with the zenith angle",
                field="polynomial",
            )
        rho = raw / raw[-1]
        object.__setattr__(self, "_table", (rho, x * 90.0))

    # -- forward -----------------------------------------------------------------------------
    @property
    def max_zenith_deg(self) -> float:
        """Largest zenith angle (degrees) the projection is defined for in radtree."""
        return {"equidistant": 180.0, "equisolid": 180.0, "stereographic": 179.0}.get(
            self.kind, 90.0
        )

    def radius(self, zenith_deg: ArrayLike) -> NDArray[np.float64]:
        """Normalised radius rho (1 at 90°) of zenith angles in degrees; NaN where undefined."""
        z = np.asarray(zenith_deg, dtype=np.float64)
        t = np.radians(z)
        with np.errstate(invalid="ignore"):
            if self.kind == "equidistant":
                rho = z / 90.0
            elif self.kind == "equisolid":
                rho = np.sin(t / 2.0) / math.sin(math.pi / 4.0)
            elif self.kind == "stereographic":
                rho = np.tan(t / 2.0)
            elif self.kind == "orthographic":
                rho = np.sin(t)
            else:
                rho = _poly(self.coefficients, z / 90.0) / self._p1
            bad = (z < 0) | (z > self.max_zenith_deg) | ~np.isfinite(z)
        return np.where(bad, np.nan, rho)

    def derivative(self, zenith_deg: ArrayLike) -> NDArray[np.float64]:
        """d rho / d theta with theta in radians (used for pixel solid angles)."""
        z = np.asarray(zenith_deg, dtype=np.float64)
        t = np.radians(z)
        if self.kind == "equidistant":
            return np.full_like(z, 1.0 / _HALF_PI)
        if self.kind == "equisolid":
            return np.cos(t / 2.0) / (2.0 * math.sin(math.pi / 4.0))
        if self.kind == "stereographic":
            return 0.5 / np.cos(t / 2.0) ** 2
        if self.kind == "orthographic":
            return np.cos(t)
        return _dpoly(self.coefficients, z / 90.0) / self._p1 / _HALF_PI

    # -- inverse -----------------------------------------------------------------------------
    def zenith(self, rho: ArrayLike) -> NDArray[np.float64]:
        """Zenith angle (degrees) of normalised radii; NaN outside the projection's range."""
        r = np.asarray(rho, dtype=np.float64)
        with np.errstate(invalid="ignore"):
            if self.kind == "equidistant":
                z = 90.0 * r
            elif self.kind == "equisolid":
                z = np.degrees(2.0 * np.arcsin(r * math.sin(math.pi / 4.0)))
            elif self.kind == "stereographic":
                z = np.degrees(2.0 * np.arctan(r))
            elif self.kind == "orthographic":
                z = np.degrees(np.arcsin(r))
            else:
                z = self._poly_inverse(r)
            bad = (r < 0) | ~np.isfinite(r) | ~(z <= self.max_zenith_deg + 1e-9)
        return np.where(bad, np.nan, z)

    @property
    def _p1(self) -> float:
        return float(sum(self.coefficients))

    def _poly_inverse(self, rho: NDArray[np.float64]) -> NDArray[np.float64]:
        assert self._table is not None
        table_rho, table_z = self._table
        inside = (rho >= 0) & (rho <= 1.0 + 1e-12)
        z = np.interp(np.clip(rho, 0.0, 1.0), table_rho, table_z)
        for _ in range(NEWTON_STEPS):  # refine the table lookup on the smooth polynomial
            f = _poly(self.coefficients, z / 90.0) / self._p1 - rho
            d = _dpoly(self.coefficients, z / 90.0) / self._p1 / 90.0
            z = np.clip(z - f / d, 0.0, 90.0)
        return np.where(inside, z, np.nan)

    def describe(self) -> str:
        """Short human-readable description (for CSV/GeoJSON provenance)."""
        if self.kind == "polynomial":
            terms = ",".join(f"{c:g}" for c in self.coefficients)
            return f"{self.name} (polynomial {terms} in x=zenith/90)"
        return self.name


def _poly(coeffs: tuple[float, ...], x: NDArray[np.float64]) -> NDArray[np.float64]:
    out = np.zeros_like(x, dtype=np.float64)
    for a in reversed(coeffs):
        out = (out + a) * x
    return out


def _dpoly(coeffs: tuple[float, ...], x: NDArray[np.float64]) -> NDArray[np.float64]:
    out = np.zeros_like(x, dtype=np.float64)
    for k in range(len(coeffs), 0, -1):
        out = out * x + k * coeffs[k - 1]
    return out


def polynomial_lens(coefficients: ArrayLike, *, unit: str = "x", name: str = "") -> Projection:
    """A polynomial lens from coefficients a1, a2, ... in ``unit`` "x" (zenith/90°) or "rad"."""
    coeffs = tuple(float(c) for c in np.atleast_1d(np.asarray(coefficients, dtype=float)))
    if unit == "rad":
        coeffs = radian_to_x_coefficients(coeffs)
    elif unit != "x":
        raise ConfigError(f"polynomial unit must be 'x' or 'rad', got '{unit}'", field="polynomial")
    return Projection("polynomial", coeffs, name or "polynomial")


LENS_PRESETS: dict[str, Projection] = {
    "equidistant": Projection("equidistant"),
    "equisolid": Projection("equisolid"),
    "stereographic": Projection("stereographic"),
    "orthographic": Projection("orthographic"),
    "fc-e8": Projection("polynomial", FC_E8_COEFFICIENTS, "FC-E8"),
    "fc-e9": Projection(
        "polynomial", radian_to_x_coefficients(FC_E9_RADIAN_COEFFICIENTS), "FC-E9"
    ),
}


def get_lens(name: str) -> Projection:
    """Look up a lens preset by name (case-insensitive; 'FC-E8', 'fce8' and 'fc_e8' all work)."""
    key = str(name).strip().lower().replace("_", "-")
    if key in ("fce8", "nikon-fc-e8"):
        key = "fc-e8"
    if key in ("fce9", "nikon-fc-e9"):
        key = "fc-e9"
    if key == "polar":
        key = "equidistant"
    if key not in LENS_PRESETS:
        names = ", ".join(p.name if p.kind == "polynomial" else k for k, p in LENS_PRESETS.items())
        raise ConfigError(f"unknown lens '{name}'; known lenses: {names}", field="lens")
    return LENS_PRESETS[key]


def parse_polynomial(text: str) -> Projection:
    """Parse ``"a1,a2,a3"`` (x = zenith/90°) into a polynomial lens."""
    try:
        coeffs = [float(p) for p in str(text).split(",") if p.strip()]
    except ValueError:
        raise ConfigError(
            f"cannot read polynomial '{text}': expected comma-separated numbers a1,a2,a3",
            field="polynomial",
        ) from None
    return polynomial_lens(coeffs, name="polynomial")
