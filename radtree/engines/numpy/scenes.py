"""Small synthetic scenes for checking and benchmarking engines (tests, ``benchmarks/engines.py``).

Slats are square leaves (two triangles) of side ``size`` inclined ``inclination_deg`` from the
horizontal with a random azimuth; they fill either a horizontal layer (Beer–Lambert checks) or
the study's sensor dome (a half ball against a wall, centred on the sensors).
"""

from __future__ import annotations

import math
from datetime import datetime, timezone

import numpy as np

from radtree.light.sky import SkyState
from radtree.light.sun import SunPosition
from radtree.scene import Mesh


def sky_state(sky_model: str = "none", *, altitude: float = 60.0, azimuth: float = 0.0,
              dni: float = 0.0, dhi: float = 0.0, zenith_luminance: float = 0.0,
              ground_reflectance: float = 0.2, ground_glow: bool = True,
              time: str = "12:00") -> SkyState:
    """A SkyState from plain numbers (compass azimuth, degrees)."""
    hh, mm = (int(x) for x in time.split(":"))
    return SkyState(time=time, datetime=datetime(2024, 12, 22, hh, mm, tzinfo=timezone.utc),
                    sun=SunPosition(altitude, azimuth), direct_normal_lux=dni,
                    diffuse_horizontal_lux=dhi, sky_model=sky_model,
                    zenith_luminance=zenith_luminance, ground_reflectance=ground_reflectance,
                    ground_glow=ground_glow)


def squares(centres: np.ndarray, normals: np.ndarray, size: float, spin: np.ndarray | None = None
            ) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (4k, 3) and faces (2k, 3) of k squares of side ``size`` with given unit normals.

    ``spin`` (k,) rotates each square about its normal (radians); default 0.
    """
    c = np.asarray(centres, float).reshape(-1, 3)
    n = np.asarray(normals, float).reshape(-1, 3)
    n = n / np.linalg.norm(n, axis=1)[:, None]
    k = len(c)
    ref = np.where((np.abs(n[:, 2]) < 0.9)[:, None], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    u = np.cross(ref, n)
    u /= np.linalg.norm(u, axis=1)[:, None]
    v = np.cross(n, u)
    if spin is not None:
        cs, sn = np.cos(spin)[:, None], np.sin(spin)[:, None]
        u, v = cs * u + sn * v, -sn * u + cs * v
    h = size / 2.0
    corners = np.stack([c - h * u - h * v, c + h * u - h * v, c + h * u + h * v,
                        c - h * u + h * v], axis=1)
    base = 4 * np.arange(k)[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]], axis=0)
    return corners.reshape(-1, 3), faces


def inclined_normals(k: int, inclination_deg: float, rng: np.random.Generator) -> np.ndarray:
    """Unit normals tilted ``inclination_deg`` from vertical, random azimuth (upward)."""
    a = rng.uniform(0.0, 2.0 * math.pi, k)
    i = math.radians(inclination_deg)
    return np.column_stack([math.sin(i) * np.cos(a), math.sin(i) * np.sin(a),
                            np.full(k, math.cos(i))])


def slat_layer(name: str, material: str, *, lai: float, extent: float, z_bottom: float,
               z_top: float, size: float, inclination_deg: float, rng: np.random.Generator,
               centre: tuple[float, float] = (0.0, 0.0)) -> Mesh:
    """Slats placed uniformly at random (Poisson) in a box: one-sided leaf area index ``lai``
    over the square ``extent`` × ``extent`` (number of slats = lai · extent² / size²)."""
    k = int(round(lai * extent * extent / (size * size)))
    xy = rng.uniform(-extent / 2, extent / 2, (k, 2)) + np.asarray(centre)
    z = rng.uniform(z_bottom, z_top, k)
    v, f = squares(np.column_stack([xy, z]), inclined_normals(k, inclination_deg, rng), size,
                   rng.uniform(0, 2 * math.pi, k))
    return Mesh(name, material, v, f)


def regular_layers(name: str, material: str, *, layers: int, cover: float, cell: float,
                   patches: int, patch_cells: int, z_bottom: float, spacing: float,
                   rng: np.random.Generator) -> tuple[Mesh, np.ndarray]:
    """``layers`` horizontal layers of square tiles, each covering a fraction ``cover`` of its
    ``cell`` × ``cell`` cell (tile side cell·√cover), in ``patches`` × ``patches`` independent
    patches of ``patch_cells`` × ``patch_cells`` cells. Every patch and layer has its own
    random shift, so a fixed point below a patch sees a gap in each layer with probability
    1 − cover independently: gap fraction (1 − cover)^layers in any direction.

    Returns the mesh and the (patches², 2) xy centres of the patches.
    """
    side = cell * math.sqrt(cover)
    patch = patch_cells * cell
    g = (np.arange(patches) - (patches - 1) / 2.0) * patch
    PX, PY = np.meshgrid(g, g)
    centres = np.column_stack([PX.ravel(), PY.ravel()])
    local = (np.arange(patch_cells) - (patch_cells - 1) / 2.0) * cell
    LX, LY = np.meshgrid(local, local)
    lx, ly = LX.ravel(), LY.ravel()
    cs, zs = [], []
    for j in range(layers):
        shift = rng.uniform(0.0, cell, (len(centres), 2))
        x = (centres[:, None, 0] + shift[:, None, 0] + lx[None, :]).ravel()
        y = (centres[:, None, 1] + shift[:, None, 1] + ly[None, :]).ravel()
        cs.append(np.column_stack([x, y]))
        zs.append(np.full(len(x), z_bottom + j * spacing))
    c = np.column_stack([np.vstack(cs), np.concatenate(zs)])
    v, f = squares(c, np.tile([0.0, 0.0, 1.0], (len(c), 1)), side)
    return Mesh(name, material, v, f), centres


def dome_slats(name: str, material: str, *, count: int, radius: float, centre: np.ndarray,
               facade_normal: np.ndarray, size: float, inclination_deg: float,
               rng: np.random.Generator, inner_radius: float = 0.0) -> Mesh:
    """``count`` slats at random positions in the half ball of ``radius`` in front of a wall
    (the study's sensor dome), leaving a ball of ``inner_radius`` around the centre free."""
    centre = np.asarray(centre, float)
    nrm = np.asarray(facade_normal, float) / np.linalg.norm(facade_normal)
    pts: list[np.ndarray] = []
    need = count
    while need > 0:
        p = rng.uniform(-radius, radius, (4 * need + 16, 3))
        r = np.linalg.norm(p, axis=1)
        ok = (r <= radius) & (r >= inner_radius) & (p @ nrm > size / 2)
        pts.append(p[ok][:need])
        need -= len(pts[-1])
    c = np.vstack(pts) + centre
    v, f = squares(c, inclined_normals(count, inclination_deg, rng), size,
                   rng.uniform(0, 2 * math.pi, count))
    return Mesh(name, material, v, f)


def hemisphere_shell(name: str, material: str, *, radius: float, centre: np.ndarray,
                     axis: np.ndarray, n_theta: int = 24, n_phi: int = 48) -> Mesh:
    """A triangulated half sphere (open on its flat side) about ``axis`` (its pole)."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    ref = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(ref, axis)
    u /= np.linalg.norm(u)
    w = np.cross(axis, u)
    th = np.linspace(0, math.pi / 2, n_theta + 1)
    ph = np.linspace(0, 2 * math.pi, n_phi, endpoint=False)
    T, P = np.meshgrid(th[1:], ph, indexing="ij")
    ring = (np.cos(T)[..., None] * axis + np.sin(T)[..., None] * (
        np.cos(P)[..., None] * u + np.sin(P)[..., None] * w)) * radius
    verts = np.vstack([axis[None] * radius, ring.reshape(-1, 3)]) + np.asarray(centre, float)
    faces = []
    for j in range(n_phi):
        faces.append([0, 1 + j, 1 + (j + 1) % n_phi])
    for i in range(n_theta - 1):
        a0, b0 = 1 + i * n_phi, 1 + (i + 1) * n_phi
        for j in range(n_phi):
            j1 = (j + 1) % n_phi
            faces.append([a0 + j, b0 + j, b0 + j1])
            faces.append([a0 + j, b0 + j1, a0 + j1])
    return Mesh(name, material, verts, np.array(faces))
