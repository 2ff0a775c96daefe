"""A synthetic fisheye of a scenario's crown: ray casting from the photo point through the
photo's lens model, one ray per pixel centre inside the 90° circle; a pixel is canopy (0) when
its ray hits any crown surface (leaves, sheet, trunks) and sky (255) otherwise. Street and
buildings are left out: the comparison is of the crown with the crown in the photo.

Photo point and axis (:mod:`radtree.config.photo`): a façade photo is taken at the sensor
circle's centre on the wall, lens axis = façade normal, photo angles (angle from n, angle
around n clockwise from up seen looking out); an upward photo at (sensors.x_m + photo_x_m,
photo_distance_m, photo_height_m) in the façade frame, lens axis up, (zenith, compass
azimuth), east–west mirrored as hemi reads upward photos. The rendering uses the photo's lens
(``tree.lens``) on a square frame with the 90° circle filling it, so ``radtree hemi`` analyses
it with the same ring × segment grid as the photo.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from radtree.config import Project, Scenario
from radtree.engines.common.raycast import any_hit, make_caster
from radtree.errors import ConfigError
from radtree.hemi import HemiConfig, HemiResult, analyse_array
from radtree.hemi.classify import ThresholdSpec
from radtree.hemi.directions import up_to_world
from radtree.hemi.geometry import FisheyeGeometry
from radtree.hemi.metrics import RingGrid
from radtree.hemi.synthetic import render_geometry
from radtree.pipeline.assemble import facade_frame, make_scene
from radtree.pipeline.build import built_scene
from radtree.trees.build import apply_switches, resolve_form
from radtree.trees.photo import AXIS_OF, PhotoSource, lens_of, photo_source

log = logging.getLogger(__name__)

DEFAULT_SIZE = 1000


@dataclass
class Rendering:
    """A rendered fisheye: ``image`` (H × W uint8, 255 sky), its ``geometry``, the photo
    point (world, m), the photo source and the seconds spent (build, cast wall; cast_cpu:
    the process CPU time of the cast, all threads)."""

    image: NDArray[np.uint8]
    geometry: FisheyeGeometry
    camera: NDArray[np.float64]
    source: PhotoSource
    seconds: dict[str, float]

    def analyse(self) -> HemiResult:
        """The rendering through :mod:`radtree.hemi` with the photo's grid (binary image:
        threshold fixed at 128, no gamma)."""
        config = HemiConfig(lens=self.geometry.lens, mask=self.geometry.mask,
                            axis=self.geometry.axis, mirror=self.geometry.mirror,
                            channel="luma", gamma=1.0, threshold=ThresholdSpec.parse("128"),
                            grid=RingGrid(9, 8, 0.0, self.source.zenith_deg), outlines=False)
        return analyse_array(self.image, config, name="model")


def scenario_photo(project: Project, sc: Scenario) -> tuple[Any, PhotoSource]:
    """The scenario's crown table (switches applied) and its photo; ConfigError without one."""
    tree, _ = apply_switches(project.tree, dict(sc.switches), source=str(project.source),
                             root=project.root)
    src = photo_source(tree)
    if src is None:
        raise ConfigError(f"scenario {sc.name} has no photo: set [tree] photo (or the switch "
                          '"tree.photo") to render or check it against one',
                          source=str(project.source), field="tree.photo")
    return tree, src


def photo_point(project: Project, tree: Any, src: PhotoSource) -> NDArray[np.float64]:
    """The photo point in world coordinates (m)."""
    s = project.sensors
    if src.direction == "upward":
        local = np.array([s.x_m + tree.photo_x_m, tree.photo_distance_m, tree.photo_height_m])
    else:
        local = np.array([s.x_m, 0.0, s.height_m])
    return np.asarray(facade_frame(project).to_world(local), float)


def pixel_directions(project: Project, geometry: FisheyeGeometry
                     ) -> tuple[Any, NDArray[np.float64]]:
    """The pixel field of ``geometry`` and world unit vectors of its valid pixels."""
    field = geometry.pixel_field()
    z = field.zenith[field.valid].astype(np.float64)
    a = field.azimuth[field.valid].astype(np.float64)
    if geometry.axis == "up":
        d = up_to_world(z, a)
    else:
        t, p = np.radians(z), np.radians(a)
        st = np.sin(t)
        f = facade_frame(project)   # u·(sinθ sinψ) + n·cosθ + z·(sinθ cosψ), no BLAS
        d = ((st * np.sin(p))[:, None] * f.along[None, :] + np.cos(t)[:, None] * f.normal[None, :])
        d[:, 2] += st * np.cos(p)
    return field, d


def render_scenario(project: Project, sc: Scenario, size: int = DEFAULT_SIZE,
                    workers: int = 2, src: PhotoSource | None = None) -> Rendering:
    """Render the scenario's crown from its photo point through its photo's lens (``src``:
    a photo's lens, direction and point for a crown made without one — e.g. to make a
    synthetic photo of a known crown)."""
    if src is None:
        tree, src = scenario_photo(project, sc)
    else:
        tree, _ = apply_switches(project.tree, dict(sc.switches), source=str(project.source),
                                 root=project.root)
    if size < 64 or size > 8000:
        raise ConfigError(f"got {size} px, expected 64–8000", field="--size")
    t0 = time.perf_counter()
    built = built_scene(project, sc)   # the build folder's crown when current, else built here
    resolve_form(project, sc)
    t1 = time.perf_counter()
    c1 = time.process_time()
    meshes = [] if built.tree is None else list(built.tree.meshes)
    verts, faces, off = [], [], 0
    for m in meshes:
        verts.append(m.vertices)
        faces.append(m.faces + off)
        off += len(m.vertices)
    axis = AXIS_OF[src.direction]
    geometry = render_geometry(size, lens_of(src.lens), axis=axis)
    field, d = pixel_directions(project, geometry)
    camera = photo_point(project, tree, src)
    sky = np.ones(len(d), bool)
    if verts:
        caster = make_caster(np.vstack(verts), np.vstack(faces), workers=workers)
        sky = ~any_hit(caster, np.broadcast_to(camera, d.shape), d)
    image = np.zeros((geometry.height, geometry.width), np.uint8)
    box = image[field.rows, field.cols]
    box[field.valid] = np.where(sky, 255, 0).astype(np.uint8)
    t2 = time.perf_counter()
    return Rendering(image, geometry, camera, src,
                     {"build": t1 - t0, "cast": t2 - t1, "triangles": float(off),
                      "cast_cpu": time.process_time() - c1})


def radiance_picture(project: Project, sc: Scenario, hour: str, size: int, out: Any,
                     ab: int | None = None) -> tuple[Any, Any]:
    """A Radiance ``rpict -vta`` fisheye of the scenario at ``hour`` (HH:MM) from its photo
    point along its photo's axis, lit by the hour's sun and sky (``ab``: ambient bounces,
    default the crown's): (HDR path, BMP path)."""
    from radtree.config import effective_project
    from radtree.engines.radiance.interface import RadianceEngine
    from radtree.engines.radiance.picture import fisheye_picture
    from radtree.light.hours import hour_states
    from radtree.pipeline.build import ensure_built

    tree, src = scenario_photo(project, sc)
    states = [s for s in hour_states(project, sc) if s.time == hour]
    if not states:
        raise ConfigError(f"unknown hour {hour!r} (site.hours: {', '.join(project.site.hours)})",
                          source=str(project.source), field="--hour")
    built = make_scene(project, sc)
    folder = ensure_built(project, sc)
    params = effective_project(project, sc).engine
    plan = RadianceEngine().prepare(built.scene, states, params, built.ab, folder)
    frame = facade_frame(project)
    if src.direction == "upward":
        axis, up = np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0])   # image north up
    else:
        axis, up = frame.normal, np.array([0.0, 0.0, 1.0])
    point = photo_point(project, tree, src)
    if src.direction != "upward":
        point = point + project.sensors.offset_m * axis   # off the wall the camera sits on
    return fisheye_picture(plan, hour=states[0].label, viewpoint=point, direction=axis, up=up,
                           size=size, ab=built.ab if ab is None else ab,
                           ad=params.radiance.ad, out=out)
