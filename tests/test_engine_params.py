"""The ``[engine]`` table: one parameter group per engine behind EngineParams, the project
file's flat keys unchanged (issue 42)."""

from __future__ import annotations

import dataclasses
import logging

import pytest

from radtree.config import EngineParams, load_project
from radtree.config.engine import ForwardParams, NumpyParams, RadianceParams
from radtree.config.spec import SchemaError, table_fields, toml_name
from radtree.config.switches import table_keys
from radtree.engines.forward.settings import ForwardSettings
from radtree.engines.numpy.interface import NumpyEngine
from radtree.engines.radiance.writer import rtrace_options
from radtree.errors import ConfigError

from .conftest import MENDOZA, copy_project

#: the [engine] keys of the project file before the groups (issue 42): unchanged
FLAT_KEYS = {
    "name", "ab", "ad", "as", "ar", "aa", "lw", "rays", "max_bounces", "seed", "sampling",
    "workers", "photons", "forward_threshold", "forward_splitting", "beam_diameter_m",
    "patch_m", "forward_batches", "forward_focus_m", "forward_split", "forward_split_radius_m",
    "forward_guide", "forward_guide_radius_m", "target_rel_se", "max_photons",
    "forward_direct_sun", "pmap_photons", "pmap_caustic_photons", "pmap_bandwidth", "dense_lw",
    "dense_rays", "mist_extinction", "mist_sun",   # + Radiance mist crowns (issue 43)
    "forward_window",   # + the forward weight window (issue 40)
    "forward_direct_sky",   # + the sky at the sensor points (issue 40)
    "forward_stages"}   # + the rounds' stages (issue 40)


def test_the_file_keeps_its_flat_keys():
    cls = EngineParams
    assert {toml_name(cls, f.name) for f in table_fields(cls)} == FLAT_KEYS
    assert set(table_keys("engine")) == FLAT_KEYS
    # each key in exactly one place: the common fields or one group
    owners = [f.name for f in dataclasses.fields(RadianceParams)] + [
        f.name for f in dataclasses.fields(NumpyParams)] + [
        f.name for f in dataclasses.fields(ForwardParams)] + ["name", "ab", "seed", "workers"]
    assert len(owners) == len(set(owners)) == len(FLAT_KEYS)


def test_flat_keywords_go_to_their_groups():
    p = EngineParams(rays=512, ad=64, photons=2000, seed=3, as_=8)
    assert (p.numpy.rays, p.radiance.ad, p.radiance.as_, p.forward.photons, p.seed) == (
        512, 64, 8, 2000, 3)
    assert p.numpy.max_bounces == NumpyParams().max_bounces   # the rest at the defaults
    q = dataclasses.replace(p, rays=16, workers=1)
    assert (q.numpy.rays, q.radiance.ad, q.workers, q.seed) == (16, 64, 1, 3)
    assert p.changed(max_bounces=2).numpy == dataclasses.replace(p.numpy, max_bounces=2)
    assert EngineParams(numpy=NumpyParams(rays=7), rays=9).numpy.rays == 9  # the key wins
    assert p == EngineParams(**p.flat())
    assert p.flat()["as_"] == 8 and len(p.flat()) == len(FLAT_KEYS)
    with pytest.raises(TypeError, match="rayz"):
        EngineParams(rayz=3)


def test_bad_values_name_the_flat_key(tmp_path):
    with pytest.raises(SchemaError, match=r"engine\.rays.*expected ≥ 1"):
        EngineParams(rays=0)
    with pytest.raises(SchemaError, match=r"engine\.as.*expected ≥ 0"):
        EngineParams(as_=-1)
    proj = copy_project(tmp_path / "p", replace={r"\[engine\]\n": "[engine]\nforward_guide = 1.0\n"})
    with pytest.raises(ConfigError) as err:
        load_project(proj)
    text = str(err.value)
    assert "engine.forward_guide" in text and "got 1.0, expected < 1" in text


def test_each_engine_reads_its_group():
    p = EngineParams(rays=300, sampling="random", seed=5, ad=96, lw=0.002, as_=12,
                     photons=5000, forward_guide=0.5, max_bounces=4)
    assert NumpyEngine().sampling(p) == "300 rays/sensor, random sampling, seed 5"
    opts = rtrace_options(p, 3)
    assert opts[opts.index("-ad") + 1] == "96" and opts[opts.index("-as") + 1] == "12"
    assert opts[opts.index("-lw") + 1] == "0.002"
    s = ForwardSettings.from_params(p)
    assert (s.photons, s.guide, s.seed, s.max_bounces) == (5000, 0.5, 5, 4)


def test_params_hashes_and_manifest_table_unchanged():
    """The hash of a scenario reads the flat table: the example's build folders keep their
    names (hashes written before the groups); the manifest's parameters keep the flat
    [engine] table."""
    p = load_project(MENDOZA)
    assert p.params_hashes([p.scenario("A"), p.scenario("B")]) == {
        "A": "e2cc1271222b", "B": "51108737228e"}
    engine = p.to_dict()["engine"]
    assert engine["rays"] == p.engine.numpy.rays and engine["as_"] == p.engine.radiance.as_
    assert "numpy" not in engine


def test_annual_weather_talks_through_logging(tmp_path, caplog, capsys):
    """A library call prints nothing; its message goes to the module's logger."""
    from radtree.light.weather import find_weather

    project = load_project(copy_project(tmp_path / "p"))
    with caplog.at_level(logging.INFO, logger="radtree.light.weather"):
        source = find_weather(project)
    assert source.generated and source.path.exists()
    assert capsys.readouterr().out == ""
    assert any("no EPW given: generating a clear-sky year" in r.getMessage()
               for r in caplog.records)
