"""Checks of the Radiance form of turbid crowns (``mist`` volumes,
:mod:`radtree.engines.radiance.mist`), rows of ``radtree verify``.

**Beer–Lambert through a mist crown** (real ``rtrace``, ``-ab 0``, the default
``engine.mist_extinction`` / ``engine.mist_sun``): one spherical crown of radius R = 2 m
(centre 3 m up) of leaf area density u, Campbell's ellipsoidal leaf angles x = 1 (G = ½) and
x = 3, a leaf of T_s = 0.3; the sun at zeniths 0°, 30°, 60°; one sensor facing the sun on the
line through the crown's centre, R + 1 m beyond it, so that its sun crosses 2R of medium. The
sensor's sun over DNI against exp(−u·G(μ)·(1 − T_s)·2R) of the spheroid (Ross 1981, ch. 2;
the deflecting leaves' rate of :mod:`radtree.engines.common.turbid`) — within 1 %: the sun's
shadow rays carry Radiance's exact transmittance (no sampling), the envelope's polyhedron (24
× 48, volume-preserving) keeps the chord within ±0.3 %.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from radtree.config import EngineParams, Louvers
from radtree.engines.radiance.engine import ENGINE_NAME
from radtree.light.sky import SkyState
from radtree.light.sun import SunPosition, local_datetime
from radtree.media import TurbidCrowns
from radtree.optics import Trans
from radtree.scene import Scene, SensorGrid
from radtree.trees.turbid import leaf_kind
from radtree.verify.checks import Check, log_checks

log = logging.getLogger(__name__)

ENGINE = ENGINE_NAME   # the Radiance engine's registered name
RADIUS = 2.0
CENTRE = np.array([0.0, 0.0, 3.0])
DNI = 100000.0
LEAF = Trans("leaf", 0.1, 0.05, 0.3)
CASES = ((1.0, 1.0), (3.0, 0.8))   # (ellipsoid x, leaf area density m²/m³)
ZENITHS = (0.0, 30.0, 60.0)


def mist_beer_lambert(x: float, lad: float, mu: float) -> float:
    """exp(−u·G(μ)·(1 − T_s)·2R): the sun's transmittance across the crown's diameter."""
    kind = leaf_kind(Louvers(inclination_distribution="ellipsoidal", ellipsoid_x=x), "leaf")
    g = float(kind.g(np.array([mu]))[0])
    return math.exp(-lad * g * (1.0 - LEAF.specular_transmittance) * 2.0 * RADIUS)


def _sun_row(x: float, lad: float, zenith: float) -> Check:
    from radtree.engines.radiance.engine import trace_hour

    kind = leaf_kind(Louvers(inclination_distribution="ellipsoidal", ellipsoid_x=x), "leaf")
    sun = SunPosition(90.0 - zenith, 180.0)
    d = sun.vector
    grid = SensorGrid("s", (CENTRE - (RADIUS + 1.0) * d)[None], d[None])
    media = TurbidCrowns.of(CENTRE[None], RADIUS, RADIUS, lad, 0, [kind])
    state = SkyState("12:00", local_datetime("2024-12-22", "12:00", -3), sun, DNI,
                     ground_glow=False)
    lux = trace_hour(Scene([], {"leaf": LEAF}, {"s": grid}, media=media), state,
                     EngineParams(ab=0))["s"].lux
    want = mist_beer_lambert(x, lad, math.cos(math.radians(zenith)))
    return Check(f"mist crown: sun across 2R, ellipsoid x {x:g}, u {lad:g}, zenith {zenith:g}°",
                 ENGINE, want, float(lux[0]) / DNI, 0.01 * want,
                 reference="Beer–Lambert exp(−u·G(μ)·(1−T_s)·2R), Ross 1981 ch. 2")


def mist_checks() -> list[Check]:
    """The rows of the module text (none when Radiance is not found), each logged (INFO)."""
    from radtree.engines.radiance.binaries import find_radiance

    if find_radiance() is None:
        log.info("mist crown checks skipped: Radiance not found")
        return []
    out = [_sun_row(x, lad, z) for x, lad in CASES for z in ZENITHS]
    return log_checks(out, log)
