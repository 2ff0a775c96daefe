"""Cut one tree's points out of a tile: ``radtree lidar clip TILE --tree ID --out tree.laz``.

The tree is found by the same segmentation as ``radtree lidar segment`` (same settings, so the
same ids); its points are the tile's points in the crown's cells (its ground points
included, so the file carries its own terrain for heights above ground), written with the
tile's own header (point format, scales, offsets, CRS; laspy), as LAZ when ``out`` ends in
``.laz``. Written to a temporary name and moved into place.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from radtree.errors import ConfigError
from radtree.fileio import atomic_path
from radtree.lidar.segment import SegmentConfig, segment_tile
from radtree.lidar.tile import SCAN_ANGLE_STEP, _las, read_tile


def write_subset(tile_path: str | Path, mask: np.ndarray, out: str | Path) -> Path:
    """Write the points of ``tile_path`` where ``mask`` holds to ``out`` (LAS/LAZ by suffix)."""
    import laspy

    out = Path(out)
    if out.suffix.lower() not in (".las", ".laz"):
        raise ConfigError(f"the output {out.name!r} must end in .las or .laz", source=str(out))
    las = _las(Path(tile_path))
    sub = laspy.LasData(las.header)
    sub.points = las.points[np.asarray(mask)].copy()
    _write(sub, out)
    return out


def write_points(out: str | Path, xyz: np.ndarray, classification: np.ndarray,
                 return_number: np.ndarray | None = None,
                 number_of_returns: np.ndarray | None = None, crs: str | None = None,
                 scale_m: float = 0.001, *, source_id: np.ndarray | None = None,
                 gps_time: np.ndarray | None = None,
                 scan_angle_deg: np.ndarray | None = None,
                 intensity: np.ndarray | None = None) -> Path:
    """Write points (m) as LAS 1.4 point format 6 (LAZ when ``out`` ends in ``.laz``), with a
    CRS (anything pyproj reads) when given; coordinates to ``scale_m``; the point source id
    (flight line, scan position), GPS time (s), scan angle (degrees; LAS 1.4 stores it
    in steps of 0.006°) and intensity (0–1, stored linearly on 16 bits: × 65535) when given."""
    import laspy

    out = Path(out)
    xyz = np.asarray(xyz, float).reshape(-1, 3)
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales = np.array([scale_m] * 3)
    header.offsets = np.floor(xyz.min(axis=0)) if len(xyz) else np.zeros(3)
    if crs is not None:
        from pyproj import CRS

        header.add_crs(CRS.from_user_input(crs))
    las = laspy.LasData(header)
    las.x, las.y, las.z = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    las.classification = np.asarray(classification, np.uint8)
    ones = np.ones(len(xyz), np.uint8)
    las.return_number = ones if return_number is None else np.asarray(return_number, np.uint8)
    las.number_of_returns = (ones if number_of_returns is None
                             else np.asarray(number_of_returns, np.uint8))
    if source_id is not None and len(source_id):
        las.point_source_id = np.asarray(source_id, np.int64) % 65536   # LAS: uint16
    if gps_time is not None and len(gps_time):
        las.gps_time = np.asarray(gps_time, float)
    if scan_angle_deg is not None and len(scan_angle_deg):
        las.scan_angle = np.clip(np.round(np.asarray(scan_angle_deg, float) / SCAN_ANGLE_STEP),
                                 -30000, 30000).astype(np.int16)
    if intensity is not None and len(intensity):
        las.intensity = np.round(np.clip(np.asarray(intensity, float), 0.0, 1.0)
                                 * 65535).astype(np.uint16)
    return _write(las, out)


def _write(las: Any, out: Path) -> Path:
    """Write ``las`` to ``out`` atomically, LAZ-compressed when ``out`` ends in ``.laz`` (a
    stream: laspy takes the compression from a path's suffix, and the temporary's is not)."""
    with atomic_path(out) as tmp, open(tmp, "wb") as fh:
        las.write(fh, do_compress=out.suffix.lower() == ".laz")
    return out


def clip_tree(tile_path: str | Path, tree_id: str, out: str | Path,
              cfg: SegmentConfig | None = None) -> tuple[Path, int]:
    """Segment the tile, write tree ``tree_id``'s points to ``out``; (path, point count)."""
    seg = segment_tile(read_tile(tile_path), cfg)
    mask = seg.tree_mask(tree_id)
    return write_subset(tile_path, mask, out), int(mask.sum())
