"""The perforated crown: the envelope as an opaque sheet (leaf reflectance, T = 0) with holes
where a hemispherical photo shows sky.

The photo is taken from the façade at the sensors, looking out (lens axis horizontal = the
façade normal n). Its gaps are projected from that camera point onto the envelope: the envelope
is tessellated finely and every face whose directions (seen from the camera) are sky is left
out — a hole is an absent face. The gap pattern enters only as a **sky predicate**::

    is_sky(directions) -> bool array    # directions: (N, 3) unit vectors in the façade frame
                                         # (u along the façade, n out of it, z up)

so any source of gaps works: :func:`photo_gap_pattern` (a fisheye photo through
:mod:`radtree.hemi`) or, without a photo, :func:`random_gap_pattern` (seeded round gaps whose
union covers ``perforated.openness`` of the hemisphere's solid angle).

Face assignment: each face's sky fraction is sampled at 16 points; faces more than half sky
become holes, then boundary faces are flipped (most-sky first / least-sky first) until the
holes' solid angle seen from the camera equals the sampled sky solid angle to within one face.
So the hole solid-angle fraction equals the openness of the predicate up to the tessellation.

* Sensor dome: the camera point is the dome centre; the shell is a hemisphere of
  ``perforated.resolution`` polar rings (cells of 90°/resolution; ≈ 5.1·resolution²
  triangles before the holes are cut).
* Free-standing crowns: the camera point is the sensor circle's centre on the wall; the sheet is
  the crowns' envelope *without* its wall-side face (open towards the wall), so every line of
  sight from the camera through a crown crosses the sheet once, as the photo sees it (a second,
  wall-side sheet 5 mm in front of the lens would be a nonsense projection). The envelope is an
  icosphere of level round(log2(63.4·resolution/180)) (at most 5) per crown.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from radtree.config import Perforated, Sensors, Street, Tree
from radtree.errors import ConfigError
from radtree.optics import Plastic
from radtree.scene import Mesh
from radtree.site.frame import FacadeFrame
from radtree.trees.envelope import crown_row_spec, dome_notes, dome_spec, row_notes
from radtree.trees.geometry import fibonacci_hemisphere, triangle_solid_angles, unit
from radtree.trees.model import BARK_REFLECTANCE, SHELL, TRUNK, TreeModel
from radtree.trees.photo import (
    PhotoSource,
    analyse_photo,
    facade_sky,
    photo_source,
    provenance,
    require_direction,
    with_source,
)

SkyPredicate = Callable[[np.ndarray], np.ndarray]
OPENNESS_SAMPLES = 200_000
MAX_RESOLUTION = 256
DEFAULT_SEED = 1
PERFORATED_AB = 5  # ambient bounces: as the homogeneous shell (trees.homogeneous.MIN_AB: why)


@dataclass(frozen=True)
class GapPattern:
    """A sky predicate and its openness: the sky share of the solid angle of the hemisphere
    n ≥ 0 seen from the camera (measured on an equal-area spiral of 200 000 directions)."""

    is_sky: SkyPredicate
    openness: float
    source: str
    photo: Any = None   # the hemi analysis (HemiResult) of a photo pattern


def measure_openness(is_sky: SkyPredicate, samples: int = OPENNESS_SAMPLES) -> float:
    """Solid-angle share of the hemisphere n ≥ 0 that ``is_sky`` calls sky."""
    d = fibonacci_hemisphere(samples)
    return float(np.mean(_chunked(is_sky, d)))


def _chunked(is_sky: SkyPredicate, d: np.ndarray, chunk: int = 65536) -> np.ndarray:
    out = np.empty(len(d), bool)
    for i in range(0, len(d), chunk):
        out[i:i + chunk] = np.asarray(is_sky(d[i:i + chunk]), bool).reshape(-1)
    return out


@lru_cache(maxsize=8)
def random_gap_pattern(openness: float, seed: int = DEFAULT_SEED, gaps: int | None = None
                       ) -> GapPattern:
    """Seeded round sky gaps over the hemisphere n ≥ 0 covering ``openness`` of its solid angle.

    ``gaps`` (default max(6, 600·openness)) caps centred uniformly over the hemisphere, with
    relative sizes log-uniform over a factor 4; one common scale is chosen so that the union's
    solid-angle share equals ``openness`` exactly on the measuring sample.
    """
    if not 0.0 <= openness <= 1.0:
        raise ValueError(f"openness must be 0–1, got {openness}")
    if openness <= 0.0:
        return GapPattern(lambda d: np.zeros(len(d), bool), 0.0, "no gaps (openness 0)")
    if openness >= 1.0:
        return GapPattern(lambda d: np.ones(len(d), bool), 1.0, "all sky (openness 1)")
    rng = np.random.default_rng(seed)
    k = gaps or max(6, int(round(600 * openness)))
    cn = rng.uniform(0.0, 1.0, k)  # uniform pole component = uniform over the hemisphere
    phi = rng.uniform(0.0, 2.0 * math.pi, k)
    s = np.sqrt(1.0 - cn * cn)
    centres = np.column_stack([s * np.cos(phi), cn, s * np.sin(phi)])
    rel = np.exp(rng.uniform(math.log(0.5), math.log(2.0), k))

    def reach(d: np.ndarray) -> np.ndarray:
        cosang = np.clip(np.asarray(d, float) @ centres.T, -1.0, 1.0)
        return np.min(np.arccos(cosang) / rel, axis=1)

    sample = fibonacci_hemisphere(OPENNESS_SAMPLES)
    m = np.concatenate([reach(sample[i:i + 50000]) for i in range(0, len(sample), 50000)])
    scale = float(np.quantile(m, openness))

    cos_limit = np.cos(np.minimum(scale * rel, math.pi))

    def is_sky(d: np.ndarray) -> np.ndarray:
        return np.any(np.asarray(d, float) @ centres.T > cos_limit, axis=1)

    measured = float(np.mean(m < scale))
    radii = np.degrees(scale * rel)
    return GapPattern(is_sky, measured,
                      f"seeded random gap pattern (seed {seed}): {k} round gaps of "
                      f"{radii.min():.1f}–{radii.max():.1f}° radius, openness {measured:.4f}")


def photo_gap_pattern(perf: Perforated, source: str | None = None,
                      src: PhotoSource | None = None) -> GapPattern:
    """The sky predicate of the crown's façade photo (``[tree] photo`` as ``src``, else
    ``perforated.photo``): a horizontal-axis fisheye photo taken from the façade looking out,
    through :mod:`radtree.hemi` (:mod:`radtree.trees.photo`).

    Directions map to the photo's angles as (angle from the lens axis n, angle around it
    clockwise from up as seen looking out, 90° = +u). Photo analysis failures surface as one
    ConfigError naming the field; there is no silent fallback to a random pattern.
    """
    if src is None:
        if perf.photo is None:
            raise ConfigError("no photo given", source=source, field="tree.perforated.photo")
        src = PhotoSource(Path(perf.photo), perf.lens, perf.mask, "facade",
                          "tree.perforated.photo")
    try:
        require_direction(src, "facade", "the perforated crown")
        result = analyse_photo(src.path, src)
    except ConfigError as exc:
        raise with_source(exc, source) from None
    is_sky = facade_sky(result)
    openness = measure_openness(is_sky)
    return GapPattern(is_sky, openness,
                      f"photo {src.path.name} ({src.lens} lens, horizontal axis = façade "
                      f"normal): openness {openness:.4f} of the hemisphere "
                      f"(hemi's own figure {result.metrics.openness:.4f})", result)


def gap_pattern_for(perf: Perforated, source: str | None = None) -> GapPattern:
    """The photo's predicate if a photo is set, else the seeded random pattern of openness
    (``perforated.seed``)."""
    if perf.photo is not None:
        return photo_gap_pattern(perf, source)
    return random_gap_pattern(perf.openness, perf.seed)


# Barycentric centres of the 16 sub-triangles of a triangle split 4 × 4 (sampling points).
def _sub_centroids(level: int = 4) -> np.ndarray:
    pts = []
    for i in range(level):
        for j in range(level - i):
            # upward triangle
            pts.append(((i + 1 / 3), (j + 1 / 3)))
            if i + j < level - 1:
                pts.append(((i + 2 / 3), (j + 2 / 3)))
    b = np.array(pts) / level
    return np.column_stack([1.0 - b.sum(axis=1), b[:, 0], b[:, 1]])


_BARY = _sub_centroids()


def face_sky_fractions(triangles: np.ndarray, camera: np.ndarray, is_sky: SkyPredicate
                       ) -> np.ndarray:
    """Share of 16 sample points of each triangle whose direction from ``camera`` is sky."""
    pts = np.einsum("sk,mkj->msj", _BARY, triangles)
    d = unit(pts.reshape(-1, 3) - camera)
    sky = _chunked(is_sky, d).reshape(len(triangles), len(_BARY))
    return sky.mean(axis=1)


def choose_holes(sky_fraction: np.ndarray, solid_angle: np.ndarray) -> np.ndarray:
    """Faces to leave out so that their solid angle matches Σ sky_fraction·solid_angle."""
    holes = sky_fraction >= 0.5
    target = float(np.sum(sky_fraction * solid_angle))
    resid = target - float(np.sum(solid_angle[holes]))
    if resid > 0:
        cand = np.flatnonzero(~holes & (sky_fraction > 0))
        cand = cand[np.argsort(-sky_fraction[cand], kind="stable")]
        w = solid_angle[cand]
        take = (np.cumsum(w) - 0.5 * w) < resid
        holes[cand[take]] = True
    elif resid < 0:
        cand = np.flatnonzero(holes & (sky_fraction < 1))
        cand = cand[np.argsort(sky_fraction[cand], kind="stable")]
        w = solid_angle[cand]
        drop = (np.cumsum(w) - 0.5 * w) < -resid
        holes[cand[drop]] = False
    return holes


@dataclass(frozen=True)
class _Sheet:
    """The sheet before the holes: triangles, where they are seen from, and the form's parts."""

    verts: np.ndarray
    faces: np.ndarray
    camera: np.ndarray
    notes: list[str]
    info: dict[str, float]
    trunks: Mesh | None = None


def build_perforated(tree: Tree, *, sensors: Sensors, street: Street, frame: FacadeFrame,
                     form: str, source: str | None = None,
                     pattern: GapPattern | None = None) -> TreeModel:
    """Build the perforated crown; ``pattern`` overrides the configured photo / random gaps:
    check, choose the gap pattern, build the form's sheet, cut its holes, assemble."""
    perf = tree.perforated
    _check_perforated(perf, source=source)
    src = photo_source(tree)
    if pattern is None:
        pattern = _pattern_of(perf, src=src, source=source)
    if form == "dome":
        sheet = _dome_sheet(tree, sensors=sensors, street=street, source=source)
    else:
        sheet = _free_sheet(tree, sensors=sensors, street=street, frame=frame, source=source)
    materials: dict = {SHELL: Plastic(SHELL, perf.reflectance)}
    meshes: list[Mesh] = []
    if sheet.trunks is not None:
        materials[TRUNK] = Plastic(TRUNK, BARK_REFLECTANCE)
        meshes.append(sheet.trunks)
    info: dict[str, float] = {"openness_pattern": pattern.openness,
                              "reflectance": perf.reflectance, **sheet.info}
    kept, hole_fraction = _cut_holes(sheet, pattern=pattern, info=info)
    meshes.insert(0, Mesh("crown_shell", SHELL, frame.to_world(sheet.verts), kept))
    notes = [*sheet.notes, *_perforated_notes(perf, pattern=pattern, form=form,
                                               hole_fraction=hole_fraction)]
    photo = (provenance(src, [pattern.photo], {"hole_fraction": hole_fraction})
             if src is not None and pattern.photo is not None else None)
    return TreeModel(meshes=meshes, materials=materials, notes=notes, recommended_ab=PERFORATED_AB,
                     info=info, form=form, model="perforated", photo=photo)


def _check_perforated(perf: Perforated, *, source: str | None) -> None:
    """Reflectance 0–1 and a resolution the mesh limit allows."""
    if not 0.0 <= perf.reflectance <= 1.0:
        raise ConfigError(f"got {perf.reflectance}, expected 0–1", source=source,
                          field="tree.perforated.reflectance")
    if not 4 <= perf.resolution <= MAX_RESOLUTION:
        raise ConfigError(f"got {perf.resolution}, expected 4–{MAX_RESOLUTION} rings "
                          "(triangles ≈ 5.1·resolution²)", source=source,
                          field="tree.perforated.resolution")


def _pattern_of(perf: Perforated, *, src: PhotoSource | None, source: str | None
                ) -> GapPattern:
    """The gap pattern of the [tree] photo if any, else :func:`gap_pattern_for`."""
    if src is None and not 0.0 <= perf.openness <= 1.0:
        raise ConfigError(f"got {perf.openness}, expected 0–1", source=source,
                          field="tree.perforated.openness")
    return (photo_gap_pattern(perf, source, src) if src is not None
            else gap_pattern_for(perf, source))


def _dome_sheet(tree: Tree, *, sensors: Sensors, street: Street, source: str | None
                ) -> _Sheet:
    """The sensor dome's hemisphere, seen from the dome centre."""
    spec = dome_spec(tree, sensors, street, source)
    verts, faces = spec.shell(tree.perforated.resolution)
    notes = [*dome_notes(spec), "Camera point = dome centre."]
    return _Sheet(verts, faces, spec.centre, notes, {"dome_radius_m": spec.radius})


def _free_sheet(tree: Tree, *, sensors: Sensors, street: Street, frame: FacadeFrame,
                source: str | None) -> _Sheet:
    """The free crowns' envelopes open towards the wall, seen from the sensor centre; trunks."""
    spec_r = crown_row_spec(tree, sensors, street, source)
    camera = spec_r.camera(sensors)
    level = int(min(5, max(2, round(math.log2(63.43 * tree.perforated.resolution / 180.0)))))
    vs, fs, off = [], [], 0
    for i in range(spec_r.count):
        v, f, on_wall = spec_r.envelope(i, level)
        vs.append(v)
        fs.append(f[~on_wall] + off)
        off += len(v)
    tv, tf = spec_r.trunks()
    trunks = Mesh("tree_trunks", TRUNK, frame.to_world(tv), tf)
    notes = list(row_notes(spec_r, tree, sensors))
    notes.append("The perforated sheet is the crowns' envelope open towards the wall: every "
                 "line of sight from the camera (sensor centre on the wall) through a crown "
                 "crosses it once, as in the photo.")
    return _Sheet(np.vstack(vs), np.vstack(fs), camera, notes,
                  {"clip_plane_n_m": spec_r.n_clip}, trunks)


def _cut_holes(sheet: _Sheet, *, pattern: GapPattern, info: dict[str, float]
               ) -> tuple[np.ndarray, float]:
    """The faces kept and the holes' share of the sheet's solid angle; the figures go into
    ``info``."""
    tri = sheet.verts[sheet.faces]
    omega = triangle_solid_angles(tri, sheet.camera)
    frac = face_sky_fractions(tri, sheet.camera, pattern.is_sky)
    holes = choose_holes(frac, omega)
    covered = float(omega.sum())
    hole_fraction = float(omega[holes].sum() / covered) if covered > 0 else 0.0
    info.update({
        "hole_fraction": hole_fraction,
        "sky_fraction_sampled": float(np.sum(frac * omega) / covered) if covered > 0 else 0.0,
        "sheet_solid_angle_sr": covered,
        "faces_total": float(len(sheet.faces)),
        "holes": float(holes.sum()),
        "direct_transmission": hole_fraction,
    })
    return sheet.faces[~holes], hole_fraction


def _perforated_notes(perf: Perforated, *, pattern: GapPattern, form: str,
                      hole_fraction: float) -> list[str]:
    """The model and its Radiance -ab note."""
    where = "the dome centre" if form == "dome" else "the sensor centre on the wall"
    return [
        f"Model: perforated — opaque sheet (reflectance {perf.reflectance:g}, T = 0) with holes "
        f"from {pattern.source}. Holes are absent faces; seen from {where} they cover "
        f"{100 * hole_fraction:.2f} % of the sheet's solid angle (pattern openness "
        f"{100 * pattern.openness:.2f} %).",
        f"Radiance: holes pass direct sun as shadow rays; -ab {PERFORATED_AB} covers "
        "ground, wall and sheet inter-reflections (-ab 3 reads about 4 % low: "
        "`radtree convergence`)."]
