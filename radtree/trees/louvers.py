"""The louvers crown: inclined leaf slats in ``layers`` filtration stages.

Optics (one ``trans`` material ``leaf``): reflectance R, transmittance T split into a specular
(undeviated) part T_s = T·specular_fraction and a diffuse part T_d = T·(1 − specular_fraction).
Each layer covers a fraction f (``cover_fraction``) of the area it spans *as seen along the
beam the layer is built for*, so a beam meets in each layer a slat with probability f and
otherwise a gap. The direct (specular) transmission of one layer and of the crown are

    τ_layer = (1 − f) + f·T_s            τ_crown = τ_layer ** layers

and, counting diffusely transmitted light as if it went on forward (an upper bound of the
first-order energy), τ'_layer = (1 − f) + f·T. Slat positions are independent between layers,
so for random (jittered) placement the stack's expected transmission is exactly τ_layer^N.

Two readings of the study's "slat-layer transmittance 0.5" (the reference case, "first physical check"):

* **study reading** — cover 1 and a slat material with T = 0.5 (R 0.11): the 0.5 is an
  *effective per-layer* transmission (gaps + leaf), put into the material.
* **gap reading** — near-opaque leaves (T ≈ 0.05 diffuse, R 0.11) covering ≈ 50 % of each layer,
  so ≈ 50 % passes each layer through gaps (direct, no ambient bounce needed).

Switch between them with the scenario switch ``"louvers.reading" = "study" | "gap"`` (presets
in :data:`radtree.config.LOUVER_READINGS`) or by setting the fields. The notes always say which reading is in use.

Geometry
--------
Slats are planar quadrilaterals of side ≈ ``slat_size_m`` s, inclined ``inclination_deg`` α
from the horizontal (leaf inclination). In each layer they sit in rows packed side by side
across (a row is one slat high), and along a row in cells of length s/f, one slat of length s
at a random place in each cell (f = 1: the cells are the slats). Rows are offset from one
another so that slat centres form a staggered (triangular) grid — with a random component: a
regular lattice would give two layers' gap patterns a moiré that biases the stack's
transmission away from τ_layer^N. Branches inclined ``branch_inclination_deg`` β: in the
dome, each row is shifted along the previous one by (row height)/tan β (± a random quarter
cell), so slat centres line up along 40° branches locally; in the free crowns, slats come in
branches of three along a row that climb at β. Randomness comes from ``louvers.seed``.

Built by form and arrangement:

* sensor dome: concentric shells of slats (:mod:`radtree.trees.louvers_dome`);
* free-standing crowns: nested lens-shaped layers (:mod:`radtree.trees.louvers_free`), or
  slats at random through the crown volume (``arrangement = "volume"``,
  :mod:`radtree.trees.volume`); both share the trunk test and the wall-side / neighbour-plane
  cutting of :mod:`radtree.trees.crown_clip`. The dome keeps its shells ("volume" with the
  dome form is an error).

This module holds the optics (:class:`LouverOptics`), the field checks and
:func:`build_louvers`, which assembles the crown model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from radtree.config import LOUVER_ARRANGEMENTS, Louvers, Sensors, Street, Tree
from radtree.errors import ConfigError
from radtree.optics import Plastic, Trans
from radtree.scene import Mesh
from radtree.site.frame import FacadeFrame
from radtree.trees.envelope import crown_row_spec, dome_notes, dome_spec, row_notes
from radtree.trees.geometry import flat_polygons_to_mesh, polygons_to_mesh, quads_to_mesh
from radtree.trees.louvers_dome import build_dome_louvers
from radtree.trees.louvers_free import BRANCH_SLATS, build_free_louvers
from radtree.trees.model import BARK_REFLECTANCE, LEAF, TRUNK, TreeModel
from radtree.trees.photo import photo_source, require_direction, with_source
from radtree.trees.photo_cut import dome_from_photo
from radtree.trees.volume import (
    build_volume_louvers,
    recommended_volume_ab,
    volume_ab_note,
    volume_note,
)


# ---------------------------------------------------------------- optics
@dataclass(frozen=True)
class LouverOptics:
    reflectance: float
    transmittance: float
    specular_fraction: float
    cover_fraction: float
    layers: int

    @classmethod
    def of(cls, lv: Louvers) -> LouverOptics:
        return cls(lv.reflectance, lv.transmittance, lv.specular_fraction, lv.cover_fraction,
                   lv.layers)

    @property
    def t_specular(self) -> float:
        return self.transmittance * self.specular_fraction

    @property
    def t_diffuse(self) -> float:
        return self.transmittance * (1.0 - self.specular_fraction)

    @property
    def tau_layer_direct(self) -> float:
        f = self.cover_fraction
        return (1.0 - f) + f * self.t_specular

    @property
    def tau_crown_direct(self) -> float:
        return self.tau_layer_direct ** self.layers

    @property
    def tau_layer_global(self) -> float:
        f = self.cover_fraction
        return (1.0 - f) + f * self.transmittance

    @property
    def tau_crown_global(self) -> float:
        return self.tau_layer_global ** self.layers

    @property
    def reading(self) -> str:
        if self.cover_fraction >= 0.999 and self.transmittance >= 0.3:
            return "study"
        if self.cover_fraction < 0.999 and self.transmittance <= 0.15:
            return "gap"
        return "custom"

    def material(self) -> Trans:
        return Trans(LEAF, self.reflectance, self.t_diffuse, self.t_specular)

    def describe_slat(self) -> str:
        """The slat material alone (volume arrangement: no layers)."""
        return (f"{self.reading} reading: slat R {self.reflectance:g}, T {self.transmittance:g} "
                f"(specular {self.t_specular:.4f}, diffuse {self.t_diffuse:.4f}); cover "
                f"{self.cover_fraction:.3f} scales the slat density")

    def describe(self) -> str:
        r = self.reading
        head = {
            "study": "study reading — each layer fully covered (cover 1) by slats whose "
                     "material carries the study's effective per-layer transmission",
            "gap": "gap reading — near-opaque leaves, light passes each layer mainly through "
                   "the gaps left by the cover fraction",
            "custom": "custom reading (neither the study's cover 1 / T 0.5 nor near-opaque "
                      "leaves in half-covered layers)",
        }[r]
        return (f"{head}: {self.layers} layers, cover {self.cover_fraction:.3f}, slat R "
                f"{self.reflectance:g}, T {self.transmittance:g} (specular "
                f"{self.t_specular:.4f}, diffuse {self.t_diffuse:.4f}); direct transmission "
                f"per layer {self.tau_layer_direct:.4f}, crown {self.tau_crown_direct:.5f}; "
                f"counting diffuse transmission as forward: per layer "
                f"{self.tau_layer_global:.4f}, crown {self.tau_crown_global:.5f}")


def required_cover(target: float, layers: int, t_specular: float) -> float:
    """Cover fraction giving a crown direct transmission ``target`` with ``layers`` layers
    (may fall outside (0, 1]: then that layer count cannot reach the target)."""
    tau = target ** (1.0 / layers)
    return (1.0 - tau) / (1.0 - t_specular) if t_specular < 1.0 else float("nan")


def check_louvers(lv: Louvers, source: str | None = None) -> None:
    def err(name: str, msg: str) -> ConfigError:
        return ConfigError(msg, source=source, field=f"tree.louvers.{name}")

    if lv.layers < 1:
        raise err("layers", f"got {lv.layers}, expected at least 1")
    if not 1 <= lv.realisations <= 64:
        raise err("realisations", f"got {lv.realisations}, expected 1–64")
    for name in ("cover_fraction", "reflectance", "transmittance", "specular_fraction"):
        v = getattr(lv, name)
        if not 0.0 <= v <= 1.0:
            raise err(name, f"got {v}, expected 0–1")
    if lv.cover_fraction <= 0.0:
        raise err("cover_fraction", "got 0: a layer without slats (use model 'none')")
    if lv.reflectance + lv.transmittance > 1.0 + 1e-9:
        raise err("transmittance", f"reflectance {lv.reflectance:g} + transmittance "
                                   f"{lv.transmittance:g} exceeds 1")
    if not 0.02 <= lv.slat_size_m <= 3.0:
        raise err("slat_size_m", f"got {lv.slat_size_m}, expected 0.02–3 m")
    if not 0.0 <= lv.inclination_deg <= 90.0:
        raise err("inclination_deg", f"got {lv.inclination_deg}, expected 0–90°")
    if not 0.0 < lv.branch_inclination_deg < 90.0:
        raise err("branch_inclination_deg",
                  f"got {lv.branch_inclination_deg}, expected between 0 and 90° (exclusive)")
    if lv.arrangement not in LOUVER_ARRANGEMENTS:
        raise err("arrangement", f"got {lv.arrangement!r}, expected one of "
                                 f"{', '.join(LOUVER_ARRANGEMENTS)}")
    if not (math.isfinite(lv.crossings) and 0.0 <= lv.crossings <= 60.0):
        raise err("crossings", f"got {lv.crossings}, expected 0–60 slats on a vertical line "
                               "(0: use layers)")


# ---------------------------------------------------------------- entry point
@dataclass
class _Slats:
    """One form's slats before assembly: local-frame mesh (``verts`` m, ``faces``), the crown
    each face belongs to (free crowns), what was built (``ginfo``), notes, the louvers in
    force (a photo fit replaces the configured ones), and whether slats fill the volume."""

    verts: np.ndarray
    faces: np.ndarray
    count: int
    ginfo: dict[str, float]
    notes: list[str]
    lv: Louvers
    volume: bool
    owners: np.ndarray | None = None
    photo: dict | None = None
    trunks: Mesh | None = None


def build_louvers(tree: Tree, *, sensors: Sensors, street: Street, frame: FacadeFrame,
                  form: str, source: str | None = None) -> TreeModel:
    """The louvers crown of ``tree`` in ``form`` (``dome`` | ``free``), in world space
    (``frame``: the façade frame; x east, y north, z up, m): check, build the form's slats,
    then assemble the model with its notes, recommended ``-ab`` and info."""
    lv = tree.louvers
    check_louvers(lv, source)
    _check_form(tree, form, source)
    optics = LouverOptics.of(lv)
    if form == "dome":
        part = _dome_slats(tree, sensors=sensors, street=street, source=source)
    else:
        part = _free_slats(tree, sensors=sensors, street=street, frame=frame, source=source)
    materials: dict = {LEAF: optics.material()}
    meshes = [Mesh("tree_leaves", LEAF, frame.to_world(part.verts), part.faces, part.owners)]
    if part.trunks is not None:
        materials[TRUNK] = Plastic(TRUNK, BARK_REFLECTANCE)
        meshes.append(part.trunks)
    from_points = tree.points is not None
    notes = [*part.notes, *_arrangement_notes(tree, part, optics, form=form)]
    volume = part.volume or from_points  # slats through the volume: its optics and -ab
    notes.extend(_optics_notes(optics, volume=volume))
    ab, ab_note = _recommended_ab(part.lv, volume=volume)
    notes.append(ab_note)
    info = _louvers_info(part, optics, volume=volume, from_points=from_points)
    return TreeModel(meshes=meshes, materials=materials, notes=notes, recommended_ab=ab,
                     info=info, form=form, model="louvers", photo=part.photo)


def _check_form(tree: Tree, form: str, source: str | None) -> None:
    """The form and arrangement go together: the dome keeps its shells; a crown from points
    is free-standing and fitted to no photo."""
    if form == "dome" and tree.louvers.arrangement == "volume":
        raise ConfigError("got arrangement 'volume' with the sensor-dome form: the dome keeps "
                          "its concentric slat shells; use arrangement = 'layers' or form "
                          "'free'", source=source, field="tree.louvers.arrangement")
    if tree.points is not None and (form == "dome" or tree.photo is not None):
        raise ConfigError("a crown from points is free-standing and fitted to no photo: use "
                          "form = 'free' and no [tree] photo", source=source,
                          field="tree.points")


def _dome_slats(tree: Tree, *, sensors: Sensors, street: Street,
                source: str | None) -> _Slats:
    """The sensor dome's concentric shells of slats, cut by the façade photo if any."""
    lv = tree.louvers
    spec = dome_spec(tree, sensors, street, source)
    quads, ginfo = build_dome_louvers(spec, lv, sensors, source)
    src = photo_source(tree) if tree.photo is not None else None
    photo = None
    notes = list(dome_notes(spec))
    if src is None:
        verts, faces = quads_to_mesh(quads)
    else:
        points, corners, photo_info, photo = dome_from_photo(quads, spec.centre, src, source)
        verts, faces = flat_polygons_to_mesh(points, corners)
        ginfo.update(photo_info)
        notes.append(
            f"Cut by the façade photo {src.path.name} ({src.lens} lens; {tree.photo}): in "
            f"every shell the slats are removed where the photo shows sky along the line "
            f"from the dome centre ({int(photo_info['photo_slats_removed'])} slats removed, "
            f"{int(photo_info['photo_slats_cut'])} cut, "
            f"{int(photo_info['photo_slats_whole'])} whole; photo openness "
            f"{photo_info['photo_openness']:.4f}).")
    notes.append(
        f"Louvers: {lv.layers} concentric shells of slats at radii "
        f"{ginfo['layer_radius_min_m']:.2f}–{ginfo['layer_radius_max_m']:.2f} m; each "
        f"shell covers {100 * lv.cover_fraction:.1f} % of the directions from the dome "
        f"centre, so every direction from it crosses {lv.layers} filtration stages. "
        f"{len(quads)} slats of ≈ {lv.slat_size_m:g} m (sides "
        f"{ginfo['slat_side_min_m']:.2f}–{ginfo['slat_side_max_m']:.2f} m), inclined "
        f"{lv.inclination_deg:g}° from horizontal, rows sheared along "
        f"{lv.branch_inclination_deg:g}° branches.")
    return _Slats(verts, faces, len(quads), ginfo, notes, lv, volume=False, photo=photo)


def _free_slats(tree: Tree, *, sensors: Sensors, street: Street, frame: FacadeFrame,
                source: str | None) -> _Slats:
    """The free-standing crown row: slats from points, through the volume (also when fitted
    to an upward photo) or in nested layers; trunks; each face's crown."""
    lv = tree.louvers
    volume = lv.arrangement == "volume"
    spec_r = crown_row_spec(tree, sensors, street, source)
    notes: list[str] = []
    photo = None
    src = photo_source(tree) if tree.photo is not None else None
    if src is not None:
        lv, photo, fit_notes = _fit_to_photo(tree, src, spec_r, sensors=sensors, frame=frame,
                                             source=source)
        notes.extend(fit_notes)
        volume = True
    if tree.points is not None:
        from radtree.trees.points_crown import build_points_louvers

        polys, ginfo, _ = build_points_louvers(spec_r, tree, source)
    elif volume:
        polys, ginfo = build_volume_louvers(spec_r, lv, source)
    else:
        polys, ginfo = build_free_louvers(spec_r, lv, source)
    verts, faces = polygons_to_mesh(polys)
    owners = spec_r.crown_ids(verts[faces].mean(axis=1)) if len(faces) else None
    tv, tf = spec_r.trunks()
    trunks = Mesh("tree_trunks", TRUNK, frame.to_world(tv), tf, spec_r.trunk_ids(len(tf)))
    notes.extend(row_notes(spec_r, tree, sensors))
    ginfo["clip_plane_n_m"] = spec_r.n_clip
    return _Slats(verts, faces, len(polys), ginfo, notes, lv, volume=volume, owners=owners,
                  photo=photo, trunks=trunks)


def _fit_to_photo(tree: Tree, src: Any, spec_r: Any, *, sensors: Sensors, frame: FacadeFrame,
                  source: str | None) -> tuple[Louvers, dict, list[str]]:
    """The free crowns' louvers fitted to an upward photo (:mod:`radtree.trees.photo_fit`):
    (fitted louvers, the photo's provenance, notes)."""
    try:
        require_direction(src, "upward", "the free louvers crowns")
    except ConfigError as exc:
        raise with_source(exc, source) from None
    from radtree.trees.photo_fit import camera_point, fitted_louvers

    lv, fit, photo = fitted_louvers(tree.louvers, src, spec_r, camera_point(tree, sensors),
                                    frame, source, tree.accept_poor_fit)
    notes = []
    if fit.problems():
        notes.append("POOR PHOTO FIT ACCEPTED ([tree] accept_poor_fit = true): "
                     + "; ".join(fit.problems()) + ".")
    tilt = (f"leaf inclinations from Campbell's ellipsoidal distribution, x = "
            f"{fit.x:.3g} (mean tilt {fit.mean_tilt_deg:.1f}°)" if fit.x is not None
            else f"slats fixed at {lv.inclination_deg:g}°")
    notes.append(
        f"Fitted to the upward photo {src.path.name} ({src.lens} lens; camera "
        f"{tree.photo_x_m:g} m along the façade from the sensors, "
        f"{tree.photo_distance_m:g} m out, {tree.photo_height_m:g} m high; zenith "
        f"0–{src.zenith_deg:g}°): leaf area density {fit.lad:.3f} m²/m³, {tilt}; "
        f"vertical crossings {lv.crossings:.2f}; gap-fraction RMS {fit.rms:.4f} "
        f"(cells), {fit.ring_rms:.4f} (rings); the photo's LAI_eff "
        f"{fit.lai_photo:.3f}, clumping {fit.clumping_photo:.3f} "
        + _clumping_fit_text(fit) + _spread_text(fit.spread()))
    return lv, photo, notes


def _arrangement_notes(tree: Tree, part: _Slats, optics: LouverOptics, *,
                       form: str) -> list[str]:
    """What the free crowns' arrangement built (points, volume or nested layers)."""
    lv, ginfo, slats = part.lv, part.ginfo, part.count
    if tree.points is not None:
        from radtree.trees.points_crown import points_note

        return [points_note(tree, ginfo, slats)]
    if part.volume:
        return [volume_note(lv, ginfo, slats, optics.t_specular)]
    if form == "dome":
        return []
    return [
        f"Louvers: {lv.layers} nested lens-shaped layers per crown (every vertical line "
        f"through a crown crosses {lv.layers}); each layer covers "
        f"{100 * lv.cover_fraction:.1f} % of its plan area with {lv.slat_size_m:g} m "
        f"square slats inclined {lv.inclination_deg:g}°, in branches of {BRANCH_SLATS} "
        f"climbing at {lv.branch_inclination_deg:g}°; {slats} slats "
        f"({int(ginfo['slats_cut'])} cut at the wall-side or shared planes). Near-"
        "horizontal views cross fewer layers than vertical ones (the reference case: first "
        "physical check, point 2)."]


def _optics_notes(optics: LouverOptics, *, volume: bool) -> list[str]:
    """The leaf optics and which reading of the study's 0.5 is in use."""
    notes = ["Leaf optics, " + (optics.describe_slat() if volume else optics.describe()) + "."]
    if optics.reading == "study":
        unit = "per-slat" if volume else "per-layer"
        notes.append(f"Study reading: the study's 0.5 is treated as an effective {unit} "
                     "transmission put into the slat material (a real leaf absorbs far more "
                     "than 1 − 0.5 − 0.11 = 39 %); the alternative is the gap reading "
                     "(switch louvers.reading = \"gap\").")
    elif optics.reading == "gap":
        notes.append("Gap reading: leaves are near-opaque real leaves and each layer passes "
                     "light mainly through its gaps (switch louvers.reading = \"study\" for an "
                     "effective slat material: every layer covered, transmittance 0.5).")
    return notes


def _recommended_ab(lv: Louvers, *, volume: bool) -> tuple[int, str]:
    """Radiance ``-ab`` for the crown and the note saying why."""
    if volume:
        ab = recommended_volume_ab(lv)
        return ab, volume_ab_note(ab)
    ab = lv.layers + 2
    return ab, (f"Radiance: slat layers with diffuse transmission pass light only through "
                f"ambient bounces; use -ab ≥ {ab} and check convergence.")


def _louvers_info(part: _Slats, optics: LouverOptics, *, volume: bool,
                  from_points: bool) -> dict[str, float]:
    """Numbers for reports and tests: analytic transmissions (layers: τ_layer^N; volume:
    the turbid-medium exp(−λ(1 − T_s)) along the vertical through a crown centre), counts,
    and what the geometry step measured."""
    lv = part.lv
    info: dict[str, float] = {
        "layers": float(lv.layers), "cover_fraction": lv.cover_fraction,
        "slat_count": float(part.count), "slat_size_m": lv.slat_size_m,
        "slat_reflectance": lv.reflectance, "slat_transmittance": lv.transmittance,
        "slat_specular_transmittance": optics.t_specular,
        "slat_diffuse_transmittance": optics.t_diffuse,
        "tau_layer_direct": optics.tau_layer_direct,
        "tau_crown_direct": optics.tau_crown_direct,
        "tau_layer_global": optics.tau_layer_global,
        "tau_crown_global": optics.tau_crown_global,
        "direct_transmission": optics.tau_crown_direct,
        "reading_study": float(optics.reading == "study"),
        "reading_gap": float(optics.reading == "gap"),
        "arrangement_volume": float(volume),
    }
    if volume and not from_points:
        lam = part.ginfo["lambda_vertical"]
        for key in ("tau_crown_direct", "direct_transmission"):
            info[key] = math.exp(-lam * (1.0 - optics.t_specular))
        info["tau_crown_global"] = math.exp(-lam * (1.0 - optics.transmittance))
        for key in ("tau_layer_direct", "tau_layer_global"):
            info.pop(key)
    info.update(part.ginfo)
    return info


def _clumping_fit_text(fit: Any) -> str:
    """How the fit treated clumping (radtree.trees.clumping), for the notes."""
    if fit.clumping >= 1.0 and not fit.clumping_fitted:
        return ("(not modelled: the slats are placed at random, the density is an effective "
                "one).")
    how = ("estimated from the photos: their Lang & Xiang clumping matched by cluster "
           f"realisations of the fitted crown (model {fit.clumping_lx_model:.3f} on the "
           "fit's 32-segment grid)" if fit.clumping_fitted else "as configured")
    return (f"(hemi's 8 segments). Slats grouped in clusters, clumping index Ω = "
            f"{fit.clumping:.3f} {how}; the density is the true one, LAI_true = "
            "LAI_eff / Ω.")


def _spread_text(spread: dict[str, float]) -> str:
    """The per-photo spread of a fit to several photos, for the notes."""
    if spread.get("photos", 1.0) <= 1.0:
        return ""
    text = f" One fit to {int(spread['photos'])} photos; per photo s.d. of the density "
    text += f"{spread.get('lad_sd', float('nan')):.3f} m²/m³"
    if "x_sd" in spread:
        text += f", of x {spread['x_sd']:.3f}"
    return text + "."
