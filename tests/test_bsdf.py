"""Crown BSDFs: rfluxmtx → wrapBSDF → checkBSDF, read back (energy, reciprocity, analytic
cases), the Radiance BSDF material's orientation, and the BSDF crown representation."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from radtree.bsdf.klems import read_klems
from radtree.config import CrownBsdf, check_key, load_project
from radtree.engines.radiance.binaries import monte_carlo_options, run
from radtree.engines.radiance.bsdf import FluxSettings, check_bsdf, klems_bsdf, write_system
from radtree.engines.radiance.materials import material_text
from radtree.errors import ConfigError, EngineError
from radtree.optics import Bsdf, Plastic
from radtree.pipeline.crown_bsdf import band_elevations, leaf_on_sample
from radtree.trees.slab import branch_slab, dome_slab
from tests.conftest import MENDOZA, copy_project, needs_radiance

FAST = FluxSettings(samples=192, ab=2, ad=2, lw=1e-3, tiles=5)


def plates(folder: Path) -> Path:
    """An opaque two-plate sample: white (ρ 0.8) facing outside (−z), black behind it."""
    sq = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    polys = {"white": (sq + [0, 0, -0.9])[None], "black": (sq + [0, 0, -0.1])[None]}
    mats = {"white": Plastic("white", 0.8), "black": Plastic("black", 0.0)}
    write_system(folder, polys, mats, 1.0, 1.0, 0.9, 15)
    return klems_bsdf(folder, replace(FAST, ab=1, samples=8), "plates", 0.9, 1.0, 1.0).xml


@needs_radiance
def test_plates_read_back_exactly_and_orient_the_bsdf_material(tmp_path):
    xml = plates(tmp_path)
    assert "Klems_Full" in check_bsdf(xml)
    k = read_klems(xml)
    assert k.lambdas.sum() == pytest.approx(math.pi, rel=1e-12)
    # every front path hits the white plate and is reflected diffusely: exactly 0.8
    np.testing.assert_allclose(k.hemispherical("rf"), 0.8, atol=2e-3)
    inner = k.theta_deg < 75.0   # grazing rays of the outer ring may leave the tiled area
    for key in ("tf", "tb", "rb"):
        assert np.abs(k.hemispherical(key)[inner]).max() < 1e-9
    # in a Radiance BSDF material the XML's front (outside) is the side away from the normal
    scene = ("void BSDF shade\n6 0 plates.xml 0 1 0 .\n0\n0\n"
             "shade polygon p\n0\n0\n12 -50 -50 0  50 -50 0  50 50 0  -50 50 0\n"
             "void glow skyglow\n0\n0\n4 1 1 1 0\nskyglow source sky\n0\n0\n4 0 0 1 360\n")
    (tmp_path / "t.rad").write_text(scene)
    run(["oconv", "t.rad"], cwd=tmp_path, stdout_path=tmp_path / "t.oct")
    out = run(["rtrace", "-h", "-I", "-u-", *monte_carlo_options(1, 256, 1e-4), "t.oct"],
              cwd=tmp_path, stdin=b"0 0 1 0 0 -1\n0 0 -1 0 0 1\n").decode().split()
    normal_side, back_side = float(out[0]), float(out[3])
    assert back_side == pytest.approx(0.8 * math.pi, rel=0.02)
    assert normal_side < 0.02


@needs_radiance
def test_one_slat_layer_energy_reciprocity_and_direct_transmission(tmp_path):
    proj = load_project(MENDOZA)
    lv = replace(proj.tree.louvers, layers=1, cover_fraction=0.5, reflectance=0.3,
                 transmittance=0.2, specular_fraction=0.0)
    sample = dome_slab(replace(proj.tree, louvers=lv), proj.sensors, proj.street, 30.0)
    write_system(tmp_path, sample.polygons, sample.materials, sample.width, sample.height,
                 sample.thickness, FAST.tiles)
    res = klems_bsdf(tmp_path, FAST, "layer", sample.thickness, sample.width, sample.height)
    assert "Klems_Full" in res.check
    k = read_klems(res.xml)
    # passive: T + R ≤ 1 for every incident patch, front and back
    for side in ("f", "b"):
        total = k.hemispherical(f"t{side}") + k.hemispherical(f"r{side}")
        assert total.max() <= 1.0 + 1e-3   # the XML holds 4 significant digits
        # near normal, half the light meets a slat that absorbs 1 − R − T = 0.5 of it
        near = np.flatnonzero(k.theta_deg <= 10.0)
        assert float(total[near].mean()) == pytest.approx(1 - 0.5 * 0.5, abs=0.05)
    # Helmholtz reciprocity on the ring exchanges (Monte Carlo noise only)
    # (transmission is mostly undeviated and well sampled; diffuse reflection spreads ~40
    # reflected rays per patch over 145 patches, so its ring-to-ring entries are noisier and
    # its ring marginals — light reflected into a ring vs out of it — are tested too)
    err = k.reciprocity_error(max_theta_deg=75.0)
    assert err["t"] < 0.05 and err["rf"] < 0.25 and err["rb"] < 0.25, err
    for key in ("rf", "rb"):
        w = k.ring_exchange(key)[:8, :8]   # ~300 reflected rays in ring 1: ~6 % noise
        assert np.abs(w.sum(axis=0) - w.sum(axis=1))[1:].max() < 0.12 * w.sum(axis=0).max()
    # near-normal incidence: undeviated light = the gaps, 1 − f = 0.5 (rings θ ≤ 15°)
    flux = k.flux("tf")
    direct = float(np.mean(np.diag(flux)[near]))
    assert direct == pytest.approx(0.5, abs=0.07)
    # and the slats' diffuse part adds about f·(T + R)/2 each way, nothing undeviated
    assert float(np.mean(k.hemispherical("rf")[near])) == pytest.approx(0.5 * 0.3 + 0.5 * 0.2
                                                                         * 0.5, abs=0.1)


def test_branch_slab_cover_and_config_keys():
    s = branch_slab(0.3, 2.0, 40.0, 0.05, seed=3)
    assert s.count % 4 == 0 and s.thickness <= 2.0 + 0.05 + 2e-3   # + the stick diameter
    # Poisson plan cover from the stick count: 1 − exp(−n l cos β d / A)
    sticks = s.count // 4
    length = min(2.4, 2.0 / math.sin(math.radians(40.0)))
    cover = 1 - math.exp(-sticks * length * math.cos(math.radians(40.0)) * 0.05 / 2.4**2)
    assert cover == pytest.approx(0.3, abs=0.01)
    assert check_key("tree.representation", "bsdf")[1] == "bsdf"
    assert check_key("bsdf.samples", 64)[0].name == "tree.bsdf.samples"
    with pytest.raises(ConfigError, match="tree.bsdf.tiles.*odd"):
        CrownBsdf(tiles=4)
    assert check_key("bsdf.sectors", 5)[0].name == "tree.bsdf.sectors"
    # the dome's defaults: 5 sectors on a 48-ring shell (the setting that holds every hour of
    # the Mendoza dome within 5 % of the slats)
    assert (CrownBsdf().sectors, CrownBsdf().segments) == (5, 192)
    assert CrownBsdf().material == "aBSDF"
    with pytest.raises(ConfigError):
        CrownBsdf(material="bsdf")
    assert check_key("bsdf.segments", 96)[0].name == "tree.bsdf.segments"
    with pytest.raises(ConfigError, match="tree.bsdf.sectors"):
        CrownBsdf(sectors=0)
    with pytest.raises(ConfigError, match="tree.bsdf.segments"):
        CrownBsdf(segments=3)
    proj = load_project(MENDOZA)
    with pytest.raises(ConfigError, match="model 'perforated'.*louvers"):
        leaf_on_sample(proj, proj.scenario("C"))
    # the dome's bands: three of 30°, sampled at their middles
    assert band_elevations(proj.tree, "dome") == [(0.0, 30.0, 15.0), (30.0, 60.0, 45.0),
                                                   (60.0, 90.0, 75.0)]
    # free crowns: the same bands, by the facets' normals (tests/test_bsdf_envelope.py)
    assert band_elevations(proj.tree, "free") == band_elevations(proj.tree, "dome")
    # the dome's slats, seen el above the horizon, are tilted |90° − α − el| from the radial
    for el, tilt in ((15.0, 45.0), (45.0, 15.0), (75.0, 15.0)):
        s15 = dome_slab(proj.tree, proj.sensors, proj.street, el)
        assert s15.info["slat_tilt_deg"] == pytest.approx(tilt, abs=1e-6)
        # cover 1: the slats tile the cell exactly, seen along the layer normal
        quads = s15.polygons["leaf"]
        a, b = quads[:, 2, :2] - quads[:, 0, :2], quads[:, 3, :2] - quads[:, 1, :2]
        area = 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum()
        assert area == pytest.approx(5 * s15.width * s15.height, rel=1e-9)


@needs_radiance
def test_bsdf_crown_scene_and_in_process_engines_refuse_it(tmp_path):
    proj_dir = copy_project(tmp_path / "p", hours=["12:30"])
    xml = plates(tmp_path / "x")
    text = (proj_dir / "radtree.toml").read_text().replace(
        '[tree.dome]', f'representation = "bsdf"\n\n[tree.bsdf]\nxml = "{xml}"\nsectors = 1\n'
        'segments = 0\n\n[tree.dome]')
    (proj_dir / "radtree.toml").write_text(text)
    proj = load_project(proj_dir)
    from radtree.engines.numpy.interface import NumpyEngine
    from radtree.pipeline.assemble import make_scene
    from radtree.pipeline.trace import trace_hours

    built = make_scene(proj, proj.scenario("B"), dense_grid=False)
    shells = [m for m in built.scene.meshes if m.material.startswith("crown_bsdf")]
    assert sorted(m.name for m in shells) == [f"crown_bsdf_b{k}{h}" for k in range(3)
                                              for h in ("", "_low")]
    assert not any(m.name == "tree_leaves" for m in built.scene.meshes)
    assert built.ab == 6
    centre = np.array([proj.sensors.x_m, 0.0, proj.sensors.height_m])
    area = 0.0
    for m in shells:
        assert isinstance(built.scene.materials[m.material], Bsdf)
        # every shell normal points to the dome centre (the XML's back side)
        t = m.triangles
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        assert np.all(np.einsum("ij,ij->i", n, t.mean(axis=1) - centre) < 0)
        el = np.degrees(np.arcsin((t.mean(axis=1) - centre)[:, 2] / np.linalg.norm(
            t.mean(axis=1) - centre, axis=1)))
        k = int(m.name[len("crown_bsdf_b")])
        assert np.all((np.abs(el) >= 30 * k - 1e-9) & (np.abs(el) <= 30 * (k + 1) + 1e-9))
        assert np.all(el < 0) if m.name.endswith("_low") else np.all(el >= 0)
        area += m.area()
    r = proj.tree.dome.radius_m
    assert area == pytest.approx(2 * math.pi * r * r, rel=0.02)   # the whole hemisphere
    # the default shell material is aBSDF (peak extraction; tests/test_absdf.py)
    assert material_text(built.scene.materials["crown_bsdf_b1_low"]) == (
        f"void aBSDF crown_bsdf_b1_low\n5 {xml.resolve()} 0 0 -1 .\n0\n0\n")
    with pytest.raises(EngineError, match="Radiance only"):
        trace_hours(proj, proj.scenario("B"), NumpyEngine(), grids=["facade"], built=built)


@needs_radiance
def test_dome_bsdf_shell_takes_its_own_segments(tmp_path):
    """tree.bsdf.segments meshes the dome's BSDF shell (rings = segments / 4; 0: the dome's
    tree.dome.segments, 48 → 12 rings): 192 segments give 16 × the facets of 48 (a hemisphere
    mesh of n rings has ∝ n² triangles) and a surface within 1 % of the hemisphere's 2πr²,
    closer than the coarse shell's."""
    from radtree.pipeline.assemble import make_scene

    proj_dir = copy_project(tmp_path / "p", hours=["12:30"])
    xml = plates(tmp_path / "x")
    base = (proj_dir / "radtree.toml").read_text()
    shells = {}
    for segments in (0, 192):
        (proj_dir / "radtree.toml").write_text(base.replace(
            "[tree.dome]", f'representation = "bsdf"\n\n[tree.bsdf]\nxml = "{xml}"\n'
            f"sectors = 1\nsegments = {segments}\n\n[tree.dome]"))
        proj = load_project(proj_dir)
        built = make_scene(proj, proj.scenario("B"), dense_grid=False)
        shells[segments] = np.concatenate([m.triangles for m in built.scene.meshes
                                           if m.material.startswith("crown_bsdf")])
        r = proj.tree.dome.radius_m
    assert proj.tree.dome.segments == 48
    assert len(shells[192]) == pytest.approx(16 * len(shells[0]), rel=0.1)
    areas = {k: 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]),
                                     axis=1).sum() for k, t in shells.items()}
    hemi = 2 * math.pi * r**2
    assert abs(areas[192] / hemi - 1) < abs(areas[0] / hemi - 1)
    assert areas[192] == pytest.approx(hemi, rel=0.01)
