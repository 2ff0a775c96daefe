"""Turbid crowns in Radiance as ``mist`` volumes (radtree.engines.radiance.mist): the emitted
text, the envelope (closed, outward, the spheroid's volume), the leaf phase function's g, and
real ``rtrace`` runs — the sun through an absorbing mist sphere is Beer–Lambert within 1 %,
through a scattering one only its absorbed share (Radiance's shadow rays), and the generated
turbid city runs end to end with ``--engine radiance``."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.spatial import ConvexHull

from radtree.cli import main
from radtree.config import EngineParams, Louvers
from radtree.engines.radiance.materials import mist_text
from radtree.engines.radiance.mist import (
    crown_mist,
    envelope,
    hour_mist_text,
    leaf_asymmetry,
    mean_g,
    mist_geometry_text,
)
from radtree.engines.radiance.writer import write_build
from radtree.errors import EngineError
from radtree.light.sky import SkyState
from radtree.light.sun import SunPosition, local_datetime
from radtree.media import TurbidCrowns
from radtree.optics import Plastic, Trans
from radtree.scene import Scene, SensorGrid, quad
from radtree.trees.turbid import leaf_kind

from .conftest import needs_radiance

ROOT = Path(__file__).resolve().parents[1]
NOON = local_datetime("2024-12-22", "12:00", -3)
LEAF = Trans("leaf", 0.11, 0.05, 0.45)           # the reference street's slat: R, T_d, T_s
SPHERICAL = leaf_kind(Louvers(inclination_distribution="ellipsoidal", ellipsoid_x=1.0), "leaf")


def _sun(alt: float, dni: float = 100000.0) -> SkyState:
    return SkyState("12:00", NOON, SunPosition(alt, 0.0), dni, ground_glow=False)


def _crown(lad: float = 0.8, planes: np.ndarray | None = None) -> TurbidCrowns:
    return TurbidCrowns.of(np.array([[0.0, 0.0, 5.0]]), 2.0, 2.0, lad, 0, [SPHERICAL], planes)


def test_mist_text_is_radiance_mist():
    assert mist_text("m", extinction=0.44, albedo=0.29091, eccentricity=0.0,
                     sources=("sun",)) == "void mist m\n1 sun\n0\n7 0.44 0.44 0.44 0.29091 " \
                                          "0.29091 0.29091 0\n"
    assert mist_text("m", extinction=1.23456789, albedo=0.0, eccentricity=0.0) == \
        "void mist m\n0\n0\n7 1.2346 1.2346 1.2346 0 0 0 0\n"


def test_hour_mist_text_of_one_crown():
    """Leaves at 30° (the reference street's slats), u = 1, T_s = 0.45: G(0) = (2/π) sin 30°,
    G(μ) = μ cos 30° for μ ≥ sin 30° (Ross 1981). Default ("horizontal", "beam"): σ =
    u·G(0)·0.55 and albedo 1 − G(μ_sun)/G(0) (the sun's shadow rays see σ at the sun), no
    sources; "scatter": ω = 0.16/0.55 and the sun listed; no sun: albedo 0."""
    kind = leaf_kind(Louvers(inclination_deg=30.0), "leaf")
    media = TurbidCrowns.of(np.array([[0.0, 0.0, 5.0]]), 2.0, 2.0, 1.0, 0, [kind])
    mats = {"leaf": LEAF}
    g0, g1 = 2 / math.pi * 0.5, math.cos(math.radians(30.0))
    sigma, albedo, _ = crown_mist(media, crown=0, leaf=LEAF, sun_mu=1.0,
                                  extinction="horizontal", sun="beam")
    assert sigma == pytest.approx(g0 * 0.55, rel=1e-6)
    assert sigma * (1 - albedo) == pytest.approx(g1 * 0.55, rel=1e-6)
    text = hour_mist_text(media, materials=mats, state=_sun(90.0), extinction="horizontal",
                          sun="beam")
    assert text == ("# turbid crowns as mist at 12:00: extinction 'horizontal', sun 'beam'\n\n"
                    "void mist crown_mist.0\n0\n0\n7 0.17507 0.17507 0.17507 -1.7207 -1.7207 "
                    "-1.7207 0\n")
    text = hour_mist_text(media, materials=mats, state=_sun(90.0), extinction="sun",
                          sun="scatter")
    assert text.splitlines()[1:] == ["", "void mist crown_mist.0", "1 sun", "0",
                                     "7 0.47631 0.47631 0.47631 0.29091 0.29091 0.29091 0"]
    no_sun = hour_mist_text(media, materials=mats, state=_sun(60.0, dni=0.0),
                            extinction="horizontal", sun="beam")
    assert no_sun.endswith("void mist crown_mist.0\n0\n0\n7 0.17507 0.17507 0.17507 0 0 0 0\n")


def test_extinction_choices():
    """Horizontal leaves (inclination 0): G(μ) = μ — σ at a 30° sun uses μ = ½, the mean ½,
    the vertical receiver (4/π)∫μ√(1−μ²)dμ = 4/(3π), horizontal 0 (with "beam" floored at
    10⁻³ of the sun's σ, the sun's own σ kept by the albedo)."""
    flat = leaf_kind(Louvers(inclination_deg=0.0), "leaf")
    media = TurbidCrowns.of(np.array([[0.0, 0.0, 5.0]]), 2.0, 2.0, 1.0, 0, [flat])
    leaf = Trans("leaf", 0.1, 0.1, 0.0)
    want = {"sun": 0.5, "mean": 0.5, "vertical": 4 / (3 * math.pi), "horizontal": 0.0}
    for extinction, value in want.items():
        sigma, albedo, _ = crown_mist(media, crown=0, leaf=leaf, sun_mu=0.5,
                                      extinction=extinction, sun="mist")
        assert sigma == pytest.approx(value, abs=1e-3) and albedo == 0.0
    sigma, albedo, _ = crown_mist(media, crown=0, leaf=leaf, sun_mu=0.5,
                                  extinction="horizontal", sun="beam")
    assert sigma == pytest.approx(5e-4, rel=1e-3) and sigma * (1 - albedo) == pytest.approx(0.5)
    assert mean_g(SPHERICAL) == pytest.approx(0.5, abs=1e-3)
    with pytest.raises(ValueError, match="mist extinction must be one of"):
        crown_mist(media, crown=0, leaf=leaf, sun_mu=0.5, extinction="up", sun="beam")


def test_leaf_asymmetry_analytic():
    """Horizontal leaves, vertical light: every leaf met faces the beam, g = −⅔(R−T)/(R+T);
    spherical leaves, any direction: |n·Ω| uniform on [0, 1], E[c²]/E[c] = ⅔, g = −(4/9)(R−T)/(R+T)."""
    flat = leaf_kind(Louvers(inclination_deg=0.0), "leaf")
    leaf = Trans("leaf", 0.3, 0.1, 0.0)
    assert leaf_asymmetry(flat, leaf=leaf, mu=1.0) == pytest.approx(-2 / 3 * 0.5, rel=1e-6)
    for mu in (0.1, 0.6, 1.0):
        assert leaf_asymmetry(SPHERICAL, leaf=leaf, mu=mu) == pytest.approx(-4 / 9 * 0.5,
                                                                            rel=5e-3)
    fwd = Trans("leaf", 0.05, 0.45, 0.0)   # transmits more than it reflects: forward, g > 0
    _, albedo, g = crown_mist(_crown(), crown=0, leaf=fwd, sun_mu=1.0, extinction="sun",
                              sun="scatter")
    assert albedo == pytest.approx(0.5) and g == pytest.approx(4 / 9 * 0.8, rel=5e-3)
    _, _, g_back = crown_mist(_crown(), crown=0, leaf=LEAF, sun_mu=1.0, extinction="sun",
                              sun="scatter")
    assert g_back == 0.0   # backward g is written as 0 (Radiance scatters g ≤ 0 isotropically)


def test_envelope_is_closed_outward_and_holds_the_volume():
    centre = np.array([1.0, 2.0, 5.0])
    normals = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]])
    planes = np.column_stack([normals, normals @ centre + [0.5, -1.0, -1.2]])
    for cut in (np.zeros((0, 4)), planes):
        verts, tri = envelope(centre, a=2.0, b=1.5, planes=cut)
        edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), 1)
        _, count = np.unique(edges, axis=0, return_counts=True)
        assert np.all(count == 2)                       # closed: every edge in two triangles
        n = np.cross(verts[tri[:, 1]] - verts[tri[:, 0]], verts[tri[:, 2]] - verts[tri[:, 0]])
        inner = verts.mean(0)
        assert np.all(np.einsum("ij,ij->i", n, verts[tri].mean(1) - inner) > 0)  # outward
        assert np.all(verts @ cut[:, :3].T >= cut[:, 3] - 1e-9)                   # cut
    # the uncut spheroid's volume exactly (the hull is scaled to it)
    verts, _ = envelope(np.zeros(3), a=2.0, b=1.5, planes=np.zeros((0, 4)))
    assert ConvexHull(verts).volume == pytest.approx(4 / 3 * math.pi * 4 * 1.5, rel=1e-9)
    # a half spheroid: half the volume within the faceting (0.5 %)
    verts, _ = envelope(np.zeros(3), a=2.0, b=1.5, planes=np.array([[1.0, 0.0, 0.0, 0.0]]))
    assert ConvexHull(verts).volume == pytest.approx(2 / 3 * math.pi * 4 * 1.5, rel=5e-3)
    assert verts[:, 0].min() == pytest.approx(0.0, abs=1e-12)


def test_geometry_text_names_each_crowns_mist():
    media = TurbidCrowns.of(np.array([[0.0, 0.0, 5.0], [6.0, 0.0, 5.0]]), 2.0, 2.0, 0.8, 0,
                            [SPHERICAL])
    text = mist_geometry_text(media)
    assert text.startswith("# 2 turbid crown(s) as mist volumes: closed convex envelopes "
                           "(24 rings x 48 segments), outward normals\n")
    assert text.count("crown_mist.0 polygon crown_envelope.0.") == 2208
    assert text.count("crown_mist.1 polygon crown_envelope.1.") == 2208


def _scene(media: TurbidCrowns, leaf: Trans = LEAF) -> Scene:
    grid = SensorGrid("s", np.array([[0.0, 0.0, 0.5], [0.5, 0.3, 0.5], [6.0, 0.0, 0.5]]),
                      np.tile([0.0, 0.0, 1.0], (3, 1)))
    return Scene([], {leaf.name: leaf}, {"s": grid}, media=media)


def test_write_build_writes_mist_per_hour(tmp_path):
    plan = write_build(_scene(_crown()), [_sun(60.0)], EngineParams(), 1, tmp_path / "b", None)
    assert plan.hour_files["1200"] == ["skies/1200_mist.rad", "geometry/crowns_mist.rad",
                                       "skies/1200.sky"]
    # spherical leaves: G(μ_sun) = G(0) = ½ up to the tabulation (2·10⁻⁵)
    assert (tmp_path / "b" / "skies" / "1200_mist.rad").read_text().endswith(
        "void mist crown_mist.0\n0\n0\n7 0.22 0.22 0.22 -2.2768e-05 -2.2768e-05 -2.2768e-05 0\n")


def test_write_build_refuses_other_media(tmp_path):
    scene = Scene([quad("g", "g", np.array([[-9, -9, 0], [9, -9, 0], [9, 9, 0], [-9, 9, 0]],
                                           float))], {"g": Plastic("g", 0.2)}, {})
    scene.media = object()  # type: ignore[assignment]
    with pytest.raises(EngineError, match="turbid spheroid crowns as mist, not object"):
        write_build(scene, [_sun(60.0)], EngineParams(), 1, tmp_path / "b", None)


@needs_radiance
def test_sun_through_absorbing_mist_is_beer_lambert():
    """u = 0.8, G = ½, T_s = 0.45: σ = 0.22 /m. Sensor under the centre: 2R = 4 m of mist on
    the vertical (the envelope's pole stands k·R high: chord 2kR); sensor 0.58 m off the axis:
    chord 2√(R² − 0.34); a sensor beside the crown: the full sun. Within 1 %."""
    from radtree.engines.radiance.engine import trace_hour
    from radtree.engines.radiance.mist import volume_scale

    lux = trace_hour(_scene(_crown()), _sun(90.0), EngineParams(ab=0))["s"].lux
    sigma = 0.22
    assert lux[0] == pytest.approx(1e5 * math.exp(-sigma * 4.0), rel=0.01)
    assert lux[0] == pytest.approx(1e5 * math.exp(-sigma * 4.0 * volume_scale()), rel=1e-4)
    assert lux[1] == pytest.approx(1e5 * math.exp(-sigma * 2 * math.sqrt(4 - 0.34)), rel=0.01)
    assert lux[2] == pytest.approx(1e5, rel=1e-5)


@needs_radiance
def test_scattering_mist_shadow_rays_see_only_absorption():
    """Radiance's reading (raytrace.c rayparticipate): a shadow ray through mist of albedo ω is
    attenuated by exp(−σ(1 − ω)L), not exp(−σL) — at -ab 0 the scattered sun adds nothing
    at a point outside the crown (the sensor's own ray does not cross it)."""
    from radtree.engines.radiance.engine import trace_hour
    from radtree.engines.radiance.mist import volume_scale

    lux = trace_hour(_scene(_crown()), _sun(90.0),
                     EngineParams(ab=0, mist_extinction="sun", mist_sun="scatter"))["s"].lux
    omega = 0.16 / 0.55
    path = 4.0 * volume_scale()
    assert lux[0] == pytest.approx(1e5 * math.exp(-0.22 * (1 - omega) * path), rel=1e-4)


@needs_radiance
def test_turbid_city_runs_on_radiance(tmp_path):
    """The generated turbid city (examples/city, 1 block, 8 trees, one hour) end to end with
    ``--engine radiance``: every façade sensor lit, shaded ones darker than the open ones."""
    spec = importlib.util.spec_from_file_location("make_city",
                                                  ROOT / "examples" / "city" / "make_city.py")
    mod = importlib.util.module_from_spec(spec)
    assert spec.loader is not None
    spec.loader.exec_module(mod)
    root = tmp_path / "city"
    (root / "data").mkdir(parents=True)
    (root / "data" / "direct_normal_illuminance.csv").write_bytes(
        (ROOT / "examples" / "city" / "data" / "direct_normal_illuminance.csv").read_bytes())
    assert mod.write(root / "data", 8, blocks=1) == (4, 8)
    text = (ROOT / "examples" / "city" / "radtree.toml").read_text()
    text = text.replace('hours = ["10:30", "11:30", "12:30", "13:30", "14:30", "15:30", '
                        '"16:30"]', 'hours = ["12:30"]').replace("ab = 2\n", "ab = 1\nad = 64\n")
    (root / "radtree.toml").write_text(text)
    res = CliRunner().invoke(main, ["simulate", str(root), "-s", "trees", "--engine",
                                    "radiance"])
    assert res.exit_code == 0, res.output
    import pandas as pd

    table = pd.read_csv(root / "results" / "illuminance.csv")
    assert len(table) > 50 and (table["engine"] == "radiance").all()
    assert (table["lux"] > 0).all()
    assert (root / "build" / "trees" / "skies" / "1230_mist.rad").exists()


@needs_radiance
def test_beam_mist_sun_exact_sky_at_the_mist_sigma():
    """Real rtrace, horizontal leaves: with sun "beam" the sun's shadow rays see σ_sun
    (Beer–Lambert at the sun's μ, within 1 %), the sky's ambient rays the mist's σ (here the
    vertical receiver's) — at the sensor beside the crown, whose sun misses it, the same
    numbers as sun "mist" (fixed seed, identical rays): the albedo, negative at a high sun
    (σ_sun > σ), acts on shadow rays only (raytrace.c rayparticipate)."""
    from radtree.engines.radiance.engine import trace_hour
    from radtree.engines.radiance.mist import volume_scale

    flat = leaf_kind(Louvers(inclination_deg=0.0), "leaf")
    media = TurbidCrowns.of(np.array([[0.0, 0.0, 5.0]]), 2.0, 2.0, 1.0, 0, [flat])
    leaf = Trans("leaf", 0.1, 0.1, 0.5)
    beam = EngineParams(ab=0, mist_extinction="vertical", mist_sun="beam")
    sun = trace_hour(_scene(media, leaf), _sun(90.0), beam)["s"].lux
    assert sun[0] == pytest.approx(1e5 * math.exp(-0.5 * 4.0 * volume_scale()), rel=0.01)
    sky = SkyState("12:00", NOON, SunPosition(80.0, 0.0), 10000.0, sky_model="uniform",
                   zenith_luminance=1000.0, ground_glow=False)
    params = EngineParams(ab=1, ad=512, mist_extinction="vertical", mist_sun="beam")
    beam_lux = trace_hour(_scene(media, leaf), sky, params)["s"].lux
    mist_lux = trace_hour(_scene(media, leaf), sky, params.changed(mist_sun="mist"))["s"].lux
    assert beam_lux[2] == pytest.approx(mist_lux[2], rel=1e-9)
    assert beam_lux[0] < 0.9 * mist_lux[0]            # σ_sun > σ: the sun darker through it
    assert " -1.3204 " in hour_mist_text(media, materials={"leaf": leaf}, state=sky,
                                         extinction="vertical", sun="beam").splitlines()[-1]
    open_sky = math.pi * 1000.0 + 10000.0 * math.sin(math.radians(80.0))
    assert beam_lux[2] < 0.998 * open_sky             # the crown shades part of its sky


def test_mist_params_lower_lw_by_the_thickest_crown():
    """τ_max = u · max G · (1 − T_s) · 2R = 0.8 · ½ · 0.55 · 4 (spherical leaves)."""
    from radtree.engines.radiance.mist import max_optical_depth, mist_params

    media = _crown()
    tau = max_optical_depth(media, {"leaf": LEAF}, extinction="horizontal")
    assert tau == pytest.approx(0.88, rel=1e-3)
    flat = TurbidCrowns.of(np.array([[0.0, 0.0, 5.0]]), 2.0, 2.0, 1.0, 0,
                           [leaf_kind(Louvers(inclination_deg=0.0), "leaf")])
    assert max_optical_depth(flat, {"leaf": LEAF}, extinction="sun") == pytest.approx(2.2)
    assert max_optical_depth(flat, {"leaf": LEAF}, extinction="horizontal") == 0.0
    p = mist_params(EngineParams(lw=0.001, dense_lw=0.01), media, {"leaf": LEAF})
    assert p.radiance.lw == pytest.approx(0.001 * math.exp(-tau))
    assert p.radiance.dense_lw == pytest.approx(0.01 * math.exp(-tau))
    assert mist_params(EngineParams(lw=0.001), None, {}).radiance.lw == 0.001


def _sky_under_crown(sigma: float, point: np.ndarray, n: int = 600) -> float:
    """E / L = ∫ exp(−σ c(ω)) cos θ dω over the upper hemisphere at ``point``, c the chord
    of the sphere (centre (0, 0, 5), R = 2) along ω (midpoint rule in cos θ and φ)."""
    mu = (np.arange(n) + 0.5) / n
    phi = 2 * math.pi * (np.arange(2 * n) + 0.5) / (2 * n)
    m, f = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1 - m * m)
    w = np.stack([s * np.cos(f), s * np.sin(f), m], -1)
    q = np.array([0.0, 0.0, 5.0]) - point
    t = w @ q
    d2 = q @ q - t * t
    chord = np.where((t > 0) & (d2 < 4.0), 2 * np.sqrt(np.maximum(4.0 - d2, 0.0)), 0.0)
    return float(np.mean(np.exp(-sigma * chord) * m) * 2 * math.pi)


@needs_radiance
def test_sky_through_mist_survives_the_weight_limit():
    """Uniform sky, a sensor 4.5 m under a dense crown (σ = 0.8 /m, τ across = 3.2): rtrace
    -ab 1 -ad 2048 -lw 0.001 against the analytic integral (within 2 %). Radiance drops a
    ray leaving mist below -lw without roulette; with -lw scaled by exp(−τ_max)
    (mist_params) the sky through the crown is kept."""
    from radtree.engines.radiance.engine import trace_hour

    media = _crown(lad=0.8 / (0.5 * 0.55))
    sigma = float(media.lad[0]) * 0.5 * 0.55
    sky = SkyState("12:00", NOON, SunPosition(60.0, 0.0), 0.0, sky_model="uniform",
                   zenith_luminance=1000.0, ground_glow=False)
    lux = trace_hour(_scene(media), sky, EngineParams(ab=1, ad=2048, lw=0.001))["s"].lux
    want = 1000.0 * _sky_under_crown(sigma, np.array([0.0, 0.0, 0.5]))
    assert want < 0.9 * math.pi * 1000.0            # the crown matters
    assert lux[0] == pytest.approx(want, rel=0.02)
