"""Honeybee out for Radiance recipes: radtree's scene, leaf by leaf, as a Honeybee model
(``radtree export PROJECT --format honeybee-scene``).

The ``honeybee`` format writes each crown as its *envelope* with an hourly transmittance
schedule: what EnergyPlus needs, but to a Radiance-based Ladybug Tools recipe (annual daylight,
point in time) that envelope is a closed shell of leaf material — two leaf layers on every
path, not the crown. This format writes what radtree actually traces: every mesh radtree adds
to the scene (the crowns' leaves or slats, trunks, branches, the ground plane; without a
``[site] honeybee`` model also the street, façades and rooms radtree built) as a detached
``ShadeMesh`` named ``radtree_<mesh>`` with its Radiance modifier
(:func:`radtree.export.honeybee.hb_modifier`: leaves ``trans``, the rest ``plastic`` or
``glass``), added to the project's own Honeybee model (rooms, apertures, sensor grids) when it
has one. Units metres; x east, y north, z up (Honeybee's axes, north = +y).

So a Honeybee recipe and radtree trace the same geometry and materials: ``rtrace`` on
honeybee-radiance's translation of this file and on radtree's own octree agree within Monte
Carlo noise (the one-room test model with a crown, the hour's sky: +0.47 %, 1.0 standard
error, ``tests/test_honeybee_scene.py``; the honeybee-office example under a uniform sky at
``-ab 4 -ad 8192``: 0.08 %). ``benchmarks/lbt_annual.py`` runs Ladybug Tools' annual-daylight
recipes on it against ``radtree annual``. There is no energy schedule on these shades: for EnergyPlus use
``--format honeybee`` or ``idf``. A crown carried by a BSDF (``representation = "bsdf"``) has
no Honeybee modifier here and is refused with that message; turbid-medium crowns have no
surfaces to write and are refused too.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING, Any

from radtree.errors import RadtreeError
from radtree.export.honeybee import hb_modifier, shade_model, write_hbjson
from radtree.scene import Mesh, Scene
from radtree.site.honeybee_model import MESH_PREFIX

if TYPE_CHECKING:
    from radtree.export.registry import ExportInputs

log = logging.getLogger(__name__)
NAME = "radtree_scene"


def radtree_meshes(scene: Scene, *, has_model: bool) -> list[Mesh]:
    """The scene's solid meshes radtree made (with a Honeybee model: all but the model's own
    ``hb_*`` meshes), empty ones left out."""
    return [m for m in scene.solid_meshes() if m.n_triangles
            and not (has_model and m.name.startswith(MESH_PREFIX))]


def scene_shades(scene: Scene, *, has_model: bool, prefix: str = "radtree") -> list[Any]:
    """One detached ``ShadeMesh`` per mesh of :func:`radtree_meshes`, with its modifier."""
    from honeybee.shademesh import ShadeMesh
    from honeybee.typing import clean_rad_string
    from ladybug_geometry.geometry3d import Mesh3D, Point3D

    if scene.media is not None and len(scene.media):
        raise RadtreeError("turbid-medium crowns have no surfaces to write as Honeybee shades: "
                           "export a scenario with representation = \"explicit\"")
    shades = []
    for m in radtree_meshes(scene, has_model=has_model):
        material = scene.materials[m.material]
        try:
            modifier = hb_modifier(material)
        except RadtreeError as exc:
            raise RadtreeError(f"mesh {m.name!r}: {exc} (export a scenario whose crown is "
                               "explicit geometry)") from None
        mesh = Mesh3D([Point3D(*map(float, v)) for v in m.vertices],
                      [tuple(int(i) for i in f) for f in m.faces])
        shade = ShadeMesh(clean_rad_string(f"{prefix}_{m.name}"), mesh, is_detached=True)
        shade.display_name = f"radtree {m.name}"
        shade.properties.radiance.modifier = modifier
        shades.append(shade)
    return shades


def export_hbjson_scene(inputs: ExportInputs, out: Path) -> list[Path]:
    """Format ``honeybee-scene`` (:mod:`radtree.export.registry`): ``radtree_scene.hbjson``."""
    built = inputs.built_scene()
    has_model = inputs.honeybee_model is not None
    shades = scene_shades(built.scene, has_model=has_model)
    if not shades:
        raise RadtreeError(f"scenario {inputs.scenario.name!r}: radtree added no geometry to "
                           "write")
    model = shade_model(inputs.project.name, shades, inputs.honeybee_model)
    path = write_hbjson(model, out, NAME)
    faces = sum(len(s.geometry.faces) for s in shades)
    log.info("%s: %d radtree meshes (%d faces) as ShadeMesh%s → %s", inputs.scenario.name,
             len(shades), faces, " in the project's Honeybee model" if has_model else "", path)
    return [path]
