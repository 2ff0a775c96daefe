"""Honeybee and EnergyPlus out: crowns as ``ShadeMesh`` with the leaf modifier and a transmittance
schedule (HBJSON), the same model as IDF (honeybee-energy), ``Schedule:File`` CSV, and grid
results in honeybee-radiance's point-in-time layout.

* HBJSON: one ``ShadeMesh`` per crown envelope (``radtree_crown_1`` …), Radiance modifier the
  crown model's leaf material (``trans``: C, trans, tspec as radtree writes it), energy
  ``transmittance_schedule`` a ``ScheduleFixedInterval`` of the 8760 hourly values of
  :mod:`radtree.export.transmittance` (type limit Fractional). With ``[site] honeybee`` the
  shades are added to the project's own model (rooms, apertures, grids), else the model holds
  the shades alone. ``check_all()`` is run before writing.
* IDF: ``honeybee_energy.writer.model_to_idf`` of that model; file schedules go next to it.
* Schedule CSV: ``crown_transmittance.csv`` — a header row of crown names, then 8760 rows
  (hour 1 = 00:00–01:00 local standard time, 1 January), one column per crown; and
  ``crown_transmittance.idf`` with the matching ``Schedule:File`` objects (1 row to skip).
* Both IDFs carry ``ShadowCalculation`` PolygonClipping, recomputed daily
  (:data:`SHADOW_CALCULATION`): without it EnergyPlus may ignore the schedule.
* Results: ``<out>/<scenario>/<HHMM>/<grid>.res`` (one lux value per sensor, in the grid's
  order) with ``grids_info.json``, and the model with its grids as ``model.hbjson`` — the
  folder Ladybug Tools' point-in-time result loaders read; and after ``radtree annual`` the
  annual layout (``sun-up-hours.txt``, ``__static_apertures__/default/total/<grid>.ill``).
"""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from radtree.errors import RadtreeError
from radtree.export.transmittance import HOURS, CrownSchedule
from radtree.fileio import atomic_path, write_text
from radtree.optics import Glass, Material, Plastic, Trans

if TYPE_CHECKING:
    from radtree.export.registry import ExportInputs

log = logging.getLogger(__name__)
CSV_NAME = "crown_transmittance"
#: EnergyPlus ShadowCalculation for scheduled shade transmittance: PolygonClipping (the
#: PixelCounting method treats transmitting shades as opaque, EnergyPlus issue #9059 and its
#: warning, pull request #9653) recomputed every day (a transmittance schedule is sampled at
#: the shadow calculation's update frequency, default 20 days: issue #3073, whose workaround
#: is frequency 1)
SHADOW_CALCULATION = {"calculation_method": "PolygonClipping",
                      "calculation_update_method": "Periodic", "calculation_frequency": 1}
RADTREE_GRIDS = ("facade", "facade_map")


def hb_modifier(material: Material) -> Any:
    """The honeybee-radiance modifier of a radtree material (grey: R = G = B)."""
    from honeybee_radiance.modifier.material import Glass as HBGlass
    from honeybee_radiance.modifier.material import Plastic as HBPlastic
    from honeybee_radiance.modifier.material import Trans as HBTrans

    if isinstance(material, Trans):
        c, trans, tspec = material.coefficients
        return HBTrans(material.name, c, c, c, 0, 0, trans, tspec)
    if isinstance(material, Plastic):
        r = material.reflectance
        return HBPlastic(material.name, r, r, r, material.specularity, material.roughness)
    if isinstance(material, Glass):
        t = material.transmissivity
        return HBGlass(material.name, t, t, t)
    raise RadtreeError(f"material {material.name!r} ({type(material).__name__}) has no "
                       "Honeybee modifier")


def crown_shades(schedules: list[CrownSchedule], leaf: Material, prefix: str = "radtree"
                 ) -> list[Any]:
    """One ``ShadeMesh`` per crown with the leaf modifier and its transmittance schedule."""
    from honeybee.shademesh import ShadeMesh
    from honeybee_energy.lib.scheduletypelimits import fractional
    from honeybee_energy.schedule.fixedinterval import ScheduleFixedInterval
    from ladybug_geometry.geometry3d import Mesh3D, Point3D

    modifier = hb_modifier(leaf)
    shades = []
    for cs in schedules:
        c = cs.crown
        mesh = Mesh3D([Point3D(*map(float, v)) for v in c.vertices],
                      [tuple(int(i) for i in f) for f in c.faces])
        shade = ShadeMesh(f"{prefix}_{c.name}", mesh)
        shade.display_name = f"radtree {c.name.replace('_', ' ')}"
        shade.properties.radiance.modifier = modifier
        shade.properties.energy.transmittance_schedule = ScheduleFixedInterval(
            f"{prefix}_{c.name}_transmittance", [float(v) for v in cs.values], fractional)
        shades.append(shade)
    return shades


def shade_model(name: str, shades: list[Any], base: Any | None = None) -> Any:
    """``base`` (a honeybee Model, e.g. the project's) with the shades added, or a new model
    of the shades alone; checked with ``check_all()``."""
    from honeybee.model import Model
    from honeybee.typing import clean_string

    model = base if base is not None else Model(clean_string(name) or "radtree",
                                                units="Meters", tolerance=0.01)
    model.add_shade_meshes(shades)
    report = model.check_all(raise_exception=False)
    if report:
        raise RadtreeError(f"the exported Honeybee model does not pass check_all():\n{report}")
    return model


def write_hbjson(model: Any, out: Path, name: str = "radtree_crowns") -> Path:
    path = out / f"{name}.hbjson"
    write_text(path, json.dumps(model.to_dict(), indent=None))
    return path


def shadow_calculation_idf() -> str:
    """The ``ShadowCalculation`` object of :data:`SHADOW_CALCULATION` (honeybee-energy)."""
    from honeybee_energy.simulation.shadowcalculation import ShadowCalculation

    return str(ShadowCalculation(**SHADOW_CALCULATION).to_idf())


def write_idf(model: Any, out: Path, name: str = "radtree_crowns") -> Path:
    """The model as IDF (honeybee-energy) with the :func:`shadow_calculation_idf` object."""
    from honeybee_energy.writer import model_to_idf

    text = model_to_idf(model, schedule_directory=str(out)) + "\n\n" + shadow_calculation_idf()
    path = out / f"{name}.idf"
    write_text(path, text)
    return path


def write_schedule_csv(schedules: list[CrownSchedule], out: Path) -> tuple[Path, Path]:
    """``crown_transmittance.csv`` (header + 8760 rows) and its ``Schedule:File`` objects."""
    from honeybee_energy.lib.scheduletypelimits import fractional
    from honeybee_energy.writer import generate_idf_string

    names = [cs.crown.name for cs in schedules]
    for cs in schedules:
        if len(cs.values) != HOURS:
            raise RadtreeError(f"{cs.crown.name}: {len(cs.values)} hourly values, not {HOURS}")
    rows = [",".join(names)] + [",".join(f"{v:.6f}" for v in row)
                                for row in np.column_stack([cs.values for cs in schedules])]
    csv = write_text(out / f"{CSV_NAME}.csv", "\n".join(rows) + "\n")
    comments = ("schedule name", "schedule type limits", "file name", "column number",
                "rows to skip", "number of hours of data", "column separator",
                "interpolate to timestep", "minutes per item")
    objs = [fractional.to_idf()] + [generate_idf_string(
        "Schedule:File", (f"radtree_{n}_transmittance", fractional.identifier, csv.name, i + 1,
                          1, HOURS, "Comma", "No", 60), comments) for i, n in enumerate(names)]
    objs.append(shadow_calculation_idf())
    idf = write_text(out / f"{CSV_NAME}.idf", "\n\n".join(objs) + "\n")
    return csv, idf


def crowns_model(inputs: ExportInputs) -> Any:
    """The crown shades of ``inputs`` (:func:`crown_shades`) in the project's Honeybee model
    when it has one, else alone (:func:`shade_model`)."""
    schedules, leaf = inputs.crown_schedules()
    return shade_model(inputs.project.name, crown_shades(schedules, leaf), inputs.honeybee_model)


def export_hbjson(inputs: ExportInputs, out: Path) -> list[Path]:
    """Format ``honeybee`` (:mod:`radtree.export.registry`): ``radtree_crowns.hbjson``."""
    path = write_hbjson(crowns_model(inputs), out)
    log.info("%d crown shades → %s", len(inputs.crown_schedules()[0]), path)
    return [path]


def export_idf(inputs: ExportInputs, out: Path) -> list[Path]:
    """Format ``idf``: ``radtree_crowns.idf`` (and the file schedules beside it)."""
    path = write_idf(crowns_model(inputs), out)
    log.info("%d crown shades → %s", len(inputs.crown_schedules()[0]), path)
    return [path]


def export_schedule(inputs: ExportInputs, out: Path) -> list[Path]:
    """Format ``schedule``: ``crown_transmittance.csv`` and ``crown_transmittance.idf``."""
    return list(write_schedule_csv(inputs.crown_schedules()[0], out))


def write_results(table: pd.DataFrame, model: Any, out: Path) -> list[Path]:
    """Grid results of the model's sensor grids in honeybee-radiance's point-in-time layout
    (see the module); ``table`` is radtree's results table. Returns the folders written."""
    grids = {g.identifier: g for g in model.properties.radiance.sensor_grids}
    write_text(out / "model.hbjson", json.dumps(model.to_dict()))
    folders = []
    sel = table[table["grid"].isin(list(grids))]
    for (scenario, time), part in sel.groupby(["scenario", "time"], sort=True):
        folder = out / str(scenario) / str(time).replace(":", "")
        info = []
        for gid, rows in part.groupby("grid", sort=False):
            g = grids[gid]
            lux = rows.sort_values("sensor")["lux"].to_numpy()
            if len(lux) != g.count:
                raise RadtreeError(f"grid {gid}: {len(lux)} results for {g.count} sensors")
            write_text(folder / f"{gid}.res", "\n".join(f"{v:.2f}" for v in lux) + "\n")
            info.append(g.info_dict())
        write_text(folder / "grids_info.json", json.dumps(info, indent=2))
        folders.append(folder)
    return folders


def write_annual_results(hourly: Path, model: Any, out: Path) -> list[Path]:
    """Annual results (``results/annual/hourly.npz`` of ``radtree annual``) of the model's grids
    in honeybee-radiance's annual layout, one folder per variant (``with``, ``without``,
    ``leaf_on``, ``leaf_off``): ``grids_info.json``, ``sun-up-hours.txt`` (hours of the year at
    the hours' middles, e.g. 12.5) and ``__static_apertures__/default/{total,direct}/<grid>.ill``
    (one row per sensor, one column per sun-up hour, lux) and the same as ``<grid>.npy``
    (float32, what honeybee-radiance-postprocess's ``AnnualDaylight`` loads)."""
    from radtree.annual.schedule import day_of_year

    data = np.load(hourly)
    grids = {g.identifier: g for g in model.properties.radiance.sensor_grids}
    hoy = (day_of_year(data["month"], data["day"]) - 1) * 24 + data["hour"]
    variants = sorted({k.split("__")[1] for k in data.files if k.startswith("total__")})
    folders = []
    for variant in variants:
        names = [g for g in grids if f"total__{variant}__{g}" in data.files]
        if not names:
            continue
        up = np.zeros(len(hoy), bool)
        for g in names:
            up |= data[f"total__{variant}__{g}"].max(axis=0) > 0
        folder = out / variant
        write_text(folder / "sun-up-hours.txt", "\n".join(f"{h:g}" for h in hoy[up]) + "\n")
        write_text(folder / "grids_info.json",
                   json.dumps([grids[g].info_dict() for g in names], indent=2))
        for g in names:
            for kind in ("total", "direct"):
                values = data[f"{kind}__{variant}__{g}"][:, up]
                text = "\n".join(" ".join(f"{v:.1f}" for v in row) for row in values)
                write_text(folder / "__static_apertures__" / "default" / kind / f"{g}.ill",
                           text + "\n")
                # honeybee-radiance-postprocess reads the same values as NumPy arrays
                with atomic_path(folder / "__static_apertures__" / "default" / kind /
                                 f"{g}.npy") as tmp, open(tmp, "wb") as fh:
                    np.save(fh, np.round(values, 1).astype(np.float32))
        folders.append(folder)
    return folders
