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
runs in the rows above) ∩ slat: convex polygons (Sutherland–Hodgman), mapped back onto the
slat's plane.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from radtree.errors import ConfigError
from radtree.trees.geometry import clip_polygons, ranks_within
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
    last_row, last_col = grid.shape[0] - 1, grid.shape[1] - 1
    _, r0, r1, a, b = _window_runs(grid, *(np.array([v]) for v in (0, last_row, 0, last_col)))
    return r0, r1, a, b


def _window_runs(grid: np.ndarray, i0: np.ndarray, i1: np.ndarray, j0: np.ndarray,
                 j1: np.ndarray) -> tuple[np.ndarray, ...]:
    """:func:`_runs` of many windows of ``grid`` at once (window w: rows i0[w]..i1[w], columns
    j0[w]..j1[w], inclusive): (window, first row, last row, start column, stop column), rows
    and columns counted from the window's corner, ordered by window, then start column, stop
    column and first row."""
    win, row, col = _window_cells(i0, i1, j0, j1)
    return _cell_runs(win, row, col, grid[i0[win] + row, j0[win] + col], (j1 - j0)[win])


def _cell_runs(win: np.ndarray, row: np.ndarray, col: np.ndarray, val: np.ndarray,
               last: np.ndarray) -> tuple[np.ndarray, ...]:
    """:func:`_window_runs` of windows given cell by cell (as :func:`_window_cells` lists
    them, whole windows only): each cell's window, row, column, value and its window's last
    column."""
    prev = np.concatenate([[False], val[:-1]]) & (col > 0)
    after = np.concatenate([val[1:], [False]]) & (col < last)
    start = np.flatnonzero(val & ~prev)
    stop = np.flatnonzero(val & ~after)              # the run's last cell, in the same order
    win, r, a, b = win[start], row[start], col[start], col[stop] + 1
    order = np.lexsort((r, b, a, win))
    win, r, a, b = win[order], r[order], a[order], b[order]
    new = np.ones(len(r), bool)
    new[1:] = ((win[1:] != win[:-1]) | (a[1:] != a[:-1]) | (b[1:] != b[:-1])
               | (r[1:] != r[:-1] + 1))
    first = np.flatnonzero(new)
    last_run = np.append(first[1:], len(r)) - 1
    return win[first], r[first], r[last_run], a[first], b[first]


def cut_slats(quads: np.ndarray, centre: np.ndarray, is_sky, cell: float = CELL
              ) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    """Slat quads (k, 4, 3) around ``centre`` cut where ``is_sky`` (unit façade-frame
    vectors → bool) is sky: the kept convex pieces one after another — points (m, 3) and
    each piece's corner count (face by face: its whole slats, then the pieces of its cut
    slats) — and counts."""
    rasters = _face_rasters(is_sky, cell)
    axes = np.array([f[0] for f in DOME_FACES])
    rel = quads - centre[None, None, :]
    cdir = rel.mean(axis=1)
    face_of = np.argmax(cdir @ axes.T, axis=1)
    points: list[np.ndarray] = []
    counts: list[np.ndarray] = []
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
        cells = (iy1 - iy0 + 1) * (ix1 - ix0 + 1)
        win, row, col = _window_cells(iy0, iy1, ix0, ix1)
        val = canopy[iy0[win] + row, ix0[win] + col]
        in_canopy = np.add.reduceat(val.astype(np.int64), np.cumsum(cells) - cells)
        is_whole = in_canopy == cells
        is_cut = (in_canopy > 0) & ~is_whole
        removed += int((in_canopy == 0).sum())
        whole += int(is_whole.sum())
        points.append(quads[sel[is_whole]].reshape(-1, 3))
        counts.append(np.full(int(is_whole.sum()), 4, np.int64))
        if not is_cut.any():
            continue
        c = is_cut[win]                  # the cells of the cut slats' windows
        of, r0, r1, a, b = _cell_runs(win[c], row[c], col[c], val[c], (ix1 - ix0)[win[c]])
        b4 = np.column_stack([edges[ix0[of] + a], edges[iy0[of] + r0],
                              edges[ix0[of] + b], edges[iy0[of] + r1] + cell])
        xy, n_xy = _clip_to_boxes(np.stack([X, Y], axis=2)[of], b4)
        keep = (n_xy >= 3) & (_areas(xy, n_xy) > MIN_PIECE)
        kept_by = np.unique(of[keep])
        removed += len(np.unique(of)) - len(kept_by)
        cut += len(kept_by)
        xy, n_xy = xy[keep], n_xy[keep]
        points.append(_on_slats(xy, n_xy, rel[sel[of[keep]]], centre, A, P, Q))
        counts.append(n_xy)
    info = {"photo_slats_whole": float(whole), "photo_slats_removed": float(removed),
            "photo_slats_cut": float(cut), "photo_pieces": float(sum(len(c) for c in counts)),
            "photo_cell_gnomonic": cell}
    if not points:
        return np.zeros((0, 3)), np.zeros(0, np.int64), info
    return np.concatenate(points), np.concatenate(counts), info


def _window_cells(i0: np.ndarray, i1: np.ndarray, j0: np.ndarray, j1: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every cell of the windows (rows i0..i1, columns j0..j1, inclusive), window after
    window, row by row: its window, and its row and column counted from the window's corner."""
    h, w = i1 - i0 + 1, j1 - j0 + 1
    size = h * w
    win = np.repeat(np.arange(len(h)), size)
    row, col = np.divmod(ranks_within(size), w[win])
    return win, row, col


def _clip_to_boxes(polys: np.ndarray, boxes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Convex polygons (n, 4, 2) each ∩ its box (n, 4: x0, y0, x1, y1), all at once: four
    Sutherland–Hodgman clips; (n, K, 2) polygons (first ``counts[i]`` rows) and counts."""
    out = polys
    n = np.full(len(polys), polys.shape[1], np.int64)
    for normal, offset in (((1.0, 0.0), boxes[:, 0]), ((0.0, 1.0), boxes[:, 1]),
                           ((-1.0, 0.0), -boxes[:, 2]), ((0.0, -1.0), -boxes[:, 3])):
        out, n = clip_polygons(out, n, np.array(normal), offset)
    return out, n


def _areas(xy: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Shoelace areas of the polygons (n, K, 2) with ``counts`` corners (rows beyond unused)."""
    slot = np.arange(xy.shape[1])
    nxt = np.take_along_axis(xy, ((slot[None, :] + 1) % np.maximum(counts, 1)[:, None]
                                  )[:, :, None], axis=1)
    with np.errstate(invalid="ignore"):   # rows beyond a polygon's count may hold NaN
        term = xy[:, :, 0] * nxt[:, :, 1] - nxt[:, :, 0] * xy[:, :, 1]
    return 0.5 * np.abs(np.where(slot[None, :] < counts[:, None], term, 0.0).sum(axis=1))


def _on_slats(xy: np.ndarray, counts: np.ndarray, corners: np.ndarray, centre: np.ndarray,
              A: np.ndarray, P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Pieces in gnomonic X, Y of one face (n, K, 2; ``counts`` corners each) mapped back onto
    the plane of their slats (``corners`` (n, 4, 3), relative to ``centre``): the points of
    all pieces one after another (sum(counts), 3)."""
    used = np.arange(xy.shape[1])[None, :] < counts[:, None]
    flat = xy[used]
    ring = np.repeat(np.arange(len(counts)), counts)
    m = np.cross(corners[:, 1] - corners[:, 0], corners[:, 3] - corners[:, 0])
    m /= np.linalg.norm(m, axis=1)[:, None]
    h = _dot(m, corners[:, 0])
    dirs = A[None, :] + flat[:, :1] * P[None, :] + flat[:, 1:2] * Q[None, :]
    t = h[ring] / _dot(dirs, m[ring])
    return centre + t[:, None] * dirs


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot products of (n, 3) arrays, summed left to right."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def dome_from_photo(quads: np.ndarray, centre: np.ndarray, src: PhotoSource,
                    source: str | None = None
                    ) -> tuple[np.ndarray, np.ndarray, dict[str, float], dict[str, Any]]:
    """The dome's slats cut by the façade photo ``src``: the pieces' points and corner counts
    (as :func:`cut_slats`), counts, provenance."""
    try:
        require_direction(src, "facade", "the louvers dome")
        if len(src.images) > 1:
            raise ConfigError(f"the louvers dome is cut from one façade photo; {src.path} "
                              f"holds {len(src.images)}", field=src.field)
        result = analyse_photo(src.images[0], src)
    except ConfigError as exc:
        raise with_source(exc, source) from None
    is_sky = facade_sky(result)
    points, corners, info = cut_slats(quads, centre, is_sky)
    info["photo_openness"] = float(result.metrics.openness)
    return points, corners, info, provenance(src, [result], {
        "slats_removed": info["photo_slats_removed"], "slats_cut": info["photo_slats_cut"]})
