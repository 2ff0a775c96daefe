"""Real Radiance runs (no mocks): analytic skies, build folder, Makefile, CLI."""

import math
import re
import subprocess

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from radtree.cli import main
from radtree.config import EngineParams
from radtree.engines.radiance.engine import trace_hour
from radtree.engines.radiance.writer import mesh_to_radiance
from radtree.errors import EngineError
from radtree.light.sky import SkyState
from radtree.light.sun import SunPosition, local_datetime
from radtree.scene import Scene, SensorGrid, quad

from .conftest import needs_radiance

pytestmark = needs_radiance

NOON = local_datetime("2024-12-22", "12:00", -3)


def sky_state(sky="uniform", L=1000.0):
    return SkyState("12:00", NOON, SunPosition(60.0, 0.0), 0.0, sky_model=sky,
                    zenith_luminance=L, ground_glow=False)


def sensors():
    return SensorGrid("s", [[0, 0, 0], [3, 2, 1], [0, 0, 0]], [[0, 0, 1], [0, 0, 1], [1, 0, 0]])


# -ab 1: the glow sky is reached by one ambient bounce; -aa 0 (no interpolation), -ad 8192
PARAMS = EngineParams(ab=1, aa=0.0, ad=8192, as_=0)


def test_uniform_sky_gives_pi_L():
    lux = trace_hour(Scene([], {}, {"s": sensors()}), sky_state(), PARAMS)["s"].lux
    assert lux[:2] == pytest.approx([math.pi * 1000] * 2, rel=0.02)
    assert lux[2] == pytest.approx(math.pi * 1000 / 2, rel=0.02)  # vertical: half the sky


def test_cosine_sky_gives_two_thirds_pi_L0():
    st = sky_state("cosine")
    lux = trace_hour(Scene([], {}, {"s": sensors()}), st, PARAMS)["s"].lux
    assert lux[:2] == pytest.approx([2 * math.pi * 1000 / 3] * 2, rel=0.02)
    # vertical sensor under L0 cos θ: ∫ L0 cosθ · sinθ cosφ dω over the facing half = L0·π/3...
    # = L0 ∫0^{π/2} cos θ sin²θ dθ ∫_{-π/2}^{π/2} cos φ dφ = L0 · (1/3) · 2
    assert lux[2] == pytest.approx(2 * 1000 / 3, rel=0.03)


def test_collimated_sun_on_unobstructed_sensor():
    st = SkyState("12:00", NOON, SunPosition(60.0, 0.0), 100000.0, ground_glow=False)
    lux = trace_hour(Scene([], {}, {"s": sensors()}), st, EngineParams(ab=0))["s"].lux
    assert lux[0] == pytest.approx(100000 * math.sin(math.radians(60)), rel=0.005)


def test_slab_of_trans_under_uniform_sky(tmp_path):
    from radtree.optics import Trans

    big = 2000.0
    slab = quad("slab", "sheet", [[-big, -big, 1], [big, -big, 1], [big, big, 1], [-big, big, 1]])
    scene = Scene([slab], {"sheet": Trans("sheet", 0.0, 0.3, 0.0)}, {"s": sensors()})
    lux = trace_hour(scene, sky_state(), EngineParams(ab=2, aa=0, ad=4096, as_=0))["s"].lux
    assert lux[0] == pytest.approx(0.3 * math.pi * 1000, rel=0.03)


def test_polygon_text():
    m = quad("w", "paint", [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]])
    text = mesh_to_radiance(m)
    assert "paint polygon w.0\n0\n0\n9 0.00000 0.00000 0.00000 1.00000 0.00000 0.00000 " \
           "1.00000 0.00000 1.00000\n" in text
    assert text.count("polygon") == 2


def test_compiled_mesh_text():
    """A large mesh: Wavefront OBJ (1-based faces, 5 decimals), one `mesh` primitive with the
    mesh's material as modifier, and the obj2mesh command of the Makefile and the runner."""
    from radtree.engines.radiance.meshes import (
        MESH_MIN_TRIANGLES,
        as_compiled_mesh,
        mesh_primitive_text,
        obj2mesh_command,
        obj_text,
    )
    from radtree.scene import Mesh

    m = Mesh("crown", "leaf", [[0, 0, 0], [1, 0, 0], [1.25, 0.5, 2]], [[0, 1, 2], [2, 1, 0]])
    assert obj_text(m) == ("# crown: 2 triangles, material leaf\n"
                           "v 0.00000 0.00000 0.00000\nv 1.00000 0.00000 0.00000\n"
                           "v 1.25000 0.50000 2.00000\nf 1 2 3\nf 3 2 1\n")
    assert mesh_primitive_text(m, "geometry/crown.rtm") == (
        "# crown: 2 triangles, material leaf, compiled by obj2mesh\n"
        "leaf mesh crown\n1 geometry/crown.rtm\n0\n0\n")
    assert obj2mesh_command("geometry/crown.obj") == ["obj2mesh", "-n", "4",
                                                      "geometry/crown.obj"]
    assert not as_compiled_mesh(m)
    big = Mesh("c", "leaf", np.zeros((3 * MESH_MIN_TRIANGLES, 3)),
               np.arange(3 * MESH_MIN_TRIANGLES).reshape(-1, 3))
    assert as_compiled_mesh(big)


def test_compiled_mesh_is_the_polygons_geometry(tmp_path):
    """The same 400 random opaque triangles as polygon text and as an obj2mesh mesh: under a
    sun alone (-ab 0: no Monte Carlo, each sensor lit or shadowed) every sensor of a 15 × 15
    grid gets the same lux to the last digit."""
    from radtree.engines.radiance.binaries import run
    from radtree.engines.radiance.meshes import mesh_primitive_text, obj2mesh_command, obj_text
    from radtree.scene import Mesh

    rng = np.random.default_rng(7)
    centres = rng.uniform([-3, -3, 1], [3, 3, 3], (400, 1, 3))
    tri = centres + rng.normal(0, 0.25, (400, 3, 3))
    crown = Mesh("crown", "slat", tri.reshape(-1, 3), np.arange(1200).reshape(-1, 3))
    common = ("void plastic slat\n0\n0\n5 0.2 0.2 0.2 0 0\n"
              "void light solar\n0\n0\n3 1e6 1e6 1e6\n"
              "solar source sun\n0\n0\n4 0.3 0.2 0.93 0.533\n")
    (tmp_path / "common.rad").write_text(common)
    (tmp_path / "poly.rad").write_text(mesh_to_radiance(crown))
    (tmp_path / "crown.obj").write_text(obj_text(crown))
    run(obj2mesh_command("crown.obj"), cwd=tmp_path, stdout_path=tmp_path / "crown.rtm")
    (tmp_path / "mesh.rad").write_text(mesh_primitive_text(crown, "crown.rtm"))
    g = np.linspace(-3, 3, 15)
    pts = "".join(f"{x:g} {y:g} 0 0 0 1\n" for x in g for y in g).encode()
    lux = {}
    for kind in ("poly", "mesh"):
        run(["oconv", "common.rad", f"{kind}.rad"], cwd=tmp_path,
            stdout_path=tmp_path / f"{kind}.oct")
        out = run(["rtrace", "-h", "-I", "-ab", "0", f"{kind}.oct"], stdin=pts, cwd=tmp_path)
        lux[kind] = np.loadtxt(out.decode().splitlines())[:, 0]
    shadowed = lux["poly"] < 0.5 * lux["poly"].max()
    assert 20 < shadowed.sum() < 205           # the crown shades part of the grid, not all
    np.testing.assert_array_equal(lux["mesh"], lux["poly"])


def test_radiance_failure_carries_command_and_stderr(tmp_path):
    from radtree.engines.radiance.binaries import run

    with pytest.raises(EngineError) as err:
        run(["oconv", str(tmp_path / "missing.rad")])
    assert "oconv" in str(err.value) and "missing.rad" in str(err.value)


def test_build_simulate_and_makefile(open_street):
    r = CliRunner().invoke(main, ["build", str(open_street), "--no-pictures"])
    assert r.exit_code == 0, r.output
    b = open_street / "build" / "A"
    for rel in ["materials.rad", "geometry/facade.rad", "geometry/ground.rad",
                "grids/facade.pts", "grids/facade_map.pts", "skies/1030.sky", "skies/1330.sky",
                "skies/1030_ground.rad", "Makefile", "manifest.json"]:
        assert (b / rel).exists(), rel
    assert (open_street / "build" / "Makefile").exists()
    # scenario A (calculated) has a black ground; B the per-hour concrete reflectance 0.151
    assert "5 0 0 0 0 0" in (b / "skies/1030_ground.rad").read_text()
    assert "5 0.151 0.151 0.151" in (open_street / "build/B/skies/1030_ground.rad").read_text()
    # the example's engine.dense_lw = 0.001: the dense map alone with -lw 0.001
    make = (b / "Makefile").read_text()
    opts = re.search(r"^RTRACE_OPTS := (.*)$", make, re.M).group(1)
    assert f"RTRACE_OPTS_facade_map := {opts.replace('-lw 0.0001', '-lw 0.001')}\n" in make
    assert "rtrace $(RTRACE_OPTS_facade_map) octrees/1330.oct < grids/facade_map.pts" in make
    assert "rtrace $(RTRACE_OPTS) octrees/1330.oct < grids/facade.pts" in make
    # the generated Makefile runs without Python
    subprocess.run(["make", "-s", "-j2", "-C", str(open_street / "build" / "B"), "1330"],
                   check=True, capture_output=True)
    make_lux = np.loadtxt(open_street / "build/B/results/1330_facade.lux")
    assert len(make_lux) == 8

    r = CliRunner().invoke(main, ["simulate", str(open_street), "--fresh"])
    assert r.exit_code == 0, r.output
    df = pd.read_csv(open_street / "results" / "illuminance.csv")
    for col in ["scenario", "model", "datetime", "time", "grid", "sensor", "row", "x", "y", "z",
                "lux", "lux_stderr", "engine", "params_hash"]:
        assert col in df.columns
    assert set(df["scenario"]) == {"A", "B", "C", "D", "E", "A-sky", "F"}
    assert set(df["engine"]) == {"radiance"}
    fac = df[(df.grid == "facade") & (df.scenario == "B") & (df.time == "13:30")]
    assert len(fac) == 8
    # the same commands (rtrace -u-: repeatable sampling) give the same numbers
    np.testing.assert_allclose(fac["lux"].to_numpy(), make_lux, rtol=1e-4)
    # open street at 13:30: direct on the façade ≈ 116450·cos(80.5°)·cos(5.85°) ≈ 19 100 lx,
    # plus ground and sky: the sensors must exceed the direct part
    assert fac["lux"].mean() > 19000
    # A: calculated reflection = black ground traced + analytic term
    a = df[(df.grid == "facade") & (df.scenario == "A") & (df.time == "13:30")]
    assert (a["lux_reflected_calc"] > 0).all()
    assert a["lux"].mean() < fac["lux"].mean()

    # a rerun reuses every finished hour
    r = CliRunner().invoke(main, ["simulate", str(open_street)])
    assert "0 hours traced, 14 reused" in r.output


def test_crown_build_folder_holds_compiled_meshes(tmp_path):
    """Scenario A's louvers dome (7 718 slat triangles): geometry/tree_leaves.obj, a `mesh`
    primitive, and the Makefile's obj2mesh rule before the octrees; the façade stays polygons."""
    from .conftest import copy_project

    p = copy_project(tmp_path / "proj", hours=["13:30"])
    r = CliRunner().invoke(main, ["build", str(p), "-s", "A", "--no-pictures"])
    assert r.exit_code == 0, r.output
    b = p / "build" / "A"
    assert (b / "geometry/tree_leaves.rad").read_text() == (
        "# tree_leaves: 7718 triangles, material leaf, compiled by obj2mesh\n"
        "leaf mesh tree_leaves\n1 geometry/tree_leaves.rtm\n0\n0\n")
    assert (b / "geometry/tree_leaves.obj").read_text().count("\nf ") == 7718
    assert "facade_paint polygon facade.0" in (b / "geometry/facade.rad").read_text()
    make = (b / "Makefile").read_text()
    assert ("geometry/tree_leaves.rtm: geometry/tree_leaves.obj\n"
            "\tobj2mesh -n 4 geometry/tree_leaves.obj > $@.tmp && mv $@.tmp $@\n") in make
    assert "geometry/tree_leaves.rad skies/1330.sky $(MESHES)\n" in make
    # the Makefile alone compiles the mesh and the octree
    subprocess.run(["make", "-s", "-C", str(b), "octrees/1330.oct"], check=True,
                   capture_output=True)
    assert (b / "geometry/tree_leaves.rtm").stat().st_size > 100_000


def test_dry_run_prints_commands(open_street):
    r = CliRunner().invoke(main, ["simulate", str(open_street), "-s", "B", "--dry-run"])
    assert r.exit_code == 0, r.output
    assert "oconv materials.rad skies/1030_ground.rad" in r.output
    assert "rtrace -h -I -u- -ab" in r.output and "< grids/facade.pts" in r.output
    assert not (open_street / "results" / "illuminance.csv").exists()


def test_unknown_hour_is_an_error(open_street):
    r = CliRunner().invoke(main, ["simulate", str(open_street), "--hour", "12:00"])
    assert r.exit_code == 2
    assert "unknown hour(s) 12:00" in r.output


def test_makefile_traces_dense_map_only_at_dense_hours(open_street):
    toml = open_street / "radtree.toml"
    text = toml.read_text().replace("[sensors]\n", '[sensors]\ndense_hours = ["13:30"]\n')
    toml.write_text(text)
    r = CliRunner().invoke(main, ["build", str(open_street), "--no-pictures", "-s", "B"])
    assert r.exit_code == 0, r.output
    make = (open_street / "build" / "B" / "Makefile").read_text()
    assert "\n1030: results/1030_facade.lux\n" in make
    assert "\n1330: results/1330_facade.lux results/1330_facade_map.lux\n" in make
    assert "results/1030_facade_map" not in make
