"""The crown-model registry: every ``scenario.model`` radtree can build, declared once.

Each entry names the model, says in one line what it is, declares its capabilities (the
forms — ``dome`` sensor dome, ``free`` free-standing row — and the ``[tree] representation``
values it honours: ``explicit`` meshes, ``turbid`` media, ``bsdf`` shell) and points at the
function that builds it as ``"module:function"`` per representation. The functions are
imported on first use by :mod:`radtree.trees.registry` (``crown_builder``); this module is
plain data so that the schema (:class:`radtree.config.schema.Scenario`) can check a model's
name when the project loads without importing the crown code (a lower layer never imports a
higher one). The schema's ``model`` choices, ``radtree calibrate --model`` and the docs'
reference all come from here.

Adding a crown model is one new module in :mod:`radtree.trees` (a builder
``build_x(tree, *, sensors, street, frame, form, source) -> TreeModel``) and one line below.
A representation a model does not list is built as ``explicit`` (the ``bsdf`` shell is
built by :mod:`radtree.pipeline.crown_bsdf` from the louvers crown's slats).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class CrownModel:
    """One registered crown model.

    ``builders``: representation → ``"module:function"`` (``explicit`` always present);
    ``representations``: the ``[tree] representation`` values the model honours;
    ``forms``: the ``tree.form`` values it builds; ``calibrated``: ``radtree calibrate``
    fits it to a measured transmission."""

    name: str
    summary: str
    builders: dict[str, str]
    representations: tuple[str, ...] = ("explicit",)
    forms: tuple[str, ...] = ("dome", "free")
    calibrated: bool = False

    def capabilities(self) -> dict[str, object]:
        """The declared capabilities as a plain dict (forms, representations, calibrated)."""
        return {"forms": self.forms, "representations": self.representations,
                "calibrated": self.calibrated}


_T = "radtree.trees."
#: name → declaration, in the order the docs list them
REGISTRY: dict[str, CrownModel] = {m.name: m for m in (
    CrownModel("homogeneous", "one semi-transparent shell (a crown of uniform transmittance)",
               {"explicit": _T + "homogeneous:build_homogeneous"}, calibrated=True),
    CrownModel("perforated", "an opaque-leaf shell with gaps (random or cut from a photo)",
               {"explicit": _T + "perforated:build_perforated"}, calibrated=True),
    CrownModel("louvers", "inclined leaf slats in filtration layers or through the volume",
               {"explicit": _T + "louvers:build_louvers",
                "turbid": _T + "turbid_voxels:build_turbid_crowns"},
               representations=("explicit", "turbid", "bsdf"), calibrated=True),
    CrownModel("none", "no crown: the unobstructed reference",
               {"explicit": _T + "model:no_crown"}),
)}

#: what ``scenario.model`` accepts
CROWN_MODELS: tuple[str, ...] = tuple(REGISTRY)
