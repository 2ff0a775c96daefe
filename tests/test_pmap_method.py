"""Radiance's photon map option (its command text, bad counts) and a sun beam that misses its
target refused before tracing. A real photon-map run takes minutes (mkpmap): it is compared
with the backward engines in benchmarks/agreement.py (--pmap)."""

from __future__ import annotations

import numpy as np
import pytest

from radtree.config import EngineParams
from radtree.engines.numpy.scenes import sky_state
from radtree.engines.radiance.writer import write_build
from radtree.engines.registry import get_engine
from radtree.errors import ConfigError
from radtree.optics import Plastic
from radtree.scene import Scene, SensorGrid, quad
from radtree.verify.compare import reduced_dome_project

UP = np.array([0.0, 0.0, 1.0])
PMAP = EngineParams(pmap_photons=200_000, pmap_caustic_photons=5_000, pmap_bandwidth=40,
                    ad=1024, ab=3)


def _square(name: str, material: str, half: float, z: float):
    return quad(name, material, np.array([[-half, -half, z], [half, -half, z],
                                          [half, half, z], [-half, half, z]], float))


def _two_bounce_scene() -> Scene:
    """Sunlit ground (ρ 0.5, 24 m square) under a white panel (ρ 0.8, 4 m square, 2 m up); a
    sensor 1 m up under the panel's centre looks up: all its light has bounced twice (sun →
    ground → panel → sensor) or more."""
    return Scene([_square("ground", "ground", 12.0, 0.0), _square("panel", "panel", 2.0, 2.0)],
                 {"ground": Plastic("ground", 0.5), "panel": Plastic("panel", 0.8)},
                 {"facade": SensorGrid("facade", np.array([[0.0, 0.0, 1.0]]), UP[None, :])})


def test_photon_map_commands_in_the_build_folder(tmp_path):
    st = sky_state("none", altitude=60.0, azimuth=180.0, dni=80000.0, ground_glow=False,
                   time="12:30")
    plan = write_build(_two_bounce_scene(), [st], PMAP, 3, tmp_path, None)
    assert plan.mkpmap_command("1230") == [
        "mkpmap", "-fo", "-apg", "pmaps/1230.gpm", "200000", "-apc", "pmaps/1230.cpm", "5000",
        "octrees/1230.oct"]
    argv = plan.rtrace_command("1230")
    assert argv[argv.index("-ab") + 1] == "1"       # final gathering, the map does the rest
    assert argv[-7:] == ["-ap", "pmaps/1230.gpm", "40", "-ap", "pmaps/1230.cpm", "40",
                         "octrees/1230.oct"]
    make = (tmp_path / "Makefile").read_text()
    assert ("\tmkpmap -fo -apg pmaps/1230.gpm 200000 -apc pmaps/1230.cpm 5000 "
            "octrees/1230.oct\n") in make
    assert "pmaps/1230.gpm pmaps/1230.cpm: octrees/1230.oct\n" in make
    assert " -ap pmaps/1230.gpm 40 -ap pmaps/1230.cpm 40 octrees/1230.oct < grids/" in make
    plain = write_build(_two_bounce_scene(), [st], EngineParams(ab=3), 3, tmp_path / "p", None)
    assert plain.mkpmap_command("1230") is None
    assert "mkpmap" not in (tmp_path / "p" / "Makefile").read_text()


@pytest.mark.parametrize("key", ["pmap_photons", "pmap_caustic_photons", "pmap_bandwidth"])
def test_photon_count_zero_is_one_clear_message(key):
    with pytest.raises(ConfigError, match=f"engine.{key}.*got 0, expected ≥ 1"):
        reduced_dome_project(scenario_overrides={f"engine.{key}": 0})


def test_beam_that_misses_is_refused_when_the_plan_is_made():
    st = sky_state("none", altitude=50, azimuth=30, dni=80000.0, ground_glow=False)
    g = SensorGrid("facade", np.array([[0, 0, 0], [1.0, 0, 0]]), np.array([UP, UP]))
    with pytest.raises(ConfigError, match="engine.beam_diameter_m.*misses its sensors"):
        get_engine("forward").prepare(Scene([], {}, {"facade": g}), [st],
                                      EngineParams(beam_diameter_m=0.5), 0)
