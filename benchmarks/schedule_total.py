"""The EnergyPlus schedule's *total* transmittance (beam + light the crown scatters forward,
radtree.export.transmittance: photons from the crown's shadow lattice, escape directions
tallied) against a traced pyranometer array behind the crown: the forward engine's public
``trace_forward`` with its own launch (the whole-scene sun, focused launch), a plane of
sun-facing square patch detectors tiling a disc-sized square behind the crown alone, the direct
beam counted at the points (``direct_sun``) and taken off, so the patches sum the scattered
flux crossing the plane. Same transport, different launch, tally and normalisation. Three sun
positions for each crown model of the Mendoza example (louvers and homogeneous: the sensor
dome; perforated: a free crown, a closed shell); the target is 2 % of the total. Prints only.

Run: ``.venv/bin/python benchmarks/schedule_total.py``.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from radtree.config import load_project  # noqa: E402
from radtree.engines.common.geometry import scene_geometry, scene_optics  # noqa: E402
from radtree.engines.forward import ForwardSettings, trace_forward  # noqa: E402
from radtree.engines.forward.direct import direct_sun  # noqa: E402
from radtree.engines.numpy.scenes import sky_state  # noqa: E402
from radtree.export.transmittance import (  # noqa: E402
    crown_envelopes,
    crown_models,
    lattice,
    own_meshes,
    own_tracer,
    scattered_forward,
    transmittances,
)
from radtree.pipeline.assemble import facade_frame  # noqa: E402
from radtree.scene import Scene, SensorGrid  # noqa: E402

MENDOZA = Path(__file__).resolve().parents[1] / "examples" / "mendoza-street"

SUNS = ((90.0, 0.0), (60.0, 135.0), (40.0, 250.0))  # (altitude, compass azimuth) degrees
DNI = 1000.0
PLANE = 8.0           # half-side of the pyranometer plane / crown radius
PATCH = 0.5           # patch side / crown radius


def _sun_vector(alt: float, az: float) -> np.ndarray:
    a, z = math.radians(alt), math.radians(az)
    return np.array([math.cos(a) * math.sin(z), math.cos(a) * math.cos(z), math.sin(a)])


def _pyranometer_plane(crown, s: np.ndarray) -> tuple[SensorGrid, float]:
    """Sun-facing sensors on a square lattice (spacing = patch side, so the patches tile it)
    perpendicular to ``s`` just behind the crown; the patch side (m)."""
    c = crown.vertices.mean(axis=0)
    r = float(np.linalg.norm(crown.vertices - c, axis=1).max())
    u = np.cross([0.0, 0.0, 1.0], s) if abs(s[2]) < 0.999 else np.array([1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(s, u)
    side = PATCH * r
    k = int(PLANE / PATCH)
    t = (np.arange(-k, k) + 0.5) * side
    a, b = np.meshgrid(t, t)
    pts = c - s * (r + 0.05) + a.ravel()[:, None] * u + b.ravel()[:, None] * v
    return SensorGrid("facade", pts, np.tile(s, (len(pts), 1))), side


def compare(scenario: str, form: str) -> None:
    proj = load_project(MENDOZA, overrides={"tree.form": form})
    sc = proj.scenario(scenario)
    frame = facade_frame(proj)
    crown = crown_envelopes(proj, sc, frame)[0]
    meshes, _, materials, _ = crown_models(proj, sc, frame)
    own = own_meshes(crown, meshes)
    rays = 4096
    for alt, az in SUNS:
        s = _sun_vector(alt, az)
        beam = float(transmittances(own_tracer(crown, meshes, materials), crown, s, rays)[0])
        total = beam + float(scattered_forward(crown, meshes, materials, s, rays)[0])
        # the beam's cross-section: the bundle's lattice points meeting the crown × their cell
        o = lattice(crown, s, rays)
        step2 = float(np.diff(np.unique(o[:, 0]))[0]) ** 2
        hit = crown.trimesh().ray.intersects_any(o, np.tile(s, (len(o), 1)))
        across = hit.sum() * step2 * s[2]        # horizontal cells → across the beam (m²)
        grid, side = _pyranometer_plane(crown, s)
        scene = Scene(own, materials, {"facade": grid})
        st = sky_state("none", altitude=alt, azimuth=az, dni=DNI, ground_glow=False)
        res = trace_forward(scene, st, ForwardSettings(
            photons=400_000, max_bounces=8, direct_sun=True, focus_m=side, seed=5))
        geo = scene_geometry(scene, "auto", 1)
        at_points = direct_sun(geo, scene_optics(scene, st, geo.material_names), grid, s, DNI)
        per_batch = (res.batches["facade"] - at_points).sum(axis=1) * side ** 2
        scattered, se = per_batch.mean(), per_batch.std(ddof=1) / math.sqrt(len(per_batch))
        ref = beam + scattered / (DNI * across)
        ref_se = se / (DNI * across)
        print(f"{scenario} ({form}) sun {alt:g}°/{az:g}°: beam {beam:.4f}, total {total:.4f}, "
              f"pyranometers {ref:.4f} ± {ref_se:.4f} ({total / ref - 1:+.2%})", flush=True)



if __name__ == "__main__":
    for case in (("A", "dome"), ("C", "free"), ("E", "dome")):
        compare(*case)
