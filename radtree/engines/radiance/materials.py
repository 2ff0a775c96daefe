"""Radiance text of radtree's materials (:mod:`radtree.optics`): the one place that writes it.

``material_text(m)`` renders one material exactly as ``materials.rad`` holds it (grey: R = G = B,
coefficients via :func:`radtree.optics.fmt`):

* :class:`~radtree.optics.Plastic` → ``void plastic NAME 0 0 5 ρ ρ ρ spec rough``;
* :class:`~radtree.optics.Trans` → ``void trans NAME 0 0 7 C C C 0 0 trans tspec`` with
  C = R + T, trans = T / C, tspec = T_s / T (Radiance reference manual, ``trans``);
* :class:`~radtree.optics.Glass` → ``void glass NAME 0 0 3 tn tn tn`` (transmissivity);
* :class:`~radtree.optics.Hole` → nothing (its geometry is not written);
* :class:`~radtree.optics.Bsdf` → ``void BSDF NAME 6 thickness xml ux uy uz . 0 0`` (the
  surface normal towards the XML's back side, ``up`` the world direction of its +y); with
  ``peak``: ``void aBSDF NAME 5 xml ux uy uz . 0 0`` (the straight-through peak extracted);
* a turbid crown's medium → ``void mist NAME N src… 0 7 σ σ σ ω ω ω g`` (:func:`mist_text`).
"""

from __future__ import annotations

from functools import singledispatch

from radtree.optics import Bsdf, Glass, Hole, Plastic, Trans, fmt


@singledispatch
def material_text(material: object) -> str:
    """The Radiance primitive of ``material`` (a :data:`radtree.optics.Material`)."""
    raise TypeError(f"no Radiance text for material type {type(material).__name__}")


@material_text.register
def _(material: Plastic) -> str:
    r = fmt(material.reflectance)
    return (f"void plastic {material.name}\n0\n0\n5 {r} {r} {r} "
            f"{fmt(material.specularity)} {fmt(material.roughness)}\n")


@material_text.register
def _(material: Trans) -> str:
    c, trans, tspec = material.coefficients
    cc = fmt(c)
    return f"void trans {material.name}\n0\n0\n7 {cc} {cc} {cc} 0 0 {fmt(trans)} {fmt(tspec)}\n"


@material_text.register
def _(material: Glass) -> str:
    t = fmt(material.transmissivity)
    return f"void glass {material.name}\n0\n0\n3 {t} {t} {t}\n"


@material_text.register
def _(material: Hole) -> str:
    return ""


@material_text.register
def _(material: Bsdf) -> str:
    ux, uy, uz = (f"{v:g}" for v in material.up)
    if material.peak:
        return f"void aBSDF {material.name}\n5 {material.xml} {ux} {uy} {uz} .\n0\n0\n"
    return (f"void BSDF {material.name}\n6 {material.thickness:g} {material.xml} {ux} {uy} {uz} ."
            "\n0\n0\n")


def mist_text(name: str, *, extinction: float, albedo: float, eccentricity: float,
              sources: tuple[str, ...] = ()) -> str:
    """A grey ``mist`` volume (Radiance reference manual, "Mist"):
    ``void mist NAME N src… 0 7 σ σ σ ω ω ω g`` — extinction σ per world unit (metres, 5
    significant digits),
    scattering albedo ω, Henyey–Greenstein g; ``sources``: the light sources scattered in the
    volume (:mod:`radtree.engines.radiance.mist`)."""
    s, a = f"{extinction:.5g}", f"{albedo:.5g}"
    src = " ".join([str(len(sources)), *sources])
    return f"void mist {name}\n{src}\n0\n7 {s} {s} {s} {a} {a} {a} {fmt(eccentricity)}\n"
