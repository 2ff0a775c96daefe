"""Writing a scene as a Radiance build folder a Radiance user recognises.

```
build/<scenario>/
  materials.rad            all materials (the ground's default reflectance)
  geometry/<mesh>.rad      one file per mesh: triangles as polygons, or for a large mesh one
                           `mesh` primitive reading geometry/<mesh>.rtm (obj2mesh of <mesh>.obj)
  grids/<grid>.pts         rtrace input: x y z dx dy dz per sensor
  skies/<HHMM>.sky         sun (and sky, ground glow) of each hour
  skies/<HHMM>_ground.rad  the hour's ground material (reflectance from the sun altitude)
  Makefile                 one target per hour: oconv → rtrace -I → rcalc (lux)
  octrees/, results/       made by `make`
```
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import cache
from pathlib import Path

import numpy as np
from jinja2 import Template

import radtree
from radtree.config import EngineParams
from radtree.engines.common.voxels import refuse_voxels
from radtree.engines.radiance.binaries import FIXED_SEED, RadianceInstall
from radtree.engines.radiance.materials import material_text
from radtree.engines.radiance.meshes import (
    as_compiled_mesh,
    mesh_primitive_text,
    mesh_to_radiance,
    obj2mesh_command,
    write_obj,
)
from radtree.engines.radiance.mist import hour_mist_text, mist_geometry_text, mist_params
from radtree.engines.radiance.pmap import FINAL_GATHER_AB, PhotonMap
from radtree.engines.radiance.sky import ANALYTIC_SKY_CAL, sky_text
from radtree.errors import EngineError
from radtree.light.sky import SkyState
from radtree.light.units import PHOTOPIC_RGB, WHITE_EFFICACY
from radtree.media import TurbidCrowns
from radtree.media_voxels import MediaSet, VoxelCrowns, media_parts
from radtree.optics import Hole, Material, Plastic, with_reflectance
from radtree.resources import template_environment
from radtree.scene import Scene
from radtree.sensor_grid import is_dense_grid


def instances_text(scene: Scene) -> str:
    """``geometry/instances.rad``: one ``instance`` per placed crown, its prototype's frozen
    octree turned (``-rz``, degrees counter-clockwise), scaled (``-s``) and moved (``-t``)."""
    out = [f"# {len(scene.instances)} instances of {len(scene.prototypes)} prototype octrees\n"]
    for k, inst in enumerate(scene.instances):
        x, y, z = inst.translate
        out.append(f"void instance {inst.prototype}.{k}\n9 {prototype_octree(inst.prototype)} "
                   f"-rz {inst.rotate_z_deg:.4f} -s {inst.scale:.6f} -t {x:.5f} {y:.5f} {z:.5f}"
                   "\n0\n0\n")
    return "\n".join(out)


def prototype_octree(name: str) -> str:
    """Where a prototype's frozen octree is made (relative to the build folder)."""
    return f"octrees/prototype_{name}.oct"


def materials_text(materials: Mapping[str, Material], ground: str | None = None) -> str:
    """``materials.rad``: every material's Radiance entry (as in ``materials/*.rad``), without
    holes (not written) and without the ground ``ground`` (written per hour in ``skies/``)."""
    entries = [material_text(m) for name, m in materials.items()
               if not isinstance(m, Hole) and name != ground]
    return "# materials (ground: per hour in skies/)\n\n" + "\n".join(entries)


def rtrace_options(params: EngineParams, ab: int) -> list[str]:
    """rtrace options for illuminance: -I (irradiance at points), -h (no header),
    :data:`~radtree.engines.radiance.binaries.FIXED_SEED` and the ambient parameters.
    With a photon map (``pmap_photons``) rtrace computes one ambient bounce (final gathering)."""
    if PhotonMap.from_params(params) is not None:
        ab = FINAL_GATHER_AB
    r = params.radiance
    return [
        "-h", "-I", FIXED_SEED, "-ab", str(ab), "-ad", str(r.ad), "-as", str(r.as_),
        "-ar", str(r.ar), "-aa", f"{r.aa:g}", "-lw", f"{r.lw:g}",
    ]


def grid_rtrace_options(params: EngineParams, ab: int, grids: list[str]) -> dict[str, list[str]]:
    """rtrace options of the grids traced differently: the dense façade maps with
    ``-lw engine.dense_lw`` (when set and a map is in ``grids``)."""
    maps = [g for g in grids if is_dense_grid(g)]
    if params.radiance.dense_lw is None or not maps:
        return {}
    options = rtrace_options(params.changed(lw=params.radiance.dense_lw), ab)
    return {g: options for g in maps}


@dataclass
class BuildPlan:
    """What a build folder holds, for the Python runner and the Makefile alike."""

    folder: Path
    hours: list[str]                       # labels HHMM
    grids: list[str]
    scene_files: list[str]                 # relative to folder, in oconv order
    hour_files: dict[str, list[str]]
    rtrace_opts: list[str]
    states: dict[str, SkyState] = field(default_factory=dict)
    hour_grids: dict[str, list[str]] = field(default_factory=dict)   # default: every grid
    photon_map: PhotonMap | None = None                               # mkpmap before rtrace
    prototypes: dict[str, str] = field(default_factory=dict)   # octree → its geometry file
    meshes: dict[str, str] = field(default_factory=dict)       # .rtm → its .obj (obj2mesh)
    grid_opts: dict[str, list[str]] = field(default_factory=dict)  # grid → its own rtrace_opts

    def mesh_commands(self) -> list[tuple[list[str], str]]:
        """``obj2mesh`` of each compiled mesh (stdout → the ``.rtm``)."""
        return [(obj2mesh_command(obj), rtm) for rtm, obj in self.meshes.items()]

    def prototype_commands(self) -> list[tuple[list[str], str]]:
        """``oconv -f`` of each prototype (frozen: instances need their octree whole)."""
        return [(["oconv", "-f", *self.scene_files, rad], oct_)
                for oct_, rad in self.prototypes.items()]

    def grids_at(self, hour: str) -> list[str]:
        """Grids the Makefile traces at ``hour`` (label HHMM)."""
        return self.hour_grids.get(hour, self.grids)

    def oconv_command(self, hour: str) -> list[str]:
        return ["oconv", *self.scene_files, *self.hour_files[hour]]

    def rtrace_command(self, hour: str, grid: str | None = None) -> list[str]:
        pm = self.photon_map.rtrace_args(hour) if self.photon_map else []
        opts = self.grid_opts.get(grid, self.rtrace_opts) if grid else self.rtrace_opts
        return ["rtrace", *opts, *pm, f"octrees/{hour}.oct"]

    def mkpmap_command(self, hour: str) -> list[str] | None:
        """The hour's ``mkpmap`` (None without a photon map)."""
        return self.photon_map.mkpmap_command(hour) if self.photon_map else None


def radiance_scene(scene: Scene) -> Scene:
    """``scene`` as the Radiance engine takes it: voxel crowns refused (no Radiance form), the
    spheroid crowns of a :class:`radtree.media_voxels.MediaSet` as plain
    :class:`~radtree.media.TurbidCrowns` (the ``mist`` volumes), other media refused."""
    if scene.media is not None and not isinstance(scene.media, TurbidCrowns | VoxelCrowns
                                                  | MediaSet):
        raise EngineError(f"the radiance engine traces turbid spheroid crowns as mist, not "
                          f"{type(scene.media).__name__} media: use --engine numpy")
    refuse_voxels(scene, engine="radiance")
    crowns, _ = media_parts(scene.media)
    return scene if crowns is scene.media else replace(scene, media=crowns)


def mist_media(scene: Scene) -> TurbidCrowns | None:
    """The spheroid crowns Radiance writes as ``mist`` (None: none) of a scene
    :func:`radiance_scene` returned."""
    media = scene.media
    return media if isinstance(media, TurbidCrowns) and len(media) else None


def _write(path: Path, text: str) -> None:
    """Write a build file in place: :func:`write_build` fills a folder that is made whole at
    once (``radtree build``'s temporary folder, renamed when complete) or a scratch folder, and
    a folder without its ``manifest.json`` is never taken as built — so no file of it needs its
    own temporary name (452 of them cost 0.5 s of ``mkstemp`` per reference-case build)."""
    path.write_text(text, encoding="utf-8")


def write_build(scene: Scene, states: list[SkyState], params: EngineParams, ab: int,
                folder: Path, install: RadianceInstall | None, scenario: str = "scene",
                hour_grids: dict[str, list[str]] | None = None) -> BuildPlan:
    """Write the scene, the hours' skies, the grids and the Makefile into ``folder``.

    ``hour_grids`` maps an hour label (HHMM) to the grids the Makefile traces then (default:
    every grid at every hour)."""
    scene = radiance_scene(scene)
    params = mist_params(params, mist_media(scene), scene.materials)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "geometry").mkdir(exist_ok=True)
    (folder / "grids").mkdir(exist_ok=True)
    (folder / "skies").mkdir(exist_ok=True)

    _write(folder / "materials.rad", materials_text(scene.materials, scene.ground_material))
    scene_files = ["materials.rad"]
    geometry_files, meshes, prototypes = _write_geometry(scene, folder=folder)
    for grid in scene.grids.values():
        _write(folder / "grids" / f"{grid.name}.pts", grid.to_pts())
    for name, cal in ANALYTIC_SKY_CAL.items():
        _write(folder / "skies" / f"{name}.cal", f"{{ {name} sky: relative luminance }}\n{cal}")
    hour_files = _write_hours(scene, states=states, folder=folder, install=install,
                              geometry_files=geometry_files, params=params)
    # oconv order: materials, hour's ground material, geometry, sky
    plan = BuildPlan(folder=folder, hours=[s.label for s in states], grids=list(scene.grids),
                     scene_files=scene_files, hour_files=hour_files,
                     rtrace_opts=rtrace_options(params, ab),
                     states={s.label: s for s in states},
                     hour_grids=dict(hour_grids or {}), prototypes=prototypes,
                     meshes=meshes, photon_map=PhotonMap.from_params(params),
                     grid_opts=grid_rtrace_options(params, ab, list(scene.grids)))
    write_makefile(plan, install, scenario)
    return plan


def _write_geometry(scene: Scene, *, folder: Path
                    ) -> tuple[list[str], dict[str, str], dict[str, str]]:
    """Write ``geometry/``: one file per solid mesh (polygons, or a ``mesh`` primitive whose
    .rtm the runner / Makefile compiles), the instancing prototypes and ``instances.rad``.
    Returns the geometry files (relative), the meshes (rtm → obj) and the prototypes
    (octree → rad file)."""
    geometry_files = []
    meshes: dict[str, str] = {}
    for mesh in scene.own_solid_meshes():
        rel = f"geometry/{mesh.name}.rad"
        if as_compiled_mesh(mesh):
            obj, rtm = f"geometry/{mesh.name}.obj", f"geometry/{mesh.name}.rtm"
            write_obj(mesh, folder / obj)
            _write(folder / rel, mesh_primitive_text(mesh, rtm))
            meshes[rtm] = obj   # compiled by the runner / the Makefile (like the octrees)
        else:
            _write(folder / rel, mesh_to_radiance(mesh))
        geometry_files.append(rel)
    crowns = mist_media(scene)
    if crowns is not None:
        rel = "geometry/crowns_mist.rad"
        _write(folder / rel, mist_geometry_text(crowns))
        geometry_files.append(rel)
    prototypes: dict[str, str] = {}
    if scene.instances:
        (folder / "geometry" / "prototypes").mkdir(exist_ok=True)
        for name, proto in scene.prototypes.items():
            rel = f"geometry/prototypes/{name}.rad"
            _write(folder / rel, "\n".join(mesh_to_radiance(m) for m in proto))
            prototypes[prototype_octree(name)] = rel
        _write(folder / "geometry" / "instances.rad", instances_text(scene))
        geometry_files.append("geometry/instances.rad")
    return geometry_files, meshes, prototypes


def _write_hours(scene: Scene, *, states: list[SkyState], folder: Path,
                 install: RadianceInstall | None, geometry_files: list[str],
                 params: EngineParams) -> dict[str, list[str]]:
    """Write each hour's ground material (a Plastic ground only), turbid crowns' mists and
    sky; returns each hour's oconv files after materials.rad: ground material, mists,
    geometry, sky."""
    hour_files: dict[str, list[str]] = {}
    ground = scene.materials.get(scene.ground_material)
    for st in states:
        files = []
        if isinstance(ground, Plastic):
            gm = with_reflectance(ground, st.ground_reflectance)
            rel = f"skies/{st.label}_ground.rad"
            _write(folder / rel, f"# ground reflectance at {st.time} "
                       f"(sun altitude {st.sun.altitude_deg:.2f}°)\n" + material_text(gm))
            files.append(rel)
        crowns = mist_media(scene)
        if crowns is not None:
            rel = f"skies/{st.label}_mist.rad"
            _write(folder / rel, hour_mist_text(
                crowns, materials=scene.materials, state=st,
                extinction=params.radiance.mist_extinction,
                sun=params.radiance.mist_sun))
            files.append(rel)
        files += geometry_files
        rel_sky = f"skies/{st.label}.sky"
        _write(folder / rel_sky, sky_text(st, install))
        files.append(rel_sky)
        hour_files[st.label] = files
    return hour_files


@cache
def _makefile_template() -> Template:
    """``templates/Makefile.j2``, compiled once per process (~50 ms a compilation)."""
    return template_environment(keep_trailing_newline=True).get_template("Makefile.j2")


def write_makefile(plan: BuildPlan, install: RadianceInstall | None, scenario: str) -> None:
    text = _makefile_template().render(
        version=radtree.__version__, scenario=scenario, hours=plan.hours, grids=plan.grids,
        hour_grids={h: plan.grids_at(h) for h in plan.hours},
        scene_files=plan.scene_files, hour_files=plan.hour_files,
        rtrace_opts=" ".join(plan.rtrace_opts),
        grid_opts={g: " ".join(o) for g, o in plan.grid_opts.items()},
        efficacy=f"{WHITE_EFFICACY:g}", weights=[f"{w:.3f}" for w in PHOTOPIC_RGB],
        bin_dir=str(install.bin_dir) if install else "/usr/local/bin",
        raypath=install.raypath if install else ".:/usr/local/lib/ray",
        mkpmap={h: " ".join(plan.mkpmap_command(h) or []) for h in plan.hours},
        pmaps={h: [f for _, f in plan.photon_map.files(h)] if plan.photon_map else []
               for h in plan.hours},
        rtrace_pmap={h: " ".join(plan.photon_map.rtrace_args(h)) if plan.photon_map else ""
                     for h in plan.hours},
        prototypes=plan.prototypes, meshes=plan.meshes,
        mesh_cmds={rtm: " ".join(argv) for argv, rtm in plan.mesh_commands()},
    )
    _write(plan.folder / "Makefile", text)


def rgb_to_lux(rgb: np.ndarray) -> np.ndarray:
    """Radiance RGB irradiance → lux: 179 · (0.265 R + 0.670 G + 0.065 B)
    (``WHITE_EFFICACY`` and ``PHOTOPIC_RGB`` of :mod:`radtree.light.units`)."""
    rgb = np.atleast_2d(np.asarray(rgb, float))
    wr, wg, wb = PHOTOPIC_RGB
    return WHITE_EFFICACY * (wr * rgb[:, 0] + wg * rgb[:, 1] + wb * rgb[:, 2])
