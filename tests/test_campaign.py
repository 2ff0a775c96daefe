"""Measurement campaigns (radtree.diagnose.campaign) and the next-measurement ranking."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from radtree.config import load_project
from radtree.diagnose.campaign import Layout, campaign_table, load_campaign, merge
from radtree.diagnose.design import rank_candidates
from radtree.errors import ConfigError
from radtree.sensor_grid import point_grid
from radtree.site.frame import FacadeFrame
from radtree.tomlout import dumps
from tests.conftest import MENDOZA


@pytest.fixture(scope="module")
def mendoza():
    return load_project(MENDOZA)


def test_mendoza_data_is_a_campaign(mendoza) -> None:
    c = load_campaign(MENDOZA / "campaign.toml", mendoza)
    assert c.days == ("2024-12-22",) and c.hours == tuple(mendoza.site.hours)
    (g,) = c.groups
    assert (g.name, g.grid, g.report, g.geometry) == ("facade", "facade", "mean", "facade")
    assert Path(g.measured_file("2024-12-22")).samefile(mendoza.measured)
    lay = Layout(c, {"facade": 8})
    assert lay.labels[0] == "2024-12-22 10:30 facade" and len(lay.labels) == 7


def test_rich_campaign_layout(mendoza) -> None:
    c = load_campaign(MENDOZA / "campaign-rich.toml", mendoza)
    assert c.synthetic and c.rays == 512 and len(c.days) == 2
    sizes = {g.geometry: (8 if g.grid else 1) for g in c.groups}
    lay = Layout(c, sizes)
    assert len(lay.observations) == 2 * 7 * (8 + 1 + 1)
    assert lay.labels[:2] == ["2024-12-22 10:30 facade:0", "2024-12-22 10:30 facade:1"]
    assert lay.labels[8] == "2024-12-22 10:30 street_under:0"
    for g in c.groups:
        for day in c.days:
            assert Path(g.measured_file(day)).is_file()


def test_campaign_round_trip_and_merge(mendoza, tmp_path) -> None:
    rich = load_campaign(MENDOZA / "campaign-rich.toml", mendoza)
    path = tmp_path / "c.toml"
    path.write_text(dumps(campaign_table(rich, tmp_path)), encoding="utf-8")
    again = load_campaign(path, mendoza)
    assert again.groups == rich.groups and again.days == rich.days
    base = load_campaign(MENDOZA / "campaign.toml", mendoza)
    both = merge(base, rich)
    assert both.days == rich.days
    assert [g.name for g in both.groups] == ["facade", "street_under", "street_open"]
    assert both.group("facade").report == "sensor"   # per-sensor readings win over means


@pytest.mark.parametrize("text, message", [
    ("[campaign]\nnoise = 0.03\nfoo = 1\n", "unknown key(s) foo"),
    ("[campaign]\n[[group]]\nname = 'x'\norientation = 'sideways'\npoints = [[0, 1, 1]]\n",
     "orientation must be one of facade, horizontal, facing_crown, ground, got 'sideways'"),
    ("[campaign]\n[[group]]\nname = 'x'\npoints = [[0, 1]]\n",
     "points must be [u, d, z] lists of three numbers (m), got [0, 1]"),
    ("[campaign]\ndays = ['22/12/2024']\n[[group]]\nname = 'f'\ngrid = 'facade'\n",
     "day '22/12/2024' is not a date YYYY-MM-DD"),
    ("[campaign]\nnoise = 0\n[[group]]\nname = 'f'\ngrid = 'facade'\n",
     "a campaign needs some noise"),
])
def test_campaign_errors_name_the_problem(mendoza, tmp_path, text, message) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError) as err:
        load_campaign(path, mendoza)
    assert message in str(err.value) and str(path) in str(err.value)


def test_point_grid_orientations() -> None:
    frame = FacadeFrame(azimuth_deg=90.0)          # façade looking east
    g = point_grid([(1.0, 2.0, 3.0)], "facade", frame, "g")
    assert g.points[0] == pytest.approx([2.0, -1.0, 3.0])   # d east, u south
    assert g.normals[0] == pytest.approx([1.0, 0.0, 0.0])
    assert point_grid([(0, 1, 1)], "horizontal", frame, "h").normals[0] == pytest.approx(
        [0, 0, 1])
    assert point_grid([(0, 1, 1)], "facing_crown", frame, "c").normals[0] == pytest.approx(
        [-1, 0, 0])
    assert point_grid([(0, 1, 1)], "ground", frame, "d").normals[0] == pytest.approx([0, 0, -1])


def test_ranking_prefers_the_measurement_that_separates() -> None:
    """Two effects identical on the present 4 values; candidate 'splits' adds 3 values where
    they differ, 'echo' 3 more where they are identical again, 'faint' separates them but
    only below the noise."""
    a = np.array([1, 2, 3, 4, 1, -1, 2, 5, 5, 5, 0.01, -0.01, 0.01]) * 100.0
    b = np.array([1, 2, 3, 4, -1, 1, -2, 5, 5, 5, -0.01, 0.01, -0.01]) * 100.0
    sigma = np.full(13, 10.0)
    idx = np.arange(13)
    base = idx < 4
    moves = {"splits": ((idx >= 4) & (idx < 7), np.zeros(13, bool)),
             "echo": ((idx >= 7) & (idx < 10), np.zeros(13, bool)),
             "faint": (idx >= 10, np.zeros(13, bool))}
    recs, before, after = rank_candidates(["a", "b"], np.column_stack([a, b]), sigma, base,
                                          moves, top=1)
    assert before.confounded == [["a", "b"]]
    assert [r["candidate"] for r in recs] == ["splits", "faint", "echo"]
    first = recs[0]
    assert first["separated_effects"] == "a;b" and first["confounded_pairs_after"] == 0
    # a·b over the 7 values: 1+4+9+16 −1 −1 −4 = 24; |a|² = |b|² = 30 + 6 = 36
    assert first["min_correlation_after"] == pytest.approx(24 / 36)
    assert after.confounded == []


def test_rich_readings_load_in_observation_order(mendoza) -> None:
    from radtree.diagnose.campaign_sim import CampaignSimulator, campaign_readings

    c = load_campaign(MENDOZA / "campaign-rich.toml", mendoza)
    sim = CampaignSimulator(mendoza, (), None, 16, None, campaign=c)
    assert sim.notes == [] and len(sim.labels) == 140
    values = campaign_readings(sim)
    first = (MENDOZA / "data" / "campaign-rich" / "facade_2024-12-22.csv").read_text(
        encoding="utf-8").splitlines()[3]
    assert first.startswith("10:30,0,") and values[0] == pytest.approx(float(first.split(",")[2]))
    open_last = (MENDOZA / "data" / "campaign-rich" / "street_open_2025-03-20.csv").read_text(
        encoding="utf-8").splitlines()[-1]
    assert sim.labels[-1] == "2025-03-20 16:30 street_open:0"
    assert values[-1] == pytest.approx(float(open_last.split(",")[2]))


def test_simulator_made_again_elsewhere_has_the_same_cache_keys(mendoza) -> None:
    """The self-test's worker processes make the campaign simulator again from its spec; the
    traced parts the parent sends must be found under the same keys (the day projects' DNI
    tables live in each simulator's own temporary folder)."""
    from radtree.diagnose.campaign_sim import CampaignSimulator

    camp = load_campaign(MENDOZA / "campaign-rich.toml", mendoza)
    a = CampaignSimulator(mendoza, (), None, None, None, campaign=camp)
    cls, args, kwargs = a.spec()
    b = cls(*args, **kwargs)
    assert a.project.light.direct_normal_table != b.project.light.direct_normal_table
    sc = mendoza.scenario("A")
    assert a._traced_key(sc) == b._traced_key(sc) and a.key(sc) == b.key(sc)
    assert a._traced_key(sc) != a._traced_key(replace(sc, model="perforated"))


def test_worker_simulators_trace_single_threaded_with_the_same_keys(mendoza) -> None:
    """The self-test's worker processes share the cores out (engine.workers = cores ÷
    processes): the spec they rebuild from differs only in engine.workers, which no cache key
    or number depends on — and the traced numbers are identical."""
    from radtree.diagnose.campaign_sim import CampaignSimulator
    from radtree.diagnose.parallel import threaded

    camp = load_campaign(MENDOZA / "campaign.toml", mendoza)
    two = replace(mendoza, engine=replace(mendoza.engine, workers=2))
    a = CampaignSimulator(two, (), None, 32, None, campaign=camp)
    cls, args, kwargs = threaded(a.spec(), 1)
    assert args[0].engine.workers == 1 and a.project.engine.workers == 2
    b = cls(*args, **kwargs)
    sc = mendoza.scenario("A")
    assert a._traced_key(sc) == b._traced_key(sc) and a.key(sc) == b.key(sc)
    assert np.array_equal(a.run(sc).lux, b.run(sc).lux)
