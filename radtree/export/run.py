"""``export_project``: one project out in one format (see :mod:`radtree.export`).

Plan → execute → publish: :func:`plan_export` checks the options and picks the scenario (the
one named, else the first with a crown model when the format needs one), :func:`prepare`
builds what the format declares it needs (:mod:`radtree.export.registry`: the year of crown
transmittances of :mod:`radtree.export.transmittance`, the whole scene, the project's Honeybee
model) and the format's writer writes the files. Messages go to the module's logger
(:mod:`radtree.log`): quiet from a script unless ``radtree.log.enable()``.

    from radtree.export.run import ExportOptions, export_project
    from radtree.export.schedule_options import ScheduleOptions
    options = ExportOptions("idf", Path("out"), schedule=ScheduleOptions(rays=64))
    export_project(project, options=options)            # → [Path("out/radtree_crowns.idf")]
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import ClassVar

from radtree.config import Project, Scenario
from radtree.config.spec import Checked, meta
from radtree.errors import ConfigError
from radtree.export.registry import EXPORT_FORMATS, ExportFormat, ExportInputs, export_format
from radtree.export.schedule_options import ScheduleOptions
from radtree.export.transmittance import CAVEATS, HOURS

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ExportOptions(Checked):
    """What to export: ``format`` (a name of :data:`radtree.export.registry.EXPORT_FORMATS`)
    into folder ``out``, of ``scenario`` (None: the first with a crown model, or the first
    when the format needs none), schedules traced as ``schedule`` says."""

    TABLE: ClassVar[str] = "export"
    format: str
    out: Path
    scenario: str | None = None
    schedule: ScheduleOptions = field(default_factory=ScheduleOptions, metadata=meta(kind="-"))

    def check(self) -> None:
        object.__setattr__(self, "out", Path(self.out))
        if self.format not in EXPORT_FORMATS:     # the registry as it is now
            raise self.fail("format", f"got {self.format!r}, expected one of "
                                      f"{', '.join(EXPORT_FORMATS)}")


@dataclass(frozen=True)
class ExportPlan:
    """The format, the scenario exported and the folder written."""

    format: ExportFormat
    scenario: Scenario
    out: Path


def export_scenario(project: Project, name: str | None, needs_crown: bool) -> Scenario:
    """The named scenario, else the first with a crown (any when no crown is needed)."""
    if name is not None:
        sc = project.scenario(name)
        if needs_crown and sc.model == "none":
            raise ConfigError(f"scenario {sc.name!r} has no crown (model 'none'): choose one "
                              "with a crown model", source=str(project.source), field="--scenario")
        return sc
    for sc in project.scenarios:
        if sc.model != "none" or not needs_crown:
            return sc
    raise ConfigError("no scenario has a crown model to export (all are model 'none')",
                      source=str(project.source), field="scenario")


def leaf_material(meshes, materials):
    """The crown model's leaf material: that of its largest non-trunk mesh."""
    from radtree.trees.model import TRUNK

    crown = [m for m in meshes if m.material != TRUNK and m.n_triangles]
    return materials[max(crown, key=lambda m: m.n_triangles).material]


def plan_export(project: Project, options: ExportOptions) -> ExportPlan:
    """The format (its extra installed), the scenario and the output folder (created)."""
    fmt = export_format(options.format)
    sc = export_scenario(project, options.scenario, "crown" in fmt.needs)
    out = Path(options.out)
    out.mkdir(parents=True, exist_ok=True)
    return ExportPlan(fmt, sc, out)


def crown_schedules(project: Project, sc: Scenario, options: ScheduleOptions) -> ExportInputs:
    """The year of hourly transmittances of the scenario's crowns and their leaf material,
    with a summary per crown and the caveats logged."""
    from radtree.export.transmittance import crown_models, default_leaf_schedule, year_schedules
    from radtree.pipeline.assemble import facade_frame

    leaf = default_leaf_schedule(project, options.leaf_on, options.leaf_off)
    season = (f"on {leaf.leaf_on} → off {leaf.leaf_off} (MM-DD)" if options.seasons
              else "on all year")
    log.info("%s: hourly crown transmittance (%s) along the sun for %d hours, %d rays per hour "
             "and crown; leaf %s", sc.name, options.definition, HOURS, options.rays, season)
    frame = facade_frame(project)
    models = crown_models(project, sc, frame)
    schedules = year_schedules(project, sc, frame, options=options, models=models)
    for cs in schedules:
        log.info("  %s: transmittance %.4f–%.4f, mean %.4f (%d leaf-on hours)", cs.crown.name,
                 cs.values.min(), cs.values.max(), cs.values.mean(), int(cs.leaf_on.sum()))
    for caveat in CAVEATS:
        log.info("  caveat: %s", caveat)
    return ExportInputs(project, sc, schedules=schedules, leaf=leaf_material(models[0], models[2]))


def prepare(project: Project, plan: ExportPlan, options: ExportOptions) -> ExportInputs:
    """What the plan's format needs, and nothing more."""
    needs = plan.format.needs
    inputs = ExportInputs(project, plan.scenario)
    if "schedules" in needs:
        inputs = crown_schedules(project, plan.scenario, options.schedule)
    if "scene" in needs:
        from radtree.pipeline.assemble import make_scene

        inputs = replace(inputs, scene=make_scene(project, plan.scenario))
    if "honeybee_model" in needs and project.honeybee is not None:
        from radtree.site.honeybee_model import load_model

        inputs = replace(inputs, honeybee_model=load_model(project.honeybee.model))
    return inputs


def export_project(project: Project, *, options: ExportOptions) -> list[Path]:
    """Write ``project`` in ``options.format`` into folder ``options.out``; return the files
    written (see the module)."""
    plan = plan_export(project, options)
    return plan.format.writer()(prepare(project, plan, options), plan.out)
