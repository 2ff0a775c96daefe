"""The Radiance material library (top-level materials/) is exactly what radtree emits."""

from __future__ import annotations

import pandas as pd
import pytest

from radtree.config import load_project
from radtree.engines.radiance.writer import materials_text
from radtree.optics import Glass, with_reflectance
from radtree.resources import material_files, material_text, read_text, template_environment
from radtree.site.office import office_materials
from radtree.site.street import street_materials
from radtree.trees.louvers import LouverOptics
from tests.conftest import MENDOZA, ROOT

OFFICE = ROOT / "examples" / "office-block"


def entries(text: str) -> dict[str, str]:
    """Radiance primitives of ``text`` by name: their exact text (comment lines dropped).

    Parses ``MODIFIER TYPE NAME``, then the three argument lists (n strings, n integers,
    n reals), each introduced by its count, and keeps the lines the entry spans verbatim."""
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    out: dict[str, str] = {}
    i = 0
    while i < len(lines):
        head = lines[i].split()
        assert len(head) == 3, f"not a primitive header: {lines[i]!r}"
        start, i = i, i + 1
        for _ in range(3):
            count = int(lines[i].split()[0])
            assert len(lines[i].split()) == count + 1, f"{head[2]}: {lines[i]!r}"
            i += 1
        name = head[2]
        assert name not in out, f"{name} defined twice"
        out[name] = "\n".join(lines[start:i]) + "\n"
    return out


def library() -> dict[str, str]:
    out: dict[str, str] = {}
    for f in material_files():
        for name, text in entries(read_text("materials", f)).items():
            assert name not in out, f"{name} in two library files"
            out[name] = text
    return out


def emitted() -> dict[str, str]:
    """What radtree writes into materials.rad for the library's materials, from the examples."""
    mendoza, office = load_project(MENDOZA), load_project(OFFICE)
    assert office.office is not None
    mats = {**street_materials(mendoza.street), **office_materials(office.office)}
    lv = LouverOptics.of(mendoza.tree.louvers)
    mats["leaf"] = lv.material()
    mats["leaf_glass"] = Glass.from_transmittance("leaf_glass", lv.transmittance)
    table = pd.read_csv(MENDOZA / "data" / "concrete_reflectance.csv", comment="#")
    rho60 = float(table.loc[table["angle_deg"] == 60, "reflectance"].iloc[0])
    mats["ground"] = with_reflectance(mats["ground"], rho60)
    return entries(materials_text(mats))


def test_library_files_and_readme() -> None:
    assert material_files() == ["concrete.rad", "glazing.rad", "leaf.rad", "paint.rad"]
    assert "leaf.rad" in read_text("materials", "README.md")
    assert "void trans leaf" in material_text("leaf")


@pytest.mark.parametrize("name", ["leaf", "leaf_glass", "facade_paint", "opposite_facade",
                                  "ground", "glazing", "window_frame"])
def test_library_entry_is_what_radtree_emits(name: str) -> None:
    lib, out = library(), emitted()
    assert set(lib) == {"leaf", "leaf_glass", "facade_paint", "opposite_facade", "ground",
                        "glazing", "window_frame"}
    assert lib[name] == out[name]


def test_library_values() -> None:
    lib = library()
    assert lib["facade_paint"].splitlines()[-1] == "5 0.9 0.9 0.9 0 0"
    assert lib["glazing"].splitlines()[-1] == "3 0.8715 0.8715 0.8715"
    assert lib["leaf"].splitlines()[-1] == "7 0.61 0.61 0.61 0 0 0.8197 0.9"


def test_templates_resolve() -> None:
    env = template_environment()
    for name in ("Makefile.j2", "report.html.j2", "report.md.j2"):
        assert env.get_template(name) is not None
