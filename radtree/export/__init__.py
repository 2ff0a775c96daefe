"""Exports of a radtree project to the tools users already have (layer 7, reads scenes and the
results table): Honeybee (HBJSON: crowns as ``ShadeMesh`` with the leaf Radiance modifier and
an hourly transmittance schedule), EnergyPlus (IDF via honeybee-energy, ``Schedule:File`` CSV),
glTF / OBJ (the whole scene via trimesh), and results in honeybee-radiance's layout.

Entry point: :func:`radtree.export.run.export_project`; the formats are registered by name in
:mod:`radtree.export.registry` (one writer module and one registry line each).
"""

from radtree.export.registry import EXPORT_FORMATS, FORMATS

__all__ = ["EXPORT_FORMATS", "FORMATS"]
