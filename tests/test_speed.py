"""Work not done twice: the -ab convergence table reuses an earlier table's runs."""

from __future__ import annotations

import numpy as np

from radtree.config import load_project
from radtree.convergence import convergence_table, read_convergence, write_convergence
from radtree.pipeline.options import RunOptions
from radtree.trees.geometry import polygons_to_mesh

from .conftest import copy_project


def test_convergence_reuses_matching_runs_only(tmp_path):
    """A second run takes every (scenario, hour, -ab, -ad, engine, parameter hash) it finds in
    results/convergence.csv and traces the rest: a stored value edited by hand comes back as
    stored, a row with another parameter hash is traced again (and gives the traced value)."""
    p = load_project(copy_project(tmp_path / "proj", hours=["13:30"]),
                     overrides={"engine.rays": 64})
    first = convergence_table(p, options=RunOptions(engine="numpy", scenarios=["E"]),
                              ab_values=(1, 2))
    assert first["ab"].tolist() == [1, 2, 5] and set(first["engine"]) == {"numpy"}
    assert (first["params_hash"] == p.params_hash(p.scenario("E"))).all()
    edited = first.copy()
    edited.loc[0, "facade_mean_lux"] = 12345.6              # -ab 1: reused as stored
    edited.loc[1, "params_hash"] = "other"                   # -ab 2: not reused, traced again
    write_convergence(p, edited)
    again = convergence_table(p, options=RunOptions(engine="numpy", scenarios=["E"]),
                              ab_values=(1, 2), previous=read_convergence(p))
    assert again["facade_mean_lux"].tolist() == [12345.6, *first["facade_mean_lux"][1:]]
    assert again["change"].iloc[1] == round((first["facade_mean_lux"].iloc[1] - 12345.6)
                                            / 12345.6, 4)


def test_polygons_to_mesh_fans_each_polygon_in_order():
    """Triangle (0, i, i + 1) of each polygon with ≥ 3 corners, vertices stacked in order."""
    tri = np.zeros((3, 3))
    quad = np.arange(12.0).reshape(4, 3)
    line = np.ones((2, 3))
    pent = np.arange(15.0).reshape(5, 3) + 100
    verts, faces = polygons_to_mesh([tri, line, quad, pent])
    np.testing.assert_array_equal(verts, np.vstack([tri, quad, pent]))
    assert faces.tolist() == [[0, 1, 2], [3, 4, 5], [3, 5, 6],
                              [7, 8, 9], [7, 9, 10], [7, 10, 11]]
    assert faces.dtype == np.int64
    v0, f0 = polygons_to_mesh([line])
    assert v0.shape == (0, 3) and f0.shape == (0, 3)
