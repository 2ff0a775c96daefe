"""Airborne beams from the file alone: each return's beam from its scan angle and flight line.

A user's ``[tree] points`` file from an airborne tile carries no flight geometry in the
project, but LAS records, for every return, its scan angle θ (degrees from nadir, across the
flight line, :attr:`radtree.lidar.tile.Tile.scan_angle_deg`) and its flight line (the point
source id). A line-scanning sensor (oscillating mirror or rotating polygon; the synthetic
scanner of :mod:`radtree.lidar.scanner`) fires in the vertical plane across its line, so on
one line a return at height z lies (A − z)·tan θ across from the nadir track, A the flight
altitude. A least-squares plane tan θ ≈ a·x + b·y + c over the line's returns gives the
across-track direction u = (a, b)/|(a, b)| (towards growing θ: the sign convention of the file
does not matter); then u·(x, y) + z·tan θ = c' + A·tan θ, linear in the track's offset c' and
A, gives the altitude. Each beam runs down along (u·sin θ, −cos θ) and its origin is the
return minus (A − z)/cos θ along it (``origins`` of
:func:`radtree.lidar.voxels.tree_voxels`, the beams followed voxel by voxel as in
:mod:`radtree.lidar.beams`).

Not derivable (None, the inversion stays in vertical columns) when the file has no scan angles
(all zero), when a line spans less than :data:`MIN_SPREAD_DEG` of scan angle (a whole-degree
``scan_angle_rank`` over one tree; H is then undetermined) or when the fit leaves residuals
over :data:`MAX_RESIDUAL_DEG` (angles that are not across-track: roll not compensated,
elliptical/Palmer scanners whose beams tilt forward and back, see the ASPRS LAS issue
"Add explanation of Scan Angle Rank", github.com/ASPRSorg/LAS/issues/41). Returns whose flight
line has fewer than :data:`MIN_LINE_POINTS` returns keep a vertical beam through their xy.
"""

from __future__ import annotations

import math

import numpy as np

from radtree.lidar.tile import Tile

#: a line's scan angles must span this much (degrees) for H to be fitted
MIN_SPREAD_DEG = 0.2
#: the fit's RMS residual (degrees) above which the angles are not taken as across-track
MAX_RESIDUAL_DEG = 0.1
#: fewer returns on a line: their beams stay vertical
MIN_LINE_POINTS = 20
#: flight heights (m above the returns) outside this range are taken as a failed fit
HEIGHT_RANGE_M = (20.0, 10000.0)


def line_geometry(xyz: np.ndarray, angle_deg: np.ndarray) -> tuple[np.ndarray, float] | None:
    """(across-track unit vector u (2,), flight altitude A m in the tile's z) of one line's
    returns (module text), or None when not derivable."""
    if len(xyz) < MIN_LINE_POINTS or np.ptp(angle_deg) < MIN_SPREAD_DEG:
        return None
    t = np.tan(np.radians(angle_deg))
    xy = xyz[:, :2] - xyz[:, :2].mean(axis=0)
    one = np.ones(len(xy))
    grad = np.linalg.lstsq(np.column_stack([xy, one]), t, rcond=None)[0][:2]
    norm = float(np.hypot(*grad))
    if norm <= 0.0:
        return None
    u = grad / norm
    # u·xy + z·tan θ = c + A·tan θ: the track's offset c and the altitude A
    lhs = xy @ u + xyz[:, 2] * t
    (c, alt), *_ = np.linalg.lstsq(np.column_stack([one, t]), lhs, rcond=None)
    above = alt - xyz[:, 2]
    if not (HEIGHT_RANGE_M[0] <= above.min() and above.max() <= HEIGHT_RANGE_M[1]):
        return None
    resid = np.degrees((lhs - c - alt * t) / above)
    if float(np.sqrt(np.mean(resid**2))) > MAX_RESIDUAL_DEG:
        return None
    return u, float(alt)


def scan_angle_origins(tile: Tile) -> np.ndarray | None:
    """Where each return's beam was fired ((n, 3), the tile's coordinates) from its scan
    angle and flight line (module text); None when no line's geometry is derivable."""
    angle = tile.scan_angle_deg
    if angle is None or not np.any(angle):
        return None
    lines = tile.source_id if tile.source_id is not None else np.zeros(len(tile), np.int64)
    origins = tile.xyz + [0.0, 0.0, HEIGHT_RANGE_M[1]]      # vertical, far above
    found = False
    for line in np.unique(lines):
        sel = lines == line
        geo = line_geometry(tile.xyz[sel], angle[sel])
        if geo is None:
            continue
        u, alt = geo
        th = np.radians(angle[sel])
        down = np.column_stack([np.sin(th)[:, None] * u[None, :], -np.cos(th)])
        reach = (alt - tile.xyz[sel, 2]) / np.cos(th)          # m along the beam
        origins[sel] = tile.xyz[sel] - reach[:, None] * down
        found = True
    return origins if found else None


def describe(tile: Tile) -> str:
    """One line on the beams' geometry of ``tile`` (for notes): lines, heights, angles."""
    angle = tile.scan_angle_deg
    if angle is None or not np.any(angle):
        return "no scan angles in the file"
    lines = tile.source_id if tile.source_id is not None else np.zeros(len(tile), np.int64)
    parts = []
    for line in np.unique(lines):
        sel = lines == line
        geo = line_geometry(tile.xyz[sel], angle[sel])
        if geo is not None:
            parts.append(f"line {int(line)}: altitude {geo[1]:.0f} m, across-track "
                         f"{math.degrees(math.atan2(geo[0][0], geo[0][1])):.0f}°")
    return "; ".join(parts) or "scan angles not across-track fittable"
