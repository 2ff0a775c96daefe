"""A scenario's crown BSDF: the planar sample of its crown layer, computed once with Radiance
and cached, and the BSDF crown (``[tree] representation = "bsdf"``) that carries it.

Leaf-on sample (:mod:`radtree.trees.slab`): the sensor dome's slat shells as a planar stack,
or a slab of the free volume crown at its fitted density, ``tree.bsdf.depth_m`` deep (0: the
crown's vertical semi-axis — two crossings of a vertical line through the centre add up to
the crown's height). The XML is cached in ``build/bsdf/<scenario>/leaf_on/`` under a key of
the sample's polygons, optics and rfluxmtx settings, so changing any of them recomputes it.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from pathlib import Path

from radtree.config import Project, Scenario
from radtree.config.schema import Tree
from radtree.engines.radiance.bsdf import (
    BsdfRun,
    FluxSettings,
    check_bsdf,
    klems_bsdf,
    tensor_tree_bsdf,
    write_system,
)
from radtree.errors import ConfigError
from radtree.fileio import write_text
from radtree.site.frame import FacadeFrame
from radtree.trees.bsdf_shell import build_bsdf_crown
from radtree.trees.build import apply_switches
from radtree.trees.model import TreeModel
from radtree.trees.slab import SlabSample, dome_slab, volume_slab
from radtree.trees.volume import recommended_volume_ab

#: -ab of a scene with a BSDF crown: every pass through the shell's Klems BSDF is an ambient
#: bounce. Measured on the Mendoza dome (scenario B, -ad 8192, façade mean): 12:30 / 14:30
#: read 1162 / 1169 lx at -ab 6 and 1148 / 1160 lx at -ab 8; -ab 4 (-ad 2048) read 1060 lx
#: at 14:30, ≈ 9 % low
BSDF_SCENE_AB = 6


def scenario_tree(project: Project, scenario: Scenario) -> tuple[Tree, str]:
    """The scenario's ``[tree]`` with its switches applied, and its form."""
    tree, _ = apply_switches(project.tree, scenario.switches, source=str(project.source),
                             root=project.root)
    return tree, scenario.form or tree.form


def slab_depth(tree: Tree) -> float:
    """One crossing's slab depth of a free crown (m): ``tree.bsdf.depth_m`` or the vertical
    semi-axis."""
    return tree.bsdf.depth_m if tree.bsdf.depth_m > 0 else tree.crown.vertical_radius_m


def band_elevations(tree: Tree, form: str) -> list[tuple[float, float, float]]:
    """(lowest, highest, sample) |elevation| of each band of the BSDF shell, degrees: the
    dome's ``tree.bsdf.bands`` equal bands sampled at their middles (one band: sampled at
    ``tree.bsdf.elevation_deg``); a free crown has one band."""
    n = tree.bsdf.bands if form == "dome" else 1
    if n == 1:
        return [(0.0, 90.0, tree.bsdf.elevation_deg)]
    step = 90.0 / n
    return [(k * step, (k + 1) * step, (k + 0.5) * step) for k in range(n)]


def leaf_on_sample(project: Project, scenario: Scenario,
                   elevation_deg: float | None = None) -> SlabSample:
    """The planar sample of the scenario's (louvers) crown layer (the dome's slats tilted as
    at ``elevation_deg``, default ``tree.bsdf.elevation_deg``)."""
    tree, form = scenario_tree(project, scenario)
    source = str(project.source)
    if scenario.model != "louvers":
        raise ConfigError(f"scenario '{scenario.name}' has model {scenario.model!r}: a crown "
                          "BSDF is computed from the louvers crown's slats", source=source,
                          field="scenario.model")
    if form == "dome":
        el = tree.bsdf.elevation_deg if elevation_deg is None else elevation_deg
        return dome_slab(tree, project.sensors, project.street, el, source)
    if tree.louvers.arrangement != "volume":
        raise ConfigError("free crowns need louvers.arrangement = 'volume' for a BSDF (the "
                          "layered lens crowns are no planar slab)", source=source,
                          field="tree.louvers.arrangement")
    return volume_slab(tree.louvers, tree.crown.vertical_radius_m, slab_depth(tree), source)


def sample_ab(tree: Tree, form: str) -> int:
    """rfluxmtx -ab: ``tree.bsdf.ab``, else the explicit crown's (layers + 2, or the volume's)."""
    if tree.bsdf.ab > 0:
        return tree.bsdf.ab
    return tree.louvers.layers + 2 if form == "dome" else recommended_volume_ab(tree.louvers)


def flux_settings(tree: Tree, form: str, nproc: int = 1) -> FluxSettings:
    b = tree.bsdf
    return FluxSettings(samples=b.samples, ab=sample_ab(tree, form), ad=b.ad, lw=b.lw,
                        tiles=b.tiles, nproc=nproc, tensor_tree=b.tensor_tree)


def sample_key(sample: SlabSample, settings: FluxSettings) -> str:
    h = hashlib.sha256()
    for name in sorted(sample.polygons):
        h.update(name.encode())
        h.update(sample.polygons[name].round(7).tobytes())
        h.update(sample.materials[name].to_radiance().encode())
    h.update(json.dumps([sample.width, sample.height, sample.thickness, repr(settings)]).encode())
    return h.hexdigest()[:16]


def ensure_bsdf(sample: SlabSample, settings: FluxSettings, folder: Path, name: str,
                progress: Callable[[str], None] | None = None) -> BsdfRun:
    """The XML of ``sample`` in ``folder`` (``<name>.xml``): reused when its key matches,
    else computed (rfluxmtx, wrapBSDF, checkBSDF)."""
    key = sample_key(sample, settings)
    xml, key_file = folder / f"{name}.xml", folder / "key.txt"
    if xml.exists() and key_file.exists() and key_file.read_text().strip() == key:
        tt = folder / f"{name}_t4.xml"
        return BsdfRun(xml, check_bsdf(xml), 0.0, tt if tt.exists() else None)
    write_system(folder, sample.polygons, sample.materials, sample.width, sample.height,
                 sample.thickness, settings.tiles)
    comment = f"radtree crown BSDF: {sample.name}; " + " ".join(sample.notes)
    result = klems_bsdf(folder, settings, name, sample.thickness, sample.width, sample.height,
                        comment=comment[:900], progress=progress)
    if settings.tensor_tree:
        result.tensor_xml = tensor_tree_bsdf(folder, settings, name, sample.thickness,
                                             sample.width, sample.height)
    write_text(key_file, key + "\n")
    return result


def scenario_xmls(project: Project, scenario: Scenario,
                  progress: Callable[[str], None] | None = None
                  ) -> list[tuple[float, float, Path]]:
    """The leaf-on XML of each band of ``scenario``'s BSDF shell, (lowest, highest |elevation|,
    XML): ``tree.bsdf.xml`` for every band when given, else computed and cached in
    ``build/bsdf/<scenario>/leaf_on[_b<k>]/``."""
    tree, form = scenario_tree(project, scenario)
    bands = band_elevations(tree, form)
    if tree.bsdf.xml is not None:
        check_bsdf(Path(tree.bsdf.xml))
        return [(lo, hi, Path(tree.bsdf.xml)) for lo, hi, _ in bands]
    out = []
    for k, (lo, hi, el) in enumerate(bands):
        name = "leaf_on" if len(bands) == 1 else f"leaf_on_b{k}"
        folder = project.build_dir / "bsdf" / scenario.name / name
        run = ensure_bsdf(leaf_on_sample(project, scenario, el), flux_settings(tree, form),
                          folder, name, progress)
        out.append((lo, hi, run.xml))
    return out


def bsdf_crown(project: Project, scenario: Scenario, frame: FacadeFrame) -> TreeModel | None:
    """The BSDF crown of ``scenario`` when its ``tree.representation`` is ``"bsdf"``, else None."""
    tree, form = scenario_tree(project, scenario)
    if tree.representation != "bsdf" or scenario.model == "none":
        return None
    model = build_bsdf_crown(tree, project.sensors, project.street, frame, form,
                             scenario_xmls(project, scenario), BSDF_SCENE_AB,
                             str(project.source))
    model.frame = frame
    model.triangles = sum(m.n_triangles for m in model.meshes)
    model.info["triangles"] = float(model.triangles)
    return model
