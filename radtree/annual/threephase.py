"""``radtree annual --method 3phase``: the crown as a complex fenestration system.

For every sensor and hour (lux, as :mod:`radtree.annual.run`)

    E(h) = Σ_g V_g · T_g(state) · D_g(state) · s(h)    sky through the crown
         + Σ_g V_g · R_g(state) · D'_g(state) · s(h)   sky reflected by the crown
         + V_sky · s(h)                                sky that misses the crown (by-pass)
         + sun(h, state)                               direct and reflected sun

* the crown is the BSDF shell of ``[tree] representation = "bsdf"``
  (:mod:`radtree.trees.bsdf_shell`): the sensor dome, or the free crowns' envelopes; its
  facets are grouped by orientation (:func:`facet_groups`, one Klems hemisphere per group);
* ``V`` — ``rfluxmtx``, sensors → every group (Klems) and the sky (Reinhart): the shell
  absorbs in this run, so ``V`` holds no crown optics and serves every leaf state. A free
  crown's wall cap is cut into tiles (:data:`GROUP_TILE_M`): a first run over all groups says
  which tiles the sensors see (:meth:`ThreePhase.d_groups`), a second traces ``V`` of the
  groups given daylight matrices (those tiles, and per material and orientation the rest);
* ``T`` — the crown BSDF of ``radtree bsdf`` (:mod:`radtree.bsdf.run`), leaf-on and leaf-off
  (the branch slab), per elevation band on the dome; for free crowns turned front ↔ back
  (light leaves a crown from its inside, :func:`radtree.engines.radiance.threephase.turned_xml`);
* ``D`` — one ``rfluxmtx`` run per group, the group → sky. The dome is crossed once: its
  ``D`` holds no crown and serves both states. A free crown is crossed twice (in through the
  far side of its envelope, out through the group): the far side is traced in ``D`` as the
  state's ``BSDF`` material, so a free crown's ``D`` is computed per leaf state;
* ``R``, ``D'`` — the crown reflects light arriving from the sensors' side (the sky, the
  street, a façade lit through the crown) back to them: ``R`` is the XML's reflection on that
  side (:func:`radtree.engines.radiance.threephase.room_reflection_xml`), ``D'`` the group →
  sky seen from the sensors' side (the crown of the state in the scene), per leaf state;
* ``s`` — ``gendaymtx -s`` (the Perez sky without its sun), as the default method;
* ``Σ_g V_g·T_g·D_g`` — ``rmtxop V_g T.xml D_g`` per group (sensors × sky patches), once per
  leaf state; times ``s`` for the 8760 hours in NumPy (``dctimestep``'s product).

**Direct sun: as the existing annual does** (no fifth phase): ``rcontrib`` with a 0.533° sun
exactly at each hour's position at ``-ab 0`` (the LM-83 direct sunlight) and the
inter-reflected sun from unit suns at Reinhart patch centres (``-ab N`` minus ``-ab 0``)
(:class:`~radtree.annual.coefficients.CoefficientRunner`, cached by content).
``AnnualOptions.sun_crown`` says through which crown: ``"explicit"`` (default) runs the
default method's sun runs on its explicit scenes of each leaf state (slats, bare branches;
its folders and cache, so a project that ran ``--method dc`` reuses them); ``"bsdf"`` traces
both on the BSDF-crown scene. The shell is Radiance's ``aBSDF`` by default
(``tree.bsdf.material``): the XML's straight-through Klems patch passes the ``-ab 0`` sun as
a shadow ray (the plain ``BSDF`` passes none: 0.0 lx on the office example, the sun through
the crown then found only by the ``-ab N`` run's sampling). That peak holds the light within
≈ 5° of the straight line, not only the gaps: on the office example the BSDF crown's ``-ab
0`` sun sums to 2.5 × the explicit crown's (leaf-on, all sensors and suns), so with
``"bsdf"`` the hourly *direct* output (LM-83) holds forward-scattered light. The daylight
matrices ignore the material (:func:`_scene_with` ``peak=False``: the chain applies the XML
as it is). Measured on the office example (CHANGELOG.md, three-phase section): the sun
scattered by the BSDF crown is where the two methods differed most (work-plane UDI > 3000 lx
+5.4 pp, façade +9.6 pp with ``"bsdf"`` on the plain BSDF; +0.7 / +0.9 pp with
``"explicit"``, for 214 s more of sun runs through the slats; with the aBSDF shell ``"bsdf"``
is within 2.2 pp on the façade, work plane up to 8.5 pp). Tracing only the ``-ab 0``
direct sun through the explicit crown and the reflected sun on the BSDF crown counts the
crown's gaps twice (the BSDF's ``-ab N`` run carries them) and was no better than ``"bsdf"``
(CHANGELOG.md). ``"fivephase"`` (issue 40) does what that tried, the five-phase way
(:mod:`radtree.annual.fivephase`): the sun on the BSDF-crown scene, minus the same run with
the surroundings black (the sun through the BSDF crown with no bounce off the surroundings),
plus the sun through the explicit crown with the surroundings black — the crown's gaps once.
The scene without the tree is computed as the default method does.

**Closure (issue 40): the chain against a direct trace of the same BSDF scene.**
:mod:`radtree.annual.closure` and ``benchmarks/threephase_closure.py`` compare Σ V·T·D (+ the
reflection and the by-pass) with ``rcontrib`` of the BSDF-crown scene under a uniform sky and
a uniform ground hemisphere. Measured:

* one planar window (a room behind a crown-BSDF window, ``tests/test_frads_crosscheck.py``):
  the chain 0.9994 × rtrace, LBNL's frads 0.9994 × — the matrices, the Klems basis
  orientation and the sky discretisation are right for a planar group; turned round (the
  light entering the XML's back side, as it leaves a free crown) the chain with
  :func:`~radtree.engines.radiance.threephase.turned_xml` 1.0024 × rtrace;
* the office example's crowns (``--xml``: the small test crown's XML on every band and the
  wall cap, so that no crown BSDF is computed; ``-ad 512``, ``-c 100``; façade / work plane):
  rfluxmtx's default up (+Z, or +Y for normals within 45° of vertical) 1.083 / 1.034; the
  ``BSDF`` material's own up vector (+z, −z on the lower half) 1.024 / 1.008 (at
  ``-ad 1024``: 1.024 / 0.9996); that and
  0.5 m cap tiles 1.032 / 1.010; that and 42 grouping directions (level 2: facets within
  ≈ 19° of their group's) 1.029 / 1.0005. Per façade row (z 4.0 … 6.0 m) the default up read
  1.28, 1.26, 1.04, 0.99, 0.94 and the material's up 1.08, 1.11, 1.04, 0.99, 0.94: the
  excess sat in the two lowest rows, which see the lower band (its XML mirrored, up −z)
  through Klems patches turned by 180° when the matrices used +Z.

Hence :data:`GROUP_MATERIAL_UP` (each group's Klems frame is its material's: the XML is
applied in that frame by rtrace). The two lowest façade rows still read 1.08–1.11 at level 0
(5 mm from the cap's lower edge, next to the curved lower band).

**One group per facet plane (issue 40, the small crown).** The small single crown of
``radtree verify`` (12 segments, facets ≈ 1.5 m across, sensors 0.5 m from it) read 0.936 at
level 0 (chain 0.807 against rcontrib 0.862). Measured there (uniform sky, leaf-on, façade
mean; rtrace of the same scene at ``-ab 8 -ad 16384 -lw 1e-5``, six seeds: 0.8604 ± 0.0005,
the shell black 0.3851): the by-pass was right (V_sky 0.385–0.393) and the reflection is 1 %;
the light through the crown read 0.88 of the trace. A crown XML without its reflection read
0.944, a Lambertian-diffuse T 1.00, a purely straight-through T 0.955; the grouping moved it
(level 0: 0.936, level 2: 0.929, level 3: 1.09, level 4 and one group per facet: 1.02–1.03).
The crown XML depends on the incidence angle relative to the facet (``crossing = "chord"``:
the depth R cos θ), and a curved group applies it at the group's mean normal; near the
vertical the groups' facets' up vectors turn round the normal. So free crowns now group only
coplanar facets (:data:`GROUP_LEVEL` = :data:`~radtree.annual.facets.FACETS`, the wall cap
by tile as before); the daylight matrices are given to the facets the sensors see
(:data:`TILE_SHARE`), the rest merged per level-0 direction, and a group's daylight matrix
traces its share of its level-0 group's rays (:func:`daylight_samples`), so the total stays
about as before. Measured with it (``radtree verify --full``'s row, ``-ad 65536 -lw 1e-6``):
chain 0.874–0.876 against rcontrib 0.855 (1.022–1.025 in two runs, per sensor row
1.018–1.034; against the six-seed rtrace 1.016–1.019): by-pass 0.385, through the crown
0.480 + 0.009 reflected against 0.475 traced. The office example
(``benchmarks/threephase_closure.py --xml … --states leaf_on``, ``-ad 1024``, ``-c 100``)
reads façade 1.029, work plane 1.013 with it — within the claim as level 0 in the same run
(1.036 / 1.009); cost: 1 278 groups in V (4 rfluxmtx runs), 88 daylight matrices against
22, the closure's matrices 470 s against 291 s (load 26–28 on 2 cores). The uniform
*ground* hemisphere (the ``h=u`` column: radiance 1 below the horizon, seen past the street's
edge, so within a few degrees of the horizon) through the crown stays high: verify crown
0.168 against rcontrib 0.144 (1.16), office 1.28; against rtrace (three seeds, 0.1365, the
shell black 0.0792) the chain's by-pass is right (0.0793) and its light through the crown
reads 0.089 against 0.057 (1.55 ×). Re-measured with the reference scene's shell as
``aBSDF`` (the default since; the chain does not see the material; ``closure_table`` as in
:func:`radtree.verify.threephase.closure_checks`, ``-ad 65536 -lw 1e-6``, 111 s): sky chain
0.8744 against 0.8551 (1.0226, unchanged), ground 0.1576 against 0.1444 (1.092; the
reference unchanged, this run's chain lower than the 0.168 above for reasons not traced
here). Not resolved; a lead: that light arrives within a few
degrees of the horizon, and the Klems patches that hold it straddle the horizon (a daylight
matrix averages over its patch, the sensors see only part of it). The same on the sky: with
facet planes a Lambertian T closes (crown part 0.99, total 0.9995) and a purely
straight-through T reads 1.06 on the crown part (total 1.0185; rtrace of the same XMLs,
``-ad 8192 -lw 1e-5``; V at ``-ad 16384 -lw 1e-5``); the daylight matrices at 4 × the rays
moved the chain by 0.1 %. So the chain's remaining +2 % is the Klems patches' angular
resolution on the crown XML's straight-through part, not its sampling — a finer basis for
that part (a tensor tree, or the sun-like treatment of the five-phase method) is the next
step.

**One group per crown; the room side turned round (issue 40, the office's row of three
crowns, 8 December 2026).** The office's closure read façade 1.135, work plane 1.025 with a
converged reference (``benchmarks/threephase_closure.py``, whose docstring holds the
measurements). Two causes: (1) a row's envelopes are glued into one shell, and grouping by
plane orientation put the facets of one orientation of all three crowns into one group, whose
daylight matrix is their mean while the sensors see the central crown — groups are now also
split by connected piece (:func:`~radtree.annual.facets.shell_parts`: each crown keeps its own
vertices), and the merged groups of :meth:`ThreePhase.d_groups` too (1.034 / 1.006); (2)
rfluxmtx sends a sender's rays away from its normal whatever ``h=±kf``, so the room-side
daylight matrices (sender wound to the room, ``h=+kf``) looked back into the crown and read
4–5 × the light arriving from the room's side; the sender is now wound away from the room
(:func:`~radtree.engines.radiance.threephase.sender_text`): façade 0.991, work plane 0.950.
(3) V·T·D mirrored T left/right about the up vector (rfluxmtx's ``h=-kf`` sender and
``h=kf`` receiver take opposite Klems x axes, ``benchmarks/klems_handedness.py``): free
crowns' outward sender is now ``h=+kf``: façade 1.009, work plane 1.014 (the dome keeps the
tutorial convention, its V side mirrored, open).

A second weather file reruns ``gendaymtx`` and the products only (the sun coefficients
are reused when the sun positions are the same, i.e. the same site); a second leaf state
reuses ``V`` (and the dome's ``D``). Not ray traced: light crossing the shell is turned
by the Klems BSDF of its group, whose frame is its facets' plane (free crowns) or the group's
mean normal (the dome: facets within 55° of it); the BSDF of a planar periodic sample holds no lateral displacement.
"""

from __future__ import annotations

import hashlib
import logging
import os
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from radtree.annual.coefficients import TraceParams, points_text, scene_text
from radtree.annual.combine import LUX
from radtree.annual.facets import FACETS, FacetGroup, facet_groups
from radtree.annual.skymatrix import (
    patch_count,
)
from radtree.config import Project, Scenario, effective_project
from radtree.engines.radiance import threephase as rad3
from radtree.optics import Bsdf
from radtree.scene import Mesh, Scene
from radtree.trees.bsdf_shell import BSDF_SHELL, WALL_CAP
from radtree.trees.model import TreeModel

log = logging.getLogger(__name__)

STATES = ("leaf_on", "leaf_off")
KLEMS = 145
#: the daylight matrices' ray weight limit (path tracing, -ad 2)
D_LW_MIN = 1e-3
#: a free crown's wall cap is cut into tiles of this size (m, cells of a world grid): a
#: daylight matrix is the mean over its sender's area, and the light inside a crown varies
#: along the 20 m × 8 m cap (measured on the office example, uniform sky: the light arriving
#: at the cap in front of the window is 0.54 of the whole cap's mean). Only the cap: it is
#: planar, so the BSDF material's frame (up +z) is the tiles' Klems frame; tiles of the
#: curved bands read 1.2–1.24 × rcontrib on the same BSDF crown (their material frames turn
#: over the crown, rfluxmtx's up is fixed), whole bands 0.94–0.99
GROUP_TILE_M = 1.5
#: a tile whose view-matrix share reaches this for some sensor gets its own daylight matrix;
#: the other tiles of a material and direction share one (their views summed), which is
#: dropped when its share stays below VISIBLE_SHARE for every sensor
TILE_SHARE = 2e-3
VISIBLE_SHARE = 1e-4
#: facet grouping of the annual runs for free crowns (:data:`radtree.annual.facets.FACETS`:
#: one group per facet plane orientation, each group in its facets' own Klems frame) and for
#: the sensor dome (:func:`radtree.annual.facets.group_directions` level 0: not re-measured),
#: and whether each group's Klems frame takes its ``BSDF`` material's up vector (module text)
GROUP_LEVEL = FACETS
DOME_GROUP_LEVEL = 0
GROUP_MATERIAL_UP = True
#: a group's daylight matrix traces ``samples`` × its share of its level-0 group's area rays
#: per Klems patch (:attr:`radtree.annual.facets.FacetGroup.weight`), at least this many
D_MIN_SAMPLES = 8


def daylight_samples(samples: int, group: FacetGroup) -> int:
    """``rfluxmtx -c`` of ``group``'s daylight matrix: ``samples`` rays per Klems patch of a
    level-0 group, shared among its finer groups by area (at least :data:`D_MIN_SAMPLES`),
    so that a finer grouping traces about as many rays in all."""
    return max(D_MIN_SAMPLES, int(np.ceil(samples * group.weight)))


def _without_shell(scene: Scene) -> Scene:
    return Scene([m for m in scene.meshes if not m.material.startswith(BSDF_SHELL)],
                 scene.materials, scene.grids, scene.notes, scene.ground_material)


def state_xmls(project: Project, scenario: Scenario
               ) -> dict[str, list[tuple[float, float, Path]]]:
    """Leaf-on bands (``tree.bsdf.xml`` or computed; a free crown's wall cap too) and the
    leaf-off branch-slab XML (for every band and the wall cap), each cached under
    ``build/bsdf/<scenario>/``."""
    from radtree.bsdf.run import leaf_off_sample
    from radtree.pipeline.crown_bsdf import (
        ensure_bsdf,
        flux_settings,
        leaf_on_sample,
        scenario_tree,
        scenario_xmls,
    )

    on = scenario_xmls(project, scenario)
    tree, form = scenario_tree(project, scenario)
    off = ensure_bsdf(leaf_off_sample(project, scenario, leaf_on_sample(project, scenario)),
                      flux_settings(tree, form, os.cpu_count() or 1),
                      project.build_dir / "bsdf" / scenario.name / "leaf_off", "leaf_off")
    return {"leaf_on": on, "leaf_off": [(lo, hi, off.xml) for lo, hi, _ in on]}


def crown_models(project: Project, scenario: Scenario,
                 xmls: dict[str, list[tuple[float, float, Path]]]) -> tuple[dict, str]:
    """The BSDF crown of each leaf state (:func:`radtree.trees.bsdf_shell.build_bsdf_crown`)."""
    from radtree.pipeline.assemble import facade_frame
    from radtree.pipeline.crown_bsdf import BSDF_SCENE_AB, scenario_tree
    from radtree.trees.bsdf_shell import build_bsdf_crown

    eff = effective_project(project, scenario)
    tree, form = scenario_tree(project, scenario)
    frame = facade_frame(eff)
    models = {s: build_bsdf_crown(tree, eff.sensors, eff.street, frame, form, xmls[s],
                                  BSDF_SCENE_AB, str(project.source)) for s in STATES}
    return models, form


def _scene_with(bare: Scene, model: TreeModel, *, peak: bool = True) -> Scene:
    """``bare`` and the crown of ``model``; ``peak=False``: its shell's materials plain
    ``BSDF`` even when ``tree.bsdf.material = "aBSDF"`` (the daylight matrices: the chain
    applies the XML as it is, without the peak extraction)."""
    materials = dict(bare.materials)
    materials.update({n: m if peak or not isinstance(m, Bsdf) else replace(m, peak=False)
                      for n, m in model.materials.items()})
    return Scene(bare.meshes + list(model.meshes), materials, bare.grids,
                 bare.notes + list(model.notes), bare.ground_material)


def _octree(folder: Path, name: str, scene: Scene, rho: float) -> Path:
    return rad3.octree(folder, name, scene_text(scene, rho))


class ThreePhase:
    """The matrices of one crown (V once, D per group and, for free crowns, per state),
    cached in ``folder`` by the text they were computed from.

    ``bare``: the scene without a crown; ``models``: the BSDF crown of each leaf state
    (:data:`STATES`); ``form``: ``dome`` or ``free``; ``grids`` the sensor grids traced;
    ``rho`` the ground reflectance (0–1); ``mf`` the Reinhart sky subdivision; ``trace`` the
    rfluxmtx settings; ``samples`` rays per Klems patch of a level-0 group's daylight
    matrix (``-c``, :func:`daylight_samples`); ``level``, ``material_up``, ``tile_m``: the
    facet grouping (:func:`facet_groups`; None: :data:`GROUP_LEVEL`, the dome
    :data:`DOME_GROUP_LEVEL`; tile 0: :data:`GROUP_TILE_M`)."""

    def __init__(self, folder: Path, *, bare: Scene, models: dict[str, TreeModel], form: str,
                 grids: list[str], rho: float, mf: int, trace: TraceParams,
                 samples: int = 400, level: int | None = None,
                 material_up: bool = GROUP_MATERIAL_UP, tile_m: float = 0.0):
        self.folder, self.samples = folder, samples
        folder.mkdir(parents=True, exist_ok=True)
        self.bare, self.models, self.grids, self.rho, self.mf = bare, models, grids, rho, mf
        self.inside = form == "dome"
        self.trace = trace
        if level is None:
            level = DOME_GROUP_LEVEL if self.inside else GROUP_LEVEL
        self.level = level
        self.groups = facet_groups(models["leaf_on"], self.inside, tile_m or GROUP_TILE_M,
                                   (WALL_CAP,), level, material_up)
        self.points = points_text(bare, grids)
        self.n = sum(len(bare.grids[g]) for g in grids)
        self.timing: dict[str, float] = {}

    def _cached(self, name: str, key: str, compute: Callable[[], Path]) -> Path:
        digest = hashlib.sha256(key.encode()).hexdigest()[:16]
        path = self.folder / f"{name}_{digest}"
        if not path.exists():
            tmp = compute()
            tmp.replace(path)
        return path

    def view(self, groups: list[FacetGroup] | None = None, tag: str = "g"
             ) -> tuple[list[Path], np.ndarray]:
        """The view matrix of each of ``groups`` (default: every tile; files
        ``view_<tag><k>.vmx``) and V_sky (sensors, patches, 3). More groups than
        :data:`~radtree.engines.radiance.threephase.VIEW_CHUNK` are traced in several
        rfluxmtx runs, each with the other groups' facets as absorbers."""
        groups = self.groups if groups is None else groups
        receivers = (rad3.group_receivers_text([(g.triangles, g.normal) for g in groups],
                                               [g.up for g in groups])
                     + "\n" + rad3.sky_receivers_text(self.mf))
        # trunks stay; the shell's materials as the matrices see them (plain BSDF)
        scene = _without_shell(_scene_with(self.bare, self.models["leaf_on"], peak=False))
        octree_text = scene_text(scene, self.rho)
        ambient = self.trace.ambient()
        key = "|".join(["-I+ -faf", receivers, octree_text, self.points, " ".join(ambient)])

        def compute() -> Path:
            t0 = time.perf_counter()
            log.info(f"    rfluxmtx view matrix: {self.n} sensors → {len(groups)} shell "
                     f"groups × {KLEMS} + {patch_count(self.mf)} sky patches")
            m = self._view_runs(groups, octree_text, ambient)
            self.timing[f"view_{tag}_s"] = time.perf_counter() - t0
            return rad3.write_matrix(self.folder / "view.vmx.tmp", m)

        path = self._cached("view", key, compute)
        m = rad3.read_matrix(path.read_bytes(), str(path))
        files = []
        for k in range(len(groups)):
            f = self.folder / f"view_{tag}{k}.vmx"
            rad3.write_matrix(f, m[:, k * KLEMS:(k + 1) * KLEMS])
            files.append(f)
        return files, m[:, len(groups) * KLEMS:]

    def _view_runs(self, groups: list[FacetGroup], octree_text: str, ambient: list[str]
                   ) -> np.ndarray:
        """(sensors, groups × 145 + sky patches, 3): one rfluxmtx run per
        :data:`~radtree.engines.radiance.threephase.VIEW_CHUNK` groups (the sky in the first)."""
        chunks = [list(range(i, min(i + rad3.VIEW_CHUNK, len(groups))))
                  for i in range(0, len(groups), rad3.VIEW_CHUNK)] or [[]]
        parts, sky = [], None
        for c, ks in enumerate(chunks):
            inside = set(ks)
            others = [g.triangles for k, g in enumerate(groups) if k not in inside]
            text = octree_text + ("\n" + rad3.blocker_text(others) if others else "")
            octree = rad3.octree(self.folder, f"view{c}", text)
            receivers = rad3.group_receivers_text([(groups[k].triangles, groups[k].normal)
                                                   for k in ks], [groups[k].up for k in ks])
            if c == 0:
                receivers += "\n" + rad3.sky_receivers_text(self.mf)
            m = rad3.view_matrix(self.folder, octree, self.points, self.n, receivers, ambient,
                                 self.trace.nproc)
            parts.append(m[:, :len(ks) * KLEMS])
            if c == 0:
                sky = m[:, len(ks) * KLEMS:]
        assert sky is not None
        return np.concatenate([*parts, sky], axis=1)

    def d_groups(self, views: list[Path], v_sky: np.ndarray) -> list[FacetGroup]:
        """The groups given daylight matrices: every tile whose view share (its columns'
        sum over all of a sensor's, sky included; ``views`` of :meth:`view`) reaches
        :data:`TILE_SHARE` for some sensor on its own; the other tiles of each material and
        level-0 direction merged, unless even merged they stay below :data:`VISIBLE_SHARE`."""
        sums = np.stack([rad3.read_matrix(v.read_bytes(), str(v)).sum(axis=(1, 2))
                         for v in views])
        total = sums.sum(axis=0) + v_sky.sum(axis=(1, 2))
        share = sums / np.where(total > 0, total, 1.0)
        groups = [g for k, g in enumerate(self.groups) if share[k].max() >= TILE_SHARE]
        rest: dict[tuple[str, int, int], list[int]] = {}
        for k, g in enumerate(self.groups):
            if share[k].max() < TILE_SHARE:
                rest.setdefault((g.material, g.coarse, g.part), []).append(k)
        for (material, coarse, _), ks in sorted(rest.items()):
            if share[ks].sum(axis=0).max() < VISIBLE_SHARE:
                continue
            mean = np.sum([self.groups[k].normal * self.groups[k].area for k in ks], axis=0)
            weight = min(1.0, sum(self.groups[k].weight for k in ks))
            groups.append(FacetGroup(material, np.concatenate([self.groups[k].triangles
                                                               for k in ks]),
                                     mean / np.linalg.norm(mean), self.groups[ks[0]].direction,
                                     self.groups[ks[0]].up, coarse, weight,
                                     self.groups[ks[0]].part))
        return groups

    def daylight(self, state: str, groups: list[FacetGroup], room_side: bool = False
                 ) -> list[Path]:
        """The daylight matrix of each of ``groups``: of the light it transmits into the
        room (the dome's: one for both states), or (``room_side``) of the light arriving at
        it from the room's side, which it reflects back."""
        with_crown = _scene_with(self.bare, self.models[state], peak=False)
        own = self.inside and not room_side      # the dome's outward D meets no crown
        scene = _without_shell(with_crown) if own else with_crown
        text = scene_text(scene, self.rho) + ("" if own else "".join(
            Path(m.xml).read_text() for m in self.models[state].materials.values()
            if isinstance(m, Bsdf)))
        # rays per Klems patch (-c) carry the sampling: path tracing, 2 rays per bounce
        ambient = ["-ab", str(self.trace.ab), "-ad", "2", "-lw",
                   f"{max(self.trace.lw, D_LW_MIN):g}", "-aa", "0"]
        octree: list[Path] = []
        t0 = time.perf_counter()
        tag = "r" if room_side else "g"
        out: list[Path] = []
        for k, g in enumerate(groups):
            sender = rad3.sender_text(g.triangles, g.normal, room_side, g.up,
                                      material_faces_room=self.inside)
            c = daylight_samples(self.samples, g)
            key = "|".join([sender, text, " ".join(ambient), str(c), str(self.mf)])

            def compute(k: int = k, sender: str = sender, c: int = c) -> Path:
                if not octree:
                    octree.append(_octree(self.folder, f"daylight_{state}", scene, self.rho))
                return rad3.daylight_matrix(self.folder, octree[0], f"{tag}{k}", sender,
                                            self.mf, c, ambient, self.trace.nproc)

            out.append(self._cached(f"daylight_{tag}{k}", key, compute))
        name = f"daylight_{'room_' if room_side else ''}{state}_s"
        self.timing[name] = time.perf_counter() - t0
        if octree:
            log.info(f"    rfluxmtx daylight matrices ({state}"
                     f"{', room side' if room_side else ''}): {len(groups)} groups (tiles seen "
                     f"from the sensors, the rest merged), -c {self.samples} per level-0 group, "
                     f"{self.timing[name]:.0f} s")
        return out

    def transmission(self, state: str, groups: list[FacetGroup], reflection: bool = False
                     ) -> list[Path]:
        """T of every group: its band's XML (turned for free crowns); ``reflection``: the
        XML of its reflection back into the room."""
        mats = self.models[state].materials
        done: dict[str, Path] = {}
        for name in {g.material for g in groups}:
            mat = mats[name]
            assert isinstance(mat, Bsdf)
            xml = Path(mat.xml)
            if not self.inside:
                xml = rad3.turned_xml(xml, self.folder / f"{state}_{name}_turned.xml")
            if reflection:
                xml = rad3.room_reflection_xml(xml, self.folder /
                                               f"{state}_{name}_room_reflection.xml")
            done[name] = xml
        return [done[g.material] for g in groups]

    def coefficients(self, state: str, views: list[Path], v_sky: np.ndarray) -> np.ndarray:
        """(sensors, patches, 3) daylight coefficients of the state: Σ_g V_g·T_g·D_g
        + Σ_g V_g·R_g·D'_g (``rmtxop``) + V_sky."""
        groups = self.d_groups(views, v_sky)
        files, v_sky = self.view(groups, "d")    # their own frames (a merged group's mean)
        self.timing["daylight_groups"] = float(len(groups))
        days = self.daylight(state, groups)
        back = self.daylight(state, groups, room_side=True)
        t0 = time.perf_counter()
        dc = v_sky.astype(np.float64)
        for v, t, d in zip(files, self.transmission(state, groups), days):
            dc = dc + rad3.multiply(v, t, d)
        for v, r, d in zip(files, self.transmission(state, groups, reflection=True), back):
            dc = dc + rad3.multiply(v, r, d)
        self.timing[f"rmtxop_{state}_s"] = time.perf_counter() - t0
        return dc.astype(np.float32)



def sky_lux(dc: np.ndarray, sky: np.ndarray) -> np.ndarray:
    """(sensors, hours) lux: the coefficients (sensors, patches, 3) times the sky matrix
    (patches, hours, 3), channel by channel (as ``dctimestep DC sky`` does)."""
    total = np.zeros((dc.shape[0], sky.shape[1]), np.float64)
    for ch in range(3):
        total += LUX[ch] * (dc[:, :, ch].astype(np.float64) @ sky[:, :, ch].astype(np.float64))
    return total


__all__ = ["FacetGroup", "Mesh", "ThreePhase", "facet_groups", "sky_lux"]
