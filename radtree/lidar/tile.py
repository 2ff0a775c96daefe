"""Read an airborne or terrestrial laser scanning tile (LAS/LAZ) with laspy (lazrs backend).

Coordinates stay those of the file: metres, x east, y north, z up (a projected CRS or a local
scanner frame). A tile in degrees (a geographic CRS, or no CRS and x, y inside a fraction of a
degree while z spans metres) is refused: the horizontal windows and voxels of
:mod:`radtree.lidar` are in metres, so it must be reprojected first (``pdal translate`` with
``filters.reprojection``, or ``las2las -target_utm auto``).

Every problem raises one :class:`~radtree.errors.ConfigError` naming the file and the fix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from radtree.errors import ConfigError

GROUND_CLASS = 2   # ASPRS LAS 1.4 R15, Table 17: classification value 2 = ground
#: the reference segmentation ids of lidR's example data (``treeID``; huge = no tree)
NO_ID = 1e300
#: degrees per unit of the LAS 1.4 ``scan_angle`` (point formats 6–10; e.g. ArcGIS Pro's
#: ``LasPoint.ScanAngleDegree``: "each increment represents 0.006 degrees")
SCAN_ANGLE_STEP = 0.006


@dataclass(frozen=True)
class Tile:
    """A point cloud: ``xyz`` (n, 3) m, ASPRS ``classification``, ``return_number``,
    ``number_of_returns``, ``extra`` dimensions by name, ``crs`` (WKT text or None), the
    LAS ``point_source_id`` (flight line or scan position), ``gps_time`` (s) and scan angle
    (degrees from nadir, + right of the flight direction) of every point (zeros when the file
    has none) and its LAS ``intensity`` (as stored, None when not read)."""

    path: Path
    xyz: np.ndarray
    classification: np.ndarray
    return_number: np.ndarray
    number_of_returns: np.ndarray
    extra: dict[str, np.ndarray]
    crs: str | None
    source_id: np.ndarray | None = None
    gps_time: np.ndarray | None = None
    scan_angle_deg: np.ndarray | None = None
    intensity: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.xyz)

    @property
    def source(self) -> str:
        return str(self.path)

    def spacing_m(self) -> float:
        """Mean point spacing (m) of the first returns: 1/√density, the density counted on
        the occupied 1 m × 1 m cells (so gaps and an irregular outline do not dilute it)."""
        first = self.xyz[self.return_number <= 1] if len(self.return_number) else self.xyz
        if len(first) < 2:
            first = self.xyz
        cells = np.unique(np.floor(first[:, :2]).astype(np.int64), axis=0)
        density = len(first) / max(len(cells), 1)
        return 1.0 / math.sqrt(density)

    def subset(self, mask: np.ndarray) -> Tile:
        """The points where ``mask`` is true (same file, CRS)."""
        return Tile(self.path, self.xyz[mask], self.classification[mask],
                    self.return_number[mask], self.number_of_returns[mask],
                    {k: v[mask] for k, v in self.extra.items()}, self.crs,
                    None if self.source_id is None else self.source_id[mask],
                    None if self.gps_time is None else self.gps_time[mask],
                    None if self.scan_angle_deg is None else self.scan_angle_deg[mask],
                    None if self.intensity is None else self.intensity[mask])


def _las(path: Path) -> Any:
    import laspy

    src = str(path)
    if not path.is_file():
        raise ConfigError("file not found: give the path of a .las or .laz tile", source=src)
    with open(path, "rb") as fh:
        magic = fh.read(4)
    if magic != b"LASF":
        raise ConfigError(f"not a LAS/LAZ file (it starts with {magic!r}, a LAS file with "
                          "b'LASF'): convert it first, e.g. `pdal translate in.ply out.laz`",
                          source=src)
    try:
        return laspy.read(path)
    except (laspy.errors.LaspyException, ValueError, OSError) as exc:
        raise ConfigError(f"cannot read this LAS/LAZ file ({exc}); for .laz the lazrs "
                          "backend is needed: pip install 'laspy[lazrs]'", source=src) from None


def crs_wkt(las: Any) -> str | None:
    """The tile's CRS as WKT (from its WKT or GeoTIFF VLRs), or None."""
    try:
        crs = las.header.parse_crs()
    except Exception:   # malformed VLRs: treated as no CRS (the user gives --crs)
        return None
    return None if crs is None else str(crs.to_wkt())


def scan_angle(las: Any) -> np.ndarray:
    """Every point's scan angle (degrees): LAS 1.4 point formats 6–10 store it in steps of
    :data:`SCAN_ANGLE_STEP` (``scan_angle``), the older formats in whole degrees
    (``scan_angle_rank``) (ASPRS LAS 1.4 R15, point data records)."""
    names = las.point_format.dimension_names
    if "scan_angle" in names:
        return np.asarray(las.scan_angle, float) * SCAN_ANGLE_STEP
    if "scan_angle_rank" in names:
        return np.asarray(las.scan_angle_rank, float)
    return np.zeros(len(las.points))


def read_tile(path: str | Path) -> Tile:
    """Read ``path``: points, classes, returns, extra dimensions and CRS; checked (module text)."""
    path = Path(path)
    las = _las(path)
    src = str(path)
    n = len(las.points)
    if n == 0:
        raise ConfigError("the tile holds no points: check the export (a clip outside the "
                          "data gives an empty file)", source=src)
    if n == 1:
        raise ConfigError("the tile holds one point: nothing to find trees in or to fill "
                          "voxels from; check the export or clip (radtree lidar clip)",
                          source=src)
    xyz = np.column_stack([np.asarray(las.x, float), np.asarray(las.y, float),
                           np.asarray(las.z, float)])
    extra = {name: np.asarray(las[name]) for name in las.point_format.extra_dimension_names}
    tile = Tile(path, xyz, np.asarray(las.classification, np.uint8),
                np.asarray(las.return_number, np.uint8),
                np.asarray(las.number_of_returns, np.uint8), extra, crs_wkt(las),
                np.asarray(las.point_source_id, np.int64),
                np.asarray(las.gps_time, float) if "gps_time" in las.point_format.dimension_names
                else np.zeros(n), scan_angle(las), np.asarray(las.intensity, float))
    check_metric(tile)
    return tile


def check_metric(tile: Tile) -> None:
    """ConfigError when the tile's horizontal coordinates are in degrees (module text)."""
    if tile.crs is not None:
        from pyproj import CRS

        crs = CRS.from_wkt(tile.crs)
        if crs.is_geographic:
            raise ConfigError(f"the tile's CRS {crs.name!r} is geographic (x, y in degrees): "
                              "reproject it to a projected CRS in metres first, e.g. `pdal "
                              "translate in.laz out.laz reprojection "
                              "--filters.reprojection.out_srs=EPSG:32633`", source=tile.source)
        return
    lo, hi = tile.xyz.min(axis=0), tile.xyz.max(axis=0)
    span_xy = float(max(hi[0] - lo[0], hi[1] - lo[1]))
    looks_lonlat = (-180 <= lo[0] and hi[0] <= 180 and -90 <= lo[1] and hi[1] <= 90)
    if looks_lonlat and span_xy < 0.05 and (hi[2] - lo[2]) > 20 * span_xy:
        raise ConfigError(f"the tile has no CRS and its x, y span only {span_xy:.3g} units "
                          f"(x {lo[0]:.5f}…{hi[0]:.5f}, y {lo[1]:.5f}…{hi[1]:.5f}) while z "
                          f"spans {hi[2] - lo[2]:.1f}: x, y look like longitude/latitude in "
                          "degrees. Reproject it to a projected CRS in metres first (pdal "
                          "filters.reprojection, las2las -target_utm auto)", source=tile.source)
