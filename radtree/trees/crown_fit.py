"""A crown fitted to upward photos: the fitted parameters, residuals, and whether the fit
describes the photo (:meth:`CrownFit.problems`); the fit itself is
:mod:`radtree.trees.photo_fit`."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from radtree.trees.leaf_angles import mean_tilt

X_BOUNDS = (0.1, 10.0)
U_BOUNDS = (1e-3, 20.0)
#: a fit whose ring gap fractions miss the photo's by more than this (RMS) is refused
#: (``[tree] accept_poor_fit`` overrides): a crown the photo does not describe
MAX_RING_RMS = 0.05


def _at_bound(v: float, bounds: tuple[float, float]) -> bool:
    """Within 1 % (in log) of either bound."""
    span = math.log(bounds[1] / bounds[0])
    return min(abs(math.log(v / bounds[0])), abs(math.log(bounds[1] / v))) < 0.01 * span

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
    clumping: float = 1.0            # the crown's Ω (fitted when clumping_fitted)
    clumping_fitted: bool = False
    clumping_lx_model: float = math.nan   # the fitted crown's clumping_lx (cluster draws)
    clumping_curve: tuple[tuple[float, float], ...] = ()   # (Ω, model clumping_lx)
    clumping_lx_target: float = math.nan   # the photos' clumping_lx on the fit's grid
    #: per zenith ring: (zenith from, to (degrees), photo gap fraction, model gap fraction)
    rings: tuple[tuple[float, float, float, float], ...] = ()

    def problems(self) -> list[str]:
        """Why the fit is poor (empty when it is acceptable): ring RMS above
        :data:`MAX_RING_RMS`, or a fitted parameter at its bound."""
        out = []
        if not self.ring_rms <= MAX_RING_RMS:
            out.append(f"gap-fraction RMS over the zenith rings {self.ring_rms:.3f} > "
                       f"{MAX_RING_RMS:g}")
        if _at_bound(self.lad, U_BOUNDS):
            out.append(f"leaf area density {self.lad:.3g} m²/m³ at its bound {U_BOUNDS}")
        if self.x is not None and _at_bound(self.x, X_BOUNDS):
            out.append(f"leaf angle parameter x = {self.x:.3g} (mean tilt "
                       f"{self.mean_tilt_deg:.1f}°) at its bound {X_BOUNDS}")
        return out

    def ring_table(self) -> str:
        """The rings, photo vs model, as text lines."""
        head = "zenith °   photo gap  model gap"
        return "\n".join([head] + [f"{a:4.0f}–{b:<4.0f}  {p:9.3f}  {m:9.3f}"
                                   for a, b, p, m in self.rings])

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
                **self.spread(), **self.clumping_dict()}

    def clumping_dict(self) -> dict[str, Any]:
        """The clumping entries (none for an unclumped crown that was not fitted)."""
        if self.clumping >= 1.0 and not self.clumping_fitted:
            return {}
        return {"clumping_omega": self.clumping, "clumping_fitted": self.clumping_fitted,
                "clumping_lx_model": self.clumping_lx_model,
                "clumping_lx_photo_fit_grid": self.clumping_lx_target,
                "clumping_curve": [list(p) for p in self.clumping_curve]}
