"""A synthetic terrestrial laser scanner: shots on an angular grid from one position → LAS points.

For round trips (scan radtree's own crowns from the ground, rebuild their leaf area, compare).
The scanner stands at (``x_m``, ``y_m``, ``z_m``) (metres, x east, y north, z up) and fires one
shot per cell of an angular grid: zenith angles θ_j = ``zenith_min_deg`` + (j + ½)·``step_deg``
up to ``zenith_max_deg`` (0° straight up), azimuths φ_i = ``azimuth_min_deg`` + (i + ½)·
``step_deg`` up to ``azimuth_max_deg`` (clockwise from north), direction (sin θ sin φ,
sin θ cos φ, cos θ). Shots are fired column by column (the head turns in azimuth, the mirror
sweeps the zenith), shot index i·n_θ + j, emitted at time index / ``PULSE_RATE_HZ`` (LAS
``gps_time``), so a reader can tell which shots came back and which went to the sky
(:meth:`TlsScan.empty_shots`).

Beam divergence: a shot is ``footprint_rays`` sub-rays from the scanner centre, directions
uniform in a cone of full angle ``beam_divergence_mrad`` (the footprint grows as range ×
divergence; the exit aperture is neglected; 0.35 mrad is e.g. the RIEGL VZ-400's). Each sub-ray
stops at the first surface; hits are grouped into echoes by range (a new echo at a jump of at
least ``range_resolution_m``; :func:`radtree.lidar.scanner.echoes`) and the shot records
``returns``: ``"first"``, ``"last"``, ``"first_last"`` (both when they differ) or ``"all"``.
Ranges beyond ``max_range_m`` give no return. With one sub-ray (``footprint_rays`` 1) a shot
has one return at most: the first surface along a thin beam.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import ClassVar

import numpy as np

from radtree.config.spec import Checked, meta
from radtree.lidar.scanner import PULSE_RATE_HZ, ScanPoints, echoes
from radtree.lidar.tile import Tile

RETURNS = ("first", "last", "first_last", "all")


@dataclass(frozen=True)
class TlsScan(Checked):
    """One terrestrial scan position (module text): metres and degrees."""

    TABLE: ClassVar[str] = "tls"
    x_m: float = 0.0
    y_m: float = 0.0
    z_m: float = field(default=1.5, metadata=meta(-1000.0, 10000.0))
    step_deg: float = field(default=0.1, metadata=meta(0.001, 10.0))
    zenith_min_deg: float = field(default=0.0, metadata=meta(0.0, 180.0))
    zenith_max_deg: float = field(default=130.0, metadata=meta(0.0, 180.0))
    azimuth_min_deg: float = field(default=0.0, metadata=meta(-360.0, 360.0))
    azimuth_max_deg: float = field(default=360.0, metadata=meta(-360.0, 720.0))
    beam_divergence_mrad: float = field(default=0.35, metadata=meta(0.0, 10.0))
    footprint_rays: int = field(default=1, metadata=meta(1, 64))
    range_resolution_m: float = field(default=0.8, metadata=meta(0.0, 100.0))
    max_range_m: float = field(default=300.0, metadata=meta(1.0, 10000.0))
    returns: str = field(default="first_last", metadata=meta(choices=RETURNS))
    position_id: int = field(default=0, metadata=meta(0, 65535))
    seed: int = 0

    @property
    def position(self) -> np.ndarray:
        return np.array([self.x_m, self.y_m, self.z_m])

    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Zenith and azimuth angles (degrees) of the shot grid's rows and columns."""
        nz = max(1, int(round((self.zenith_max_deg - self.zenith_min_deg) / self.step_deg)))
        na = max(1, int(round((self.azimuth_max_deg - self.azimuth_min_deg) / self.step_deg)))
        return (self.zenith_min_deg + (np.arange(nz) + 0.5) * self.step_deg,
                self.azimuth_min_deg + (np.arange(na) + 0.5) * self.step_deg)

    def directions(self) -> np.ndarray:
        """Unit directions (n, 3) of every shot, in shot order (column by column)."""
        zen, az = self.grid()
        t, p = np.meshgrid(np.radians(zen), np.radians(az))   # [azimuth, zenith]
        t, p = t.ravel(), p.ravel()
        return np.column_stack([np.sin(t) * np.sin(p), np.sin(t) * np.cos(p), np.cos(t)])

    def empty_shots(self, time_s: np.ndarray) -> np.ndarray:
        """Directions of the shots with no return among the points' emission times (s)."""
        d = self.directions()
        got = np.zeros(len(d), bool)
        idx = np.round(np.asarray(time_s, float) * PULSE_RATE_HZ).astype(np.int64)
        got[idx[(idx >= 0) & (idx < len(d))]] = True
        return d[~got]


def _sub_rays(d: np.ndarray, *, scan: TlsScan, rng: np.random.Generator) -> np.ndarray:
    """``footprint_rays`` directions per shot, uniform in the divergence cone (n·m, 3)."""
    m = scan.footprint_rays
    if m == 1:
        return d
    half = 0.5 * scan.beam_divergence_mrad / 1000.0
    cos_t = 1.0 - rng.random((len(d), m)) * (1.0 - math.cos(half))   # uniform in solid angle
    sin_t = np.sqrt(1.0 - cos_t**2)
    phi = rng.uniform(0.0, 2.0 * math.pi, (len(d), m))
    helper = np.where(np.abs(d[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    e1 = np.cross(d, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(d, e1)
    out = (cos_t[..., None] * d[:, None, :] + (sin_t * np.cos(phi))[..., None] * e1[:, None, :]
           + (sin_t * np.sin(phi))[..., None] * e2[:, None, :])
    return out.reshape(-1, 3)


def scan_tls(vertices: np.ndarray, *, faces: np.ndarray, face_class: np.ndarray,
             scan: TlsScan) -> ScanPoints:
    """Scan the triangles (``face_class``: ASPRS class of each face) from ``scan``'s position
    (module text); the points' ``line`` is the scan's ``position_id``."""
    import trimesh

    mesh = trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces, np.int64),
                           process=False)
    rng = np.random.default_rng(scan.seed)
    d = scan.directions()
    dirs = _sub_rays(d, scan=scan, rng=rng)
    m = scan.footprint_rays
    origins = np.broadcast_to(scan.position, dirs.shape)
    loc, ray, tri = mesh.ray.intersects_location(origins, dirs, multiple_hits=False)
    dist = np.einsum("ij,ij->i", loc - scan.position, dirs[ray])
    near = dist <= scan.max_range_m
    loc, ray, tri, dist = loc[near], ray[near], tri[near], dist[near]
    xyz, cls, number, total, shot, _ = echoes(loc, pulse=ray // m, dist=dist, tri=tri,
                                              face_class=face_class, pulses=len(d),
                                              resolution_m=scan.range_resolution_m, rays=m)
    last = number == total
    keep = {"first": number == 1, "last": last, "first_last": (number == 1) | last,
            "all": np.ones(len(number), bool)}[scan.returns]
    xyz, cls, number, total, shot = xyz[keep], cls[keep], number[keep], total[keep], shot[keep]
    # renumber the recorded returns 1…k per shot
    n_kept = np.bincount(shot, minlength=len(d))
    first = np.ones(len(shot), bool)
    first[1:] = shot[1:] != shot[:-1]
    idx = np.arange(len(shot))
    number = idx - np.maximum.accumulate(np.where(first, idx, 0)) + 1
    return ScanPoints(xyz, cls, number.astype(np.uint8), n_kept[shot].astype(np.uint8),
                      np.full(len(shot), scan.position_id), shot / PULSE_RATE_HZ)


def merge_scans(scans: list[ScanPoints]) -> ScanPoints:
    """Several scan positions' points in one cloud (each keeps its position id and times)."""
    return ScanPoints(*(np.concatenate([getattr(s, f) for s in scans]) for f in (
        "xyz", "classification", "return_number", "number_of_returns", "line", "time")))


def tls_beams(scans: list[TlsScan]) -> dict:
    """The ``origins`` and ``empty`` arguments of :func:`radtree.lidar.voxels.tree_voxels` for
    a cloud of these scan positions (points told apart by their position id, LAS point
    source id; shots by their emission time, LAS GPS time). A shot whose return was clipped
    out of the file counts as empty: right when its return lay beyond the tree's grid."""
    table = np.zeros((max(s.position_id for s in scans) + 1, 3))
    for s in scans:
        table[s.position_id] = s.position

    def origins(tile: Tile) -> np.ndarray:
        return table[np.asarray(tile.source_id, np.int64)]

    def empty(tile: Tile) -> tuple[np.ndarray, np.ndarray]:
        ids = np.asarray(tile.source_id, np.int64)
        times = np.asarray(tile.gps_time, float)
        dirs = [s.empty_shots(times[ids == s.position_id]) for s in scans]
        orig = [np.broadcast_to(s.position, d.shape) for s, d in zip(scans, dirs)]
        return np.vstack(orig), np.vstack(dirs)

    return {"origins": origins, "empty": empty}


def write_scans(path: str | Path, scans: list[TlsScan]) -> Path:
    """The scan positions as TOML, one ``[[scan]]`` table each (what ``tree.points_scans``
    reads: :func:`read_scans`)."""
    from radtree.fileio import write_text
    from radtree.tomlout import dumps

    rows = [{f.name: getattr(s, f.name) for f in fields(s)} for s in scans]
    write_text(Path(path), dumps({"scan": rows}, header="# terrestrial scan positions "
                                 "(radtree.lidar.tls): metres, degrees"))
    return Path(path)


def read_scans(path: str | Path) -> list[TlsScan]:
    """The ``[[scan]]`` tables of ``path`` (TOML, fields of :class:`TlsScan`); ConfigError
    naming the file, the field and the fix."""
    import tomllib

    from radtree.config.spec import SchemaError
    from radtree.errors import ConfigError

    src = str(path)
    try:
        data = tomllib.loads(Path(path).read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"cannot read the scan positions ({exc}): a TOML file of [[scan]] "
                          "tables (x_m, y_m, z_m, step_deg, …)", source=src) from None
    tables = data.get("scan")
    if not isinstance(tables, list) or not tables:
        raise ConfigError("no [[scan]] table: give one per scan position (x_m, y_m, z_m, "
                          "step_deg, zenith_min_deg, …, position_id)", source=src)
    known = {f.name for f in fields(TlsScan)}
    out = []
    for i, t in enumerate(tables):
        unknown = sorted(set(t) - known)
        if unknown:
            raise ConfigError(f"scan {i + 1}: unknown field {unknown[0]!r} (known: "
                              f"{', '.join(sorted(known))})", source=src, field="scan")
        try:
            out.append(TlsScan(**t))
        except SchemaError as exc:
            raise ConfigError(f"scan {i + 1}: {exc.detail}", source=src, field=exc.key) from None
    ids = [s.position_id for s in out]
    if len(set(ids)) != len(ids):
        raise ConfigError(f"position_id {ids}: each scan needs its own (the LAS point source id "
                          "of its points)", source=src, field="tls.position_id")
    return out
