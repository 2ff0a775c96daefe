"""Which tree: the NumPy engine's attribution of the light each tree removes
(radtree.engines.numpy.attribution) and results/tree_impact.csv (radtree.pipeline.tree_impact)."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from radtree.config import EngineParams, load_project
from radtree.engines.numpy.attribution import attribute_hour
from radtree.engines.numpy.scenes import sky_state, slat_layer
from radtree.engines.numpy.tracing import trace_hour
from radtree.engines.registry import attributing_engine, get_engine
from radtree.optics import Plastic, Trans
from radtree.pipeline.tree_impact import COLUMNS, removal_check, target_rows
from radtree.scene import Mesh, Scene, SensorGrid, quad

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def _street() -> Scene:
    """A wall (y = 0, facing south) over a ground plane, two slat crowns ("t1", "t2") 5–6 m in
    front of it, 6 m apart, and a row of 9 façade sensors at 4 m."""
    rng = np.random.default_rng(3)
    ground = quad("ground", "ground", np.array([[-30, -30, 0], [30, -30, 0], [30, 30, 0],
                                                [-30, 30, 0]], float))
    wall = quad("wall", "wall", np.array([[-20, 0, 0], [20, 0, 0], [20, 0, 15], [-20, 0, 15]],
                                         float))
    crowns = []
    for name, centre in (("t1", (-3.0, -5.0)), ("t2", (3.0, -6.0))):
        m = slat_layer(name, "leaf", lai=2, extent=5, z_bottom=3, z_top=8, size=0.3,
                       inclination_deg=45, rng=rng, centre=centre)
        crowns.append(Mesh(m.name, m.material, m.vertices, m.faces,
                           np.full(m.n_triangles, name)))
    x = np.linspace(-8, 8, 9)
    grid = SensorGrid("facade", np.column_stack([x, np.full(9, -0.1), np.full(9, 4.0)]),
                      np.tile([0.0, -1.0, 0.0], (9, 1)), labels={"facade": ["south"] * 9})
    mats = {"ground": Plastic("ground", 0.2), "wall": Plastic("wall", 0.4),
            "leaf": Trans("leaf", 0.1, 0.1, 0.05)}
    return Scene([ground, wall, *crowns], mats, {"facade": grid})


STATE = sky_state("perez", altitude=50, azimuth=180, dni=60000, dhi=15000)
PARAMS = EngineParams(rays=128, max_bounces=2, seed=1)


def test_attribution_leaves_the_traced_numbers_alone_and_adds_up():
    scene = _street()
    att = attribute_hour(scene, STATE, PARAMS)["facade"]
    ref = trace_hour(scene, STATE, PARAMS)["facade"]
    # the with-trees trace is the engine's trace to the last bit (same streams, same numbers)
    np.testing.assert_array_equal(att.with_trees.lux, ref.lux)
    np.testing.assert_array_equal(att.with_trees.stderr, ref.stderr)
    # the tree-less trace is the engine's trace of the scene without the trees' faces
    bare = trace_hour(scene.without_owners(), STATE, PARAMS)["facade"]
    np.testing.assert_allclose(att.without.lux, bare.lux, rtol=1e-12)
    # a path that crosses no crown's box changes nothing
    assert np.all(att.unattributed == 0.0)
    assert att.owners == ["t1", "t2"]
    # each tree's light is what the engine's trace without that tree alone gives back, on the
    # same paths (those that cross both crowns' boxes traced again with the tree skipped)
    for i, name in enumerate(att.owners):
        alone = trace_hour(scene.without_owners({name}), STATE, PARAMS)["facade"]
        np.testing.assert_allclose(att.removed[i], alone.lux - ref.lux, rtol=1e-9, atol=1e-6)
    # the joint part: light both crowns take (either would), given to neither
    joint = (att.without.lux - att.with_trees.lux) - att.removed.sum(axis=0)
    assert joint.max() > 0
    # the west sensors lose most to t1 (in front of them), the east ones to t2
    assert att.removed[0, 0] > 3 * att.removed[1, 0]
    assert att.removed[1, -1] > 3 * att.removed[0, -1]


def test_removing_a_tree_changes_the_facade_by_its_attributed_light():
    # the attribution and the change when the tree alone is removed and the scene traced
    # again (another seed: independent estimates) agree within their standard errors
    table = removal_check(get_engine("numpy"), _street(), STATE, PARAMS, 2, top=2)
    assert sorted(table["tree"]) == ["t1", "t2"]
    assert (table["attributed"] > 1000).all()
    assert (table["z"].abs() < 3).all(), table.to_string()
    # with the attribution's own seed the removal is the attribution, path for path
    assert (table["same_seed"].abs() < 1e-6).all()


def test_target_rows_give_facade_means_and_shares():
    scene = _street()
    att = attribute_hour(scene, STATE, PARAMS)["facade"]
    rows = target_rows("trees", "12:00", "facade", scene.grids["facade"].labels, att)
    assert list(rows.columns) == COLUMNS
    assert list(rows["tree"]) == ["t1", "t2"]
    change = (att.without.lux - att.with_trees.lux).mean()
    np.testing.assert_allclose(rows["share"], rows["lux_removed"] / change, rtol=1e-12)
    assert 0.5 < rows["share"].sum() <= 1.0   # the rest: light both crowns take
    assert rows["lux_removed"].iloc[0] == pytest.approx(att.removed[0].mean())
    assert rows["lux_removed_stderr"].iloc[0] == pytest.approx(
        np.sqrt((att.stderr[0] ** 2).sum()) / 9)


@pytest.fixture(scope="module")
def district():
    """The district example (8 paths per sensor) and its ``trees`` scene."""
    from radtree.pipeline.assemble import make_scene

    project = load_project(EXAMPLES / "district", {"engine.rays": 8})
    return project, make_scene(project, project.scenario("trees"), dense_grid=False)


def test_inventory_crowns_name_their_trees(district):
    scene = district[1].scene
    owners = scene.owners()
    assert len(owners) == 64 and owners[0].startswith("T")
    # every crown face belongs to a tree; removing one tree removes its instance only
    solid = scene.solid_meshes()
    assert all(m.owners is not None and (m.owners != "").all() for m in solid
               if m.material.startswith("leaf_") or m.material == "trunk")
    fewer = scene.without_owners({owners[0]})
    assert len(fewer.instances) + sum(1 for i in scene.instances if i.owner == owners[0]) \
        == len(scene.instances)
    assert fewer.owners() == owners[1:]
    assert attributing_engine() is not None and attributing_engine().attributes_trees


def test_row_crowns_are_numbered():
    from radtree.pipeline.assemble import make_scene

    project = load_project(EXAMPLES / "mendoza-street")
    scene = make_scene(project, project.scenario("F"), dense_grid=False).scene
    assert scene.owners() == ["C1", "C2", "C3"]
    leaves, trunks = scene.mesh("tree_leaves"), scene.mesh("tree_trunks")
    assert leaves.owners is not None and (leaves.owners != "").all()
    # each crown's leaves gather around its own place in the row, C2 between C1 and C3
    c = leaves.vertices[leaves.faces].mean(axis=1)
    m1, m2, m3 = (c[leaves.owners == k].mean(axis=0) for k in ("C1", "C2", "C3"))
    d12, d23, d13 = (float(np.linalg.norm(a - b)) for a, b in ((m1, m2), (m2, m3), (m1, m3)))
    assert min(d12, d23) > 2.0 and d13 > max(d12, d23)
    assert list(np.unique(trunks.owners, return_counts=True)[1]) == [32, 32, 32]


def test_an_engine_that_cannot_attribute_hands_over_and_says_so(district, caplog):
    from radtree.engines.registry import engine_class
    from radtree.light.hours import hour_states
    from radtree.pipeline.tree_impact import tree_impact

    project, built = district
    sc = project.scenario("trees")
    grid = next(iter(built.scene.grids))
    radiance = engine_class("radiance")()
    assert not radiance.attributes_trees
    with caplog.at_level(logging.INFO, logger="radtree"):
        table = tree_impact(project, radiance, [sc, project.scenario("bare")],
                            {"trees": (built, hour_states(project, sc, ["12:30"]))},
                            grids=[grid])
    assert table is not None and list(table.columns) == COLUMNS
    assert ("does not attribute light to trees; attributed by the numpy engine"
            in caplog.messages[0])
    assert set(table["grid"]) == {grid} and set(table["scenario"]) == {"trees"}
    assert set(table["target"]) <= set(built.scene.grids[grid].labels["facade"])
    # no pair, no table: the reference street has no scenario without trees
    street = load_project(EXAMPLES / "mendoza-street")
    assert tree_impact(street, radiance, [street.scenario("F")], {"F": (built, [])}) is None


def test_simulate_with_and_without_the_tree_impact(tmp_path):
    """``radtree simulate --no-tree-impact`` writes the illuminance table alone (the same
    numbers); the default also attributes the light to the trees (results/tree_impact.csv)."""
    import re
    import shutil

    import pandas as pd
    from click.testing import CliRunner

    from radtree.cli import main

    p = tmp_path / "office"
    shutil.copytree(EXAMPLES / "office-block", p,
                    ignore=shutil.ignore_patterns("build", "results", "report"))
    toml = p / "radtree.toml"
    text = toml.read_text()
    for pat, rep in ((r"^rays = \d+", "rays = 16"), (r"^workers = \d+", "workers = 1")):
        text, n = re.subn(pat, rep, text, flags=re.M)
        assert n == 1
    toml.write_text(text)
    args = ["simulate", str(p), "--engine", "numpy", "--hour", "13:30"]
    skipped = CliRunner().invoke(main, [*args, "--no-tree-impact"])
    assert skipped.exit_code == 0, skipped.output
    impact = p / "results" / "tree_impact.csv"
    assert not impact.exists()
    lux = pd.read_csv(p / "results" / "illuminance.csv")["lux"].to_numpy()
    full = CliRunner().invoke(main, [*args, "--fresh"])
    assert full.exit_code == 0, full.output
    table = pd.read_csv(impact)
    assert set(table["scenario"]) == {"with"} and (table["lux_removed"].abs() > 0).any()
    np.testing.assert_array_equal(pd.read_csv(p / "results" / "illuminance.csv")["lux"], lux)
