"""Volume arrangement of the free louvers crowns: Beer–Lambert through random slats, slat
count against density × volume, configuration errors, dome + volume, crossings calibration."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import poisson

from radtree.calibrate.permeability import CrossingsSearch, calibrate_crossings
from radtree.config import Louvers, Scenario, load_project
from radtree.errors import ConfigError
from radtree.optics import Plastic, Trans
from radtree.scene import Mesh
from radtree.trees.build import build_tree
from radtree.trees.envelope import CrownRowSpec, crown_row_spec
from radtree.trees.geometry import polygons_to_mesh
from radtree.trees.raycast import DirectTracer
from radtree.trees.volume import (
    VOLUME_AB_CAP,
    build_volume_louvers,
    projection_g,
    recommended_volume_ab,
    volume_density,
)

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "mendoza-street"
VOLUME = {"louvers.arrangement": "volume", "louvers.crossings": 12}


# ---------------------------------------------------------------- Beer–Lambert
R_BALL = 3.0  # a free sphere of random slats: no wall, no neighbours, no trunk
S = 0.1       # slat side; rays 0.15 m apart > s·√2, so no slat meets two rays
SPACING = 0.15
CROSSINGS = 3.0
SEEDS = (1, 2, 3)


def ball_spec() -> CrownRowSpec:
    return CrownRowSpec(centres=np.array([[0.0, 10.0, 10.0]]), a=R_BALL, b=R_BALL,
                        n_clip=0.0, strips=np.array([[-np.inf, np.inf]]), trunk_radius=0.01,
                        trunk_top=-100.0)


def ball_meshes(seed: int) -> tuple[Mesh, Louvers]:
    lv = Louvers(slat_size_m=S, arrangement="volume", crossings=CROSSINGS, seed=seed)
    polys, _ = build_volume_louvers(ball_spec(), lv)
    verts, faces = polygons_to_mesh(polys)
    return Mesh("slats", "leaf", verts, faces), lv


def parallel_rays(direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Origins of parallel rays on a square grid (spacing SPACING) across the ball, offsets
    r < 0.8 R from its centre, and the chord length of each ray through the ball."""
    d = direction / np.linalg.norm(direction)
    e1 = np.cross(d, [0.0, 1.0, 0.0] if abs(d[1]) < 0.9 else [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(d, e1)
    g = np.arange(-0.8 * R_BALL, 0.8 * R_BALL + 1e-9, SPACING)
    X, Y = (v.ravel() for v in np.meshgrid(g, g))
    r = np.hypot(X, Y)
    X, Y, r = X[r < 0.8 * R_BALL], Y[r < 0.8 * R_BALL], r[r < 0.8 * R_BALL]
    centre = ball_spec().centres[0]
    origins = centre + X[:, None] * e1 + Y[:, None] * e2 - 2.0 * R_BALL * d
    return origins, 2.0 * np.sqrt(R_BALL**2 - r**2)


@pytest.fixture(scope="module")
def ball_runs():
    """Per direction: slat crossings k per ray, λ per ray, and the direct transmission with
    opaque slats and with specular slat transmission T_s = 0.5 (three realisations)."""
    directions = {"vertical": np.array([0.0, 0.0, -1.0]),
                  "80° from vertical": np.array([math.sin(math.radians(80.0)), 0.0,
                                                 -math.cos(math.radians(80.0))])}
    out = {}
    meshes = [ball_meshes(seed) for seed in SEEDS]
    for name, d in directions.items():
        d = d / np.linalg.norm(d)
        origins, chord = parallel_rays(d)
        dirs = np.repeat(d[None, :], len(origins), axis=0)
        k, t_opaque, t_spec, lam = [], [], [], []
        for mesh, lv in meshes:
            rho = volume_density(lv, R_BALL)
            g = float(projection_g(abs(d[2]), lv.inclination_deg))
            lam.append(rho * S * S * g * chord)
            opaque = DirectTracer([mesh], {"leaf": Plastic("leaf", 0.1)})
            spec = DirectTracer([mesh], {"leaf": Trans("leaf", 0.1, 0.0, 0.5)})
            k.append(opaque.crossings(origins, dirs))
            t_opaque.append(opaque.transmission(origins, dirs))
            t_spec.append(spec.transmission(origins, dirs))
        out[name] = tuple(np.concatenate(x) for x in (k, lam, t_opaque, t_spec))
    return out


def test_projection_g():
    a = 30.0
    assert projection_g(1.0, a) == pytest.approx(math.cos(math.radians(a)))
    assert projection_g(0.0, a) == pytest.approx(2.0 / math.pi * math.sin(math.radians(a)))
    for mu in (0.1, 0.17, 0.5, 0.9):  # against a brute-force mean over the azimuth
        phi = np.linspace(0.0, 2.0 * math.pi, 200_001)[:-1]
        m = np.stack([np.sin(math.radians(a)) * np.cos(phi), np.sin(math.radians(a))
                      * np.sin(phi), np.full_like(phi, math.cos(math.radians(a)))], axis=1)
        omega = np.array([math.sqrt(1 - mu * mu), 0.0, mu])
        assert projection_g(mu, a) == pytest.approx(np.mean(np.abs(m @ omega)), abs=1e-6)


@pytest.mark.parametrize("name", ["vertical", "80° from vertical"])
def test_crossings_are_poisson(ball_runs, name):
    """k slats crossed per ray ~ Poisson(λ_i), λ_i = ρ s² G(Ω) L_i: the histogram of k within
    4 binomial s.d. of Σ_i Poisson(k; λ_i) for every k with ≥ 20 expected rays, and the mean
    within 4 s.e. (s.e. = √(Σλ_i)/n for independent rays)."""
    k, lam, _, _ = ball_runs[name]
    n = len(k)
    assert n > 2000
    assert abs(k.mean() - lam.mean()) <= 4.0 * math.sqrt(lam.sum()) / n
    checked = 0
    for kk in range(0, 15):
        p = poisson.pmf(kk, lam)
        expected = p.sum()
        if expected < 20:
            continue
        sd = math.sqrt(np.sum(p * (1.0 - p)))
        assert abs(np.sum(k == kk) - expected) <= 4.0 * sd, (name, kk)
        checked += 1
    assert checked >= 5
    # the layered arrangement would put exactly `crossings` on every vertical line: here the
    # spread is Poisson (variance ≈ mean + the spread of λ between rays)
    assert k.var() == pytest.approx(lam.mean() + lam.var(), rel=0.15)


@pytest.mark.parametrize("name", ["vertical", "80° from vertical"])
def test_beer_lambert_transmission(ball_runs, name):
    """Opaque slats: transmission mean(exp(−λ_i)); specular slat transmission T_s = 0.5:
    mean(exp(−λ_i(1 − T_s))). Tolerance 4 s.e. of the ray mean (variance per ray of
    T_s^k: exp(−λ(1 − T_s²)) − exp(−2λ(1 − T_s)))."""
    k, lam, t_opaque, t_spec = ball_runs[name]
    n = len(k)
    e0 = np.exp(-lam)
    assert np.array_equal(t_opaque, (k == 0).astype(float))
    assert abs(t_opaque.mean() - e0.mean()) <= 4.0 * math.sqrt(np.sum(e0 * (1 - e0))) / n
    ts = 0.5
    e1 = np.exp(-lam * (1 - ts))
    var = np.exp(-lam * (1 - ts * ts)) - np.exp(-2 * lam * (1 - ts))
    assert np.allclose(t_spec, ts**k)
    assert abs(t_spec.mean() - e1.mean()) <= 4.0 * math.sqrt(var.sum()) / n


def test_g_differs_between_directions(ball_runs):
    """Same path lengths, G(vertical) = cos 30° = 0.866, G(80°) = 0.328: the near-horizontal
    rays cross 2.6 × fewer slats."""
    kv, lv, _, _ = ball_runs["vertical"]
    kh, lh, _, _ = ball_runs["80° from vertical"]
    assert lv.mean() / lh.mean() == pytest.approx(0.866 / 0.328, rel=0.01)
    assert kv.mean() / kh.mean() == pytest.approx(0.866 / 0.328, rel=0.1)


# ---------------------------------------------------------------- count and crown build
def test_slat_count_matches_density_times_volume(project):
    """Slats whose centre lies in the clipped crowns (three overlapping Mendoza crowns, wall
    cut) against ρ·V, V by an independent Monte Carlo (10⁶ points, s.e. 0.1 %); the binomial
    s.d. of the count is ≈ 0.3 %. Also the unclipped ball: exactly round(ρ · 4/3 π R³)."""
    lv = replace(project.tree.louvers, arrangement="volume", crossings=12.0)
    spec = crown_row_spec(project.tree, project.sensors, project.street)
    polys, info = build_volume_louvers(spec, lv)
    rho = volume_density(lv, spec.b)
    assert rho == pytest.approx(12.0 / (0.09 * math.cos(math.radians(30.0)) * 2 * 4.75))
    rng = np.random.default_rng(12345)
    lo = spec.centres.min(axis=0) - [spec.a, spec.a, spec.b]
    hi = spec.centres.max(axis=0) + [spec.a, spec.a, spec.b]
    pts = lo + rng.random((1_000_000, 3)) * (hi - lo)
    volume = float(np.prod(hi - lo)) * float(np.mean(spec.inside(pts)))
    assert info["crown_volume_m3"] == pytest.approx(volume, rel=0.01)
    in_crown = info["slats_centre_in_crown"] + info["slats_dropped"]  # trunk drops: < 0.5 %
    assert info["slats_dropped"] < 0.005 * in_crown
    assert in_crown == pytest.approx(rho * volume, rel=0.02)
    assert len(polys) >= info["slats_centre_in_crown"]  # + slats cut from outside the share
    ball = Louvers(slat_size_m=0.3, arrangement="volume", crossings=4.0)
    polys, info = build_volume_louvers(ball_spec(), ball)
    assert info["slats_cut"] == 0 and info["slats_dropped"] == 0
    assert len(polys) == round(volume_density(ball, R_BALL) * 4 / 3 * math.pi * R_BALL**3)


def test_free_crown_build_and_notes(project, frame):
    tm = build_tree(project, Scenario("v", "louvers", form="free", switches=VOLUME), frame)
    info = tm.info
    assert info["arrangement_volume"] == 1.0
    assert info["lambda_vertical"] == pytest.approx(12.0)
    assert info["lambda_horizontal"] == pytest.approx(
        12.0 * (2 / math.pi * 0.5) / math.cos(math.radians(30.0)) * 5.0 / 4.75)
    assert 18_000 < info["slat_count"] < 24_000
    pts = frame.to_local(tm.meshes[0].vertices)
    assert pts[:, 1].min() >= 0.015 - 1e-9  # cut at the wall-side clip plane
    text = " ".join(tm.notes)
    for words in ("volume arrangement", "slats/m³", "λ vertical", "λ horizontal",
                  f"{int(info['slat_count'])} slats"):
        assert words in text
    assert tm.recommended_ab == VOLUME_AB_CAP
    # nested realisations: more crossings keep the slats of fewer
    lv = replace(project.tree.louvers, arrangement="volume")
    spec = crown_row_spec(project.tree, project.sensors, project.street)
    a, _ = build_volume_louvers(spec, replace(lv, crossings=4.0))
    b, _ = build_volume_louvers(spec, replace(lv, crossings=4.5))
    key = {tuple(np.round(p.mean(axis=0), 9)) for p in b}
    assert len(b) > len(a) and all(tuple(np.round(p.mean(axis=0), 9)) in key for p in a)


def test_recommended_ab():
    assert recommended_volume_ab(Louvers(arrangement="volume", crossings=2)) == 4
    assert recommended_volume_ab(Louvers(arrangement="volume", crossings=15)) == VOLUME_AB_CAP
    assert recommended_volume_ab(Louvers(arrangement="volume", layers=3)) == 5  # crossings 0


# ---------------------------------------------------------------- errors
@pytest.mark.parametrize("key, value, field", [
    ("tree.louvers.arrangement", "lattice", "tree.louvers.arrangement"),
    ("tree.louvers.arrangement", 3, "tree.louvers.arrangement"),
    ("tree.louvers.crossings", -1, "tree.louvers.crossings"),
    ("tree.louvers.crossings", "many", "tree.louvers.crossings"),
    ("tree.louvers.crossings", 100, "tree.louvers.crossings"),
])
def test_config_errors(key, value, field):
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        load_project(EXAMPLE, {key: value})


def test_config_accepts_volume():
    p = load_project(EXAMPLE, {"tree.louvers.arrangement": "volume",
                               "tree.louvers.crossings": 14.5})
    assert p.tree.louvers.arrangement == "volume" and p.tree.louvers.crossings == 14.5
    assert load_project(EXAMPLE).tree.louvers.arrangement == "layers"


@pytest.mark.parametrize("switches, field", [
    ({"louvers.arrangement": "lattice"}, "tree.louvers.arrangement"),
    ({"louvers.crossings": -2}, "tree.louvers.crossings"),
    ({"louvers.crossings": "x"}, "switches.louvers.crossings"),
    ({"louvers.arrangement": "volume", "louvers.crossings": 60, "louvers.slat_size_m": 0.05},
     "tree.louvers.slat_size_m"),  # too many slats
])
def test_switch_errors(project, frame, switches, field):
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        build_tree(project, Scenario("x", "louvers", form="free", switches=switches), frame)


def test_dome_with_volume_is_an_error(project, frame):
    with pytest.raises(ConfigError, match=r"tree\.louvers\.arrangement.*") as exc:
        build_tree(project, Scenario("x", "louvers", form="dome", switches=VOLUME), frame)
    assert "dome" in str(exc.value)


# ---------------------------------------------------------------- calibration
def test_calibrate_crossings_cheap(project):
    """One hour, 0.6 m slats, 96 rays per sensor, one realisation: the search brackets a 20 %
    target and stops within 2 % (or 2 s.e.) of it; permeability falls with the crossings."""
    p = replace(project, site=replace(project.site, hours=("13:30",)))
    res = calibrate_crossings(p, target=0.2, switches={"louvers.slat_size_m": 0.6},
                              search=CrossingsSearch(start=(2.0, 6.0), rays=96))
    t = res.table
    assert res.converged
    assert abs(math.log(res.permeability / 0.2)) <= max(0.02, 2 * res.stderr / res.permeability)
    assert np.all(np.diff(t["permeability"].to_numpy()) < 0)
    assert 2.0 < res.crossings < 12.0
