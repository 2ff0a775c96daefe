"""Export formats by name (``radtree export PROJECT --format NAME``), shaped like the engine
registry (:mod:`radtree.engines.registry`): name → a writer function imported on first use,
with what the format needs declared beside it.

A writer is ``write(inputs: ExportInputs, out: Path) -> list[Path]`` (the files written into
folder ``out``). :func:`radtree.export.run.export_project` prepares the :class:`ExportInputs`
the format's :attr:`ExportFormat.needs` name (and only those: the 8760 traced hours of the
schedules cost a minute, the scene a few seconds) and calls it. **A new format is one module
with its writer and one line of** :data:`EXPORT_FORMATS`; ``radtree export --format`` offers
the registry's names, and :func:`reference_rows` gives the docs' table.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import import_module
from importlib.util import find_spec
from pathlib import Path
from typing import TYPE_CHECKING, Any

from radtree.errors import ConfigError, RadtreeError, install_extra

if TYPE_CHECKING:
    from radtree.config import Project, Scenario
    from radtree.export.transmittance import CrownSchedule
    from radtree.optics import Material
    from radtree.pipeline.assemble import BuiltScene

#: what a format may need (:attr:`ExportFormat.needs`) → what the export prepares for it
NEEDS: dict[str, str] = {
    "crown": "a scenario with a crown model (default: the first that has one)",
    "schedules": "each crown's 8760 hourly transmittances along the sun "
                 "(radtree.export.transmittance; --rays, --definition, --leaf-on/--leaf-off)",
    "scene": "the scenario's whole scene: street, rooms, glazing, crowns, trunks",
    "honeybee_model": "the project's Honeybee model ([site] honeybee) when it has one: the "
                      "crown shades are added to it",
}
#: pip extras a format may need → modules that must be importable
EXTRAS: dict[str, tuple[str, ...]] = {
    "honeybee": ("honeybee", "honeybee_energy", "honeybee_radiance", "ladybug_geometry"),
}


@dataclass(frozen=True)
class ExportInputs:
    """What a writer gets: the project and scenario, and what its format needs (None when
    not asked for): ``schedules`` with ``leaf`` (the crown model's leaf material), ``scene``,
    ``honeybee_model`` (the project's own, or None when it has none)."""

    project: Project
    scenario: Scenario
    schedules: list[CrownSchedule] | None = None
    leaf: Material | None = None
    scene: BuiltScene | None = None
    honeybee_model: Any = None

    def crown_schedules(self) -> tuple[list[CrownSchedule], Material]:
        """The schedules and the leaf material (a format that needs ``schedules``)."""
        if self.schedules is None or self.leaf is None:
            raise RadtreeError("this export format reads schedules but does not declare "
                               "'schedules' among its needs")
        return self.schedules, self.leaf

    def built_scene(self) -> BuiltScene:
        """The scenario's scene (a format that needs ``scene``)."""
        if self.scene is None:
            raise RadtreeError("this export format reads the scene but does not declare "
                               "'scene' among its needs")
        return self.scene


Writer = Callable[[ExportInputs, Path], list[Path]]


@dataclass(frozen=True)
class ExportFormat:
    """One export format: ``target`` ``"module:function"`` of its writer, a one-line
    ``summary`` of what it writes, what it ``needs`` (keys of :data:`NEEDS`) and the pip
    ``extra`` its writer imports (a key of :data:`EXTRAS`, or None)."""

    target: str
    summary: str
    needs: frozenset[str] = field(default_factory=frozenset)
    extra: str | None = None

    def __post_init__(self) -> None:
        unknown = sorted(set(self.needs) - set(NEEDS))
        if unknown or (self.extra is not None and self.extra not in EXTRAS):
            raise ValueError(f"{self.target}: unknown needs {unknown} or extra {self.extra!r}")

    def writer(self) -> Writer:
        """The writer function (its module imported now)."""
        module, _, name = self.target.partition(":")
        return getattr(import_module(module), name)  # type: ignore[no-any-return]

    def available(self) -> bool:
        """Whether the modules of its extra are installed."""
        return self.extra is None or all(find_spec(m) is not None for m in EXTRAS[self.extra])

    @property
    def missing_hint(self) -> str:
        return f"it needs the '{self.extra}' extra: {install_extra(str(self.extra))}"


def _f(target: str, summary: str, *needs: str, extra: str | None = None) -> ExportFormat:
    return ExportFormat(f"radtree.export.{target}", summary, frozenset(needs), extra)


#: name → format (``--format`` offers these, in this order)
EXPORT_FORMATS: dict[str, ExportFormat] = {
    "honeybee": _f("honeybee:export_hbjson", "radtree_crowns.hbjson: crowns as Honeybee "
                   "ShadeMesh with the leaf modifier and an hourly transmittance schedule",
                   "crown", "schedules", "honeybee_model", extra="honeybee"),
    "idf": _f("honeybee:export_idf", "radtree_crowns.idf: the same shades and schedules for "
              "EnergyPlus (ShadowCalculation PolygonClipping, frequency 1)",
              "crown", "schedules", "honeybee_model", extra="honeybee"),
    "schedule": _f("honeybee:export_schedule", "crown_transmittance.csv (8760 rows, a column "
                   "per crown) and its Schedule:File objects (crown_transmittance.idf)",
                   "crown", "schedules", extra="honeybee"),
    "honeybee-scene": _f("honeybee_scene:export_hbjson_scene", "radtree_scene.hbjson: what "
                         "radtree traces, leaf by leaf (crowns, trunks, ground; the street "
                         "without a Honeybee model) as ShadeMesh with Radiance modifiers, for "
                         "Ladybug Tools' Radiance recipes", "scene", "honeybee_model",
                         extra="honeybee"),
    "gltf": _f("scene_files:export_gltf", "<scenario>_scene.glb: the whole scene for any 3-D "
               "viewer, coloured by material", "scene"),
    "obj": _f("scene_files:export_obj", "<scenario>_scene.obj: the same as Wavefront OBJ",
              "scene"),
}
#: what ``--format`` accepts
FORMATS: tuple[str, ...] = tuple(EXPORT_FORMATS)


def export_format(name: str) -> ExportFormat:
    """The registered format ``name``; an unknown name → ConfigError naming ``--format``, a
    format whose extra is not installed → RadtreeError with the pip command."""
    if name not in EXPORT_FORMATS:
        raise ConfigError(f"got {name!r}, expected one of {', '.join(FORMATS)}", field="--format")
    fmt = EXPORT_FORMATS[name]
    if not fmt.available():
        raise RadtreeError(f"export format {name!r} asked for, but {fmt.missing_hint}")
    return fmt


def formats_needing(need: str) -> list[str]:
    """Names of the formats that declare ``need`` (a key of :data:`NEEDS`)."""
    return [name for name, f in EXPORT_FORMATS.items() if need in f.needs]


def reference_rows() -> list[tuple[str, str, str]]:
    """(name, summary, needs) of every format, in registry order: the docs' reference table
    (needs as comma-separated :data:`NEEDS` keys, with the extra as ``extra:NAME``)."""
    return [(name, f.summary, ", ".join(sorted(f.needs) + ([f"extra:{f.extra}"] if f.extra
                                                            else [])))
            for name, f in EXPORT_FORMATS.items()]
