"""The light of an hour as Radiance text: sun, sky, ground glow and ``gendaylit``.

Everything that writes (or reads back) Radiance syntax for skies lives here; the skies
themselves (:class:`~radtree.light.sky.SkyState`, :mod:`radtree.light.perez`) are data in
:mod:`radtree.light`. Radiance radiances are W/(sr·m²) of its visible channel:
radiance = luminance / ``WHITE_EFFICACY`` (:mod:`radtree.light.units`).
"""

from __future__ import annotations

import functools
import re

from radtree.engines.radiance.binaries import RadianceInstall, run
from radtree.light.perez import PerezSky
from radtree.light.sky import SkyState
from radtree.light.sun import SUN_ANGLE_DEG
from radtree.light.units import WHITE_EFFICACY

ANALYTIC_SKY_CAL = {
    "cosine": "skybright = if(Dz, Dz, 0);\n",
    "cie_overcast": "skybright = if(Dz, (1 + 2*Dz)/3, 0);\n",
}


def _glow(name: str, radiance: float, modifier: str = "void") -> str:
    v = f"{radiance:.6g}"
    return f"{modifier} glow {name}\n0\n0\n4 {v} {v} {v} 0\n"


def _source(modifier: str, name: str, direction: str, angle: float) -> str:
    return f"{modifier} source {name}\n0\n0\n4 {direction} {angle:g}\n"


def sun_radiance_text(state: SkyState) -> str:
    """The collimated sun as Radiance ``light`` + ``source`` (0.533° disc)."""
    v = f"{state.sun_radiance:.6g}"
    d = state.sun.vector
    return (
        f"void light solar\n0\n0\n3 {v} {v} {v}\n\n"
        f"solar source sun\n0\n0\n4 {d[0]:.6f} {d[1]:.6f} {d[2]:.6f} {SUN_ANGLE_DEG:g}\n"
    )


def analytic_sky_text(state: SkyState, cal_name: str | None = None) -> str:
    """Radiance text of the analytic test skies; ``cal_name`` is the .cal file for non-uniform ones."""
    L = state.zenith_luminance / WHITE_EFFICACY
    if state.sky_model == "uniform":
        return _glow("sky_glow", L) + "\n" + _source("sky_glow", "sky", "0 0 1", 180)
    if cal_name is None:
        raise ValueError(f"the {state.sky_model} sky needs a .cal file name")
    return (
        f"void brightfunc skyfunc\n2 skybright {cal_name}\n0\n0\n\n"
        + _glow("sky_glow", L, "skyfunc")
        + "\n"
        + _source("sky_glow", "sky", "0 0 1", 180)
    )


def ground_glow_text(state: SkyState) -> str:
    """The distant ground below the horizon (glow of radiance ρ·E_h/π), or '' when off."""
    if not state.ground_glow or state.ground_luminance <= 0:
        return ""
    L = state.ground_luminance / WHITE_EFFICACY
    return _glow("ground_glow", L) + "\n" + _source("ground_glow", "ground", "0 0 -1", 180)


def perez_sky_suffix(ground_glow: bool) -> str:
    """What follows ``gendaylit``'s output: the glow sky (and ground) using its skyfunc."""
    text = _glow("sky_glow", 1.0, "skyfunc") + "\n" + _source("sky_glow", "sky", "0 0 1", 180)
    if ground_glow:
        text += "\n" + _glow("ground_glow", 1.0, "skyfunc") + "\n"
        text += _source("ground_glow", "ground", "0 0 -1", 180)
    return text


def gendaylit_command(state: SkyState) -> list[str]:
    """``gendaylit`` argument list for a Perez sky of this hour (visible output, lux inputs).

    The sun position is radtree's own (``-ang`` altitude and azimuth west of south); ``-s``
    leaves the sun out when there is no direct sun, ``-g`` sets the ground reflectance.
    """
    cmd = [
        "gendaylit",
        "-ang",
        f"{state.sun.altitude_deg:.4f}",
        f"{state.sun.radiance_azimuth_deg:.4f}",
        "-L",
        f"{state.direct_normal_lux:g}",
        f"{state.diffuse_horizontal_lux:g}",
        "-O",
        "0",
        "-g",
        f"{state.ground_reflectance:.4f}",
    ]
    if not state.sun_on:
        cmd.append("-s")
    return cmd


@functools.lru_cache(maxsize=512)
def _gendaylit(bin_dir: str, cmd: tuple[str, ...]) -> str:
    """``gendaylit``'s output for an argument list, run once per process and Radiance
    installation ``bin_dir`` (the crown realisations and scenarios of one sky share hours)."""
    return run(list(cmd)).decode()


def sky_text(state: SkyState, install: RadianceInstall | None) -> str:
    """The hour's light in Radiance: sun (if on), sky (if any) and distant ground glow."""
    header = (f"# {state.time} local ({state.datetime.isoformat()}): sun altitude "
              f"{state.sun.altitude_deg:.3f}°, azimuth {state.sun.azimuth_deg:.3f}° "
              f"(compass; Radiance {state.sun.radiance_azimuth_deg:.3f}° west of south)\n"
              f"# direct normal {state.direct_normal_lux:g} lx, sky model {state.sky_model}\n\n")
    if state.sky_model == "perez":
        if install is None:
            raise RuntimeError("a Perez sky needs gendaylit (Radiance)")
        cmd = gendaylit_command(state)
        text = _gendaylit(str(install.bin_dir), tuple(cmd))
        return header + f"# {' '.join(cmd)}\n" + text + "\n" + perez_sky_suffix(state.ground_glow)
    parts = [header]
    if state.sun_on:
        parts.append(sun_radiance_text(state) + "\n")
    if state.sky_model in ("uniform", "cosine", "cie_overcast"):
        cal = "skybright.cal" if state.sky_model != "uniform" else None
        parts.append(analytic_sky_text(state, f"skies/{state.sky_model}.cal" if cal else None))
        parts.append("\n")
    parts.append(ground_glow_text(state))
    return "".join(parts)


_SKYFUNC = re.compile(r"brightfunc\s+skyfunc\s+2\s+skybright\s+perezlum\.cal\s+0\s+10((?:\s+\S+){10})")
_EPS = re.compile(r"epsilon, delta.*?:\s*(\S+)\s+(\S+)")


def parse_gendaylit(text: str, output_units: int = 0) -> PerezSky:
    """The :class:`PerezSky` in gendaylit's printed output (``-O 0`` radiances × ``WHITE_EFFICACY`` → cd/m²)."""
    m = _SKYFUNC.search(text)
    if m is None:
        raise ValueError("no 'brightfunc skyfunc ... perezlum.cal' with 10 arguments in the text")
    v = [float(x) for x in m.group(1).split()]
    scale = WHITE_EFFICACY if output_units == 0 else 1.0
    eps = delta = float("nan")
    me = _EPS.search(text)
    if me:
        eps, delta = float(me.group(1)), float(me.group(2))
    return PerezSky(v[0] * scale, v[1] * scale, (v[2], v[3], v[4], v[5], v[6]),
                    (v[7], v[8], v[9]), eps, delta)
