"""A crown's plant area density on a voxel grid, read from a CSV file (``[tree] voxels``).

The format, one row per voxel (columns in any order, others ignored, lines starting with ``#``
skipped — what a table exported from AMAPVox or another leaf-area-density tool reduces to):

* ``x_m``, ``y_m``, ``z_m`` — the voxel's centre in metres from the trunk base: x along the
  façade (the façade frame's u, growing the way the row's trunks are numbered), y away from
  the façade (n), z up from the street;
* ``pad_m2_m3`` — its one-sided plant area density (m² of leaf and wood per m³, ≥ 0).

The voxels are cubes of side ``[tree] voxels_size_m`` (left out: the smallest spacing between
distinct centres along x, y or z); every centre must lie on one lattice of that side (the
centres of a regular grid), each voxel at most once; voxels not listed are empty. Errors name
the file, the data row (1: the first under the header) and the fix (:class:`~radtree.errors.ConfigError`,
exit 2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from radtree.errors import ConfigError

HEADER = ("x_m", "y_m", "z_m", "pad_m2_m3")
FIELD = "tree.voxels"
LATTICE_TOL = 1e-3     # centres may be off the lattice by this share of a voxel (rounding)
MAX_VOXELS = 20_000_000   # cells of the bounding grid (memory: 8 bytes each)


@dataclass(frozen=True)
class VoxelFile:
    """The grid read: ``pad`` [i, j, k] (m²/m³) of voxels ``size_m`` wide whose voxel (0, 0, 0)
    has its lower corner at ``corner`` (x, y, z m from the trunk base, façade frame)."""

    path: Path
    pad: np.ndarray
    corner: np.ndarray
    size_m: float
    rows: int


def _fail(path: Path, message: str) -> ConfigError:
    return ConfigError(message, source=str(path), field=FIELD)


def _table(path: Path) -> pd.DataFrame:
    """The file's rows with the four columns as floats (ConfigError: missing, unreadable, a
    column absent, a value not a finite number)."""
    if not path.is_file():
        raise ConfigError(f"voxel file {path} not found: give the path of a CSV file with "
                          f"columns {', '.join(HEADER)}", field=FIELD)
    try:
        df = pd.read_csv(path, comment="#", skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise _fail(path, f"not a readable CSV table ({exc}); expected columns "
                          f"{', '.join(HEADER)}") from None
    df.columns = [str(c).strip() for c in df.columns]
    missing = [c for c in HEADER if c not in df.columns]
    if missing:
        raise _fail(path, f"missing column(s) {', '.join(missing)}; found "
                          f"{', '.join(df.columns) or 'none'}; expected {', '.join(HEADER)} "
                          "(voxel centres in m from the trunk base, density in m²/m³)")
    if len(df) == 0:
        raise _fail(path, "no voxel rows: list at least one voxel")
    out = df[list(HEADER)].apply(pd.to_numeric, errors="coerce")
    bad = ~np.isfinite(out.to_numpy(float))
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise _fail(path, f"data row {r + 1}: {HEADER[c]} = {df.iloc[r][HEADER[c]]!r} is not a "
                          "finite number")
    neg = (out["pad_m2_m3"] < 0).to_numpy()
    if neg.any():
        r = int(np.argmax(neg))
        raise _fail(path, f"data row {r + 1}: pad_m2_m3 = {out['pad_m2_m3'].iloc[r]:g}, expected a "
                          "plant area density ≥ 0 m²/m³")
    return out


def infer_size(xyz: np.ndarray) -> float | None:
    """The smallest positive spacing between distinct centre coordinates along any axis
    (None: one voxel)."""
    gaps = [np.diff(np.unique(np.round(xyz[:, a], 9))) for a in range(3)]
    pos = np.concatenate(gaps) if gaps else np.zeros(0)
    pos = pos[pos > 1e-9]
    return float(pos.min()) if len(pos) else None


def read_voxel_file(path: str | Path, size_m: float | None = None) -> VoxelFile:
    """The grid of ``path`` (module text); ConfigError naming the file, the row and the fix
    for a missing file, bad columns or values, a negative density, an irregular grid or a
    voxel listed twice."""
    path = Path(path)
    t = _table(path)
    xyz = t[["x_m", "y_m", "z_m"]].to_numpy(float)
    pad = t["pad_m2_m3"].to_numpy(float)
    size = infer_size(xyz) if size_m is None else float(size_m)
    if size is None:
        raise _fail(path, "one voxel only: give its side, tree.voxels_size_m (m)")
    lo = xyz.min(axis=0)
    steps = (xyz - lo) / size
    idx = np.round(steps).astype(np.int64)
    off = np.abs(steps - idx).max(axis=1)
    if off.max() > LATTICE_TOL:
        r = int(np.argmax(off))
        raise _fail(path, f"data row {r + 1}: the centre ({', '.join(f'{v:g}' for v in xyz[r])}) m "
                          f"is not on the {size:g} m lattice of the first voxel's "
                          f"({', '.join(f'{v:g}' for v in lo)}) — an irregular grid; give "
                          f"regular voxel centres or the right "
                          "tree.voxels_size_m")
    dims = idx.max(axis=0) + 1
    if math.prod(dims.tolist()) > MAX_VOXELS:
        raise _fail(path, f"a grid of {dims[0]} × {dims[1]} × {dims[2]} voxels of {size:g} m "
                          f"exceeds {MAX_VOXELS:,} cells: use larger voxels (resample the "
                          "grid)")
    lin = np.ravel_multi_index(idx.T, dims)
    order = np.argsort(lin, kind="stable")
    dup = np.nonzero(np.diff(lin[order]) == 0)[0]
    if len(dup):
        a, b = sorted((int(order[dup[0]]), int(order[dup[0] + 1])))
        raise _fail(path, f"data rows {a + 1} and {b + 1} are the same voxel "
                          f"({', '.join(f'{v:g}' for v in xyz[b])}) m: list each voxel once")
    grid = np.zeros(tuple(dims.tolist()))
    grid[idx[:, 0], idx[:, 1], idx[:, 2]] = pad
    return VoxelFile(path, grid, lo - 0.5 * size, size, len(pad))
