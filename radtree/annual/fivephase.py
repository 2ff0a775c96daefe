"""The sun through a BSDF crown by the five-phase idea (``radtree annual --method 3phase
--sun-crown fivephase``).

The five-phase method (LBNL's matrix methods; sources read: frads, LBNL-ETA/frads — its
early ``mtxmethod`` script's ``five_phase``: a daylight matrix at ``-ab 0`` and a view
matrix at ``-ab 1`` for the three-phase *direct* term, plus sun coefficients ``cdsmx``; its
``test/five_phase.cfg``: ``sensor_sun_matrix = -ab 1``; S. Subramaniam's public recipe
gist sariths/981ad4aff33aee28322b35fb8ad773e3: the sun-coefficient octree with the room
*black* and the shading device as its BSDF, Reinhart solar discs, ``rcontrib -ab 1``; the
LBNL tutorial "Daylighting simulations with Radiance using matrix-based methods"
(Subramaniam 2017) is cited from memory) corrects the three-phase result for the sun: the
direct part of the sun through the Klems BSDF, smeared over its patches (≈ 0.01–0.3 sr), is
taken out (the three-phase "direct" run) and the direct sun computed accurately (a fine BSDF
or the real geometry, the room black) is put in:

    sun = sun(BSDF crown) − sun(BSDF crown, surroundings black) + sun(explicit crown,
          surroundings black)

Here, per leaf state, each term is the default method's sun runs
(:func:`radtree.annual.run.scene_year_lux`: the hourly sun at ``-ab 0`` and the Reinhart
patch suns' reflected part at ``-ab N``) on a scene:

1. the BSDF-crown scene (the ``sun_crown = "bsdf"`` runs; the chain's sky matrix holds no
   sun, ``gendaymtx -s``, so the three-phase sun *is* this run);
2. the same with the **surroundings black** (every material of the scene without a crown —
   ground, façades, buildings, room surfaces — a black plastic, the ground reflectance 0;
   glazing stays): the sun that reaches the sensors through the crown's BSDF without a
   bounce off the surroundings, the "three-phase direct";
3. the explicit crown (slats, or bare branches leaf-off) with the surroundings black: the
   sun through the crown's real geometry, its gaps and the scattering among its slats
   included — the "direct sun" of the five-phase method **from the explicit geometry** (no
   fine tensor tree: the free crowns' chord envelope is assembled ring by ring in the Klems
   basis, ``tree.bsdf.tensor_tree`` refuses it).

(1) − (2) is the sun reflected by the surroundings, carried to and from them by the BSDF
crown. Noise: (1) and (2) are separate Monte Carlo estimates (blackening changes the ray
trees), so their difference holds the noise of both. With the shell as Radiance's ``aBSDF``
(``tree.bsdf.material``, the default) the sun through the XML's straight-through peak is a
shadow ray, the same in (1) and (2) (their ``-ab 0`` runs agree exactly and cancel); with the
plain ``BSDF`` it was found by each run's ambient sampling, and the difference was larger
than itself where the sensors see the sun through the crown (see :func:`five_phase_sun`).
The hourly direct sun (the ``direct`` output, LM-83) is (3)'s ``-ab 0`` part.

Measured on the office example (``benchmarks/threephase.py``, CHANGELOG.md), against the
explicit-crown annual (``sun_crown = "explicit"`` within 0.5 pp on every band): with the
plain BSDF the per-sensor-hour noise of (1) − (2) moved UDI < 100 lx by +9.0 / +14.9
percentage points (façade / work plane); with the aBSDF shell every band within 1.1 pp on
the façade, the work plane UDI < 100 +5.2, 100–300 −5.8 pp — not met, and now a bias rather
than noise: summed over sensors and the Reinhart patch suns, the surroundings' reflected
sun (1) − (2) is 0.71 × the explicit crown's (0.67 with the plain BSDF), while the
sensor-patch values below zero fell from 9.7 % to 1.7 %. Not the default.

Where the 0.71 comes from (``benchmarks/fivephase_paths.py``): it is both grids together,
the façade's 0.68 (its reflected sun 7 × the work plane's; work plane alone 0.94). On the
façade the *ground* holds the deficit (ground-reflected sun 0.63 ×; the sun reaching the
street through the crown 1.00 ×; the crown sending the façade paint's light back 1.0–1.4 ×,
4 % of the total): the light from the street to the window through the crown is 0.61 × (a
uniformly glowing ground), 0.52–0.66 × from every direction below the horizon, 0.85–0.95 ×
from above. The shell's facets and cap are oriented right (lower facets = upper mirrored;
cap depth as its table); the cause is the representation: a shell holds the crown's depth at
its surface, so the light inside it is the same wherever the receiver sits, while the window
lies in the crown's lower third, 1–2 m above its base, where the real crown passes 4–6 × more
of the street's light than at its centre (inside the crown, from below, BSDF/explicit 0.14–0.16 at
z 4 m, 0.9–1.1 at the centre). On the work plane, applying the explicit crown's reflected sun
times the BSDF's per-patch ratio (0.72–1.09) moves UDI < 100 / 100–300 by +2.5 / −2.0 pp;
the rest of the +4.5 / −4.7 pp (hourly replay of the cached runs; +3.3 / −3.1 and +4.9 / −4.7
with two more realisations of (1) and (2)) is per-sensor, per-patch scatter: one realisation's
s.d. there is 64 % of the explicit value, so one explicit run at the sun runs' ``-ad 512``
does not resolve 3 pp on the work plane.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from radtree.annual.coefficients import CoefficientRunner
from radtree.optics import Plastic
from radtree.scene import Scene


def black_surroundings(scene: Scene, surroundings: Scene) -> Scene:
    """``scene`` with every opaque (plastic) material of ``surroundings`` (the scene without
    a crown) black: reflectance and specularity 0. The crown's materials, glazing and
    translucent materials are kept."""
    materials = dict(scene.materials)
    for name, m in surroundings.materials.items():
        if name in materials and isinstance(m, Plastic):
            materials[name] = Plastic(name, 0.0)
    return replace(scene, materials=materials)


def five_phase_sun(year_lux, *, bsdf_crown: Scene, explicit: Scene, surroundings: Scene,
                   grids: list[str], rho: float, folders: tuple[Path, Path, Path]
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(total, direct) sun lux (sensors, hours) of one leaf state by the five-phase idea (module
    text). ``year_lux(runner)``: the default method's sun runs of a
    :class:`~radtree.annual.coefficients.CoefficientRunner` over the year (no sky);
    ``bsdf_crown``, ``explicit``: the scenes with the BSDF crown and the explicit crown;
    ``surroundings``: the scene without a crown; ``rho``: the ground reflectance (0–1);
    ``folders``: the runs' caches for terms (1), (2), (3)."""
    tot_b, _ = year_lux(CoefficientRunner(bsdf_crown, grids, folders[0], rho))
    tot_bb, _ = year_lux(CoefficientRunner(black_surroundings(bsdf_crown, surroundings),
                                           grids, folders[1], 0.0))
    tot_eb, dir_e = year_lux(CoefficientRunner(black_surroundings(explicit, surroundings),
                                               grids, folders[2], 0.0))
    # (1) − (2) ≥ 0 in expectation, not per sensor-hour: the runs' ambient rays differ
    # (blackening changes the ray trees). With a plain BSDF shell the sun through the Klems
    # peak is a bright patch-sized disc each run hits differently; the aBSDF shell (default)
    # passes it as a shadow ray in both. Clipping would bias: on the test crown (plain BSDF,
    # sun -ad 32) clipping the total at the direct sun raised the leaf-on year's sun by 44 %,
    # at 0 by 27 %. The sum is kept unclipped (unbiased; a sensor-hour may read below zero).
    total = tot_b.astype(np.float64) - tot_bb + tot_eb
    return total.astype(np.float32), dir_e


__all__ = ["black_surroundings", "five_phase_sun"]
