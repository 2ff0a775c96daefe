"""The louvers dome cut by its façade photo: slats removed, in every layer, wherever the photo
shows sky along the line from the photo point (the study's "projection and subtraction").

The photo point is the dome centre (the façade photo is taken at the sensors). Each slat is
cut in the gnomonic coordinates of the dome's cube face it lies in (the five half faces of
:data:`radtree.trees.louvers_dome.DOME_FACES`; a slat belongs to the face whose axis A is
nearest its centre direction): a direction d maps to (X, Y) = (d·P, d·Q) / (d·A). This is a
central projection, so straight slat edges stay straight, and every shell is cut on **one
grid shared by all layers**: cell (i, j) of side :data:`CELL` (gnomonic units; ≈ 0.57° at a
face centre, finer towards its edges) is sky when the photo shows sky at the cell centre's
direction, and the part of every slat inside a sky cell is removed. So a direction through a
sky cell passes every layer and a direction through a canopy cell meets every layer's slat —
the layers' gaps line up along the lines from the photo point, as in the photo, up to one
cell. The pieces kept are (rectangles of canopy cells: runs along a row, merged with the same
runs in the rows above) ∩ slat: convex polygons (shapely), mapped back onto the slat's plane.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import shapely

from radtree.errors import ConfigError
from radtree.trees.louvers_dome import DOME_FACES
from radtree.trees.photo import (
    PhotoSource,
    analyse_photo,
    facade_sky,
    provenance,
    require_direction,
    with_source,
)

CELL = 0.01            # gnomonic cell side (X = tan a): 0.57° at a face centre
EXTENT = 1.10          # the grid covers |X|, |Y| ≤ this (a face spans ±1)
MIN_PIECE = 1e-9       # pieces smaller than this (gnomonic units², ≈ 2e-9 sr) are dropped


def _face_rasters(is_sky, cell: float = CELL) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per face: the cell edges (same in X and Y) and the canopy raster (ny, nx) (True =
    canopy: the photo shows no sky at the cell centre's direction)."""
    edges = np.arange(-EXTENT, EXTENT + 0.5 * cell, cell)
    mid = 0.5 * (edges[1:] + edges[:-1])
    X, Y = np.meshgrid(mid, mid)
    out = []
    for A, P, Q, _a, _b in DOME_FACES:
        d = A[None, :] + X.reshape(-1, 1) * P[None, :] + Y.reshape(-1, 1) * Q[None, :]
        d /= np.linalg.norm(d, axis=1)[:, None]
        canopy = np.ones(len(d), bool)
        front = d[:, 1] >= 0.0         # behind the wall: no photo, no cut
        sky = np.zeros(len(d), bool)
        for i in range(0, int(front.sum()), 65536):
            idx = np.flatnonzero(front)[i:i + 65536]
            sky[idx] = np.asarray(is_sky(d[idx]), bool)
        canopy &= ~sky
        out.append((edges, canopy.reshape(X.shape)))
    return out


def _runs(grid: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The True cells of ``grid`` as rectangles: runs of consecutive True cells along each row,
    runs with the same columns in consecutive rows merged into one — (first row, last row,
    start column, stop column) index arrays. They cover exactly the True cells."""
    pad = np.zeros((grid.shape[0], grid.shape[1] + 2), np.int8)
    pad[:, 1:-1] = grid
    d = np.diff(pad, axis=1)
    r, a = np.nonzero(d == 1)
    _, b = np.nonzero(d == -1)
    order = np.lexsort((r, b, a))
    r, a, b = r[order], a[order], b[order]
    new = np.ones(len(r), bool)
    new[1:] = (a[1:] != a[:-1]) | (b[1:] != b[:-1]) | (r[1:] != r[:-1] + 1)
    first = np.flatnonzero(new)
    last = np.append(first[1:], len(r)) - 1
    return r[first], r[last], a[first], b[first]


def cut_slats(quads: np.ndarray, centre: np.ndarray, is_sky, cell: float = CELL
              ) -> tuple[list[np.ndarray], dict[str, float]]:
    """Slat quads (k, 4, 3) around ``centre`` cut where ``is_sky`` (unit façade-frame
    vectors → bool) is sky: the kept convex pieces (each an (m, 3) polygon) and counts."""
    rasters = _face_rasters(is_sky, cell)
    axes = np.array([f[0] for f in DOME_FACES])
    rel = quads - centre[None, None, :]
    cdir = rel.mean(axis=1)
    face_of = np.argmax(cdir @ axes.T, axis=1)
    pieces: list[np.ndarray] = []
    whole = removed = cut = 0
    for f, (A, P, Q, _a, _b) in enumerate(DOME_FACES):
        edges, canopy = rasters[f]
        sel = np.flatnonzero(face_of == f)
        if not len(sel):
            continue
        D = rel[sel]
        w = D @ A
        X, Y = (D @ P) / w, (D @ Q) / w
        n_cells = canopy.shape[0]
        ix0 = np.clip(np.floor((X.min(axis=1) + EXTENT) / cell).astype(int), 0, n_cells - 1)
        ix1 = np.clip(np.floor((X.max(axis=1) + EXTENT) / cell).astype(int), 0, n_cells - 1)
        iy0 = np.clip(np.floor((Y.min(axis=1) + EXTENT) / cell).astype(int), 0, n_cells - 1)
        iy1 = np.clip(np.floor((Y.max(axis=1) + EXTENT) / cell).astype(int), 0, n_cells - 1)
        bx: list[np.ndarray] = []
        owner: list[int] = []
        slat_of: list[int] = []
        for k, q in enumerate(sel):
            sub = canopy[iy0[k]:iy1[k] + 1, ix0[k]:ix1[k] + 1]
            if sub.all():
                pieces.append(quads[q])
                whole += 1
                continue
            if not sub.any():
                removed += 1
                continue
            r0, r1, a, b = _runs(sub)
            bx.append(np.column_stack([edges[ix0[k] + a], edges[iy0[k] + r0],
                                       edges[ix0[k] + b], edges[iy0[k] + r1] + cell]))
            owner.extend([int(q)] * len(r0))
            slat_of.extend([k] * len(r0))
        if not bx:
            continue
        b4 = np.concatenate(bx)
        boxes = shapely.box(b4[:, 0], b4[:, 1], b4[:, 2], b4[:, 3])
        slat_polys = shapely.polygons(np.stack([X, Y], axis=2))
        got = shapely.intersection(boxes, slat_polys[np.array(slat_of)])
        own = np.array(owner)
        keep = ~shapely.is_empty(got) & (shapely.area(got) > MIN_PIECE)
        kept_by = set(own[keep].tolist())
        removed += len(set(owner) - kept_by)
        cut += len(kept_by)
        pieces.extend(_pieces_on_slats(got[keep], own[keep], rel, centre, A, P, Q))
    info = {"photo_slats_whole": float(whole), "photo_slats_removed": float(removed),
            "photo_slats_cut": float(cut), "photo_pieces": float(len(pieces)),
            "photo_cell_gnomonic": cell}
    return pieces, info


def _pieces_on_slats(got: np.ndarray, own: np.ndarray, rel: np.ndarray, centre: np.ndarray,
                     A: np.ndarray, P: np.ndarray, Q: np.ndarray) -> list[np.ndarray]:
    """The polygons of the kept intersections ``got`` (gnomonic X, Y of one face; multi-part
    results split, parts that are not polygons or smaller than :data:`MIN_PIECE` dropped),
    each mapped back onto the plane of its slat ``own`` (slat corners ``rel`` around
    ``centre``): (m, 3) polygons in the order of ``got`` and its parts."""
    parts, of = shapely.get_parts(got, return_index=True)
    ok = (shapely.get_type_id(parts) == 3) & (shapely.area(parts) > MIN_PIECE)   # 3: Polygon
    parts, of = parts[ok], of[ok]
    if not len(parts):
        return []
    xy, ring = shapely.get_coordinates(shapely.get_exterior_ring(parts), return_index=True)
    count = np.bincount(ring, minlength=len(parts))
    last = np.cumsum(count) - 1
    keep = np.ones(len(xy), bool)
    keep[last] = False               # the closing vertex of each ring
    xy, ring = xy[keep], ring[keep]
    q = own[of]                      # the slat of each part
    corners = rel[q]
    m = np.cross(corners[:, 1] - corners[:, 0], corners[:, 3] - corners[:, 0])
    m /= np.linalg.norm(m, axis=1)[:, None]
    h = _dot(m, corners[:, 0])
    dirs = A[None, :] + xy[:, :1] * P[None, :] + xy[:, 1:2] * Q[None, :]
    t = h[ring] / _dot(dirs, m[ring])
    points = centre + t[:, None] * dirs
    return np.split(points, np.cumsum(count - 1)[:-1])


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot products of (n, 3) arrays, summed left to right."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def dome_from_photo(quads: np.ndarray, centre: np.ndarray, src: PhotoSource,
                    source: str | None = None
                    ) -> tuple[list[np.ndarray], dict[str, float], dict[str, Any]]:
    """The dome's slats cut by the façade photo ``src``: pieces, counts, provenance."""
    try:
        require_direction(src, "facade", "the louvers dome")
        if len(src.images) > 1:
            raise ConfigError(f"the louvers dome is cut from one façade photo; {src.path} "
                              f"holds {len(src.images)}", field=src.field)
        result = analyse_photo(src.images[0], src)
    except ConfigError as exc:
        raise with_source(exc, source) from None
    is_sky = facade_sky(result)
    pieces, info = cut_slats(quads, centre, is_sky)
    info["photo_openness"] = float(result.metrics.openness)
    return pieces, info, provenance(src, [result], {
        "slats_removed": info["photo_slats_removed"], "slats_cut": info["photo_slats_cut"]})
