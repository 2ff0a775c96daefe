"""The light of one hour: sun (collimated source) and sky, as data.

Illuminances in lux, luminances in cd/m². Radiance radiance units are W/(sr·m²) of its
"visible" channel: luminance = ``WHITE_EFFICACY`` × radiance (:mod:`radtree.light.units`).
The sun is a collimated source of the sun's 0.533° disc; its radiance is
DNI / (``WHITE_EFFICACY`` · Ω_sun). The Radiance text of these skies is written by
:mod:`radtree.engines.radiance.sky`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime

from radtree.light.sun import SUN_SOLID_ANGLE_SR, SunPosition
from radtree.light.units import WHITE_EFFICACY

SKY_MODELS = ("none", "perez", "uniform", "cosine", "cie_overcast")


@dataclass(frozen=True)
class SkyState:
    """Everything an engine needs to light one hour.

    * ``sky_model``: ``none`` (sun only, as in the reference study), ``perez`` (``gendaylit``
      clear-sky Perez from DNI and DHI), or an analytic test sky (``uniform``, ``cosine``:
      L = L₀·cos θ, ``cie_overcast``) of zenith luminance ``zenith_luminance`` cd/m².
    * ``direct_normal_lux``: beam illuminance of the sun (0 = no sun).
    * ``diffuse_horizontal_lux``: sky illuminance on an unobstructed horizontal plane (Perez).
    * ``ground_reflectance``: the hour's reflectance of the ground material (set from the sun
      altitude for concrete); ``ground_glow``: a distant ground below the horizon of radiance
      ρ·E_h/π (off when the ground-reflected light is calculated instead of traced).
    """

    time: str
    datetime: datetime
    sun: SunPosition
    direct_normal_lux: float
    diffuse_horizontal_lux: float = 0.0
    sky_model: str = "none"
    zenith_luminance: float = 0.0
    ground_reflectance: float = 0.2
    ground_glow: bool = True

    def __post_init__(self) -> None:
        if self.sky_model not in SKY_MODELS:
            raise ValueError(f"sky model must be one of {SKY_MODELS}, got {self.sky_model!r}")
        if self.direct_normal_lux < 0 or self.diffuse_horizontal_lux < 0:
            raise ValueError(f"{self.time}: illuminances must be ≥ 0")
        if self.direct_normal_lux > 0 and not self.sun.above_horizon:
            raise ValueError(
                f"{self.time}: the sun is below the horizon (altitude {self.sun.altitude_deg:.2f}°)"
                " but a direct normal illuminance is given"
            )
        if not 0.0 <= self.ground_reflectance <= 1.0:
            raise ValueError(f"{self.time}: ground reflectance must be in [0, 1]")

    @property
    def label(self) -> str:
        """``HHMM``, used for file names and Makefile targets."""
        return self.time.replace(":", "")

    @property
    def decimal_hour(self) -> float:
        """Clock hour as a decimal number (gendaylit silently drops ``:MM``)."""
        return self.datetime.hour + self.datetime.minute / 60.0

    @property
    def sun_on(self) -> bool:
        return self.direct_normal_lux > 0 and self.sun.above_horizon

    @property
    def sun_radiance(self) -> float:
        """Radiance of the sun disc, W/(sr·m²) Radiance units."""
        return self.direct_normal_lux / WHITE_EFFICACY / SUN_SOLID_ANGLE_SR

    @property
    def direct_horizontal_lux(self) -> float:
        return self.direct_normal_lux * max(0.0, math.sin(math.radians(self.sun.altitude_deg)))

    @property
    def sky_horizontal_lux(self) -> float:
        """Unobstructed horizontal illuminance from the sky alone (analytic for test skies)."""
        L0 = self.zenith_luminance
        if self.sky_model == "uniform":
            return math.pi * L0
        if self.sky_model == "cosine":
            return 2.0 * math.pi * L0 / 3.0
        if self.sky_model == "cie_overcast":
            return 7.0 * math.pi * L0 / 9.0
        if self.sky_model == "perez":
            return self.diffuse_horizontal_lux
        return 0.0

    @property
    def global_horizontal_lux(self) -> float:
        return self.direct_horizontal_lux + self.sky_horizontal_lux

    @property
    def ground_luminance(self) -> float:
        """Luminance of the distant ground glow, cd/m² (ρ·E_h/π), 0 when off."""
        if not self.ground_glow:
            return 0.0
        return self.ground_reflectance * self.global_horizontal_lux / math.pi


def sky_luminance(state: SkyState, dz):
    """Luminance (cd/m²) of the analytic test skies for direction z-components ``dz`` (array).

    Perez skies are evaluated by the engines from :func:`radtree.light.perez.perez_sky`.
    """
    import numpy as np

    dz = np.asarray(dz, float)
    up = dz > 0
    L0 = state.zenith_luminance
    if state.sky_model == "uniform":
        return np.where(up, L0, 0.0)
    if state.sky_model == "cosine":
        return np.where(up, L0 * np.clip(dz, 0, 1), 0.0)
    if state.sky_model == "cie_overcast":
        return np.where(up, L0 * (1.0 + 2.0 * np.clip(dz, 0, 1)) / 3.0, 0.0)
    return np.zeros_like(dz)
