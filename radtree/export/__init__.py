"""Exports of a radtree project to the tools users already have (layer 7, reads scenes and the
results table): Honeybee (HBJSON: crowns as ``ShadeMesh`` with the leaf Radiance modifier and
an hourly transmittance schedule), EnergyPlus (IDF via honeybee-energy, ``Schedule:File`` CSV),
glTF / OBJ (the whole scene via trimesh), and results in honeybee-radiance's layout.

Entry point: :func:`radtree.export.run.export_project`.
"""

FORMATS = ("honeybee", "idf", "schedule", "gltf", "obj")

__all__ = ["FORMATS"]
