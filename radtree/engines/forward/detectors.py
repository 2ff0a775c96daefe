"""Square patch detectors around sensor points, tallying the flux that crosses them.

Each sensor of a grid becomes a square of side ``side`` (m) centred on the sensor point, in the
plane through it perpendicular to its normal (sides: horizontal and up the plane for tilted
sensors, x and y for horizontal ones). A photon segment that crosses a square towards the
sensor's front (travelling against the normal) adds its flux (lm) to that detector; the
detector's illuminance is the flux per batch / side² (lux). Detectors are virtual: they stop
nothing. Coplanar detectors (a façade circle, a dense map) are tested together: one plane
crossing per segment, then only the segments landing inside the group's bounding square are
matched to squares.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radtree.scene import SensorGrid

_PLANE_DIGITS = 6  # normals and plane offsets rounded to 1 µm to group coplanar detectors


def patch_axes(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """In-plane unit axes (u, v) of a detector with unit ``normal``: u horizontal (x for a
    horizontal detector), v = n × u."""
    n = np.asarray(normal, float)
    up = np.array([0.0, 0.0, 1.0])
    u = np.cross(up, n) if abs(n[2]) < 0.999 else np.array([1.0, 0.0, 0.0]) - n[0] * n
    u = u / np.linalg.norm(u)
    return u, np.cross(n, u)


@dataclass
class _Group:
    normal: np.ndarray
    offset: float          # n · p for points p of the plane
    u: np.ndarray
    v: np.ndarray
    cu: np.ndarray         # detector centres along u, v
    cv: np.ndarray
    index: np.ndarray      # global detector index of each member
    lo: np.ndarray         # bounding square (u, v) of the group, detectors included
    hi: np.ndarray


class PatchDetectors:
    """The detectors of several grids; ``slices[name]`` their global indices."""

    def __init__(self, grids: dict[str, SensorGrid], side: float):
        self.side = float(side)
        self.area = self.side * self.side
        self.slices: dict[str, slice] = {}
        self.groups: list[_Group] = []
        start = 0
        for name, grid in grids.items():
            self.slices[name] = slice(start, start + len(grid))
            keys: dict[tuple, list[int]] = {}
            for i, (p, n) in enumerate(zip(grid.points, grid.normals)):
                key = (*np.round(n, _PLANE_DIGITS), round(float(n @ p), _PLANE_DIGITS))
                keys.setdefault(key, []).append(i)
            for members in keys.values():
                idx = np.array(members)
                n = grid.normals[idx[0]]
                u, v = patch_axes(n)
                pts = grid.points[idx]
                cu, cv = pts @ u, pts @ v
                h = self.side / 2.0
                self.groups.append(_Group(n, float(n @ pts[0]), u, v, cu, cv, idx + start,
                                          np.array([cu.min() - h, cv.min() - h]),
                                          np.array([cu.max() + h, cv.max() + h])))
            start += len(grid)
        self.count = start

    def corners(self) -> np.ndarray:
        """(count, 4, 3) corner points of every detector (for bounding spheres and checks)."""
        out = np.zeros((self.count, 4, 3))
        h = self.side / 2.0
        for g in self.groups:
            base = (g.cu[:, None] * g.u + g.cv[:, None] * g.v + g.offset * g.normal)
            for k, (a, b) in enumerate(((-h, -h), (h, -h), (h, h), (-h, h))):
                out[g.index, k] = base + a * g.u + b * g.v
        return out

    def tally(self, origins: np.ndarray, dirs: np.ndarray, lengths: np.ndarray,
              flux: np.ndarray, batch: np.ndarray, out: np.ndarray) -> tuple[int, float]:
        """Add the flux of segments ``origins + s·dirs`` (0 < s < ``lengths``) crossing a
        detector from its front into ``out[batch, detector]`` (lm); the crossings and their
        flux (lm)."""
        n_det = out.shape[1]
        crossings, crossed = 0, 0.0
        h = self.side / 2.0
        for g in self.groups:
            denom = dirs @ g.normal
            towards = denom < -1e-12
            if not towards.any():
                continue
            sel = np.flatnonzero(towards)
            s = (g.offset - origins[sel] @ g.normal) / denom[sel]
            ok = (s > 0.0) & (s < lengths[sel])
            sel, s = sel[ok], s[ok]
            if len(sel) == 0:
                continue
            q = origins[sel] + s[:, None] * dirs[sel]
            qu, qv = q @ g.u, q @ g.v
            inside = (qu >= g.lo[0]) & (qu <= g.hi[0]) & (qv >= g.lo[1]) & (qv <= g.hi[1])
            sel, qu, qv = sel[inside], qu[inside], qv[inside]
            for c0 in range(0, len(sel), 8192):
                part = slice(c0, c0 + 8192)
                m = ((np.abs(qu[part, None] - g.cu[None, :]) <= h)
                     & (np.abs(qv[part, None] - g.cv[None, :]) <= h))
                ray, det = np.nonzero(m)
                if len(ray) == 0:
                    continue
                r = sel[part][ray]
                flat = batch[r] * n_det + g.index[det]
                out += np.bincount(flat, flux[r], minlength=out.size).reshape(out.shape)
                crossings += len(r)
                crossed += float(flux[r].sum())
        return crossings, crossed
