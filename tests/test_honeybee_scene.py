"""``radtree export --format honeybee-scene``: radtree's scene, leaf by leaf, as a Honeybee model
that Ladybug Tools' Radiance recipes trace as radtree does.

The one-room Honeybee model of ``test_honeybee_model`` with one radtree louvers crown in front
of its window is built; the ``crown`` scenario is exported; honeybee-radiance's *own*
translation of the exported model (``model_to_rad``) and radtree's build folder are traced by
the same ``rtrace`` (radtree's octree from its build folder's Makefile; the hour's sky without
the sun and radtree's ground material added to Honeybee's translation) on the
office's work plane, eight independent fixed-seed estimates each: the means must agree within
1 % or 3 combined standard errors.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

from radtree.config import load_project

from .conftest import needs_radiance
from .test_honeybee_model import CROWN, TOML, write_project

pytest.importorskip("honeybee.model")   # a guard only: CI installs radtree[honeybee]

REPEATS = 8        # independent fixed-seed estimates per octree


def rtrace(build: Path, octree: Path, pts: str) -> np.ndarray:
    """(REPEATS, sensors) lux at ``pts`` in ``octree``: the grid fed :data:`REPEATS` times to
    one fixed-seed ``rtrace -ab 2 -ad 1024`` (independent, reproducible estimates)."""
    from radtree.engines.radiance.binaries import FIXED_SEED, monte_carlo_options, require_radiance
    from radtree.engines.radiance.writer import rgb_to_lux

    opts = ["-h", "-I", FIXED_SEED, *monte_carlo_options(2, 1024, 1e-4)]
    out = subprocess.run(["rtrace", *opts, str(octree)], cwd=build,
                         input=(pts * REPEATS).encode(), capture_output=True, check=True,
                         env=require_radiance().env()).stdout
    return rgb_to_lux(np.loadtxt(out.decode().splitlines()).reshape(-1, 3)).reshape(REPEATS, -1)


def honeybee_octree(build: Path, files: list[Path]) -> Path:
    """``files`` with the 13:30 sky and ground material of radtree's ``build``."""
    from radtree.engines.radiance.binaries import require_radiance

    oct_path = build.parent / "honeybee_scene.oct"
    with oct_path.open("wb") as fh:
        subprocess.run(["oconv", "skies/1330_ground.rad", "skies/1330.sky", *map(str, files)],
                       cwd=build, stdout=fh, check=True, env=require_radiance().env())
    return oct_path


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    from radtree.export.run import ExportOptions, export_project
    from radtree.pipeline.build import build_project

    folder = write_project(tmp_path_factory.mktemp("hbs") / "p", dni=0.0,
                           toml=TOML.replace("[sensors]", "[sensors]\nheight_m = 1.5") + CROWN)
    project = load_project(folder)
    build_project(project, pictures=False)
    out = folder / "export"
    files = export_project(project, options=ExportOptions(format="honeybee-scene", out=out,
                                                          scenario="crown"))
    return project, files


def test_scene_export_holds_every_leaf_with_its_modifier(exported):
    from honeybee.model import Model

    from radtree.pipeline.assemble import make_scene

    project, files = exported
    assert [f.name for f in files] == ["radtree_scene.hbjson"]
    model = Model.from_hbjson(str(files[0]))
    assert len(model.rooms) == 1 and model.properties.radiance.sensor_grids == ()
    shades = {s.identifier: s for s in model.shade_meshes}
    scene = make_scene(project, next(s for s in project.scenarios if s.name == "crown")).scene
    ours = {f"radtree_{m.name}": m for m in scene.solid_meshes()
            if m.n_triangles and not m.name.startswith("hb_")}
    assert set(shades) == set(ours) >= {"radtree_tree_leaves", "radtree_ground"}
    for name, mesh in ours.items():
        assert len(shades[name].geometry.faces) == mesh.n_triangles
        assert shades[name].is_detached
    leaf = shades["radtree_tree_leaves"].properties.radiance.modifier
    c, trans, tspec = scene.materials["leaf"].coefficients
    assert type(leaf).__name__ == "Trans"
    assert (leaf.r_reflectance, leaf.transmitted_diff, leaf.transmitted_spec) == pytest.approx(
        (c, trans, tspec))


@needs_radiance
def test_honeybee_translation_traces_as_radtree(exported, tmp_path):
    """rtrace on honeybee-radiance's translation of the export = rtrace on radtree's build."""
    from honeybee.model import Model
    from honeybee_radiance.writer import model_to_rad

    project, files = exported
    build = project.build_dir / "crown"
    geometry, modifiers = model_to_rad(Model.from_hbjson(str(files[0])))
    (tmp_path / "modifiers.rad").write_text(modifiers)
    (tmp_path / "hb_scene.rad").write_text(geometry)
    pts = (build / "grids" / "office.pts").read_text()
    theirs = rtrace(build, honeybee_octree(build, [tmp_path / "modifiers.rad",
                                                  tmp_path / "hb_scene.rad"]), pts)
    subprocess.run(["make", "-s", "octrees/1330.oct"], cwd=build, check=True,
                   capture_output=True)          # radtree's own octree (its Makefile)
    ours = rtrace(build, build / "octrees" / "1330.oct", pts)
    A, B = ours.mean(axis=1), theirs.mean(axis=1)
    assert ours.shape == (REPEATS, 15) and A.min() > 10
    se = float(np.hypot(A.std(ddof=1), B.std(ddof=1)) / np.sqrt(REPEATS))
    diff = float(B.mean() - A.mean())
    print(f"honeybee-scene: work-plane mean radtree {A.mean():.1f}, honeybee {B.mean():.1f} lx "
          f"({100 * diff / A.mean():+.2f} %, {diff / se:+.2f} SE)")
    assert abs(diff) <= max(0.01 * A.mean(), 3.0 * se)
