"""The free crown's envelope BSDF (``tree.bsdf.crossing = "chord"``): one planar sample per
Klems ring whose optical depth is the half chord R cos θ, ring exchanges made reciprocal, the
slats turned as an envelope facet sees them, and the bands of the BSDF crown."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from radtree.bsdf.klems import read_klems
from radtree.config import check_key, load_project
from radtree.engines.radiance.bsdf import (
    FluxSettings,
    klems_patch_rings,
    reciprocal_rings,
)
from radtree.errors import ConfigError
from radtree.optics import KLEMS_FULL_RINGS
from radtree.pipeline.crown_bsdf import band_elevations, ensure_bsdf, leaf_on_sample
from radtree.trees.slab import branch_slab, chord_rings, volume_slab
from tests.conftest import ROOT, needs_radiance

OFFICE = ROOT / "examples" / "office-block"


def test_klems_rings_hold_the_145_patches_and_pi():
    ring, lam = klems_patch_rings()
    assert ring.size == 145 and sum(n for *_, n in KLEMS_FULL_RINGS) == 145
    assert lam.sum() == pytest.approx(math.pi, rel=1e-12)
    assert np.bincount(ring).tolist() == [1, 8, 16, 20, 24, 24, 24, 16, 12]


def test_chord_rings_carry_the_half_chord():
    rings = chord_rings(4.75, 0.6)
    for (_, _, centre, _), (depth, scale) in zip(KLEMS_FULL_RINGS, rings):
        # optical depth along θ: scale · depth / cos θ = R cos θ (the half chord)
        assert scale * depth == pytest.approx(4.75 * math.cos(math.radians(centre)) ** 2)
        assert 0.6 - 1e-12 <= depth <= 4.75 and 0 < scale <= 1.0
    assert rings[0] == (4.75, 1.0)
    assert rings[-1][0] == 0.6 and rings[-1][1] == pytest.approx(
        4.75 * math.cos(math.radians(82.5)) ** 2 / 0.6)


def test_reciprocal_rings_makes_every_ring_exchange_reciprocal():
    rng = np.random.default_rng(5)
    ring, lam = klems_patch_rings()
    flux = {k: rng.random((145, 145)) * 1e-3 for k in ("tf", "rf", "tb", "rb")}
    out = reciprocal_rings(flux)
    onehot = np.eye(9)[ring]

    def w(f):
        return onehot.T @ (f * lam[None, :]) @ onehot

    np.testing.assert_allclose(w(out["tf"]), w(out["tb"]).T, rtol=1e-12)
    for key in ("rf", "rb"):
        np.testing.assert_allclose(w(out[key]), w(out[key]).T, rtol=1e-12)
    # each pair takes the smaller of the two: no block grows, no patch gains energy
    wf, wb = w(flux["tf"]), w(flux["tb"])
    np.testing.assert_allclose(w(out["tf"]), np.minimum(wf, wb.T), rtol=1e-12)
    for key in out:
        assert np.all(out[key] <= flux[key] * (1 + 1e-12))
    # already reciprocal data are left as they are; the azimuthal pattern inside a block too
    again = reciprocal_rings(out)
    for key in out:
        np.testing.assert_allclose(again[key], out[key], rtol=1e-12)
    block = (ring[:, None] == 4) & (ring[None, :] == 2)
    ratio = out["tf"][block] / flux["tf"][block]
    assert np.ptp(ratio) < 1e-12
    # a block no sample reached empties its partner
    sparse = {k: v.copy() for k, v in flux.items()}
    sparse["rf"][np.ix_(ring == 1, ring == 8)] = 0.0
    fixed = reciprocal_rings(sparse)
    np.testing.assert_allclose(w(fixed["rf"]), w(fixed["rf"]).T, rtol=1e-12)
    assert w(fixed["rf"])[8, 1] == 0.0

def test_slats_turn_with_the_facet_and_keep_their_density():
    proj = load_project(OFFICE)
    lv = proj.tree.louvers

    def normals(el):
        q = volume_slab(lv, 4.75, 2.0, normal_elevation_deg=el).polygons["leaf"]
        n = np.cross(q[:, 1] - q[:, 0], q[:, 3] - q[:, 0])
        return n / np.linalg.norm(n, axis=1)[:, None]

    # the vertical of a facet whose outward normal is e above the horizon: (0, cos e, −sin e)
    for el in (90.0, 45.0, 15.0, 0.0):
        v = np.array([0.0, math.cos(math.radians(el)), -math.sin(math.radians(el))])
        tilt = np.degrees(np.arccos(np.abs(normals(el) @ v)))
        np.testing.assert_allclose(tilt, lv.inclination_deg, atol=1e-6)
    # the count follows the density scale (the chord rings)
    full = volume_slab(lv, 4.75, 2.0)
    half = volume_slab(lv, 4.75, 2.0, density_scale=0.5)
    assert half.count == pytest.approx(0.5 * full.count, abs=1)


def test_sparse_branch_slab_grows_its_cell():
    thin = branch_slab(0.002, 0.6, 40.0, 0.08, cell_m=2.4, min_sticks=12)
    assert thin.count // 4 >= 12 and thin.width > 2.4
    sticks = thin.count // 4
    length = min(thin.width, 0.6 / math.sin(math.radians(40.0)))
    cover = 1 - math.exp(-sticks * length * math.cos(math.radians(40.0)) * 0.08 / thin.width**2)
    assert cover == pytest.approx(0.002, rel=0.1)
    assert branch_slab(0.3, 2.0, 40.0, 0.05, seed=3).width == 2.4   # dense: as before


def test_free_crown_bands_and_the_crossing_key():
    proj = load_project(OFFICE)
    assert band_elevations(proj.tree, "free") == [(0.0, 30.0, 15.0), (30.0, 60.0, 45.0),
                                                   (60.0, 90.0, 75.0)]
    slab = replace(proj.tree, bsdf=replace(proj.tree.bsdf, crossing="slab"))
    assert band_elevations(slab, "free") == [(0.0, 90.0, 90.0)]
    assert check_key("tree.bsdf.crossing", "slab")[1] == "slab"
    with pytest.raises(ConfigError, match="tree.bsdf.crossing"):
        check_key("tree.bsdf.crossing", "lens")
    on = leaf_on_sample(proj, proj.scenario("with"))
    assert len(on.rings) == 9 and on.thickness == 4.75
    assert [r.info["normal_elevation_deg"] for r in on.rings] == [15.0] * 9
    # grazing rings hold fewer slats: their optical depth is R cos² θ at full density
    counts = [r.count for r in on.rings]
    assert counts == sorted(counts, reverse=True) and counts[-1] < counts[0] / 20


@needs_radiance
def test_chord_envelope_bsdf_is_reciprocal_passive_and_clearer_at_grazing(tmp_path):
    """A thin crown (2 m half chord): checkBSDF accepts the XML; ring exchanges reciprocal;
    T + R ≤ 1; the direct (diagonal) transmission at grazing incidence is far above a slab's
    — the half chord shortens as the slab path lengthens."""
    proj = load_project(OFFICE, overrides={"tree.bsdf.depth_m": 2.0})
    settings = FluxSettings(samples=24, ab=1, ad=2, lw=1e-3, tiles=5, nproc=1)
    on = leaf_on_sample(proj, proj.scenario("with"), 75.0)
    k = read_klems(ensure_bsdf(on, settings, tmp_path / "chord", "chord").xml)
    err = k.reciprocity_error()
    assert max(err.values()) < 1e-3, err                        # exact up to 4 digits
    for side in ("f", "b"):
        assert (k.hemispherical(f"t{side}") + k.hemispherical(f"r{side}")).max() <= 1.0 + 1e-3
    slab_proj = load_project(OFFICE, overrides={"tree.bsdf.depth_m": 2.0,
                                                "tree.bsdf.crossing": "slab"})
    slab = read_klems(ensure_bsdf(leaf_on_sample(slab_proj, slab_proj.scenario("with")),
                                  settings, tmp_path / "slab", "slab").xml)
    ring, _ = klems_patch_rings()
    chord_direct, slab_direct = np.diag(k.flux("tf")), np.diag(slab.flux("tf"))
    normal = float(chord_direct[0]), float(slab_direct[0])
    assert normal[0] == pytest.approx(normal[1], rel=0.5)      # same depth at θ = 0
    graze = ring == 7                                          # θ 65–75°
    assert chord_direct[graze].mean() > 5 * slab_direct[graze].mean()


def test_free_bsdf_crown_bands_by_normal_and_its_wall_cap(tmp_path):
    from radtree.pipeline.assemble import facade_frame
    from radtree.pipeline.crown_bsdf import wall_half_chord
    from radtree.trees.bsdf_shell import WALL_BAND, build_bsdf_crown

    proj = load_project(OFFICE)
    # the crown centres stand 3 m out, the clip plane 1.5 cm out: a cap of half chord 2.985 m
    assert wall_half_chord(proj.tree, proj.sensors, proj.street) == pytest.approx(2.985)
    xmls = [(lo, hi, tmp_path / f"b{k}.xml") for k, (lo, hi, _) in
            enumerate(band_elevations(proj.tree, "free"))] + [(*WALL_BAND, tmp_path / "w.xml")]
    frame = facade_frame(proj)
    model = build_bsdf_crown(proj.tree, proj.sensors, proj.street, frame, "free", xmls, 6)
    shells = {m.name: m for m in model.meshes if m.material.startswith("crown_bsdf")}
    assert sorted(shells) == sorted([f"crown_bsdf_b{k}{h}" for k in range(3)
                                     for h in ("", "_low")] + ["crown_bsdf_wall"])
    assert model.materials["crown_bsdf_wall"].xml == str((tmp_path / "w.xml").resolve())
    assert model.materials["crown_bsdf_b0_low"].up == (0.0, 0.0, -1.0)
    normal_out = frame.to_world(np.array([[0.0, 1.0, 0.0]])) - frame.to_world(np.zeros((1, 3)))
    for name, m in shells.items():
        t = m.triangles
        n = -np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])      # outward (wound inwards)
        n /= np.linalg.norm(n, axis=1)[:, None]
        if name == "crown_bsdf_wall":     # the cap faces the wall: outward = −façade normal
            np.testing.assert_allclose(n @ normal_out[0], -1.0, atol=1e-9)
            continue
        el = np.degrees(np.arcsin(np.clip(n[:, 2], -1, 1)))
        k = int(name[len("crown_bsdf_b")])
        assert np.all((np.abs(el) >= 30 * k - 1e-6) & (np.abs(el) <= 30 * (k + 1) + 1e-6))
        assert np.all(el < 0) if name.endswith("_low") else np.all(el >= 0)
