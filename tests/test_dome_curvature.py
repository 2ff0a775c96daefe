"""The transfer of explicit surfaces traced backwards, and the dome's curvature in its BSDF."""

from __future__ import annotations

import math
import re

import numpy as np

from radtree.config import load_project
from radtree.engines.numpy.transfer import trace_escapes
from radtree.engines.radiance.bsdf import klems_patch_rings
from radtree.optics import Trans
from radtree.pipeline.crown_bsdf import scenario_tree
from radtree.pipeline.dome_curvature import (
    RingRow,
    band_directions,
    curved_dome,
    curved_flux,
    curved_ring_row,
    klems_patch,
    planar_ring_row,
    reciprocal_patch,
    shell_frames,
    visible_fraction,
)
from radtree.scene import Mesh, Scene
from radtree.trees.bsdf_shell import facade_angle, sector_bounds
from tests.conftest import MENDOZA, copy_project, needs_radiance


def leaf_sheet() -> Scene:
    """One 200 m square of R 0.1, T_d 0.2, T_s 0.3 at z = 1."""
    v = np.array([[-100, -100, 1], [100, -100, 1], [100, 100, 1], [-100, 100, 1]], float)
    return Scene([Mesh("sheet", "leaf", v, np.array([[0, 1, 2], [0, 2, 3]]))],
                 {"leaf": Trans("leaf", 0.1, 0.2, 0.3)}, {}, [])


def test_escapes_of_one_translucent_sheet_are_its_three_parts():
    n = 200_000
    up = np.tile([0.0, 0.0, 1.0], (n, 1))
    esc = trace_escapes(leaf_sheet(), np.zeros((n, 3)), up, seed=3)
    cz = esc.direction[:, 2]
    through = cz > 1 - 1e-12
    diffuse_t = (cz > 0) & ~through
    back = cz < 0
    # each event is drawn ∝ its coefficient and the throughput is their sum 0.6
    for sel, expected in ((through, 0.3), (diffuse_t, 0.2), (back, 0.1)):
        share = esc.weight[sel].sum() / n
        sigma = 0.6 * math.sqrt(expected / 0.6 * (1 - expected / 0.6) / n)
        assert abs(share - expected) < 4 * sigma, (expected, share)
    # diffuse transmission is Lambertian about +z: mean cos θ = 2/3
    assert abs(cz[diffuse_t].mean() - 2 / 3) < 0.005
    assert esc.launched == n and np.all(esc.path < n)


def test_curvature_row_rescales_rings_and_keeps_reciprocity():
    ring, lam = klems_patch_rings()
    rng = np.random.default_rng(0)
    flux = {k: rng.uniform(0.001, 0.003, (145, 145)) for k in ("tf", "rf", "tb", "rb")}
    planar = planar_ring_row(flux["tf"])
    target = planar * np.linspace(1.0, 2.0, 9)
    out, factor = curved_flux(flux, RingRow(target, np.zeros(9), 0.0, 1), per="ring")
    np.testing.assert_allclose(planar_ring_row(out["tf"]), target, rtol=1e-12)
    np.testing.assert_allclose(factor, np.linspace(1.0, 2.0, 9), rtol=1e-12)
    # only the normal-outgoing row of T_f and the normal-incident column of T_b change
    np.testing.assert_array_equal(out["tf"][1:], flux["tf"][1:])
    np.testing.assert_array_equal(out["tb"][:, 1:], flux["tb"][:, 1:])
    np.testing.assert_array_equal(out["rf"], flux["rf"])
    # T_f[0, j] / T_b[j, 0] is scaled alike: a reciprocal pair stays reciprocal
    np.testing.assert_allclose(out["tf"][0] / flux["tf"][0], out["tb"][:, 0] / flux["tb"][:, 0])


def test_curvature_row_per_patch_replaces_the_row_and_its_reciprocal_column():
    ring, lam = klems_patch_rings()
    rng = np.random.default_rng(1)
    flux = {k: rng.uniform(0.001, 0.003, (145, 145)) for k in ("tf", "rf", "tb", "rb")}
    patch = rng.uniform(0.0, 1e-3, 145)
    weight = np.bincount(ring, patch, minlength=9)
    out, factor = curved_flux(flux, RingRow(weight, np.zeros(9), 0.0, 1, patch, np.zeros(145)))
    # the row's BSDF values are the traced P_j / Λ_j: F_tf[0, j] = f Λ_0
    np.testing.assert_allclose(out["tf"][0] / lam[0], patch / lam, rtol=1e-12)
    np.testing.assert_allclose(planar_ring_row(out["tf"]), weight, rtol=1e-12)
    np.testing.assert_allclose(factor, weight / planar_ring_row(flux["tf"]), rtol=1e-12)
    # T_b's normal-incident column: the same values at the azimuth turned by 180°
    # (f_tb[j', 0] = f_tf[0, j]); the first patch of ring 1 (φ = 0°) pairs with its fifth
    back = out["tb"][:, 0] / lam
    j = reciprocal_patch()
    np.testing.assert_allclose(back[j], patch / lam, rtol=1e-12)
    assert j[0] == 0 and j[1] == 5 and j[5] == 1 and sorted(j) == list(range(145))
    np.testing.assert_array_equal(out["tf"][1:], flux["tf"][1:])
    np.testing.assert_array_equal(out["tb"][:, 1:], flux["tb"][:, 1:])


def test_klems_patch_and_shell_frames():
    """Patch indices by (θ, φ) and the BSDF frame of the shell at a view direction."""
    assert list(klems_patch(np.array([2.0, 10.0, 10.0, 10.0, 80.0]),
                            np.array([123.0, 0.0, 44.0, -30.0, 359.0]))) == [0, 1, 2, 8, 133]
    d = np.array([[0.0, 1.0, 0.0], [0.0, math.cos(0.5), -math.sin(0.5)]])
    x, y, z = shell_frames(d)
    np.testing.assert_allclose(z, -d)
    np.testing.assert_allclose(y[0], [0.0, 0.0, 1.0], atol=1e-12)     # up above the horizon
    assert y[1][2] < 0                                                   # down below it
    np.testing.assert_allclose(np.cross(x, y), z, atol=1e-12)           # x × y = z


def test_curved_mendoza_dome_passes_more_scattered_light_than_its_planar_stack():
    """Traced on the example's explicit dome (5 shells, 1.60–3.82 m) from its centre: the
    direct part (ring 0) is the layers' product of gaps; the scattered part grows with the
    band's elevation, where the inner shells are seen most obliquely from outside."""
    p = load_project(MENDOZA)
    sc = p.scenario("B")
    tree = scenario_tree(p, sc)[0]
    dome = curved_dome(p, sc, tree)
    rows = [curved_ring_row(dome, lo, hi, paths=60_000) for lo, hi in ((0, 30), (60, 90))]
    for row in rows:
        assert 0.016 < row.weight[0] < 0.021          # ≈ 0.0186 (1.2 M paths)
        assert np.all(row.stderr < 0.1 * row.weight + 1e-4)
    low, high = (float(r.weight[1:].sum()) for r in rows)
    assert 0.0115 < low < 0.0155 and 0.020 < high < 0.027   # ≈ 0.0135 and 0.0235 (600 k)
    assert 0 < rows[0].reflected < rows[1].reflected < 0.1
    ring, _ = klems_patch_rings()
    for row in rows:
        assert row.patch is not None and row.patch_stderr is not None
        np.testing.assert_allclose(np.bincount(ring, row.patch, minlength=9), row.weight,
                                   rtol=1e-9)
    # the band at the horizon, with the façade inside the shell traced: at grazing incidence
    # (ring 55–65°) light arriving from above (T_f azimuth 180–360°) passes 1.2 × what arrives
    # from below (0.00083 and 0.00070 at 600 k paths; without the façade, light leaving the
    # stack through its open face in the wall plane made it 1.6 ×, 0.00092 against 0.00058)
    p6 = rows[0].patch[ring == 6]
    above, below = float(p6[13:23].sum()), float(p6[1:11].sum())
    assert 0.9 < above / below < 1.5, (above, below)


def test_sectors_of_the_dome_band_mirror_each_other_and_differ_at_the_rim():
    """tree.bsdf.sectors: the band at the horizon traced in the sectors at the wall's rim
    (−90…−54° and 54…90° from the façade normal) and facing the street (−18…18°). The dome is
    mirror-symmetric: both rim sectors pass the same (0.0161 / 0.0161 scattered, 600 k
    paths); at the rim grazing light (ring 75–90°) passes 1.5 × what it does facing the
    street (0.00267 against 0.00174)."""
    p = load_project(MENDOZA)
    sc = p.scenario("B")
    dome = curved_dome(p, sc, scenario_tree(p, sc)[0])
    left, right, mid = (curved_ring_row(dome, 0, 30, paths=60_000, sector_deg=s)
                        for s in ((-90, -54), (54, 90), (-18, 18)))
    for a, b in ((left, right),):
        sa, sb = float(a.weight[1:].sum()), float(b.weight[1:].sum())
        se = math.hypot(float(np.sqrt((a.stderr[1:] ** 2).sum())),
                        float(np.sqrt((b.stderr[1:] ** 2).sum())))
        assert abs(sa - sb) < 4 * se, (sa, sb, se)
    assert 0.0135 < float(left.weight[1:].sum()) < 0.019
    assert 0.0105 < float(mid.weight[1:].sum()) < 0.0152
    assert left.weight[8] > 1.25 * mid.weight[8], (left.weight[8], mid.weight[8])
    for row in (left, mid):
        assert 0.016 < row.weight[0] < 0.021          # the direct part: the same gaps


def test_facade_angle_sectors_and_the_wall_fraction_of_patches():
    n = np.array([0.0, 1.0, 0.0])
    u = np.cross([0.0, 0.0, 1.0], n)
    d = np.array([n, u, -u, (n + u) / math.sqrt(2), [0.0, 0.6, 0.8]])
    np.testing.assert_allclose(facade_angle(d, n), [0.0, 90.0, -90.0, 45.0, 0.0], atol=1e-9)
    assert sector_bounds(5) == [(-90.0, -54.0), (-54.0, -18.0), (-18.0, 18.0), (18.0, 54.0),
                                (54.0, 90.0)]
    rng = np.random.default_rng(4)
    # looking straight out from the wall every patch is in front of it ...
    np.testing.assert_allclose(visible_fraction(n[None, :], n, rng), 1.0)
    # ... looking along it, each ring is half behind it
    ring, _ = klems_patch_rings()
    vis = visible_fraction(u[None, :], n, rng, per_patch=4000)
    per_ring = np.bincount(ring, vis) / np.bincount(ring)
    np.testing.assert_allclose(per_ring, 0.5, atol=0.02)
    dirs = band_directions(n, 0.0, 30.0, 5000, rng, (54.0, 90.0))
    psi = facade_angle(dirs, n)
    el = np.degrees(np.arcsin(np.abs(dirs[:, 2])))
    assert psi.min() >= 54.0 and psi.max() <= 90.0 and el.max() <= 30.0


def test_dome_shell_cut_into_sectors_gets_one_material_per_band_sector_and_half(tmp_path):
    from radtree.trees.bsdf_shell import dome_bands

    centre = np.zeros(3)
    n = np.array([0.0, 1.0, 0.0])
    rng = np.random.default_rng(2)
    c = band_directions(n, 0.0, 90.0, 3000, rng)
    c[::2, 2] *= -1                                   # upper and lower half
    # one tiny triangle at each direction (centroid on the unit sphere)
    verts = np.repeat(c, 3, axis=0) + np.tile([[1e-4, 0, 0], [0, 0, 1e-4], [-1e-4, 0, -1e-4]],
                                              (len(c), 1))
    faces = np.arange(len(verts)).reshape(-1, 3)
    xmls = [tmp_path / f"b{b}_s{s}.xml" for b in range(2) for s in range(3)]
    bands = [(45.0 * (k // 3), 45.0 * (k // 3 + 1), x) for k, x in enumerate(xmls)]
    parts = dome_bands(verts, faces, centre, bands, n, 3)
    assert len(parts) == 2 * 3 * 2
    assert sum(len(f) for _, _, f in parts) == len(faces)
    for name, mat, fs in parts:
        m = re.fullmatch(r"crown_bsdf_b(\d)(_low)?_s(\d)", name)
        assert m is not None, name
        b, s = int(m.group(1)), int(m.group(3))
        assert mat.name == name and mat.xml.endswith(f"b{b}_s{s}.xml")
        cen = verts[fs].mean(axis=1)
        psi = facade_angle(cen, n)
        lo, hi = sector_bounds(3)[s]
        assert psi.min() >= lo - 1e-6 and psi.max() <= hi + 1e-6
        assert (mat.up[2] < 0) == (m.group(2) is not None)


@needs_radiance
def test_scenario_xml_of_the_dome_carries_the_traced_row(tmp_path):
    """representation = "bsdf" on the dome: the computed XML (checkBSDF accepts it) has the
    planar sample's matrices but for the normal-outgoing row, whose ring sums are the traced
    ones; T + R stays ≤ 1 and the ring exchanges stay reciprocal."""
    from radtree.bsdf.klems import read_klems
    from radtree.pipeline.crown_bsdf import scenario_xmls

    proj_dir = copy_project(tmp_path / "p", hours=["12:30"])
    text = (proj_dir / "radtree.toml").read_text().replace(
        "[tree.dome]", 'representation = "bsdf"\n\n[tree.bsdf]\nsamples = 20\nbands = 1\n'
        'sectors = 1\n\n'
        "[tree.dome]")
    (proj_dir / "radtree.toml").write_text(text)
    p = load_project(proj_dir)
    sc = p.scenario("B")
    [(lo, hi, xml)] = scenario_xmls(p, sc)
    assert (lo, hi) == (0.0, 90.0) and xml.parent.name == "curved"
    planar = read_klems(xml.parent.parent / "leaf_on.xml")
    curved = read_klems(xml)
    ring, lam = klems_patch_rings()
    traced = np.bincount(ring, curved.matrices["tf"][0] * lam, minlength=9)
    row = curved_ring_row(curved_dome(p, sc, scenario_tree(p, sc)[0]), 0.0, 90.0, 400_000)
    np.testing.assert_allclose(traced, row.weight, rtol=2e-3, atol=1e-7)   # XML rounding
    # patch by patch: the traced row itself (tree.bsdf.curvature = "traced")
    np.testing.assert_allclose(curved.matrices["tf"][0] * lam, row.patch, rtol=2e-3,
                               atol=1e-7)
    np.testing.assert_allclose(curved.matrices["rf"], planar.matrices["rf"], rtol=2e-3,
                               atol=1e-6)
    assert max(curved.energy_excess().values()) <= 1e-6
    assert curved.reciprocity_error(75.0)["t"] <= planar.reciprocity_error(75.0)["t"] + 1e-3
    # a second call reuses the cached XML
    assert scenario_xmls(p, sc)[0][2] == xml
