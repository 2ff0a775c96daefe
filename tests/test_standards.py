"""EN 17037 and LEED v4.1 metrics of the annual run (radtree.annual.standards) on analytic cases:
a plane with a known illuminance series, a window with a known sun path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radtree.annual import standards
from radtree.config import EngineParams
from radtree.engines.registry import seeded_engine
from radtree.errors import ConfigError
from radtree.optics import Plastic
from radtree.scene import Scene, SensorGrid, quad


def test_daylight_hours_are_the_half_year_of_most_diffuse_light():
    dhi = np.arange(8760, dtype=float)[::-1]
    day = standards.daylight_hours(dhi)
    assert day.sum() == 4380 and day[:4380].all() and not day[4380:].any()


def test_provision_on_a_plane_with_a_known_series():
    # 20 sensors, 4380 daylight hours. Hours 0–2999: every sensor at 600 lx; hours 3000–4379:
    # 10 sensors at 350 lx, 10 at 80 lx. Target 300 lx over 50 %: every hour (100 %); minimum
    # 100 lx over 95 %: 3000 of 4380 hours (68.5 %); medium 500 lx over 50 %: 3000 hours;
    # 300 lx over 95 % (medium minimum): 3000 hours; high 750 lx: never.
    lux = np.full((20, 4380), 600.0)
    lux[:10, 3000:] = 350.0
    lux[10:, 3000:] = 80.0
    rows = {m: v for m, v, _, _ in standards.provision(lux, np.ones(4380, bool))}
    assert rows["en17037_minimum_target_hours"] == 100.0
    assert rows["en17037_minimum_minimum_hours"] == pytest.approx(100 * 3000 / 4380)
    assert rows["en17037_medium_target_hours"] == pytest.approx(100 * 3000 / 4380)
    assert rows["en17037_medium_minimum_hours"] == pytest.approx(100 * 3000 / 4380)
    assert rows["en17037_high_target_hours"] == 0.0
    assert rows["en17037_provision_level"] == 2.0
    # one sensor in 20 below 100 lx (5 %: exactly the 95 % allowed) keeps the minimum met;
    # two (10 %) lose it: the plane falls to level 0 for those hours
    lux2 = np.full((20, 4380), 400.0)
    lux2[0] = 50.0
    assert dict((m, v) for m, v, _, _ in standards.provision(lux2, np.ones(4380, bool)))[
        "en17037_provision_level"] == 1.0
    lux2[1] = 50.0
    assert dict((m, v) for m, v, _, _ in standards.provision(lux2, np.ones(4380, bool)))[
        "en17037_provision_level"] == 0.0


def test_leed_sda_and_ase_on_a_known_series():
    occupied = np.zeros(8760, bool)
    occupied[:3650] = True
    lux = np.zeros((4, 8760))
    lux[0, :1825] = 300.0      # DA300 exactly 50 % → counts
    lux[1, :1824] = 300.0      # just below
    direct = np.zeros((4, 8760))
    direct[2, :251] = 1001.0   # 251 h > 1000 lx → counts
    direct[3, :250] = 1001.0   # 250 h: not more than 250
    rows = {m: v for m, v, _, _ in standards.leed(lux, direct, occupied)}
    assert rows["leed_sda_300_50"] == 25.0
    assert rows["leed_ase_1000_250"] == 25.0


def _window(wall_top: float | None) -> Scene:
    """A point at the origin looking east; with ``wall_top``, an opaque wall 10 m east of it
    reaching ``wall_top`` m above the point (and far below and to both sides)."""
    grid = SensorGrid("window", np.zeros((1, 3)), np.array([[1.0, 0.0, 0.0]]))
    meshes = []
    if wall_top is not None:
        meshes.append(quad("wall", "wall", np.array([[10, -500, -500], [10, 500, -500],
                                                    [10, 500, wall_top], [10, -500, wall_top]],
                                                   float)))
    return Scene(meshes, {"wall": Plastic("wall", 0.3)}, {"window": grid})


@pytest.mark.parametrize("wall_top, lowest", [(None, 11.0), (10 * math.tan(math.radians(30)), 30.0)])
def test_sun_hours_of_an_east_window_at_the_equator_at_the_equinox(wall_top, lowest):
    # latitude 0, 21 March (declination ≈ +0.4°): the sun climbs ≈ 15° an hour along the
    # east–west vertical and stands in front of an east-facing window from sunrise to noon,
    # so the window gets (90° − lowest unblocked altitude) / 15° h: 5.27 h above 11°, 4 h
    # when a wall hides it below 30°.
    times, alt, az = standards.sun_steps(0.0, 0.0, 0.0, 2023, "03-21")
    scene = _window(wall_top)
    trace = standards.direct_tracer(seeded_engine(), scene, EngineParams(rays=1), ["window"])
    hours = standards.sun_hours(trace, {"window": (scene.grids["window"].points,
                                                   scene.grids["window"].normals)},
                                times, alt, az)["window"]
    assert hours[0] == pytest.approx((90.0 - lowest) / 15.0, abs=0.06)


def test_sunlight_levels_and_dates():
    rows = {m: v for m, v, _, _ in standards.sunlight(np.array([1.0, 1.5, 3.2, 4.5]), "03-21")}
    assert rows["en17037_sunlight_hours"] == pytest.approx(2.55)
    assert rows["en17037_sunlight_minimum"] == 75.0
    assert rows["en17037_sunlight_medium"] == 50.0
    assert rows["en17037_sunlight_high"] == 25.0
    assert standards.check_sunlight_date("02-01") == "02-01"
    with pytest.raises(ConfigError, match="between 02-01 and 03-21"):
        standards.check_sunlight_date("03-22")


def test_standards_table_names_every_scenario_target_and_definition():
    hours = 8760
    total = {t: {"room": np.full((3, hours), 400.0)} for t in ("with", "without")}
    direct = {t: {"room": np.zeros((3, hours))} for t in ("with", "without")}
    sun = {"with": {"room": np.array([1.0, 2.0, 5.0])}, "without": {"room": np.full(3, 5.0)}}
    occ = np.zeros(hours, bool)
    occ[:3650] = True
    table = standards.standards_table({"with": "trees", "without": "open"}, ["room"], total,
                                      direct, np.ones(hours), occ, sun)
    assert list(table.columns) == standards.COLUMNS
    assert set(table["scenario"]) == {"trees", "open"}
    assert table["definition"].str.len().min() > 40
    level = table.set_index(["scenario", "metric"])["value"]
    assert level["trees", "en17037_provision_level"] == 1.0
    assert level["open", "en17037_sunlight_high"] == 100.0
    assert level["trees", "en17037_sunlight_high"] == pytest.approx(100 / 3)
