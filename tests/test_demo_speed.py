"""What made `make demo` faster changes no number it should not (issue 22): the dense map's own
path count, traces in spawned worker processes, the build's pickled scene."""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
import pytest

from radtree.calibrate.scan import _run_job
from radtree.config import Scenario, load_project
from radtree.engines.numpy.tracing import trace_hour
from radtree.light.hours import hour_states
from radtree.pipeline import build as build_mod
from radtree.pipeline.assemble import make_scene
from radtree.pipeline.build import SCENE_FILE, build_project, build_staleness, built_scene
from radtree.pipeline.processes import spawned_map, with_threads
from radtree.sensor_grid import DENSE_GRID
from tests.conftest import copy_project


@pytest.fixture(scope="module")
def proj(tmp_path_factory):
    return load_project(copy_project(tmp_path_factory.mktemp("speed") / "proj",
                                     hours=["13:30"]))


def _scene_arrays(built):
    return [(m.name, m.material, m.vertices, m.faces) for m in built.scene.meshes]


def test_dense_rays_trace_the_map_only(proj):
    """``engine.dense_rays`` sets the dense map's paths per point; the façade sensors keep
    ``engine.rays`` and their numbers; 4 × fewer paths give a map s.e. ≈ 2 × larger."""
    sc = proj.scenario("E")
    built = make_scene(proj, sc, dense_grid=True)
    assert DENSE_GRID in built.scene.grids
    state = hour_states(proj, sc)[0]
    params = replace(proj.engine, rays=256, dense_rays=None, max_bounces=built.ab, workers=1)
    full = trace_hour(built.scene, state, params)
    few = trace_hour(built.scene, state, replace(params, dense_rays=64))
    np.testing.assert_array_equal(full["facade"].lux, few["facade"].lux)
    assert not np.array_equal(full[DENSE_GRID].lux, few[DENSE_GRID].lux)
    ratio = np.median(few[DENSE_GRID].stderr / full[DENSE_GRID].stderr)
    assert 1.7 < ratio < 2.4, ratio
    # the two maps agree within their errors: the same expectation
    z = (few[DENSE_GRID].lux - full[DENSE_GRID].lux) / np.hypot(few[DENSE_GRID].stderr,
                                                                full[DENSE_GRID].stderr)
    assert abs(float(np.mean(z))) < 4 / np.sqrt(len(z)) + 0.2


def test_traces_in_spawned_processes_equal_the_same_traces_here(proj):
    """The permeability scan's jobs give the very same numbers in 2 spawned processes with 1
    engine thread each as in this process with 2."""
    a = proj.scenario("A")
    jobs = [("sum", proj, Scenario("open", "none", "traced"), 128, 1),
            ("sum", proj, replace(a, reflection="traced"), 128, 1),
            ("hourly", proj, a, 128, 3)]
    here = [_run_job(j) for j in jobs]
    there = spawned_map(_run_job, [(k, with_threads(p, 1), s, r, sd)
                                   for k, p, s, r, sd in jobs], workers=2)
    assert here[0] == there[0] and here[1] == there[1]
    np.testing.assert_array_equal(here[2].to_numpy(), there[2].to_numpy())
    assert here[1][0] < here[0][0]   # the crown takes light: a real trace, not an echo


def test_simulate_and_report_load_the_built_scene(proj, monkeypatch):
    """A current build folder's scene.pickle is the scene ``make_scene`` builds, and is what
    :func:`built_scene` returns (no crown built); a changed pickle makes the folder stale and
    the scene is built anew."""
    build_project(proj, ["C"], pictures=False)
    sc = proj.scenario("C")
    fresh = make_scene(proj, sc)
    assert build_staleness(proj, sc) == ""

    def no_building(*_a, **_k):
        raise AssertionError("make_scene called although the build is current")

    monkeypatch.setattr(build_mod, "make_scene", no_building)
    loaded = built_scene(proj, sc)
    assert loaded.ab == fresh.ab and loaded.triangles == fresh.triangles
    for x, y in zip(_scene_arrays(loaded), _scene_arrays(fresh), strict=True):
        assert x[:2] == y[:2]
        np.testing.assert_array_equal(x[2], y[2])
        np.testing.assert_array_equal(x[3], y[3])
    monkeypatch.undo()
    (proj.build_dir / "C" / SCENE_FILE).write_bytes(b"not a pickle")
    assert "scene.pickle" in build_staleness(proj, sc)
    again = built_scene(proj, sc)
    assert again.triangles == fresh.triangles


def _scene_files(folder):
    """``relative path → [bytes, sha256]`` of a build folder's scene files (its manifest),
    without radtree's own pickle (it holds the build's timings)."""
    import json

    files = json.loads((folder / "manifest.json").read_text())["files"]
    return {k: v for k, v in files.items() if k != SCENE_FILE}


def test_build_in_two_processes_writes_the_same_folders(proj, tmp_path, caplog):
    """Four folders built by this process and a spawned worker are byte for byte the folders
    one process writes (the pickle aside); the facts come back for every scenario, in order."""
    names = ["A", "B", "C", "E"]
    one = build_project(proj, names, pictures=False, workers=1)
    first = {n: _scene_files(proj.build_dir / n) for n in names}
    with caplog.at_level(logging.INFO, logger="radtree"):
        two = build_project(proj, names, pictures=False, workers=2)
    lines = [r.getMessage() for r in caplog.records if r.name == "radtree.pipeline.build"]
    assert list(two) == names and [two[n]["triangles"] for n in names] == [
        one[n]["triangles"] for n in names]
    assert {n: _scene_files(proj.build_dir / n) for n in names} == first
    assert len(lines) == 4 and all("triangles" in m for m in lines)
    assert not list(proj.build_dir.glob(".*"))   # no temporary folder left behind


def test_build_keeps_current_folders_unless_fresh(proj, caplog):
    """``fresh=False`` keeps a current folder (not rewritten, facts from its manifest) and
    rebuilds a stale one; ``fresh=True`` rebuilds both."""
    build_project(proj, ["C", "E"], pictures=False)
    manifest_c = proj.build_dir / "C" / "manifest.json"
    stamp = manifest_c.stat().st_mtime_ns
    (proj.build_dir / "E" / "grids" / "facade.pts").write_text("0 0 0 0 1 0\n")  # stale
    with caplog.at_level(logging.INFO, logger="radtree"):
        facts = build_project(proj, ["C", "E"], pictures=False, fresh=False)
    lines = [r.getMessage() for r in caplog.records if r.name == "radtree.pipeline.build"]
    assert manifest_c.stat().st_mtime_ns == stamp
    assert facts["C"]["triangles"] == 19610 and facts["C"]["model"] == "perforated"
    assert any(m.startswith("  C: current, kept") for m in lines)
    assert any(m.startswith("  E: homogeneous") for m in lines)
    assert build_staleness(proj, proj.scenario("E")) == ""
    build_project(proj, ["C"], pictures=False,
                  fresh=True)
    assert manifest_c.stat().st_mtime_ns != stamp


def test_a_worker_error_reads_as_it_was_raised(tmp_path):
    """A build error in the spawned worker is re-raised here with its field and message, and
    leaves no half-written folder. The queue is heaviest first: this process takes A-photo
    from the front, the worker takes E (a dome too large for the sensors: an error only the
    build finds) from the back."""
    from radtree.errors import ConfigError

    p = copy_project(tmp_path / "proj", hours=["13:30"], photo=True)
    toml = p / "radtree.toml"
    head, _, tail = toml.read_text().partition('name = "E"\n')
    toml.write_text(head + 'name = "E"\nswitches = { "dome.radius_m" = 6.0 }\n' + tail)
    proj = load_project(p)
    with pytest.raises(ConfigError) as err:
        build_project(proj, ["A", "E", "A-photo"], pictures=False, workers=2)
    assert err.value.field == "tree.dome.radius_m" and "radius 6 m" in str(err.value)
    assert not (proj.build_dir / "E").exists()
    assert (proj.build_dir / "A-photo" / "manifest.json").is_file()   # built here, first
    assert not list(proj.build_dir.glob(".*"))


def _worker_dies(_project, sc, build_root):
    """A build worker killed mid-folder (run in the spawned process): its temporary folder
    begun, then the process gone."""
    import os

    (build_root / f".{sc.name}.begun").mkdir()
    os._exit(9)


def test_a_dead_worker_is_a_clear_error(proj, monkeypatch):
    """A worker process that dies (killed, out of memory) is reported as a RadtreeError
    naming the folder it was building and the one-process way out; no temporary folder is
    left behind."""
    from radtree.errors import RadtreeError

    monkeypatch.setattr(build_mod, "_build_in_worker", _worker_dies)
    with pytest.raises(RadtreeError, match=r"worker process building (A|E) ended abruptly.*"
                                           r"--workers 1"):
        build_project(proj, ["C", "A", "E"], pictures=False, workers=2)
    assert not list(proj.build_dir.glob(".*"))   # the temporary folders begun are gone
