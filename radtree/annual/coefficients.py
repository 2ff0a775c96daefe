"""Daylight coefficients with ``rcontrib``: sky patches, and suns for the direct-sun treatment.

One scene (a :class:`radtree.scene.Scene`) is written once as Radiance text; three kinds of
coefficients are computed for its sensor points (``rcontrib -I+``: irradiance at the points,
``-V+`` contributions divided by the source radiance: the response to a source of unit radiance):

1. **Sky** — a ``glow`` of unit radiance on a 360° ``source`` (sky and ground below the
   horizon), binned by ray direction into Reinhart patches with ``reinhartb.cal``
   (``-b rbin+1``: bin 0 = ground, as in ``gendaymtx``) at ``-ab N``: every path of sky
   light, inter-reflections included → ``(sensors, patches, 3)``.
2. **Direct sun** — one ``light`` of unit radiance per *hour's* sun, a 0.533° ``source``
   exactly where ``gendaymtx`` puts that hour's sun, ``-ab 0``: the sun seen straight through
   openings, glazing and the specular part of leaf transmission (shadow rays), nothing
   reflected → ``(sensors, suns, 3)``. This is the LM-83 "direct sunlight".
3. **Sun patches** — one unit sun at the centre of every Reinhart patch (subdivision
   ``sun_mf``) the sun visits, computed twice, ``-ab N`` and ``-ab 0``. Their difference is the
   *inter-reflected* sunlight (sun → ground, façades, slats, room surfaces → sensor) of a sun
   in that patch.

The direct part is computed with ``-dj 0 -dc 1 -dt 0``: deterministic shadow rays to every
source, so the ``-ab 0`` part of a sun-patch coefficient is exactly the one inside its
``-ab N`` value and the difference of (3) holds no Monte Carlo noise from the direct term.
"""

from __future__ import annotations

import hashlib
import logging
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from radtree.annual.skymatrix import patch_count
from radtree.engines.radiance.binaries import FIXED_SEED, run
from radtree.engines.radiance.materials import material_text
from radtree.engines.radiance.writer import mesh_to_radiance
from radtree.errors import EngineError
from radtree.fileio import atomic_path, write_text
from radtree.light.sun import SUN_ANGLE_DEG
from radtree.optics import Hole, Plastic, with_reflectance
from radtree.scene import Scene

log = logging.getLogger(__name__)

SUN_UNIT = 1e6
SKY_TEXT = ("# unit-radiance sky and ground: rcontrib bins it into Reinhart patches\n"
            "void glow skyglow\n0\n0\n4 1 1 1 0\n\n"
            "skyglow source skyball\n0\n0\n4 0 0 1 360\n")


@dataclass(frozen=True)
class TraceParams:
    """rcontrib settings of the indirect runs (``-ab``, ``-ad``, ``-lw``) and processes.

    The runs sample with :data:`~radtree.engines.radiance.binaries.FIXED_SEED`, and the
    points are split into ``nproc`` fixed chunks (one single-process ``rcontrib`` each), so the
    same ``nproc`` gives the same coefficients every time.

    ``replicates`` R > 1: every chunk's points are traced R times in a row. Under the fixed
    seed each ray of a run gets its own sample sequence (Radiance indexes its correlated
    samples by the ray's number), so the R passes are R independent estimates of every
    coefficient at ``-ad``; their mean has the noise of one run at about R × ``-ad`` and
    their spread measures it (:mod:`radtree.annual.uncertainty`). ``-ab 0`` runs (no Monte
    Carlo part with ``-dj 0``) are traced once whatever R."""

    ab: int
    ad: int
    lw: float
    nproc: int = 1
    replicates: int = 1

    def ambient(self, ab: int | None = None) -> list[str]:
        use_ab = self.ab if ab is None else ab
        return [FIXED_SEED, "-ab", str(use_ab), "-ad", str(self.ad), "-lw", f"{self.lw:g}", "-aa", "0"]

    def key(self) -> str:
        rep = f"_r{self.replicates}" if self.replicates > 1 else ""
        return f"u-_ab{self.ab}_ad{self.ad}_lw{self.lw:g}{rep}"


def scene_text(scene: Scene, ground_reflectance: float | None) -> str:
    """All materials and solid meshes of ``scene`` as one Radiance file."""
    parts = ["# radtree annual: scene geometry and materials\n"]
    for name, m in scene.materials.items():
        if isinstance(m, Hole):
            continue
        if name == scene.ground_material and isinstance(m, Plastic) and \
                ground_reflectance is not None:
            m = with_reflectance(m, ground_reflectance)
        parts.append(material_text(m))
    for mesh in scene.solid_meshes():
        parts.append(mesh_to_radiance(mesh))
    return "\n".join(parts)


def points_text(scene: Scene, grids: list[str]) -> str:
    return "".join(scene.grids[g].to_pts() for g in grids)


def sun_sources_text(directions: np.ndarray, prefix: str = "sun") -> tuple[str, list[str]]:
    """0.533° suns of radiance :data:`SUN_UNIT`, one modifier each (text, modifiers).

    Radiance skips a source whose contribution at a surface is below its ``FTINY`` (1e-6):
    a unit-radiance 0.533° sun (6.8e-5 sr) lighting a surface at a grazing angle would be
    dropped (seen here: the ground-reflected sun vanished below ≈ 13° sun altitude). Hence
    the 1e6 of Radiance's five-phase recipe, with ``rcontrib -V+`` (contributions, divided by
    1e6 afterwards): ``-V-`` coefficients are traced at unit value and hit the same cut."""
    out, mods = [], []
    for i, d in enumerate(np.asarray(directions, float).reshape(-1, 3)):
        mod = f"{prefix}{i}"
        mods.append(mod)
        out.append(f"void light {mod}\n0\n0\n3 {SUN_UNIT:g} {SUN_UNIT:g} {SUN_UNIT:g}\n\n"
                   f"{mod} source {prefix}_src{i}\n0\n0\n"
                   f"4 {d[0]:.6f} {d[1]:.6f} {d[2]:.6f} {SUN_ANGLE_DEG}\n")
    return "\n".join(out), mods


def _digest(*parts: str) -> str:
    h = hashlib.sha256()
    for p in parts:
        h.update(p.encode())
        h.update(b"\0")
    return h.hexdigest()[:16]


class CoefficientRunner:
    """Writes a scene once and computes its coefficients, caching each result by content."""

    def __init__(self, scene: Scene, grids: list[str], folder: Path,
                 ground_reflectance: float | None):
        self.scene = scene
        self.grids = list(grids)
        self.folder = folder.resolve()
        self.folder.mkdir(parents=True, exist_ok=True)
        self.scene_rad = self.folder / "scene.rad"
        text = scene_text(scene, ground_reflectance)
        if not self.scene_rad.exists() or self.scene_rad.read_text() != text:
            write_text(self.scene_rad, text)
        self.pts_text = points_text(scene, self.grids)
        self.n_sensors = sum(len(scene.grids[g]) for g in self.grids)
        self.scene_key = _digest(text, self.pts_text)

    # -------------------------------------------------------------- helpers
    def _octree(self, name: str, light_text: str) -> Path:
        light = self.folder / f"{name}.rad"
        write_text(light, light_text)
        octree = self.folder / f"{name}.oct"
        with atomic_path(octree) as tmp:
            run(["oconv", str(self.scene_rad), str(light)], stdout_path=tmp)
        return octree

    def _rcontrib(self, argv: list[str], octree: Path, ncols: int, scale: float = 1.0, *,
                  nproc: int = 1, replicates: int = 1) -> np.ndarray:
        """(replicates, sensors, ncols, 3): ``rcontrib`` over the sensor points, in ``nproc``
        contiguous chunks of points, one single-process ``rcontrib`` each, run side by side:
        unlike ``rcontrib -n`` (whose children take rays as they come free, so each draws a
        different sample sequence from run to run) the same ``nproc`` gives the same
        coefficients every time. Each chunk's points are sent ``replicates`` times in a row
        (:class:`TraceParams`)."""
        cmd = ["rcontrib", "-I+", "-h-", "-faf", "-V+", "-dj", "0", "-dc", "1", "-dt", "0",
               *argv, str(octree)]
        lines = self.pts_text.splitlines(keepends=True)
        bounds = np.linspace(0, len(lines), max(1, min(nproc, len(lines))) + 1).astype(int)
        chunks = ["".join(lines[a:b]).encode() * replicates
                  for a, b in zip(bounds[:-1], bounds[1:])]
        with ThreadPoolExecutor(max_workers=len(chunks)) as pool:
            parts = list(pool.map(lambda text: run(cmd, stdin=text, cwd=self.folder), chunks))
        expected = self.n_sensors * ncols * 3 * replicates
        got = sum(len(p) for p in parts) // 4
        if got != expected:
            raise EngineError(f"rcontrib gave {got} values, expected {expected}", command=cmd)
        per_chunk = [np.frombuffer(p, dtype=np.float32).reshape(replicates, -1, ncols, 3)
                     for p in parts]
        a = np.concatenate(per_chunk, axis=1)
        return (a / np.float32(scale)).astype(np.float32)

    def _cached(self, kind: str, key: str, compute) -> np.ndarray:
        path = self.folder / f"{kind}_{_digest(self.scene_key, key)}.npy"
        if path.exists():
            value = np.load(path)
            return value[None] if value.ndim == 3 else value  # cached before replicates
        value = compute()
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                np.save(fh, value)
        return value

    # -------------------------------------------------------------- coefficients
    def sky(self, mf: int, params: TraceParams) -> np.ndarray:
        """(sensors, patches, 3) sky coefficients at ``-ab N`` (the replicates' mean)."""
        return self.sky_replicates(mf, params).mean(axis=0)

    def sky_replicates(self, mf: int, params: TraceParams) -> np.ndarray:
        """(replicates, sensors, patches, 3) sky coefficients at ``-ab N``, one estimate per
        replicate of ``params``."""
        n = patch_count(mf)

        def compute() -> np.ndarray:
            log.info(f"    rcontrib sky MF {mf} ({n} patches), {params.key()}")
            octree = self._octree("sky", SKY_TEXT)
            argv = [*params.ambient(), "-f", "reinhartb.cal", "-e", f"MF:{mf}", "-b",
                    "rbin+1", "-bn", "Nrbins+1", "-m", "skyglow"]
            return self._rcontrib(argv, octree, n, nproc=params.nproc,
                                  replicates=params.replicates)

        return self._cached("sky", f"mf{mf}_{params.key()}", compute)

    def suns(self, name: str, directions: np.ndarray, ab: int, params: TraceParams
             ) -> np.ndarray:
        """(sensors, suns, 3) coefficients of unit suns at ``directions`` at ``-ab ab`` (the
        replicates' mean)."""
        return self.suns_replicates(name, directions, ab, params).mean(axis=0)

    def suns_replicates(self, name: str, directions: np.ndarray, ab: int,
                        params: TraceParams) -> np.ndarray:
        """(replicates, sensors, suns, 3) coefficients of unit suns at ``directions`` at
        ``-ab ab``; one replicate at ``-ab 0`` (deterministic)."""
        directions = np.asarray(directions, float).reshape(-1, 3)
        reps = params.replicates if ab else 1
        if len(directions) == 0:
            return np.zeros((reps, self.n_sensors, 0, 3), np.float32)
        text, mods = sun_sources_text(directions)
        key = f"{name}_ab{ab}_{params.key() if ab else 'direct'}_" + _digest(text)

        def compute() -> np.ndarray:
            log.info(f"    rcontrib {name}: {len(mods)} suns, -ab {ab}")
            octree = self._octree(f"suns_{name}", text)
            modfile = self.folder / f"suns_{name}.mod"
            write_text(modfile, "\n".join(mods) + "\n")
            argv = [*params.ambient(ab), "-M", str(modfile)]
            return self._rcontrib(argv, octree, len(mods), SUN_UNIT, nproc=params.nproc,
                                  replicates=reps)

        return self._cached(f"sun_{name}", key, compute)
