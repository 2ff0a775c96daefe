"""The louvers crown: inclined leaf slats in ``layers`` filtration stages.

Optics (one ``trans`` material ``leaf``): reflectance R, transmittance T split into a specular
(undeviated) part T_s = T·specular_fraction and a diffuse part T_d = T·(1 − specular_fraction).
Each layer covers a fraction f (``cover_fraction``) of the area it spans *as seen along the
beam the layer is built for*, so a beam meets in each layer a slat with probability f and
otherwise a gap. The direct (specular) transmission of one layer and of the crown are

    τ_layer = (1 − f) + f·T_s            τ_crown = τ_layer ** layers

and, counting diffusely transmitted light as if it went on forward (an upper bound of the
first-order energy), τ'_layer = (1 − f) + f·T. Slat positions are independent between layers,
so for random (jittered) placement the stack's expected transmission is exactly τ_layer^N.

Two readings of the study's "slat-layer transmittance 0.5" (SPEC, "first physical check"):

* **study reading** — cover 1 and a slat material with T = 0.5 (R 0.11): the 0.5 is an
  *effective per-layer* transmission (gaps + leaf), put into the material.
* **gap reading** — near-opaque leaves (T ≈ 0.05 diffuse, R 0.11) covering ≈ 50 % of each layer,
  so ≈ 50 % passes each layer through gaps (direct, no ambient bounce needed).

Switch between them with the scenario switch ``"louvers.reading" = "study" | "gap"`` (presets
in :data:`radtree.config.LOUVER_READINGS`) or by setting the fields. The notes always say which reading is in use.

Geometry
--------
Slats are planar quadrilaterals of side ≈ ``slat_size_m`` s, inclined ``inclination_deg`` α
from the horizontal (leaf inclination). In each layer they sit in rows packed side by side
across (a row is one slat high), and along a row in cells of length s/f, one slat of length s
at a random place in each cell (f = 1: the cells are the slats). Rows are offset from one
another so that slat centres form a staggered (triangular) grid — with a random component: a
regular lattice would give two layers' gap patterns a moiré that biases the stack's
transmission away from τ_layer^N. Branches inclined ``branch_inclination_deg`` β: in the
dome, each row is shifted along the previous one by (row height)/tan β (± a random quarter
cell), so slat centres line up along 40° branches locally; in the free crowns, slats come in
branches of three along a row that climb at β. Randomness comes from ``louvers.seed``.

* **Sensor dome.** ``layers`` concentric hemispherical shells of slats around the dome centre
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
  + 40·layers (≈ 3 000 slats, 6 000 triangles for the Mendoza dome of 4 m with 0.3 m slats).
* **Free-standing crowns.** ``layers`` nested lens-shaped surfaces inside each spheroid,
  z_k(ρ) = z_c + h(ρ)·(2(k + ½)/N − 1) with h(ρ) = b·√(1 − ρ²/a²), so every vertical line
  through a crown crosses each layer exactly once. Slats are exact squares of side s with their
  tilt axis along the rows, so their plan projections are s × s·cos α rectangles; rows are
  s·cos α apart with a random heading per layer: a vertical beam meets a slat in each layer
  with probability exactly f. Branch steps are s·tan β/f (at most a quarter of the local layer
  spacing). Slats that would leave the spheroid, come within 4·s·sin α of the next layer
  (near the rim) or cut the trunk are dropped; slats crossing the wall-side clip plane or the
  plane shared with a neighbour crown are cut there. Bound (:func:`free_slat_bound`):
  slats ≤ count · N · π(a + s)² f / (s² cos α); triangles ≤ 3 × that bound (cut slats have up
  to 6 corners). Near-horizontal views from a façade sensor cross far fewer than N layers.
* **Free-standing crowns, volume arrangement** (``arrangement = "volume"``): slats scattered
  at random through the crown volume (:mod:`radtree.trees.volume`), so the slats met along a
  path follow Beer–Lambert / Poisson statistics in every direction. They share this module's
  trunk test and wall-side / neighbour-plane cutting (:func:`trunk_clash`,
  :func:`touches_share`, :func:`cut_to_share`). The dome keeps its shells ("volume" with the
  dome form is an error).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radtree.config import LOUVER_ARRANGEMENTS, Louvers, Sensors, Street, Tree
from radtree.errors import ConfigError
from radtree.optics import Plastic, Trans
from radtree.scene import Mesh
from radtree.site.frame import FacadeFrame
from radtree.trees.envelope import (
    CrownRowSpec,
    DomeSpec,
    crown_row_spec,
    dome_notes,
    dome_spec,
    row_notes,
)
from radtree.trees.geometry import clip_polygon, polygons_to_mesh, quads_to_mesh
from radtree.trees.model import BARK_REFLECTANCE, LEAF, TRUNK, TreeModel

MAX_SLATS = 200_000
MIN_COS = 0.3  # slats are never seen more edge-on than this from the dome centre
BRANCH_SLATS = 3

# ---------------------------------------------------------------- optics
@dataclass(frozen=True)
class LouverOptics:
    reflectance: float
    transmittance: float
    specular_fraction: float
    cover_fraction: float
    layers: int

    @classmethod
    def of(cls, lv: Louvers) -> LouverOptics:
        return cls(lv.reflectance, lv.transmittance, lv.specular_fraction, lv.cover_fraction,
                   lv.layers)

    @property
    def t_specular(self) -> float:
        return self.transmittance * self.specular_fraction

    @property
    def t_diffuse(self) -> float:
        return self.transmittance * (1.0 - self.specular_fraction)

    @property
    def tau_layer_direct(self) -> float:
        f = self.cover_fraction
        return (1.0 - f) + f * self.t_specular

    @property
    def tau_crown_direct(self) -> float:
        return self.tau_layer_direct ** self.layers

    @property
    def tau_layer_global(self) -> float:
        f = self.cover_fraction
        return (1.0 - f) + f * self.transmittance

    @property
    def tau_crown_global(self) -> float:
        return self.tau_layer_global ** self.layers

    @property
    def reading(self) -> str:
        if self.cover_fraction >= 0.999 and self.transmittance >= 0.3:
            return "study"
        if self.cover_fraction < 0.999 and self.transmittance <= 0.15:
            return "gap"
        return "custom"

    def material(self) -> Trans:
        return Trans(LEAF, self.reflectance, self.t_diffuse, self.t_specular)

    def describe_slat(self) -> str:
        """The slat material alone (volume arrangement: no layers)."""
        return (f"{self.reading} reading: slat R {self.reflectance:g}, T {self.transmittance:g} "
                f"(specular {self.t_specular:.4f}, diffuse {self.t_diffuse:.4f}); cover "
                f"{self.cover_fraction:.3f} scales the slat density")

    def describe(self) -> str:
        r = self.reading
        head = {
            "study": "study reading — each layer fully covered (cover 1) by slats whose "
                     "material carries the study's effective per-layer transmission",
            "gap": "gap reading — near-opaque leaves, light passes each layer mainly through "
                   "the gaps left by the cover fraction",
            "custom": "custom reading (neither the study's cover 1 / T 0.5 nor near-opaque "
                      "leaves in half-covered layers)",
        }[r]
        return (f"{head}: {self.layers} layers, cover {self.cover_fraction:.3f}, slat R "
                f"{self.reflectance:g}, T {self.transmittance:g} (specular "
                f"{self.t_specular:.4f}, diffuse {self.t_diffuse:.4f}); direct transmission "
                f"per layer {self.tau_layer_direct:.4f}, crown {self.tau_crown_direct:.5f}; "
                f"counting diffuse transmission as forward: per layer "
                f"{self.tau_layer_global:.4f}, crown {self.tau_crown_global:.5f}")


def required_cover(target: float, layers: int, t_specular: float) -> float:
    """Cover fraction giving a crown direct transmission ``target`` with ``layers`` layers
    (may fall outside (0, 1]: then that layer count cannot reach the target)."""
    tau = target ** (1.0 / layers)
    return (1.0 - tau) / (1.0 - t_specular) if t_specular < 1.0 else float("nan")


def check_louvers(lv: Louvers, source: str | None = None) -> None:
    def err(name: str, msg: str) -> ConfigError:
        return ConfigError(msg, source=source, field=f"tree.louvers.{name}")

    if lv.layers < 1:
        raise err("layers", f"got {lv.layers}, expected at least 1")
    if not 1 <= lv.realisations <= 64:
        raise err("realisations", f"got {lv.realisations}, expected 1–64")
    for name in ("cover_fraction", "reflectance", "transmittance", "specular_fraction"):
        v = getattr(lv, name)
        if not 0.0 <= v <= 1.0:
            raise err(name, f"got {v}, expected 0–1")
    if lv.cover_fraction <= 0.0:
        raise err("cover_fraction", "got 0: a layer without slats (use model 'none')")
    if lv.reflectance + lv.transmittance > 1.0 + 1e-9:
        raise err("transmittance", f"reflectance {lv.reflectance:g} + transmittance "
                                   f"{lv.transmittance:g} exceeds 1")
    if not 0.02 <= lv.slat_size_m <= 3.0:
        raise err("slat_size_m", f"got {lv.slat_size_m}, expected 0.02–3 m")
    if not 0.0 <= lv.inclination_deg <= 90.0:
        raise err("inclination_deg", f"got {lv.inclination_deg}, expected 0–90°")
    if not 0.0 < lv.branch_inclination_deg < 90.0:
        raise err("branch_inclination_deg",
                  f"got {lv.branch_inclination_deg}, expected between 0 and 90° (exclusive)")
    if lv.arrangement not in LOUVER_ARRANGEMENTS:
        raise err("arrangement", f"got {lv.arrangement!r}, expected one of "
                                 f"{', '.join(LOUVER_ARRANGEMENTS)}")
    if not (math.isfinite(lv.crossings) and 0.0 <= lv.crossings <= 60.0):
        raise err("crossings", f"got {lv.crossings}, expected 0–60 slats on a vertical line "
                               "(0: use layers)")


# ---------------------------------------------------------------- dome form
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


def _dome_layer(r: float, lv: Louvers, rng: np.random.Generator) -> np.ndarray:
    """Slat quads (k, 4, 3) of one shell of radius r around the origin.

    Rows (constant b) are as high as one slat seen from the centre (so they pack the shell
    without gaps across); along a row, cells of width s/f each hold one slat of width s, placed
    at random within its cell. Row offsets follow the branch direction (shift = row height /
    tan β) plus a random step of ±¼ cell, so the pattern has no long-range order (long-range
    order would make two layers' gaps correlate, a moiré that biases the stack).
    """
    s, f = lv.slat_size_m, lv.cover_fraction
    tanb = math.tan(math.radians(lv.branch_inclination_deg))
    quads = []
    for A, P, Q, (a0, a1), (b0, b1) in DOME_FACES:
        a_mid = 0.5 * (a0 + a1)

        def c_at(a: np.ndarray, b: np.ndarray, A=A, P=P, Q=Q) -> np.ndarray:
            d = _face_dir(A, P, Q, np.tan(a), np.tan(b))
            d = d / np.linalg.norm(d, axis=-1, keepdims=True)
            return slat_normals(d.reshape(-1, 3), lv.inclination_deg)[1].reshape(np.shape(a))

        def row_density(b: np.ndarray, a_mid=a_mid, c_at=c_at) -> np.ndarray:
            am = np.full_like(b, a_mid)
            hb = _metric(np.tan(am), np.tan(b))[1]
            return r * hb / (s * c_at(am, b))

        b_edges = _partition(b0, b1, row_density)
        offset = rng.uniform(0.0, 1.0)
        cells = []
        for j in range(len(b_edges) - 1):
            bl, bh = b_edges[j], b_edges[j + 1]
            bm = 0.5 * (bl + bh)

            def cell_density(a: np.ndarray, bm=bm) -> np.ndarray:
                return r * f * _metric(np.tan(a), np.tan(np.full_like(a, bm)))[0] / s

            x = np.linspace(a0, a1, 257)
            mid = 0.5 * (x[1:] + x[:-1])
            cum = np.concatenate([[0.0], np.cumsum(cell_density(mid) * np.diff(x))])
            total = cum[-1]
            if j > 0:
                c_row = float(c_at(np.array([a_mid]), np.array([bm]))[0])
                offset = (offset + c_row * f / tanb + rng.uniform(-0.25, 0.25)) % 1.0
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
            a_lo, a_hi = np.interp(lo_u, cum, x), np.interp(hi_u, cum, x)
            for i in range(len(a_lo)):
                cells.append((a_lo[i], a_hi[i], bl, bh))
        cl = np.array(cells)
        X1, X2 = np.tan(cl[:, 0]), np.tan(cl[:, 1])
        Y1, Y2 = np.tan(cl[:, 2]), np.tan(cl[:, 3])
        cx = np.stack([X1, X2, X2, X1], axis=1)
        cy = np.stack([Y1, Y1, Y2, Y2], axis=1)
        D = _face_dir(A, P, Q, cx, cy)  # (k, 4, 3) corner directions (not unit)
        dc = _face_dir(A, P, Q, 0.5 * (X1 + X2), 0.5 * (Y1 + Y2))
        dc = dc / np.linalg.norm(dc, axis=1)[:, None]
        m, _ = slat_normals(dc, lv.inclination_deg)
        md = np.einsum("kj,kcj->kc", m, D) / np.linalg.norm(D, axis=2)
        if np.any(md < 0.05):
            raise ConfigError(
                f"slats of {s:g} m are too large for a slat shell of radius {r:.2f} m (a slat "
                "would be seen edge-on across its own cell): use smaller slats or a larger "
                "dome", field="tree.louvers.slat_size_m")
        t = r / np.einsum("kj,kcj->kc", m, D)  # plane m·x = r (m·dc)… through r·dc
        t = t * np.einsum("kj,kj->k", m, dc)[:, None]
        quads.append(t[:, :, None] * D)
    return np.concatenate(quads, axis=0)


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
        layers.append(_dome_layer(float(r), lv, np.random.default_rng(child)))
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


# ---------------------------------------------------------------- free form
def trunk_clash(rho: np.ndarray, z_low: np.ndarray, spec: CrownRowSpec, s: float) -> np.ndarray:
    """Slats (plan distance ``rho`` of their centre from the trunk axis, lowest corner
    ``z_low``) that would cut the trunk: within trunk radius + 0.75·s of the axis and reaching
    below 5 cm above the trunk top."""
    return (rho < spec.trunk_radius + 0.75 * s) & (z_low < spec.trunk_top + 0.05)


def touches_share(corners: np.ndarray, spec: CrownRowSpec, lo: float, hi: float) -> np.ndarray:
    """Slats (k, m, 3) with at least one corner in a crown's share of the row: on the street
    side of the wall-side clip plane and within the crown's strip [lo, hi] of u."""
    return (np.any(corners[:, :, 1] >= spec.n_clip, axis=1)
            & np.any(corners[:, :, 0] >= lo, axis=1) & np.any(corners[:, :, 0] <= hi, axis=1))


def cut_to_share(corners: np.ndarray, spec: CrownRowSpec, lo: float, hi: float
                 ) -> tuple[list[np.ndarray], int]:
    """Slats (k, m, 3) touching a crown's share, cut at the wall-side clip plane and at the
    planes shared with neighbour crowns. Returns the polygons and how many were cut."""
    inside = (np.all(corners[:, :, 1] >= spec.n_clip, axis=1)
              & np.all(corners[:, :, 0] >= lo, axis=1) & np.all(corners[:, :, 0] <= hi, axis=1))
    polys: list[np.ndarray] = list(corners[inside])
    cut = 0
    for poly in corners[~inside]:
        p = clip_polygon(poly, _N, spec.n_clip)
        if np.isfinite(lo) and len(p) >= 3:
            p = clip_polygon(p, _U, lo)
        if np.isfinite(hi) and len(p) >= 3:
            p = clip_polygon(p, -_U, -hi)
        if len(p) >= 3:
            polys.append(p)
            cut += 1
    return polys, cut


def free_slat_bound(spec: CrownRowSpec, lv: Louvers) -> int:
    """Upper bound on the number of slats of the free form (documented, tested)."""
    s = lv.slat_size_m
    cos_a = max(math.cos(math.radians(lv.inclination_deg)), 0.05)
    per_layer = math.pi * (spec.a + s) ** 2 * lv.cover_fraction / (s * s * cos_a)
    return int(math.ceil(spec.count * lv.layers * per_layer))


def build_free_louvers(spec: CrownRowSpec, lv: Louvers, source: str | None = None
                       ) -> tuple[list[np.ndarray], dict[str, float]]:
    """Slat polygons (local coordinates) of the free form and geometry info."""
    s, f, N = lv.slat_size_m, lv.cover_fraction, lv.layers
    bound = free_slat_bound(spec, lv)
    if bound > MAX_SLATS:
        raise ConfigError(f"the louvers would need up to {bound} slats (limit {MAX_SLATS}): "
                          "use larger slats (tree.louvers.slat_size_m) or fewer layers",
                          source=source, field="tree.louvers.slat_size_m")
    alpha = math.radians(lv.inclination_deg)
    tana, cosa = math.tan(alpha), math.cos(alpha)
    dx, dy = s / f, s * cosa
    if dy <= 1e-9:
        raise ConfigError("vertical slats (inclination 90°) cannot cover a horizontal layer",
                          source=source, field="tree.louvers.inclination_deg")
    climb = dx * math.tan(math.radians(lv.branch_inclination_deg))
    min_spacing = 4.0 * s * math.sin(alpha) + 0.05
    a, b = spec.a, spec.b
    ss = np.random.SeedSequence(lv.seed)
    polys: list[np.ndarray] = []
    dropped = 0
    cut = 0
    for ti, child in enumerate(ss.spawn(spec.count)):
        c = spec.centres[ti]
        lo, hi = spec.strips[ti]
        for layer, lchild in enumerate(child.spawn(N)):
            rng = np.random.default_rng(lchild)
            psi = rng.uniform(0.0, 2.0 * math.pi)
            ex = np.array([math.cos(psi), math.sin(psi)])
            ey = np.array([-math.sin(psi), math.cos(psi)])
            oy = rng.uniform(0.0, 1.0)
            nj = int(math.ceil((a + s) / dy)) + 1
            ni = int(math.ceil((a + s) / dx)) + 1
            row_offset = rng.uniform(0.0, 1.0, 2 * nj + 1)
            jj, ii = np.meshgrid(np.arange(-nj, nj + 1), np.arange(-ni, ni + 1), indexing="ij")
            J, Ii = jj.ravel(), ii.ravel()
            # rows packed across (height s·cosα = one slat); along a row cells of s/f, one
            # slat of side s at a random place in each; every row at a random offset
            xs = (Ii + row_offset[J + nj]) * dx + rng.uniform(-0.5, 0.5, len(J)) * (dx - s)
            ys = (J + oy) * dy
            sigma = rng.choice([-1.0, 1.0], len(J))
            plan = c[:2][None, :] + xs[:, None] * ex + ys[:, None] * ey
            rho = np.hypot(plan[:, 0] - c[0], plan[:, 1] - c[1])
            ok = rho < a
            h = b * np.sqrt(np.clip(1.0 - (rho / a) ** 2, 0.0, 1.0))
            spacing = 2.0 * h / N
            z_layer = c[2] + h * (2.0 * (layer + 0.5) / N - 1.0)
            q = np.mod(Ii, BRANCH_SLATS) - (BRANCH_SLATS - 1) / 2.0
            step = np.minimum(climb, 0.25 * spacing / max((BRANCH_SLATS - 1) / 2.0, 1.0))
            zc = z_layer + q * step
            ok &= spacing >= min_spacing
            # corners: (±s/2 along rows, ±s·cosα/2 across), rising σ·tanα across the rows
            hx = np.array([-0.5, 0.5, 0.5, -0.5]) * s
            hy = np.array([-0.5, -0.5, 0.5, 0.5]) * s * cosa
            cu = plan[:, None, 0] + hx[None, :] * ex[0] + hy[None, :] * ey[0]
            cn = plan[:, None, 1] + hx[None, :] * ex[1] + hy[None, :] * ey[1]
            cz = zc[:, None] + sigma[:, None] * tana * hy[None, :]
            corners = np.stack([cu, cn, cz], axis=2)
            qv = (((corners[:, :, 0] - c[0]) ** 2 + (corners[:, :, 1] - c[1]) ** 2) / a**2
                  + (corners[:, :, 2] - c[2]) ** 2 / b**2)
            ok &= np.all(qv <= 1.0, axis=1)
            ok &= ~trunk_clash(rho, cz.min(axis=1), spec, s)
            ok &= touches_share(corners, spec, lo, hi)
            dropped += int(np.sum(~ok & (rho < a)))
            kept, n_cut = cut_to_share(corners[ok], spec, lo, hi)
            polys.extend(kept)
            cut += n_cut
    info = {"slat_bound": float(bound), "slats_cut": float(cut), "slats_dropped": float(dropped),
            "slat_mean_area_m2": s * s, "layer_spacing_axis_m": 2.0 * b / N,
            "branch_step_m": climb}
    return polys, info


# ---------------------------------------------------------------- entry point
def build_louvers(tree: Tree, sensors: Sensors, street: Street, frame: FacadeFrame, form: str,
                  source: str | None = None) -> TreeModel:
    lv = tree.louvers
    check_louvers(lv, source)
    optics = LouverOptics.of(lv)
    materials: dict = {LEAF: optics.material()}
    meshes: list[Mesh] = []
    notes: list[str] = []
    if form == "dome" and lv.arrangement == "volume":
        raise ConfigError("got arrangement 'volume' with the sensor-dome form: the dome keeps "
                          "its concentric slat shells; use arrangement = 'layers' or form "
                          "'free'", source=source, field="tree.louvers.arrangement")
    volume = form != "dome" and lv.arrangement == "volume"
    if form == "dome":
        spec = dome_spec(tree, sensors, street, source)
        quads, ginfo = build_dome_louvers(spec, lv, sensors, source)
        verts, faces = quads_to_mesh(quads)
        slats = len(quads)
        notes.extend(dome_notes(spec))
        notes.append(
            f"Louvers: {lv.layers} concentric shells of slats at radii "
            f"{ginfo['layer_radius_min_m']:.2f}–{ginfo['layer_radius_max_m']:.2f} m; each "
            f"shell covers {100 * lv.cover_fraction:.1f} % of the directions from the dome "
            f"centre, so every direction from it crosses {lv.layers} filtration stages. "
            f"{slats} slats of ≈ {lv.slat_size_m:g} m (sides "
            f"{ginfo['slat_side_min_m']:.2f}–{ginfo['slat_side_max_m']:.2f} m), inclined "
            f"{lv.inclination_deg:g}° from horizontal, rows sheared along "
            f"{lv.branch_inclination_deg:g}° branches.")
    else:
        spec_r = crown_row_spec(tree, sensors, street, source)
        if volume:
            from radtree.trees.volume import build_volume_louvers
            polys, ginfo = build_volume_louvers(spec_r, lv, source)
        else:
            polys, ginfo = build_free_louvers(spec_r, lv, source)
        verts, faces = polygons_to_mesh(polys)
        slats = len(polys)
        tv, tf = spec_r.trunks()
        materials[TRUNK] = Plastic(TRUNK, BARK_REFLECTANCE)
        meshes.append(Mesh("tree_trunks", TRUNK, frame.to_world(tv), tf))
        notes.extend(row_notes(spec_r, tree, sensors))
        ginfo["clip_plane_n_m"] = spec_r.n_clip
    if volume:
        from radtree.trees.volume import recommended_volume_ab, volume_note
        notes.append(volume_note(lv, ginfo, slats, optics.t_specular))
    elif form != "dome":
        notes.append(
            f"Louvers: {lv.layers} nested lens-shaped layers per crown (every vertical line "
            f"through a crown crosses {lv.layers}); each layer covers "
            f"{100 * lv.cover_fraction:.1f} % of its plan area with {lv.slat_size_m:g} m "
            f"square slats inclined {lv.inclination_deg:g}°, in branches of {BRANCH_SLATS} "
            f"climbing at {lv.branch_inclination_deg:g}°; {slats} slats "
            f"({int(ginfo['slats_cut'])} cut at the wall-side or shared planes). Near-"
            "horizontal views cross fewer layers than vertical ones (SPEC: first physical "
            "check, point 2).")
    meshes.insert(0, Mesh("tree_leaves", LEAF, frame.to_world(verts), faces))
    if volume:
        notes.append("Leaf optics, " + optics.describe_slat() + ".")
    else:
        notes.append("Leaf optics, " + optics.describe() + ".")
    if optics.reading == "study":
        unit = "per-slat" if volume else "per-layer"
        notes.append(f"Study reading: the study's 0.5 is treated as an effective {unit} "
                     "transmission put into the slat material (a real leaf absorbs far more "
                     "than 1 − 0.5 − 0.11 = 39 %); the alternative is the gap reading "
                     "(switch louvers.reading = \"gap\").")
    elif optics.reading == "gap":
        notes.append("Gap reading: leaves are near-opaque real leaves and each layer passes "
                     "light mainly through its gaps (switch louvers.reading = \"study\" for the "
                     "study's effective slat material).")
    if volume:
        ab = recommended_volume_ab(lv)
        notes.append(f"Radiance: -ab {ab} (crossings + 2, capped at 6: light crossing many "
                     "slats does so mostly by specular transmission, which needs no ambient "
                     "bounce; on Mendoza scenario F, crossings 15, the façade mean moved 0.1 % "
                     "from -ab 6 to -ab 8 at 13:30 (1457 → 1456 lx) and to -ab 12 at 10:30 "
                     "(1089 → 1090 lx), and −1.1 % from -ab 6 to -ab 5 — check with radtree "
                     "simulate --convergence).")
    else:
        ab = lv.layers + 2
        notes.append(f"Radiance: slat layers with diffuse transmission pass light only through "
                     f"ambient bounces; use -ab ≥ {ab} and check convergence.")
    info: dict[str, float] = {
        "layers": float(lv.layers), "cover_fraction": lv.cover_fraction,
        "slat_count": float(slats), "slat_size_m": lv.slat_size_m,
        "slat_reflectance": lv.reflectance, "slat_transmittance": lv.transmittance,
        "slat_specular_transmittance": optics.t_specular,
        "slat_diffuse_transmittance": optics.t_diffuse,
        "tau_layer_direct": optics.tau_layer_direct,
        "tau_crown_direct": optics.tau_crown_direct,
        "tau_layer_global": optics.tau_layer_global,
        "tau_crown_global": optics.tau_crown_global,
        "direct_transmission": optics.tau_crown_direct,
        "reading_study": float(optics.reading == "study"),
        "reading_gap": float(optics.reading == "gap"),
        "arrangement_volume": float(volume),
    }
    if volume:
        # turbid-medium direct transmission along the vertical through a crown centre
        lam = ginfo["lambda_vertical"]
        for key in ("tau_crown_direct", "direct_transmission"):
            info[key] = math.exp(-lam * (1.0 - optics.t_specular))
        info["tau_crown_global"] = math.exp(-lam * (1.0 - optics.transmittance))
        for key in ("tau_layer_direct", "tau_layer_global"):
            info.pop(key)
    info.update(ginfo)
    return TreeModel(meshes=meshes, materials=materials, notes=notes, recommended_ab=ab,
                     info=info, form=form, model="louvers")
