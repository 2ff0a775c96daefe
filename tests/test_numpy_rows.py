"""The NumPy engine's arithmetic on (3, n) / (4, n) rows gives the numbers of the (n, 3) / (n, 4)
arithmetic it replaced, to the bit (the golden tables depend on it).

The shadow-ray loop (``radtree.engines.numpy.shadow``) and the path loop keep rays as one row
per axis because NumPy broadcasts over 3-wide rows several times slower; the sums of three
products follow ``einsum``'s order, ``(a₀b₀ + a₂b₂) + a₁b₁``. If a NumPy release sums in another
order, these tests say so before the golden tests do.
"""

from __future__ import annotations

import numpy as np
import pytest

from radtree.config import EngineParams
from radtree.engines.common.sampling import cosine_hemisphere, cosine_rows
from radtree.engines.numpy import tracing
from radtree.engines.numpy.bounce import _cumulative, _event
from radtree.engines.numpy.engine import DEFAULT_OPTIONS
from radtree.engines.numpy.scenes import dome_slats, sky_state
from radtree.engines.numpy.shadow import crossed, crossed_sun
from radtree.optics import Plastic, Trans
from radtree.scene import Scene, SensorGrid


def test_einsum_sums_three_products_in_the_order_the_rows_use():
    rng = np.random.default_rng(4)
    for m in (1, 2, 3, 17, 4096):
        a = rng.normal(size=(m, 3)) * 10.0 ** rng.uniform(-6, 6, (m, 3))
        b = rng.normal(size=(m, 3))
        p = a.T * b.T
        rows = p[0] + p[2]
        rows += p[1]
        assert np.array_equal(np.einsum("ij,ij->i", a, b), rows)


def _tracer() -> tracing._Tracer:
    slats = dome_slats("crown", "leaf", count=300, radius=2.0, centre=np.array([0.0, 0.0, 3.0]),
                       facade_normal=np.array([0.0, 1.0, 0.0]), size=0.3, inclination_deg=30,
                       rng=np.random.default_rng(2), inner_radius=0.3)
    grid = SensorGrid("g", np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]]))
    scene = Scene([slats], {"leaf": Trans("leaf", 0.1, 0.3, 0.1), "ground": Plastic("ground", 0.2)},
                  {"g": grid})
    state = sky_state("perez", altitude=50, azimuth=140, dni=60000, dhi=12000,
                      ground_reflectance=0.2, time="12:00")
    tracer, _ = tracing._tracer(scene, state, EngineParams(rays=16), None, DEFAULT_OPTIONS)
    return tracer


def test_shadow_crossing_by_rows_equals_the_plane_distance_arithmetic():
    tr = _tracer()
    rng = np.random.default_rng(9)
    m = 5000
    tri = rng.integers(0, tr.n_tri, m)
    o = np.ascontiguousarray((tr.geo.centroids[tri] + rng.normal(scale=0.3, size=(m, 3))).T)
    d = np.broadcast_to(tr.sun, (m, 3))
    assert not tr.sun_grazing
    assert np.array_equal(crossed_sun(tr, o, d, tri, 0), crossed(tr, o, d, tri, None))


def test_cosine_rows_are_cosine_hemisphere_transposed():
    n = np.random.default_rng(1).normal(size=(3000, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    n[:5] = [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, 0], [0, 0, 0.0]]
    rows = cosine_rows(np.ascontiguousarray(n.T), np.random.default_rng(7))
    assert np.array_equal(rows, cosine_hemisphere(n, np.random.default_rng(7)).T)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_event_rows_equal_cumsum_and_count(seed):
    rng = np.random.default_rng(seed)
    coef = rng.random((5000, 4)) * (rng.random((5000, 4)) < 0.7)
    cum = _cumulative(np.ascontiguousarray(coef.T))
    assert np.array_equal(cum, np.cumsum(coef, axis=1).T)
    assert np.array_equal(cum[3], coef.sum(axis=1))
    pick = rng.random(5000) * cum[3]
    expected = np.minimum((pick[:, None] >= np.cumsum(coef, axis=1)).sum(axis=1), 3)
    assert np.array_equal(_event(pick, cum), expected)


def test_unit32_equals_trimesh_unitize():
    """The float32 unit directions handed to Embree: ``raycast._unit32`` (no BLAS) gives
    trimesh's ``unitize`` + float32 to the bit — rows over five decades, zero rows, a row."""
    from trimesh.util import unitize

    from radtree.engines.common.raycast import _unit32

    rng = np.random.default_rng(12)
    v = (rng.normal(size=(200_000, 3)) * 10.0 ** rng.uniform(-4, 1, (200_000, 3)))
    v = v.astype(np.float32)
    v[:5] = 0.0
    v[5] = (1e-7, 0.0, 0.0)   # below trimesh's zero threshold once squared: left as it is
    for d in (v, v[:1], np.broadcast_to(v[7], (50, 3))):
        assert np.array_equal(_unit32(d), np.asarray(unitize(d), dtype=np.float32))


def test_a_trace_makes_no_blas_product_on_the_rays(monkeypatch):
    """No ``np.dot`` on the rays while tracing (several hour states, two workers): a BLAS product
    wakes OpenBLAS's threads, which then spin beside the engine's (trimesh's ``unitize`` did:
    3.3 CPU-s of 8.4 in a 7-hour trace on one thread)."""
    big: list[tuple[int, ...]] = []
    dot = np.dot

    def counting_dot(a, b, *args, **kwargs):
        if max(np.size(a), np.size(b)) > 3000:
            big.append(np.shape(a))
        return dot(a, b, *args, **kwargs)

    slats = dome_slats("crown", "leaf", count=300, radius=2.0, centre=np.array([0.0, 0.0, 3.0]),
                       facade_normal=np.array([0.0, 1.0, 0.0]), size=0.3, inclination_deg=30,
                       rng=np.random.default_rng(2), inner_radius=0.3)
    grid = SensorGrid("g", np.array([[0.0, 0.0, 1.0], [0.4, 0.2, 2.2]]),
                      np.tile([0.0, 0.0, 1.0], (2, 1)))
    scene = Scene([slats], {"leaf": Trans("leaf", 0.1, 0.3, 0.1)}, {"g": grid})
    hours = [sky_state("perez", altitude=a, azimuth=az, dni=60000, dhi=12000, time=t)
             for a, az, t in [(50, 140, "12:00"), (30, 100, "09:00")]]
    monkeypatch.setattr(np, "dot", counting_dot)
    out = tracing.trace_states(scene, hours, EngineParams(rays=4000, max_bounces=3, workers=2))
    assert all(np.all(r["g"].lux > 0) for r in out)
    assert big == [], f"np.dot on the rays: {big[:3]}"
