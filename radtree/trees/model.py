"""What every crown builder returns (re-exported by :mod:`radtree.trees.build`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from radtree.media_voxels import Media
from radtree.optics import Material
from radtree.scene import Instance, Mesh
from radtree.site.frame import FacadeFrame

# Material names used by the crown models; they must not clash with the street's
# (``facade_paint``, ``ground``, ``opposite_facade``).
LEAF = "leaf"
SHELL = "crown_shell"
TRUNK = "trunk"
BARK_REFLECTANCE = 0.2
MAX_SLATS = 200_000  # most slats a louvers crown may have (dome: up to 1.5 × this bound)


@dataclass
class TreeModel:
    """A built crown: world-space meshes tagged with material names, the materials, notes.

    ``recommended_ab`` is the Radiance ambient-bounce count this model needs (diffusely
    transmitting layers pass light only through ambient bounces). ``info`` holds numbers for
    reports and tests (analytic transmissions, openness, slat counts, radii ...).
    """

    meshes: list[Mesh]
    materials: dict[str, Material]
    notes: list[str]
    recommended_ab: int
    triangles: int = 0
    build_seconds: float = 0.0
    info: dict[str, float] = field(default_factory=dict)
    form: str = "dome"
    model: str = "none"
    frame: FacadeFrame | None = None  # the façade frame the crown was built in
    photo: dict | None = None  # provenance of a photo-derived crown (radtree.trees.photo)
    # inventory crowns shared by several trees (radtree.trees.district): prototype meshes
    # in their own frame and where each tree places one (radtree.scene.Instance)
    prototypes: dict[str, list[Mesh]] = field(default_factory=dict)
    instances: list[Instance] = field(default_factory=list)
    from_cache: bool = False  # loaded from the build cache (radtree.cache), not built
    media: Media | None = None  # turbid-medium crowns (radtree.trees.turbid)

    def __post_init__(self) -> None:
        for m in [*self.meshes, *(p for ms in self.prototypes.values() for p in ms)]:
            if m.material not in self.materials:
                raise ValueError(f"mesh '{m.name}' uses undefined material '{m.material}'")
        if not self.triangles:
            self.triangles = sum(m.n_triangles for m in self.meshes)


def no_crown(tree: object, sensors: object, street: object, frame: FacadeFrame, form: str,
             source: str | None = None) -> TreeModel:
    """The crown model ``none`` (no meshes): the unobstructed reference."""
    return TreeModel(meshes=[], materials={}, notes=[
        "No crown (model 'none'): the unobstructed reference."], recommended_ab=2,
        form=form, model="none")
