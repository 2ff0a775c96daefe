"""How much of a parallel beam passes through a set of surfaces (a crown), undeviated and in all.

For each beam direction (``travel``: unit vector the light travels along) photons of equal flux
start at given points (one per start point: a lattice across the beam, so each stands for an
equal area of it) and are forward-traced through the meshes alone (no ground, no sky; the
forward engine's transport, :class:`~radtree.engines.forward.tracer.ForwardTracer`, Russian
roulette, at most ``max_bounces`` diffuse events). A photon that leaves the meshes travelling
*ahead* (d · travel > 0) has passed: the **total** passage is that flux over the flux launched,
the **beam** part the flux that left still undeviated (specular transmissions only), the rest
— light the surfaces scattered forward — the **scattered** part. Light scattered back towards
the source (d · travel ≤ 0) and absorbed light have not passed.

Every direction is one batch of one trace, so a year of sun positions is traced at once.
"""

from __future__ import annotations

import numpy as np

from radtree.engines.common.geometry import scene_geometry, scene_optics
from radtree.engines.forward.detectors import PatchDetectors
from radtree.engines.forward.sources import Launch
from radtree.engines.forward.tracer import ForwardTracer, Photons
from radtree.scene import Mesh, Scene


def beam_passage(meshes: list[Mesh], materials: dict, travel: np.ndarray,
                 starts: list[np.ndarray], *, max_bounces: int = 8, seed: int = 1,
                 threshold: float = 0.05, chunk: int = 1 << 17
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(total, beam) passage fractions (0–1) per direction of ``travel`` (k, 3): photons start
    at ``starts[i]`` (points before the meshes, m) travelling along ``travel[i]``."""
    travel = np.atleast_2d(np.asarray(travel, float))
    travel = travel / np.linalg.norm(travel, axis=1)[:, None]
    n = np.array([len(s) for s in starts])
    if len(travel) != len(starts) or (n == 0).any():
        raise ValueError("one non-empty set of start points per direction is needed")
    scene = Scene(list(meshes), dict(materials), {})
    geo = scene_geometry(scene, "auto", 1)
    # no ground material in a crown-only scene: the hour's state is never read
    optics = scene_optics(scene, None, geo.material_names)  # type: ignore[arg-type]
    tracer = ForwardTracer(geo, optics, PatchDetectors({}, 1.0), len(travel), threshold=threshold,
                           splitting=False, max_bounces=max_bounces, max_specular=64,
                           chunk=chunk, rng=np.random.default_rng(seed), escape_axes=travel)
    who = np.repeat(np.arange(len(travel)), n)
    launch = Launch(np.vstack(starts), travel[who], np.ones(len(who)))
    tracer.run(Photons.start(launch, who, direct=True))
    return tracer.ahead / n, tracer.ahead_direct / n
