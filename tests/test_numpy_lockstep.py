"""The NumPy engine's batch split over worker threads draws the one-thread random stream.

``radtree.engines.numpy.lockstep``: parts of a batch traced in parallel threads must get exactly
the numbers the serial tracer draws for their paths, so results do not depend on
``engine.workers`` (the golden tables, traced with 2 workers, pin the serial numbers).
"""

from __future__ import annotations

import threading

import numpy as np
import pytest

from radtree.config import EngineParams
from radtree.engines.numpy import TraceOptions, trace
from radtree.engines.numpy.lockstep import LockstepRandom
from radtree.engines.numpy.scenes import sky_state, slat_layer
from radtree.optics import Glass, Plastic, Trans
from radtree.scene import Scene, SensorGrid, quad


def test_parts_get_the_serial_numbers_in_tag_and_part_order():
    # part 0 skips tag (2,) and stops after (3,); part 1 skips (1,) and draws twice at (4,)
    plans = {0: [((1,), 3), ((3,), 2)],
             1: [((2,), 4), ((3,), 1), ((4, 1), 5), ((4, 2), 2)]}
    shared = LockstepRandom(np.random.default_rng(11), 2)
    got: dict[int, list[np.ndarray]] = {0: [], 1: []}

    def part(i: int) -> None:
        try:
            for tag, size in plans[i]:
                got[i].append(shared.draw(i, tag, size))
        finally:
            shared.finish(i)

    threads = [threading.Thread(target=part, args=(i,)) for i in (1, 0)]
    for th in threads:
        th.start()
    for th in threads:
        th.join(timeout=10)
    assert not any(th.is_alive() for th in threads)
    serial = np.random.default_rng(11)
    expect0 = [serial.random(3)]          # (1,): part 0 only
    expect1 = [serial.random(4)]          # (2,): part 1 only
    both = serial.random(2 + 1)           # (3,): part 0 first, then part 1
    expect0.append(both[:2])
    expect1.append(both[2:])
    expect1 += [serial.random(5), serial.random(2)]  # (4, 1), (4, 2): part 0 has finished
    for i, expect in ((0, expect0), (1, expect1)):
        assert len(got[i]) == len(expect)
        for a, b in zip(got[i], expect):
            np.testing.assert_array_equal(a, b)


def _slat_scene() -> Scene:
    rng = np.random.default_rng(3)
    layer = slat_layer("leaves", "leafy", lai=4.0, extent=8, z_bottom=1, z_top=4, size=0.3,
                       inclination_deg=30, rng=rng)
    pane = quad("pane", "glass", np.array([[-1.0, -1, 0.6], [1, -1, 0.6], [1, 1, 0.6],
                                           [-1, 1, 0.6]]))
    street = quad("street", "ground", np.array([[-20.0, -20, -0.01], [20, -20, -0.01],
                                                [20, 20, -0.01], [-20, 20, -0.01]]))
    pts = np.array([[0.0, 0, 0], [1.5, 1.5, 0], [-1.5, 0.5, 0.2]])
    g = SensorGrid("g", pts, np.tile([0.0, 0.0, 1.0], (3, 1)))
    mats = {"ground": Plastic("ground", 0.2), "leafy": Trans("leafy", 0.11, 0.2, 0.35),
            "glass": Glass.from_transmittance("glass", 0.7)}
    return Scene([layer, pane, street], mats, {"g": g})


@pytest.mark.parametrize("sun_disc", [False, True])
def test_results_do_not_depend_on_the_number_of_worker_threads(sun_disc):
    """Slats with specular transmission (shadow rays through layers, their roulette), glass,
    diffuse bounces, sun and sky: 1, 2 and 3 workers give the same numbers to the bit."""
    sc = _slat_scene()
    st = sky_state("perez", altitude=55.0, azimuth=30.0, dni=70000, dhi=12000)
    opts = TraceOptions(min_part_paths=8, batch_paths=48, sun_disc=sun_disc)
    out = [trace(sc, st, EngineParams(rays=300, max_bounces=5, seed=4, workers=w),
                 options=opts)["g"] for w in (1, 2, 3)]
    for other in out[1:]:
        np.testing.assert_array_equal(other.lux, out[0].lux)
        np.testing.assert_array_equal(other.stderr, out[0].stderr)
    assert np.all(out[0].lux > 0)
