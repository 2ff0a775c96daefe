"""Louvers of the sensor dome: concentric hemispherical shells of slats (optics, readings and
the assembled crown: :mod:`radtree.trees.louvers`).

``layers`` concentric hemispherical shells of slats around the dome centre
(radii evenly spaced from max(0.4·R, sensor radius + 0.6·s + 0.1 m) to R − 0.6·s, at least
1.2·s apart). The hemisphere of directions is cut into the five half faces of an
equi-angular cubed sphere; rows and cells have straight edges on the cube faces, so their
central projections tile the hemisphere *exactly*. A slat is the plane section of the cone
over its cell (f = 1) or over the fraction f of its cell along the row (f < 1; rows run on
past the face edges and slats are cut there, so the chance of meeting a slat is f
everywhere). So every direction from the dome centre meets each shell's slats with
probability f — with cover 1, every direction crosses exactly ``layers`` slats. Slat normals
are tilted α from vertical about the horizontal tangent, in the sense that shows the slat
more face-on to the centre (|cos| = sin(α + |elevation|), never below 0.3). Slats are about
s × s (sides within about ±35 % of s near the cube-face seams; a shell of radius r holds
≈ 2π r² f / (s² c̄) slats, c̄ ≈ 0.75 at α = 30°). Each slat is 2 triangles; the slat count is
bounded by :func:`dome_slat_bound` = 1.5 · 2π f Σ r_k² / (s² · max(0.3, min(sin α, cos α)))
+ 40·layers (≈ 3 000 slats, 6 000 triangles for the reference-case dome of 4 m with 0.3 m slats).
"""

from __future__ import annotations

import math

import numpy as np

from radtree.config import Louvers, Sensors
from radtree.errors import ConfigError
from radtree.trees.envelope import DomeSpec
from radtree.trees.model import MAX_SLATS

MIN_COS = 0.3  # slats are never seen more edge-on than this from the dome centre

# Half cube faces covering the directions n ≥ 0: (axis A, a-axis P, b-axis Q, a-range, b-range).
_U, _N, _Z = np.eye(3)
_Q = math.pi / 4
DOME_FACES = (
    (_N, _U, _Z, (-_Q, _Q), (-_Q, _Q)),   # front: looking out
    (_U, _N, _Z, (0.0, _Q), (-_Q, _Q)),   # +u side
    (-_U, _N, _Z, (0.0, _Q), (-_Q, _Q)),  # −u side
    (_Z, _U, _N, (-_Q, _Q), (0.0, _Q)),   # up
    (-_Z, _U, _N, (-_Q, _Q), (0.0, _Q)),  # down
)


def slat_normals(d: np.ndarray, inclination_deg: float, min_cos: float = MIN_COS
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Slat normals for slats seen along unit directions ``d`` (k, 3) from the dome centre.

    Tilted α from vertical about the horizontal tangent, towards the side that makes the slat
    face the centre more (|m·d| = sin(α + |elevation|)); where that is below ``min_cos`` the
    normal is turned towards d until |m·d| = min_cos. Returns (normals with m·d > 0, m·d).
    """
    a = math.radians(inclination_deg)
    h = d.copy()
    h[:, 2] = 0.0
    hn = np.linalg.norm(h, axis=1)
    h = np.where(hn[:, None] > 1e-9, h / np.maximum(hn, 1e-12)[:, None], _N)
    sigma = np.where(d[:, 2] >= 0.0, 1.0, -1.0)
    m = math.cos(a) * _Z[None, :] + (sigma * math.sin(a))[:, None] * h
    c = np.einsum("ij,ij->i", m, d)
    m = m * np.sign(np.where(c == 0, 1.0, c))[:, None]
    c = np.abs(c)
    low = c < min_cos
    if np.any(low):
        c0 = c[low]
        lam = -c0 + np.sqrt(c0 * c0 - (c0 * c0 - min_cos**2) / (1.0 - min_cos**2))
        mm = m[low] + lam[:, None] * d[low]
        m[low] = mm / np.linalg.norm(mm, axis=1)[:, None]
        c = np.einsum("ij,ij->i", m, d)
    return m, c


def _face_dir(A: np.ndarray, P: np.ndarray, Q: np.ndarray, X: np.ndarray, Y: np.ndarray
              ) -> np.ndarray:
    return A[None, :] + X[..., None] * P[None, :] + Y[..., None] * Q[None, :]


def _metric(X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Arc length per radian of a and of b on an equi-angular cube face (X = tan a, Y = tan b)."""
    s = 1.0 + X * X + Y * Y
    return (1.0 + X * X) * np.sqrt(1.0 + Y * Y) / s, (1.0 + Y * Y) * np.sqrt(1.0 + X * X) / s


def _partition(lo: float, hi: float, density, samples: int = 256) -> np.ndarray:
    """Edges splitting [lo, hi] into cells of ~1 unit of the integral of ``density``."""
    x = np.linspace(lo, hi, samples + 1)
    mid = 0.5 * (x[1:] + x[:-1])
    cum = np.concatenate([[0.0], np.cumsum(density(mid) * np.diff(x))])
    n = max(1, int(round(cum[-1])))
    return np.interp(np.linspace(0.0, cum[-1], n + 1), cum, x)


def _tidy_ends(edges: np.ndarray) -> np.ndarray:
    """Merge partial cells at both ends of a row (cell units) so every cell is 2/3–4/3 of a
    unit: a piece < 1/3 joins its neighbour; a piece of 1/3–2/3 and its neighbour share the
    combined length equally."""
    e = list(edges)
    for side in (0, 1):
        if len(e) <= 2:
            break
        if side == 1:
            e.reverse()
        piece = abs(e[1] - e[0])
        if piece < 1.0 / 3.0:
            del e[1]
        elif piece < 2.0 / 3.0 and len(e) > 3:
            e[1] = 0.5 * (e[0] + e[2])
        if side == 1:
            e.reverse()
    return np.asarray(e)


def dome_layer_radii(spec: DomeSpec, lv: Louvers, sensors: Sensors, source: str | None = None
                     ) -> np.ndarray:
    s = lv.slat_size_m
    r_out = spec.radius - 0.6 * s
    r_in = max(0.4 * spec.radius, sensors.radius_m + sensors.offset_m + 0.6 * s + 0.1)
    if lv.layers == 1:
        return np.array([r_out])
    spacing = (r_out - r_in) / (lv.layers - 1)
    if r_out <= r_in or spacing < 1.2 * s:
        need = (lv.layers - 1) * 1.2 * s
        raise ConfigError(
            f"{lv.layers} slat shells of {s:g} m slats do not fit in a dome of radius "
            f"{spec.radius:g} m (shells from {r_in:.2f} to {r_out:.2f} m, need ≥ {need:.2f} m "
            "between the first and last): use fewer layers, smaller slats or a larger "
            "tree.dome.radius_m", source=source, field="tree.louvers.layers")
    return r_in + spacing * np.arange(lv.layers)


def dome_slat_bound(radii: np.ndarray, lv: Louvers) -> int:
    """Upper bound on the number of slats of the dome form (documented, tested)."""
    c_lo = max(MIN_COS, min(math.sin(math.radians(lv.inclination_deg)),
                            math.cos(math.radians(lv.inclination_deg))))
    est = 2.0 * math.pi * lv.cover_fraction * float(np.sum(radii**2)) / (lv.slat_size_m**2 * c_lo)
    return int(math.ceil(1.5 * est)) + 40 * len(radii)


def _dome_layer(r: float, *, lv: Louvers, rng: np.random.Generator) -> np.ndarray:
    """Slat quads (k, 4, 3) of one shell of radius r around the origin.

    Rows (constant b) are as high as one slat seen from the centre (so they pack the shell
    without gaps across); along a row, cells of width s/f each hold one slat of width s, placed
    at random within its cell. Row offsets follow the branch direction (shift = row height /
    tan β) plus a random step of ±¼ cell, so the pattern has no long-range order (long-range
    order would make two layers' gaps correlate, a moiré that biases the stack).
    """
    quads = []
    for face in DOME_FACES:
        cells = _face_cells(face, r=r, lv=lv, rng=rng)
        quads.append(_face_quads(face, cells=cells, r=r, lv=lv))
    return np.concatenate(quads, axis=0)


def _face_cells(face: tuple, *, r: float, lv: Louvers, rng: np.random.Generator
                ) -> np.ndarray:
    """The slats of one cube face as angle cells (k, 4): (a_lo, a_hi, b_lo, b_hi), rows one
    slat high seen from the centre, each row's offset sheared along the branches."""
    A, P, Q, (a0, a1), (b0, b1) = face
    s, f = lv.slat_size_m, lv.cover_fraction
    tanb = math.tan(math.radians(lv.branch_inclination_deg))
    a_mid = 0.5 * (a0 + a1)

    def c_at(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        d = _face_dir(A, P, Q, np.tan(a), np.tan(b))
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        return slat_normals(d.reshape(-1, 3), lv.inclination_deg)[1].reshape(np.shape(a))

    def row_density(b: np.ndarray) -> np.ndarray:
        am = np.full_like(b, a_mid)
        hb = _metric(np.tan(am), np.tan(b))[1]
        return r * hb / (s * c_at(am, b))

    b_edges = _partition(b0, b1, row_density)
    offset = rng.uniform(0.0, 1.0)
    cells = []
    for j in range(len(b_edges) - 1):
        bl, bh = b_edges[j], b_edges[j + 1]
        bm = 0.5 * (bl + bh)
        if j > 0:
            c_row = float(c_at(np.array([a_mid]), np.array([bm]))[0])
            offset = (offset + c_row * f / tanb + rng.uniform(-0.25, 0.25)) % 1.0
        a_lo, a_hi = _row_cells((a0, a1), bm=bm, offset=offset, r=r, lv=lv, rng=rng)
        for i in range(len(a_lo)):
            cells.append((a_lo[i], a_hi[i], bl, bh))
    return np.array(cells)


def _row_cells(a_range: tuple[float, float], *, bm: float, offset: float, r: float,
               lv: Louvers, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The slats' angle spans (a_lo, a_hi) along the row at b = ``bm`` starting at ``offset``
    (cell units)."""
    a0, a1 = a_range
    s, f = lv.slat_size_m, lv.cover_fraction
    x = np.linspace(a0, a1, 257)
    mid = 0.5 * (x[1:] + x[:-1])
    density = r * f * _metric(np.tan(mid), np.tan(np.full_like(mid, bm)))[0] / s
    cum = np.concatenate([[0.0], np.cumsum(density * np.diff(x))])
    total = cum[-1]
    if f >= 1.0:
        # full cover: cells are the slats; partial cells at the row ends are merged
        cuts = offset + np.arange(-1, int(math.ceil(total)) + 2)
        cuts = cuts[(cuts > 0.0) & (cuts < total)]
        edges = _tidy_ends(np.concatenate([[0.0], cuts, [total]]))
        lo_u, hi_u = edges[:-1], edges[1:]
    else:
        # the row continues past the face edge: one slat of f cell units at a random
        # place in every cell, cut at the face edge, so the chance of meeting a slat is
        # f everywhere along the row (also at the face seams that all layers share)
        left = offset + np.arange(-1, int(math.ceil(total)) + 1)
        left = left + rng.uniform(0.0, 1.0 - f, len(left))
        lo_u, hi_u = np.clip(left, 0.0, total), np.clip(left + f, 0.0, total)
        keep = hi_u - lo_u > 1e-9
        lo_u, hi_u = lo_u[keep], hi_u[keep]
    return np.interp(lo_u, cum, x), np.interp(hi_u, cum, x)


def _face_quads(face: tuple, *, cells: np.ndarray, r: float, lv: Louvers) -> np.ndarray:
    """The slat quads (k, 4, 3) of one face's angle cells ``cells``: each cell's slat, tilted
    as :func:`slat_normals` says, in the plane through r·(cell centre direction)."""
    A, P, Q = face[:3]
    X1, X2 = np.tan(cells[:, 0]), np.tan(cells[:, 1])
    Y1, Y2 = np.tan(cells[:, 2]), np.tan(cells[:, 3])
    cx = np.stack([X1, X2, X2, X1], axis=1)
    cy = np.stack([Y1, Y1, Y2, Y2], axis=1)
    D = _face_dir(A, P, Q, cx, cy)  # (k, 4, 3) corner directions (not unit)
    dc = _face_dir(A, P, Q, 0.5 * (X1 + X2), 0.5 * (Y1 + Y2))
    dc = dc / np.linalg.norm(dc, axis=1)[:, None]
    m, _ = slat_normals(dc, lv.inclination_deg)
    md = np.einsum("kj,kcj->kc", m, D) / np.linalg.norm(D, axis=2)
    if np.any(md < 0.05):
        raise ConfigError(
            f"slats of {lv.slat_size_m:g} m are too large for a slat shell of radius {r:.2f} m "
            "(a slat would be seen edge-on across its own cell): use smaller slats or a larger "
            "dome", field="tree.louvers.slat_size_m")
    t = r / np.einsum("kj,kcj->kc", m, D)  # plane m·x = r (m·dc)… through r·dc
    t = t * np.einsum("kj,kj->k", m, dc)[:, None]
    return t[:, :, None] * D


def build_dome_louvers(spec: DomeSpec, lv: Louvers, sensors: Sensors,
                       source: str | None = None) -> tuple[np.ndarray, dict[str, float]]:
    """All slat quads (local coordinates) of the dome form and geometry info."""
    radii = dome_layer_radii(spec, lv, sensors, source)
    bound = dome_slat_bound(radii, lv)
    if bound > MAX_SLATS * 1.5:
        raise ConfigError(f"the louvers would need up to {bound} slats (limit {MAX_SLATS}): "
                          "use larger slats (tree.louvers.slat_size_m) or fewer layers",
                          source=source, field="tree.louvers.slat_size_m")
    ss = np.random.SeedSequence(lv.seed)
    layers = []
    for r, child in zip(radii, ss.spawn(len(radii))):
        layers.append(_dome_layer(float(r), lv=lv, rng=np.random.default_rng(child)))
    quads = np.concatenate(layers, axis=0)
    dist = np.linalg.norm(quads, axis=2)
    if dist.max() > spec.radius + 1e-6:
        raise ConfigError(f"slats reach {dist.max():.3f} m from the dome centre, beyond the "
                          f"dome radius {spec.radius:g} m: use smaller slats",
                          source=source, field="tree.louvers.slat_size_m")
    if len(radii) > 1:
        counts = [len(x) for x in layers]
        starts = np.cumsum([0] + counts)
        depth = max(float(np.max(np.abs(dist[starts[i]:starts[i + 1]] - radii[i])))
                    for i in range(len(radii)))
        spacing = float(radii[1] - radii[0])
        if depth >= 0.5 * spacing:
            raise ConfigError(
                f"neighbouring slat shells would touch (slat depth ±{depth:.2f} m, shells "
                f"{spacing:.2f} m apart): use fewer layers or smaller slats",
                source=source, field="tree.louvers.layers")
    quads = quads + spec.centre
    quads[:, :, 1] = np.maximum(quads[:, :, 1], spec.centre[1])  # rounding: never behind wall
    e1 = np.linalg.norm(quads[:, 1] - quads[:, 0], axis=1)
    e2 = np.linalg.norm(quads[:, 3] - quads[:, 0], axis=1)
    info = {
        "dome_radius_m": spec.radius,
        "layer_radius_min_m": float(radii[0]),
        "layer_radius_max_m": float(radii[-1]),
        "slat_side_min_m": float(min(e1.min(), e2.min())),
        "slat_side_max_m": float(max(e1.max(), e2.max())),
        "slat_mean_area_m2": float(np.mean(0.5 * np.linalg.norm(np.cross(
            quads[:, 2] - quads[:, 0], quads[:, 3] - quads[:, 1]), axis=1))),
        "slat_bound": float(bound),
    }
    return quads, info
