"""The homogeneous crown: the envelope as one translucent sheet of uniform diffuse transmittance.

Material: ``trans`` with reflectance ``homogeneous.reflectance`` (leaf, 0.11) and diffuse
transmittance T (no specular part: light through the sheet is fully diffused, so Radiance
passes it only through ambient bounces).

* Sensor dome: the sensors see everything through the shell once, so T = permeability.
* Free-standing crowns: the envelope is closed (the wall-side clip face is part of it), so light
  reaching a façade sensor behind the crown crosses it twice — in and out — and
  T = √permeability, giving T² = permeability.

``homogeneous.transmittance`` set explicitly overrides that choice.
"""

from __future__ import annotations

from radtree.config import Sensors, Street, Tree
from radtree.errors import ConfigError
from radtree.optics import Plastic, Trans
from radtree.scene import Mesh
from radtree.site.frame import FacadeFrame
from radtree.trees.envelope import (
    crown_row_spec,
    dome_notes,
    dome_spec,
    icosphere_level,
    row_notes,
)
from radtree.trees.model import BARK_REFLECTANCE, SHELL, TRUNK, TreeModel

MIN_AB = 5  # ambient bounces: -ab 3 reads ≈ 4 % low on the reference-case dome (convergence check)


def shell_transmittance(tree: Tree, form: str) -> tuple[float, int, str]:
    """(T, crossings, how) for the homogeneous sheet in this form."""
    h = tree.homogeneous
    crossings = 1 if form == "dome" else 2
    if h.transmittance is not None:
        return h.transmittance, crossings, "set by homogeneous.transmittance"
    t = h.permeability ** (1.0 / crossings)
    how = ("= permeability (crossed once)" if crossings == 1
           else "= √permeability (crossed twice: in and out)")
    return t, crossings, how


def build_homogeneous(tree: Tree, sensors: Sensors, street: Street, frame: FacadeFrame,
                      form: str, source: str | None = None) -> TreeModel:
    h = tree.homogeneous
    t, crossings, how = shell_transmittance(tree, form)
    if not 0.0 <= h.reflectance <= 1.0:
        raise ConfigError(f"got {h.reflectance}, expected 0–1", source=source,
                          field="tree.homogeneous.reflectance")
    if not 0.0 <= t <= 1.0:
        raise ConfigError(f"got {t}, expected 0–1", source=source,
                          field="tree.homogeneous.transmittance")
    if t + h.reflectance > 1.0 + 1e-9:
        raise ConfigError(f"reflectance {h.reflectance:g} + transmittance {t:.4f} exceeds 1",
                          source=source, field="tree.homogeneous.transmittance")
    materials: dict = {SHELL: Trans(SHELL, h.reflectance, t, 0.0)}
    meshes: list[Mesh] = []
    info: dict[str, float] = {
        "transmittance": t, "reflectance": h.reflectance, "crossings": float(crossings),
        "crown_transmission": t**crossings, "permeability_target": h.permeability,
        "direct_transmission": 0.0,
    }
    notes: list[str] = []
    if form == "dome":
        spec = dome_spec(tree, sensors, street, source)
        rings = max(3, spec.segments // 4)
        verts, faces = spec.shell(rings)
        meshes.append(Mesh("crown_shell", SHELL, frame.to_world(verts), faces))
        info["dome_radius_m"] = spec.radius
        notes.extend(dome_notes(spec))
    else:
        spec_r = crown_row_spec(tree, sensors, street, source)
        level = icosphere_level(360.0 / tree.crown.segments)
        parts = []
        for i in range(spec_r.count):
            v, f, _ = spec_r.envelope(i, level)
            parts.append(Mesh(f"crown_shell_{i}", SHELL, v, f))
        shell = Mesh.merge("crown_shell", SHELL, parts)
        shell.vertices = frame.to_world(shell.vertices)
        meshes.append(shell)
        tv, tf = spec_r.trunks()
        materials[TRUNK] = Plastic(TRUNK, BARK_REFLECTANCE)
        meshes.append(Mesh("tree_trunks", TRUNK, frame.to_world(tv), tf))
        info["clip_plane_n_m"] = spec_r.n_clip
        notes.extend(row_notes(spec_r, tree, sensors))
        notes.append("The envelope is closed, including its wall-side face, so light reaching "
                     "the façade behind a crown crosses the sheet twice.")
    notes.append(
        f"Model: homogeneous — the envelope is one translucent sheet, diffuse transmittance "
        f"T = {t:.4f} ({how}), reflectance {h.reflectance:g}, no specular transmission; "
        f"the crown passes T^{crossings} = {t**crossings:.4f} of the light crossing it "
        f"(target permeability {h.permeability:g}).")
    ab = max(MIN_AB, crossings + 3)
    notes.append(f"Radiance: diffuse transmission only reaches the sensors through ambient "
                 f"bounces; -ab {ab} (the sheet's {crossings} crossing(s) + 3: -ab 3 reads "
                 f"about 4 % low on the reference-case dome, `radtree convergence`).")
    info["area_m2"] = float(sum(m.area() for m in meshes if m.material == SHELL))
    return TreeModel(meshes=meshes, materials=materials, notes=notes,
                     recommended_ab=ab, info=info, form=form, model="homogeneous")


__all__ = ["build_homogeneous", "shell_transmittance"]
