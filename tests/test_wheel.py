"""The wheel carries templates/ and materials/: build it, install it apart, render from it.

The checkout's shipping files are copied to a temporary folder (so the build leaves nothing in
the checkout), ``pip wheel --no-deps`` builds the wheel there (build isolation: setuptools comes
from pip's cache or PyPI), ``pip install --no-deps --target`` unpacks it into another folder,
and this interpreter runs there with only that folder added to its path, from a directory
outside the checkout: radtree must come from the wheel and find its files inside it.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from tests.conftest import ROOT

pytestmark = pytest.mark.slow

SHIPPED = ["pyproject.toml", "setup.py", "README.md", "radtree", "templates", "materials"]

PROBE = textwrap.dedent("""
    import json, sys
    import radtree
    from radtree import resources
    make = resources.template_environment(keep_trailing_newline=True).get_template(
        "Makefile.j2").render(version="0", scenario="S", hours=["1200"], grids=["facade"],
        hour_grids={"1200": ["facade"]}, scene_files=["materials.rad"],
        hour_files={"1200": ["skies/1200.sky"]}, rtrace_opts="-h -I -ab 2",
        efficacy="179", weights=["0.265", "0.670", "0.065"], bin_dir="/usr/local/bin", raypath=".",
        prototypes={}, mkpmap={"1200": ""}, pmaps={"1200": []}, rtrace_pmap={"1200": ""},
    grid_opts={}, meshes={}, mesh_cmds={})
    print(json.dumps({"radtree": radtree.__file__, "templates": str(resources.folder("templates")),
                      "makefile": make, "leaf": resources.material_text("leaf"),
                      "materials": resources.material_files(),
                      "species": sorted(p.name for p in resources.folder("materials")
                                        .joinpath("species").iterdir()),
                      "sections": sorted(p.name for p in resources.folder("templates")
                                         .joinpath("sections").iterdir())}))
""")


def _pip(*args: str, cwd: Path) -> None:
    subprocess.run([sys.executable, "-m", "pip", "--disable-pip-version-check", *args],
                   cwd=cwd, check=True, capture_output=True, text=True, timeout=240)


def test_wheel_ships_templates_and_materials(tmp_path: Path) -> None:
    src = tmp_path / "src"
    src.mkdir()
    for name in SHIPPED:
        p = ROOT / name
        if p.is_dir():
            shutil.copytree(p, src / name, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copyfile(p, src / name)
    dist = tmp_path / "dist"
    _pip("wheel", "--no-deps", "--quiet", "-w", str(dist), str(src), cwd=tmp_path)
    wheels = list(dist.glob("radtree-*.whl"))
    assert len(wheels) == 1, wheels
    site = tmp_path / "site"
    _pip("install", "--no-deps", "--quiet", "--target", str(site), str(wheels[0]), cwd=tmp_path)
    assert (site / "radtree" / "templates" / "Makefile.j2").is_file()
    assert (site / "radtree" / "materials" / "leaf.rad").is_file()

    away = tmp_path / "elsewhere"
    away.mkdir()
    env = {"PYTHONPATH": str(site), "PYTHONNOUSERSITE": "1", "PATH": "/usr/bin:/bin"}
    run = subprocess.run([sys.executable, "-c", PROBE], cwd=away, env=env, check=True,
                         capture_output=True, text=True, timeout=60)
    got = json.loads(run.stdout)
    assert Path(got["radtree"]).is_relative_to(site), got["radtree"]
    assert Path(got["templates"]).is_relative_to(site / "radtree"), got["templates"]
    assert "RTRACE_OPTS := -h -I -ab 2" in got["makefile"]
    assert "octrees/1200.oct: $(SCENE) skies/1200.sky" in got["makefile"]
    assert "void trans leaf" in got["leaf"] and "7 0.61 0.61 0.61 0 0 0.8197 0.9" in got["leaf"]
    assert got["materials"] == ["concrete.rad", "glazing.rad", "leaf.rad", "paint.rad"]
    assert "morus_alba.toml" in got["species"] and "morus_alba.rad" in got["species"]
    assert "provenance.html.j2" in got["sections"]
