"""Sky and sun of every hour of the year, from an EPW through ``epw2wea`` and ``gendaymtx``.

* :func:`epw_to_wea` — ``epw2wea`` turns the EPW into a WEA weather tape: one row per hour,
  ``month day hour dni dhi`` with the hour at the *middle* of the EPW interval (EPW hour 13 →
  12.5) and irradiances in W/m² (``weather_data_file_units 1``).
* :func:`sky_matrix` — ``gendaymtx -s -m MF -O0 -c 1 1 1 -g ρ ρ ρ``: the Perez all-weather
  **sky without the sun** for all 8760 hours, as visible radiance (W sr⁻¹ m⁻², ×179 = cd/m²)
  per Reinhart patch: row 0 is the ground (ρ·E_global/π), rows 1… the sky patches of
  subdivision MF (145·MF² patches), night hours are zero. White sky (``-c 1 1 1``) as in the
  point-in-time ``gendaylit`` skies.
* :func:`sun_positions` — ``gendaymtx -n -D``: the sun of every hour in which any part of
  it is above the horizon, as gendaymtx places it (Radiance's solar position at the WEA
  time, site from the WEA header) with its visible radiance for a 0.533° disc (Perez
  luminous efficacy of the hour's DNI).

Patch numbering (:func:`reinhart_bins`, :func:`reinhart_directions`) follows Radiance's
``reinhart.cal``/``reinsrc.cal`` (0 = ground, then rows from the horizon up, each row
starting at north and running east, i.e. clockwise seen from above with +Y north).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from radtree.engines.radiance.binaries import run
from radtree.errors import ConfigError, EngineError

HOURS_PER_YEAR = 8760
_TNAZ = (30, 30, 24, 24, 18, 12, 6)


# ---------------------------------------------------------------- WEA
@dataclass
class Wea:
    """A WEA weather tape: site header and hourly rows (irradiances W/m²)."""

    path: Path
    place: str
    latitude: float
    longitude_west: float  # Radiance convention: degrees west positive
    meridian_west: float
    elevation_m: float
    month: np.ndarray
    day: np.ndarray
    hour: np.ndarray  # decimal local standard time (middle of the hour)
    dni: np.ndarray
    dhi: np.ndarray

    @property
    def n_hours(self) -> int:
        return int(len(self.month))

    def day_of_year(self) -> np.ndarray:
        """Day of a non-leap year, 1…365 (as gendaymtx numbers its sun minutes)."""
        starts = np.cumsum([0, 31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30])
        return starts[self.month - 1] + self.day

    def minute_index(self) -> np.ndarray:
        """Minutes since 1 January 00:00 (gendaymtx's sun names)."""
        return (self.day_of_year() - 1) * 1440 + np.rint(self.hour * 60.0).astype(int)


def read_wea(path: Path) -> Wea:
    """Parse a WEA file (6 header lines, then ``month day hour dni dhi``)."""
    try:
        lines = Path(path).read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as exc:
        raise ConfigError(f"cannot read WEA file {path}: {exc}") from exc
    head: dict[str, str] = {}
    body: list[str] = []
    for line in lines:
        parts = line.split(None, 1)
        if not parts:
            continue
        if parts[0] in ("place", "latitude", "longitude", "time_zone", "site_elevation",
                        "weather_data_file_units"):
            head[parts[0]] = parts[1].strip() if len(parts) > 1 else ""
        else:
            body.append(line)
    try:
        data = np.loadtxt(body, ndmin=2) if body else np.zeros((0, 5))
        lat, lon = float(head["latitude"]), float(head["longitude"])
        mer, elev = float(head["time_zone"]), float(head.get("site_elevation", "0"))
    except (KeyError, ValueError) as exc:
        raise ConfigError(f"{path} is not a readable WEA file: {exc}") from exc
    if head.get("weather_data_file_units", "1") != "1":
        raise ConfigError(f"{path}: weather_data_file_units must be 1 (W/m²)")
    if data.shape[1] < 5:
        raise ConfigError(f"{path}: expected 'month day hour dni dhi' rows")
    return Wea(path=Path(path), place=head.get("place", ""), latitude=lat, longitude_west=lon,
               meridian_west=mer, elevation_m=elev, month=data[:, 0].astype(int),
               day=data[:, 1].astype(int), hour=data[:, 2].astype(float),
               dni=data[:, 3].astype(float), dhi=data[:, 4].astype(float))


def epw_to_wea(epw: Path, wea: Path) -> Wea:
    """``epw2wea EPW WEA``; the result must hold the 8760 hours of a year."""
    wea.parent.mkdir(parents=True, exist_ok=True)
    run(["epw2wea", str(epw), str(wea)])
    w = read_wea(wea)
    if w.n_hours != HOURS_PER_YEAR:
        raise ConfigError(f"{epw}: {w.n_hours} hourly rows, expected {HOURS_PER_YEAR} "
                          "(a full non-leap year)")
    return w


# ---------------------------------------------------------------- Reinhart patches
def patch_count(mf: int) -> int:
    """Rows of a gendaymtx matrix for subdivision ``mf``: ground + 145·mf² sky patches."""
    return 1 + sum(_rnaz(r, mf) for r in range(7 * mf + 1))


def _rnaz(r: int, mf: int) -> int:
    if r > 7 * mf - 0.5:
        return 1
    return mf * _TNAZ[int(math.floor((r + 0.5) / mf))]


def reinhart_bins(dirs: np.ndarray, mf: int) -> np.ndarray:
    """Patch index (0 = ground) of unit directions (x east, y north, z up), as reinhart.cal."""
    d = np.atleast_2d(np.asarray(dirs, float))
    alt = np.degrees(np.arcsin(np.clip(d[:, 2], -1.0, 1.0)))
    azi = np.degrees(np.arctan2(d[:, 0], d[:, 1])) % 360.0
    alpha = 90.0 / (mf * 7 + 0.5)
    nrows = 7 * mf + 1
    naz = np.array([_rnaz(r, mf) for r in range(nrows)])
    accum = np.concatenate([[0], np.cumsum(naz)])
    row = np.clip(np.floor(alt / alpha).astype(int), 0, nrows - 1)
    inc = 360.0 / naz[row]
    azn = np.where(359.9999 - 0.5 * inc - azi > 0, np.floor((azi + 0.5 * inc) / inc), 0)
    return np.where(alt > 0, accum[row] + azn.astype(int) + 1, 0)


def reinhart_directions(mf: int) -> np.ndarray:
    """Centre direction of every patch (index 0 = ground, straight down), as reinsrc.cal."""
    alpha = math.radians(90.0 / (mf * 7 + 0.5))
    out = [np.array([0.0, 0.0, -1.0])]
    for r in range(7 * mf + 1):
        n = _rnaz(r, mf)
        alt = (r + 0.5) * alpha if r < 7 * mf else math.pi / 2
        for c in range(n):
            azi = c * 2 * math.pi / n if n > 1 else 0.0
            out.append(np.array([math.sin(azi) * math.cos(alt), math.cos(azi) * math.cos(alt),
                                 math.sin(alt)]))
    return np.array(out)


# ---------------------------------------------------------------- gendaymtx
def _read_matrix(data: bytes, what: str) -> tuple[dict[str, str], np.ndarray]:
    """A Radiance matrix with a header and binary float body."""
    end = data.find(b"\n\n")
    if end < 0:
        raise EngineError(f"{what}: no header end in the output")
    head = {}
    for line in data[:end].decode(errors="replace").splitlines():
        if "=" in line:
            k, _, v = line.partition("=")
            head[k.strip()] = v.strip()
    body = np.frombuffer(data[end + 2:], dtype="<f4" if head.get("BigEndian", "0") == "0"
                         else ">f4")
    try:
        shape = (int(head["NROWS"]), int(head["NCOLS"]), int(head.get("NCOMP", "3")))
    except (KeyError, ValueError) as exc:
        raise EngineError(f"{what}: malformed matrix header {head}") from exc
    if body.size != shape[0] * shape[1] * shape[2]:
        raise EngineError(f"{what}: {body.size} values, expected {shape}")
    return head, body.reshape(shape)


def sky_matrix_command(wea: Path, mf: int, ground_reflectance: float) -> list[str]:
    g = f"{ground_reflectance:.4f}"
    return ["gendaymtx", "-s", "-m", str(mf), "-O0", "-c", "1", "1", "1", "-g", g, g, g, "-of",
            str(wea)]


def sky_matrix(wea: Wea, mf: int, ground_reflectance: float) -> np.ndarray:
    """Sky-only matrix (patches, hours, 3) of visible radiance, float32."""
    cmd = sky_matrix_command(wea.path, mf, ground_reflectance)
    _, m = _read_matrix(run(cmd), "gendaymtx")
    if m.shape[0] != patch_count(mf) or m.shape[1] != wea.n_hours:
        raise EngineError(f"gendaymtx gave a {m.shape} matrix, expected "
                          f"({patch_count(mf)}, {wea.n_hours}, 3)", command=cmd)
    return np.ascontiguousarray(m)


@dataclass
class Suns:
    """One sun per hour with any part of the disc above the horizon (gendaymtx ``-D``)."""

    hour_index: np.ndarray  # (k,) index into the year's hours
    direction: np.ndarray  # (k, 3) unit vectors towards the sun, x east, y north, z up
    radiance: np.ndarray  # (k,) visible radiance of the 0.533° disc, W sr⁻¹ m⁻²

    def __len__(self) -> int:
        return int(len(self.hour_index))

    def subset(self, mask: np.ndarray) -> Suns:
        return Suns(self.hour_index[mask], self.direction[mask], self.radiance[mask])


_SUN_RE = re.compile(
    r"void\s+light\s+solar(\d+)\s+0\s+0\s+3\s+(\S+)\s+\S+\s+\S+\s+"
    r"solar\1\s+source\s+\S+\s+0\s+0\s+4\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)")


def sun_positions(wea: Wea, workdir: Path) -> Suns:
    """Every hour's sun as gendaymtx places it (``gendaymtx -n -D``)."""
    workdir.mkdir(parents=True, exist_ok=True)
    out = workdir / "suns_gendaymtx.rad"
    run(["gendaymtx", "-n", "-O0", "-D", str(out), str(wea.path)])
    text = out.read_text()
    minutes = wea.minute_index()
    where = {int(m): i for i, m in enumerate(minutes)}
    idx, dirs, rad = [], [], []
    for m in _SUN_RE.finditer(text):
        minute = int(m.group(1))
        if minute not in where:
            raise EngineError(f"gendaymtx sun at minute {minute} matches no WEA row")
        idx.append(where[minute])
        rad.append(float(m.group(2)))
        dirs.append([float(m.group(3)), float(m.group(4)), float(m.group(5))])
    d = np.array(dirs, float).reshape(-1, 3)
    if len(d):
        d = d / np.linalg.norm(d, axis=1)[:, None]
    return Suns(np.array(idx, int), d, np.array(rad, float))


def sun_patch_weights(directions: np.ndarray, mf: int, chunk: int = 512
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Interpolation of every sun direction between Reinhart patch centres.

    The patch centres of subdivision ``mf`` (plus the nadir, index 0, whose coefficient is
    taken as zero) are triangulated on the sphere (their convex hull); a sun direction d is
    written as d = Σ wⱼ vⱼ over the three corners of the triangle whose cone holds it. The
    weights reproduce exactly any quantity linear in the direction — the irradiance n·d of
    every sunlit plane — so a coefficient interpolated this way has no first-order error from
    the sun sitting off the patch centre (the nearest-patch error is ≈ 5 % for low suns with
    MF 2). Returns (k, 3) vertex indices into :func:`reinhart_directions` and (k, 3) weights.
    """
    from scipy.spatial import ConvexHull

    d = np.atleast_2d(np.asarray(directions, float))
    centres = reinhart_directions(mf)
    tri = ConvexHull(centres).simplices
    inv = np.linalg.inv(centres[tri].transpose(0, 2, 1))  # (F, 3, 3): columns = corners
    verts = np.zeros((len(d), 3), int)
    weights = np.zeros((len(d), 3))
    for s in range(0, len(d), chunk):
        part = d[s:s + chunk]
        w = np.einsum("fij,kj->kfi", inv, part)
        ok = np.all(w >= -1e-9, axis=2)
        if not ok.any(axis=1).all():
            raise EngineError("a sun direction fell outside the patch triangulation")
        f = np.argmax(ok, axis=1)
        verts[s:s + chunk] = tri[f]
        weights[s:s + chunk] = w[np.arange(len(part)), f]
    return verts, weights
