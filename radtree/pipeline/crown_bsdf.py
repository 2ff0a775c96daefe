"""A scenario's crown BSDF: the planar sample of its crown layer, computed once with Radiance
and cached, and the BSDF crown (``[tree] representation = "bsdf"``) that carries it.

Leaf-on sample (:mod:`radtree.trees.slab`): the sensor dome's slat shells as a planar stack,
or, for a free volume crown, slabs at its fitted density whose optical depth at incidence θ is
the half chord ``tree.bsdf.depth_m`` · cos θ of a sphere (one sample per Klems ring;
``tree.bsdf.crossing = "slab"``: one slab ``depth_m`` deep; ``depth_m`` 0: the crown's
vertical semi-axis — two crossings of a vertical line through the centre add up to the
crown's height). The XML is cached in ``build/bsdf/<scenario>/leaf_on/`` under a key of
the sample's polygons, optics and rfluxmtx settings, so changing any of them recomputes it.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from radtree.config import Project, Scenario
from radtree.config.schema import Tree
from radtree.engines.radiance.bsdf import (
    XML_VERSION,
    BsdfRun,
    FluxSettings,
    check_bsdf,
    klems_bsdf,
    klems_bsdf_rings,
    tensor_tree_bsdf,
    write_system,
)
from radtree.engines.radiance.materials import material_text
from radtree.errors import ConfigError
from radtree.fileio import write_text
from radtree.pipeline.dome_curvature import (
    CURVATURE_PATHS,
    CURVATURE_VERSION,
    CurvedDome,
    curved_dome,
    curved_ring_row,
    write_curved_xml,
)
from radtree.pipeline.wall_cap import (
    PatchDepthSample,
    depth_bsdf,
    wall_cap_sample,
    write_systems,
)
from radtree.site.frame import FacadeFrame
from radtree.trees.bsdf_shell import WALL_BAND, build_bsdf_crown, sector_bounds
from radtree.trees.build import apply_switches
from radtree.trees.envelope import crown_row_spec
from radtree.trees.model import TreeModel
from radtree.trees.slab import RingSamples, SlabSample, chord_samples, dome_slab, volume_slab
from radtree.trees.volume import recommended_volume_ab

#: -ab of a scene with a BSDF crown: every pass through the shell's Klems BSDF is an ambient
#: bounce, and the Mendoza dome's façade mean settles by -ab 6 (-ab 4 reads ≈ 9 % low);
#: `radtree convergence PROJECT` prints the ladder, figures in CHANGELOG.md
BSDF_SCENE_AB = 6
#: thinnest chord-ring slab, in slat sizes (a thinner slab is no random medium of slats)
CHORD_MIN_SLATS = 2.0


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
    """(lowest, highest, sample) |elevation| of each band of the BSDF shell, degrees:
    ``tree.bsdf.bands`` equal bands sampled at their middles (one band: sampled at
    ``tree.bsdf.elevation_deg``). The dome's elevation is that of the shell seen from the
    dome centre (its slats turn with it); a free crown's that of the facet's outward normal
    (its slats keep their inclination from the vertical, so a side facet sees them turned).
    A free crown with ``tree.bsdf.crossing = "slab"`` has one band, its slats inclined from
    the facet normal (the representation before the chord envelope)."""
    n = 1 if form != "dome" and tree.bsdf.crossing == "slab" else tree.bsdf.bands
    if n == 1:
        el = 90.0 if form != "dome" and tree.bsdf.crossing == "slab" else tree.bsdf.elevation_deg
        return [(0.0, 90.0, el)]
    step = 90.0 / n
    return [(k * step, (k + 1) * step, (k + 0.5) * step) for k in range(n)]


def wall_half_chord(tree: Tree, sensors, street, source: str | None = None) -> float:
    """Half chord (m) of a free crown's wall cap — the distance from the crown centre to the
    wall-side clip plane — or 0 when the crowns do not reach it.

    A line from a point S on the cap to the envelope point P runs b + R cos θ_P inside the
    crown, b = (C − S)·u: for S at the cap's foot point b = h cos ψ (h the centre's distance,
    ψ the angle from the cap normal) — a chord crossing of half chord h."""
    spec = crown_row_spec(tree, sensors, street, source)
    h = float(spec.centres[0][1] - spec.n_clip)
    return h if h < spec.a else 0.0


def leaf_on_sample(project: Project, scenario: Scenario,
                   elevation_deg: float | None = None, half_chord_m: float | None = None
                   ) -> SlabSample | RingSamples:
    """The planar sample of the scenario's (louvers) crown layer: the dome's slats tilted as
    at ``elevation_deg`` (default ``tree.bsdf.elevation_deg``); a free crown's for an envelope
    facet whose outward normal is ``elevation_deg`` above the horizon (default: the first
    band's, :func:`band_elevations`), crossed along the half chord ``half_chord_m`` · cos θ
    (default :func:`slab_depth`)."""
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
    lv, semi = tree.louvers, tree.crown.vertical_radius_m
    if tree.bsdf.crossing == "slab":
        return volume_slab(lv, semi, slab_depth(tree), source)
    el = band_elevations(tree, form)[0][2] if elevation_deg is None else elevation_deg
    half = slab_depth(tree) if half_chord_m is None else half_chord_m
    on_normal = volume_slab(lv, semi, half, source, normal_elevation_deg=el)
    return chord_samples(lambda d, c: volume_slab(lv, semi, d, source, c, el), half,
                         CHORD_MIN_SLATS * lv.slat_size_m, "volume_leaf_on",
                         on_normal.notes[:1])


def sample_ab(tree: Tree, form: str) -> int:
    """rfluxmtx -ab: ``tree.bsdf.ab``, else the explicit crown's (layers + 2, or the volume's)."""
    if tree.bsdf.ab > 0:
        return tree.bsdf.ab
    return tree.louvers.layers + 2 if form == "dome" else recommended_volume_ab(tree.louvers)


def flux_settings(tree: Tree, form: str, nproc: int = 1) -> FluxSettings:
    b = tree.bsdf
    return FluxSettings(samples=b.samples, ab=sample_ab(tree, form), ad=b.ad, lw=b.lw,
                        tiles=b.tiles, nproc=nproc, tensor_tree=b.tensor_tree)


def sample_key(sample: SlabSample | RingSamples | PatchDepthSample,
               settings: FluxSettings) -> str:
    h = hashlib.sha256()
    slabs = sample.rings if isinstance(sample, (RingSamples, PatchDepthSample)) else [sample]
    if isinstance(sample, PatchDepthSample):
        h.update(sample.key_bytes())
    for slab in slabs:
        for name in sorted(slab.polygons):
            h.update(name.encode())
            h.update(slab.polygons[name].round(7).tobytes())
            h.update(material_text(slab.materials[name]).encode())
        h.update(json.dumps([slab.width, slab.height, slab.thickness]).encode())
    # rfluxmtx -n only splits the work: not part of the key
    h.update(json.dumps([sample.thickness, repr(replace(settings, nproc=1)),
                         XML_VERSION]).encode())
    return h.hexdigest()[:16]


def ensure_bsdf(sample: SlabSample | RingSamples | PatchDepthSample, settings: FluxSettings,
                folder: Path, name: str) -> BsdfRun:
    """The XML of ``sample`` in ``folder`` (``<name>.xml``): reused when its key matches,
    else computed (rfluxmtx, wrapBSDF, checkBSDF; an envelope sample: one system per Klems
    ring in ``folder/ring<k>/``)."""
    key = sample_key(sample, settings)
    xml, key_file = folder / f"{name}.xml", folder / "key.txt"
    if xml.exists() and key_file.exists() and key_file.read_text().strip() == key:
        tt = folder / f"{name}_t4.xml"
        return BsdfRun(xml, check_bsdf(xml), 0.0, tt if tt.exists() else None)
    comment = (f"radtree crown BSDF: {sample.name}; " + " ".join(sample.notes))[:900]
    if isinstance(sample, PatchDepthSample):
        result = depth_bsdf(folder, sample, settings, name, comment)
        write_text(key_file, key + "\n")
        return result
    if isinstance(sample, RingSamples):
        if settings.tensor_tree:
            raise ConfigError("tree.bsdf.tensor_tree needs tree.bsdf.crossing = 'slab' (the "
                              "chord envelope is assembled ring by ring in the Klems basis)",
                              field="tree.bsdf.tensor_tree")
        subs = write_systems(folder, "ring", sample.rings, settings.tiles)
        result = klems_bsdf_rings(folder, ring_folders=subs, settings=settings, name=name,
                                  thickness=sample.thickness, width=sample.width,
                                  height=sample.height, comment=comment)
        write_text(key_file, key + "\n")
        return result
    write_system(folder, sample.polygons, sample.materials, sample.width, sample.height,
                 sample.thickness, settings.tiles)
    result = klems_bsdf(folder, settings, name, sample.thickness, sample.width, sample.height,
                        comment=comment)
    if settings.tensor_tree:
        result.tensor_xml = tensor_tree_bsdf(folder, settings, name, sample.thickness,
                                             sample.width, sample.height)
    write_text(key_file, key + "\n")
    return result


def scenario_xmls(project: Project, scenario: Scenario) -> list[tuple[float, float, Path]]:
    """The leaf-on XML of each band of ``scenario``'s BSDF shell, (lowest, highest |elevation|,
    XML) — for a dome with ``tree.bsdf.sectors`` > 1 one entry per band and sector
    (band-major, :func:`radtree.trees.bsdf_shell.sector_bounds`): ``tree.bsdf.xml`` for every
    band when given, else computed and cached in
    ``build/bsdf/<scenario>/leaf_on[_b<k>]/``. A free crown with the chord crossing that
    reaches the wall adds its wall cap as a last entry :data:`WALL_BAND` (its own half chord,
    :func:`wall_half_chord`; ``leaf_on_wall/``)."""
    tree, form = scenario_tree(project, scenario)
    bands = band_elevations(tree, form)
    if tree.bsdf.xml is not None:
        check_bsdf(Path(tree.bsdf.xml))
        copies = tree.bsdf.sectors if form == "dome" else 1
        return [(lo, hi, Path(tree.bsdf.xml)) for lo, hi, _ in bands for _ in range(copies)]
    settings = flux_settings(tree, form, os.cpu_count() or 1)
    jobs: list[tuple[str, float, float, float, float | None]] = [
        ("leaf_on" if len(bands) == 1 else f"leaf_on_b{k}", lo, hi, el, None)
        for k, (lo, hi, el) in enumerate(bands)]
    if form != "dome" and tree.bsdf.crossing == "chord":
        h = wall_half_chord(tree, project.sensors, project.street, str(project.source))
        if h > 0:
            jobs.append(("leaf_on_wall", *WALL_BAND, 0.0, h))
    out = []
    dome: list[CurvedDome] = []   # the explicit dome, built once for all bands that need it

    def curved() -> CurvedDome:
        if not dome:
            dome.append(curved_dome(project, scenario, tree))
        return dome[0]

    sectors = sector_bounds(tree.bsdf.sectors) if form == "dome" else [(-90.0, 90.0)]
    for name, lo, hi, el, half in jobs:
        folder = project.build_dir / "bsdf" / scenario.name / name
        sample: SlabSample | RingSamples | PatchDepthSample
        if (lo, hi) == WALL_BAND and tree.bsdf.wall_depth == "sensors":
            sample = wall_cap_sample(project, scenario, tree, slab_depth(tree),
                                     CHORD_MIN_SLATS * tree.louvers.slat_size_m)
        else:
            sample = leaf_on_sample(project, scenario, el, half)
        run = ensure_bsdf(sample, settings, folder, name)
        for sector in sectors:
            xml = run.xml
            if (form == "dome" and tree.bsdf.curvature != "planar"
                    and not isinstance(sample, PatchDepthSample)):
                xml = ensure_curved(project, tree, curved, sample, settings, folder=folder,
                                    name=name, band=(lo, hi),
                                    sector=sector if len(sectors) > 1 else None)
            out.append((lo, hi, xml))
    return out


def ensure_curved(project: Project, tree: Tree, dome: Callable[[], CurvedDome],
                  sample: SlabSample | RingSamples, settings: FluxSettings, *, folder: Path,
                  name: str, band: tuple[float, float],
                  sector: tuple[float, float] | None = None) -> Path:
    """The dome band's XML (``band``: its lowest and highest |elevation|, degrees) with the view from the centre traced through the curved slats
    (``dome()``, :mod:`radtree.pipeline.dome_curvature`), in ``folder/curved/``; reused when
    the planar sample's key and the trace's settings match. ``sector``: (lowest, highest)
    horizontal angle from the façade normal of the part of the band traced
    (``tree.bsdf.sectors``; in ``folder/curved_s<lo>_<hi>/``), None: the whole band."""
    lo, hi = band
    per = "ring" if tree.bsdf.curvature == "rings" else "patch"
    span = (-90.0, 90.0) if sector is None else sector
    key = (f"{sample_key(sample, settings)}|{lo:g}|{hi:g}|{CURVATURE_PATHS}|{per}|v{CURVATURE_VERSION}|"
           f"{tree.louvers.seed}|{tree.dome.radius_m:g}|{project.sensors.radius_m:g}|"
           f"{project.sensors.offset_m:g}|{project.street.facade_azimuth_deg:g}"
           + ("" if sector is None else f"|{span[0]:g}|{span[1]:g}"))
    tag = "" if sector is None else f"_s{span[0]:g}_{span[1]:g}"
    sub = folder / f"curved{tag}"
    xml, key_file = sub / f"{name}_curved{tag}.xml", sub / "key.txt"
    if xml.exists() and key_file.exists() and key_file.read_text().strip() == key:
        return xml
    row = curved_ring_row(dome(), lo, hi, CURVATURE_PATHS, workers=os.cpu_count() or 1,
                          sector_deg=span)
    where = "" if sector is None else f", {span[0]:g}° to {span[1]:g}° from the façade normal"
    comment = (f"radtree crown BSDF: {sample.name}, curved dome |elevation| {lo:g}–{hi:g}°"
               f"{where}: the normal-outgoing row traced per {per} through the dome's slats "
               f"({row.paths} paths); "
               + " ".join(sample.notes))[:900]
    out, _ = write_curved_xml(folder, sub, f"{name}_curved{tag}", row,
                              size=(sample.thickness, sample.width, sample.height),
                              comment=comment, per=per)
    check_bsdf(out)
    write_text(key_file, key + "\n")
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
