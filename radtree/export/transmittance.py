"""Each crown's hourly transmittance along the sun direction for a year (energy shading schedules).

**Definitions.** Two, both fractions of the open-sky beam falling on the crown's shadow: for a
sun direction s (unit vector towards the sun), the crown's solid (the convex hull of its
envelope, :meth:`Crown.solid`) projected along s is the area A⊥ (m²) the crown intercepts
across the beam; with direct normal illuminance E_n the open beam brings Φ₀ = E_n·A⊥ onto it.

* ``beam`` — the regular (undeviated) transmittance: the mean, over a bundle of parallel rays
  through the solid towards the sun, of the product of the *specular* transmittances of every
  surface of the crown the ray crosses (:class:`radtree.trees.raycast.DirectTracer`: ``trans``
  T_s, holes 1, trunk and branches 0). A crown of leaves without specular transmission (the
  homogeneous crown, T_s = 0) passes no beam.
* ``total`` (**the default**) — the crown's direct–hemispherical transmittance: of the flux Φ₀,
  the share that leaves the crown travelling away from the sun (direction d with d·s < 0):
  the beam plus what leaves and branches scatter into that hemisphere (diffuse transmission,
  reflections between leaves) — regular plus diffuse transmittance, τ = τ_r + τ_d (CIE
  e-ILV 17-24-067), the quantity an integrating sphere measures on a flat sample (Kessel 1986,
  Applied Optics 25, 2752). Equivalently: sun-facing pyranometers tiling the whole plane
  perpendicular to s behind the crown, their readings summed over the plane (every such ray
  crosses it, none other does), less what they sum with no crown, over E_n·A⊥ — at any
  distance behind the crown, but only on the *whole* plane: leaves scatter into a cosine lobe
  about their own normal, so the crown's flanks send light nearly at right angles to the beam,
  and a square 16 crown radii wide just behind it catches only 60–85 % of the scattered light
  (benchmarks/schedule_total.py). Light scattered back towards the sun (d·s ≥ 0) is not in it
  (a horizontal pyranometer plane would count the downward half instead: up to +50 % of the
  scattered part for a sun at 40°). Traced by the forward engine's transport from the same
  bundle (:func:`radtree.engines.forward.passage.beam_passage`: the scattered part is its
  total minus its beam), added to the exact ``beam``; against traced pyranometers on that
  plane within 2 % for each crown model of the reference case at three sun positions
  (benchmarks/schedule_total.py: −1.4 … +0.4 %).

*Why total by default:* an EnergyPlus shading surface stops what its schedule does not pass,
and scattered light passes the crown: with ``beam`` every crown without gaps exports as opaque
(the reference case's homogeneous dome, sun at the zenith, 60° and 40° altitude: beam
0.3 %, total 4.6–5.2 %, benchmarks/schedule_total.py) and all scattered light is dropped. The
whole plane, not the shadow alone: EnergyPlus lets τ·E_n·A⊥ through the shade (into its
shadow), and with τ so defined that is the flux that passes the crown.
Remaining caveats (logged by the export): EnergyPlus applies the
value to the beam *and* diffuse solar on the shade and passes it on undeviated, as solar and
visible alike (its issue #992: "the solar and visible transmittance is the same and … the
surfaces are non-diffusing"); the schedule takes effect only with the ``PolygonClipping``
shadow calculation (#9059: ``PixelCounting`` treats the shade as opaque) recomputed every day
(#3073: a transmittance schedule follows the shadow calculation's update frequency) — the IDF
written sets ``ShadowCalculation`` so (:func:`radtree.export.honeybee.shadow_calculation_idf`).

**Sampling.** Each hour is traced with about ``rays`` bundle rays and as many photons, so an
hour's value carries that sample's error: at the export's default 128 rays an hour of the
reference case's crowns scatters by 5–22 % (one standard deviation over photon seeds) and its
beam, a 128-point lattice over slats about as wide as its step, is off by up to 0.026 (the
louvers dome at the zenith: 0.002 against 0.028); 65 536 rays bring it under 1 %
(benchmarks/schedule_total.py). Sums over many hours (a season's energy) average much of it
out; ``--rays`` buys hourly precision.

The bundle (:func:`bundle`) starts on the horizontal plane 1 cm below the crown's lowest point:
the points of a square lattice whose ray towards the sun meets the crown's solid, i.e. the
crown's shadow on that plane sampled uniformly (equal area across the beam), about ``rays``
points.

**Year.** 8760 hours of a non-leap year (the site's year, or the year before when that is a
leap year), hour k covering local standard time [k, k + 1) h; the sun position is taken at
the middle of the hour (pvlib SPA, as :func:`radtree.light.sun.sun_position`). Hours with the
sun below 2° (no meaningful beam: the shadow plane grows without bound) take the crown's
transmittance towards the zenith of the same leaf state.

**Leaf on / off.** :class:`radtree.annual.schedule.LeafSchedule` dates: leafed crown inside
the season, the bare branches of :func:`radtree.annual.branches.build_leaf_off` outside it
(:class:`ScheduleOptions` ``seasons=False`` keeps the leafed crown all year).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from datetime import datetime, timedelta, timezone

import numpy as np
import trimesh

from radtree.config import Project, Scenario
from radtree.errors import RadtreeError
from radtree.export.schedule_options import ScheduleOptions
from radtree.log import progress
from radtree.optics import Material
from radtree.scene import Mesh
from radtree.site.frame import FacadeFrame
from radtree.trees.raycast import DirectTracer

HOURS = 8760
CAVEATS = (
    "EnergyPlus passes a shade's scheduled transmittance on undeviated and applies it to beam and "
    "diffuse solar and to daylight alike (EnergyPlus issue #992); 'total' counts the scattered "
    "light as if it went on along the sun",
    "the schedule takes effect only with ShadowCalculation PolygonClipping (PixelCounting makes "
    "the shade opaque, EnergyPlus issue #9059) recomputed every day (frequency 1, issue #3073): "
    "the IDF written sets it; keep it if you merge the objects into another model",
    "the hourly value is the crown's own: light reflected back by the crown and by neighbouring "
    "crowns is not in it",
)
MIN_ALTITUDE_DEG = 2.0
"""Below this sun altitude an hour takes the zenith transmittance (see the module)."""
PLANE_GAP_M = 0.01
OWN_TOLERANCE_M = 0.1
"""How far outside its envelope a triangle's corner may lie and still be the crown's own (m):
a crown shell on the envelope, whose facets are chords of the spheroid the shell follows
(:func:`own_meshes`)."""


@dataclass
class Crown:
    """One crown's envelope (world metres) as a triangle mesh, and its name. The mesh may be
    open where the crown meets the wall or a neighbour (those faces are left out); the crown's
    solid is its convex hull (:meth:`solid`)."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray

    def solid(self) -> trimesh.Trimesh:
        """The closed convex hull of the envelope's vertices (the envelopes are convex)."""
        return trimesh.convex.convex_hull(self.vertices)

    def trimesh(self) -> trimesh.Trimesh:
        return trimesh.Trimesh(self.vertices, self.faces, process=False)


@dataclass
class CrownSchedule:
    """A crown and its 8760 hourly transmittances (fractions 0–1)."""

    crown: Crown
    values: np.ndarray
    leaf_on: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))


def crown_envelopes(project: Project, scenario: Scenario, frame: FacadeFrame) -> list[Crown]:
    """The envelopes of the scenario's crowns: one per free-standing crown, or the sensor dome."""
    from radtree.trees.build import apply_switches, resolve_form
    from radtree.trees.envelope import crown_row_spec, dome_spec

    tree, _ = apply_switches(project.tree, scenario.switches, source=str(project.source),
                             root=project.root)
    if resolve_form(project, scenario) == "dome":
        spec = dome_spec(tree, project.sensors, project.street, str(project.source))
        v, f = spec.shell(24)
        return [Crown("crown_dome", frame.to_world(v), f)]
    row = crown_row_spec(tree, project.sensors, project.street, str(project.source))
    out = []
    for i in range(row.count):
        v, f, _ = row.envelope(i, 3)
        out.append(Crown(f"crown_{i + 1}", frame.to_world(v), f))
    return out


def year_of(project: Project) -> int:
    """The site's year, or the year before when that is a leap year (8760 hours)."""
    y = int(project.site.date[:4])
    return y - 1 if (y % 4 == 0 and (y % 100 != 0 or y % 400 == 0)) else y


def year_hours(project: Project) -> list[datetime]:
    """Middles of the year's 8760 hours, local standard time (site.utc_offset_hours)."""
    tz = timezone(timedelta(hours=project.site.utc_offset_hours))
    start = datetime(year_of(project), 1, 1, 0, 30, tzinfo=tz)
    return [start + timedelta(hours=k) for k in range(HOURS)]


def sun_vectors(project: Project, hours: list[datetime]) -> tuple[np.ndarray, np.ndarray]:
    """(N, 3) unit vectors towards the sun (x east, y north, z up) and altitudes (degrees)."""
    import pandas as pd
    import pvlib

    s = project.site
    sp = pvlib.solarposition.spa_python(pd.DatetimeIndex(hours), s.latitude, s.longitude,
                                        altitude=s.elevation_m)
    alt = np.radians(sp["apparent_elevation"].to_numpy())
    az = np.radians(sp["azimuth"].to_numpy())
    vec = np.column_stack([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)])
    return vec, np.degrees(alt)


def shadow_areas(crown: Crown, suns: np.ndarray) -> np.ndarray:
    """Area (m²) of the convex crown's shadow on a horizontal plane for each sun (k, 3):
    its projected area across the beam, ½ Σ_faces A·|n·s| over its closed :meth:`Crown.solid`
    (Cauchy), divided by s_z."""
    tri = crown.solid().triangles
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])   # 2·A·n
    return 0.25 * np.abs(suns @ cross.T).sum(axis=1) / suns[:, 2]


def lattice(crown: Crown, sun: np.ndarray, rays: int, area: float | None = None) -> np.ndarray:
    """Candidate origins: a square lattice over the crown's shadow on the plane 1 cm below the
    crown, its step chosen from the shadow's area so that about ``rays`` points fall inside."""
    s = np.asarray(sun, float) / np.linalg.norm(sun)
    if s[2] <= 0:
        raise ValueError("the sun must be above the horizon")
    z0 = float(crown.vertices[:, 2].min()) - PLANE_GAP_M
    shadow = crown.vertices[:, :2] - s[:2] * ((crown.vertices[:, 2] - z0) / s[2])[:, None]
    lo, hi = shadow.min(axis=0), shadow.max(axis=0)
    if area is None:
        area = float(shadow_areas(crown, s[None, :])[0])
    step = float(np.sqrt(area / max(rays, 1)))
    X, Y = np.meshgrid(np.arange(lo[0] + step / 2, hi[0], step),
                       np.arange(lo[1] + step / 2, hi[1], step))
    return np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z0)])


def bundle(crown: Crown, sun: np.ndarray, rays: int) -> np.ndarray:
    """Ray origins (k, 3): the :func:`lattice` points whose ray towards ``sun`` meets the
    envelope — the crown's shadow sampled uniformly (equal area across the beam)."""
    o = lattice(crown, sun, rays)
    s = np.asarray(sun, float) / np.linalg.norm(sun)
    return o[crown.solid().ray.intersects_any(o, np.tile(s, (len(o), 1)))]


def transmittances(tracer: DirectTracer, crown: Crown, suns: np.ndarray, rays: int
                   ) -> np.ndarray:
    """The crown's transmittance along each of ``suns`` (k, 3) (see the module): the mean over
    each direction's :func:`bundle`, all directions traced in one batch."""
    suns = np.atleast_2d(np.asarray(suns, float))
    suns = suns / np.linalg.norm(suns, axis=1)[:, None]
    areas = shadow_areas(crown, suns)
    grids = [lattice(crown, s, rays, a) for s, a in zip(suns, areas)]
    who = np.concatenate([np.full(len(g), k) for k, g in enumerate(grids)])
    o, d = np.vstack(grids), suns[who]
    hit = crown.solid().ray.intersects_any(o, d)
    who, o, d = who[hit], o[hit], d[hit]
    n = np.bincount(who, minlength=len(suns))
    if (n == 0).any():
        raise RadtreeError(f"{crown.name}: no ray of the bundle meets the crown")
    tau = tracer.transmission(o, d)
    return np.bincount(who, tau, minlength=len(suns)) / n


def crown_models(project: Project, scenario: Scenario, frame: FacadeFrame
                 ) -> tuple[list[Mesh], list[Mesh], dict[str, Material], list[str]]:
    """Meshes of the leafed crown model and of its bare (leaf-off) branches, their materials."""
    from radtree.annual.branches import build_leaf_off
    from radtree.trees.build import build_tree

    if scenario.model == "none":
        raise RadtreeError(f"scenario {scenario.name!r} has no crown (model 'none'): choose "
                           "one with a crown model")
    leafed = build_tree(project, scenario, frame)
    bare = build_leaf_off(project, scenario, frame)
    return (list(leafed.meshes), list(bare.meshes), {**leafed.materials, **bare.materials},
            leafed.notes[:1] + bare.notes[:1])


def own_tracer(crown: Crown, meshes: list[Mesh], materials: dict[str, Material]
               ) -> DirectTracer:
    """A tracer of :func:`own_meshes` (a crown's schedule leaves its neighbours out: they are
    shades of their own; the part of a trunk below the crown is below the rays' start plane
    and never crossed)."""
    return DirectTracer(own_meshes(crown, meshes), materials)


def own_meshes(crown: Crown, meshes: list[Mesh]) -> list[Mesh]:
    """The crown's own triangles: those with a corner in its :meth:`Crown.solid` or within
    :data:`OWN_TOLERANCE_M` outside a face of its envelope (a leaf poking out, a shell on the
    envelope), and with the centroid on the crown's side of every face the envelope leaves open
    (the plane shared with a neighbouring crown, the wall): every triangle of a row of touching
    crowns is one crown's."""
    solid = crown.solid()
    n, p0 = solid.face_normals, solid.triangles[:, 0]
    closed = _closed_faces(crown, solid)
    own = []
    for m in meshes:
        if not m.n_triangles:
            continue
        t = m.triangles
        keep = np.zeros(len(t), bool)
        for c in range(0, len(t), 1024):       # (triangle, corner, face) distances, in chunks
            out = np.einsum("tcj,fj->tcf", t[c:c + 1024], n) - np.einsum("fj,fj->f", n, p0)
            corner_in = (out[:, :, closed] <= OWN_TOLERANCE_M).all(axis=2).any(axis=1)
            keep[c:c + 1024] = corner_in & (out.mean(axis=1)[:, ~closed] <= 0.0).all(axis=1)
        if keep.any():
            own.append(Mesh(m.name, m.material, t[keep].reshape(-1, 3),
                            np.arange(3 * int(keep.sum())).reshape(-1, 3)))
    return own


def _closed_faces(crown: Crown, solid: trimesh.Trimesh) -> np.ndarray:
    """Per face of ``solid``: True where the envelope has a face there (a probe 1 mm outside
    the face's centre, cast inwards, meets the envelope 1 mm on)."""
    n = solid.face_normals
    env = crown.trimesh()
    probe = solid.triangles_center + 1e-3 * n
    tri = env.ray.intersects_first(probe, -n)
    hit = tri >= 0
    gap = np.full(len(n), np.inf)
    en = env.face_normals[tri[hit]]
    gap[hit] = (np.einsum("ij,ij->i", probe[hit] - env.triangles[tri[hit], 0], en)
                / np.einsum("ij,ij->i", n[hit], en))
    return np.abs(gap - 1e-3) < 1e-4


def scattered_forward(crown: Crown, meshes: list[Mesh], materials: dict[str, Material],
                      suns: np.ndarray, rays: int, seed: int = 1, *,
                      own_only: bool = False) -> np.ndarray:
    """The part of the ``total`` definition beyond the beam, per sun of ``suns`` (k, 3): the
    crown's forward-scattered sunlight over the open beam on its shadow (0–1), forward-traced
    from the :func:`lattice` bundle (photons start above the crown, travel along −s).
    ``own_only``: ``meshes`` are already the crown's :func:`own_meshes`."""
    from radtree.engines.forward.passage import beam_passage

    suns = np.atleast_2d(np.asarray(suns, float))
    suns = suns / np.linalg.norm(suns, axis=1)[:, None]
    own = meshes if own_only else own_meshes(crown, meshes)
    top = max([float(crown.vertices[:, 2].max())]
              + [float(m.vertices[:, 2].max()) for m in own if m.n_triangles]) + PLANE_GAP_M
    solid = crown.solid()
    starts = []
    for s, a in zip(suns, shadow_areas(crown, suns)):
        o = lattice(crown, s, rays, a)
        o = o[solid.ray.intersects_any(o, np.tile(s, (len(o), 1)))]
        if len(o) == 0:
            raise RadtreeError(f"{crown.name}: no ray of the bundle meets the crown")
        starts.append(o + s * ((top - o[:, 2]) / s[2])[:, None])
    total, beam = beam_passage(own, materials, -suns, starts, seed=seed)
    return np.maximum(total - beam, 0.0)


def leaf_states(project: Project, hours: list[datetime], options: ScheduleOptions
                ) -> np.ndarray:
    """Per hour of ``hours``: True when the crown is leafed (always, without ``seasons``)."""
    if not options.seasons:
        return np.ones(len(hours), bool)
    leaf = default_leaf_schedule(project, options.leaf_on, options.leaf_off)
    return np.asarray(leaf.in_leaf(np.array([h.month for h in hours]),
                                   np.array([h.day for h in hours])), bool)


#: hours traced in one batch (a progress step)
CHUNK_HOURS = 240


def year_schedules(project: Project, scenario: Scenario, frame: FacadeFrame, *,
                   options: ScheduleOptions | None = None,
                   models: tuple | None = None) -> list[CrownSchedule]:
    """8760 hourly transmittances per crown (leafed in the leaf season, bare outside it), of
    ``options.definition`` ``total`` or ``beam`` (see the module), a progress bar per crown
    and leaf state (:func:`radtree.log.progress`). ``models``: the :func:`crown_models` of
    the scenario when already built; ``options`` None: the defaults."""
    options = options or ScheduleOptions()
    crowns = crown_envelopes(project, scenario, frame)
    on_meshes, off_meshes, materials, _ = models or crown_models(project, scenario, frame)
    hours = year_hours(project)
    sun, alt = sun_vectors(project, hours)
    in_leaf = leaf_states(project, hours, options)
    up = alt >= MIN_ALTITUDE_DEG
    out = []
    for crown in crowns:
        values = np.zeros(HOURS)
        for state, meshes in ((True, on_meshes), (False, off_meshes)):
            sel = in_leaf == state
            if sel.any():
                trace = _Trace(crown, meshes, materials, options)
                values[sel & ~up] = trace(np.array([[0.0, 0.0, 1.0]]), seed=1)[0]
                idx = np.flatnonzero(sel & up)
                chunks = [idx[i:i + CHUNK_HOURS] for i in range(0, len(idx), CHUNK_HOURS)]
                desc = f"{crown.name} ({'leaf-on' if state else 'leaf-off'})"
                for chunk in progress(chunks, desc=desc, unit="chunk"):
                    values[chunk] = trace(sun[chunk], seed=int(chunk[0]) + 1)
        out.append(CrownSchedule(crown, np.clip(values, 0.0, 1.0), in_leaf))
    return out


@dataclass
class _Trace:
    """One crown in one leaf state: its transmittance of ``options.definition`` along suns."""

    crown: Crown
    meshes: list[Mesh]
    materials: dict[str, Material]
    options: ScheduleOptions

    def __post_init__(self) -> None:
        self.own = own_meshes(self.crown, self.meshes)
        self.tracer = DirectTracer(self.own, self.materials)

    def __call__(self, suns: np.ndarray, seed: int) -> np.ndarray:
        rays = self.options.rays
        values = transmittances(self.tracer, self.crown, suns, rays)
        if self.options.definition == "total":
            values = values + scattered_forward(self.crown, self.own, self.materials, suns,
                                                rays, seed=seed, own_only=True)
        return values


def default_leaf_schedule(project: Project, leaf_on: str | None, leaf_off: str | None):
    """The leaf season: the given dates, else the project's
    (:func:`radtree.annual.schedule.leaf_season`: ``[tree] leaf_on/leaf_off`` or the species'
    phenology in the site's hemisphere)."""
    from radtree.annual.schedule import leaf_season

    return leaf_season(project, leaf_on, leaf_off)


