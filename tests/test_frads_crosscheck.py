"""The three-phase chain against LBNL's frads and against a direct rtrace, on one room whose
window is a radtree crown BSDF (issue 40, item 2).

A 4 m × 4 m × 3 m room (floor 0.2, walls 0.5, ceiling 0.7), a 2 m × 1.6 m south window of the
``BSDF`` material carrying a crown XML (the small free crown of
:mod:`radtree.verify.threephase`, ``tree.bsdf.samples = 10``), ground 0.2 outside, a uniform
sky of radiance 1 above the horizon; nine work-plane sensors 0.8 m up. Three computations of
the same irradiance:

* ``rtrace`` of the scene with the BSDF window (the reference);
* radtree's chain: :func:`radtree.engines.radiance.threephase.view_matrix`,
  :func:`~radtree.engines.radiance.threephase.daylight_matrix` and
  :func:`~radtree.engines.radiance.threephase.multiply` (``rmtxop V T.xml D``);
* frads' ``ThreePhaseMethod`` (its own rfluxmtx set-up: receivers, senders, up vectors,
  sky receiver) with the same XML.

Mean over the sensors, against ``rtrace`` without super-sampling (``-as 0``,
:func:`radtree.engines.radiance.binaries.monte_carlo_options`): radtree's chain 0.9998, frads
1.007, window turned round 0.992 (8 Dec 2026) — the issue's 3 % is met on this room
(``benchmarks/threephase_reciprocity.py``: ≤ 1.1 % at higher ``-ad``). Needs the
``crosscheck`` extra (frads).

The chain reads the XML's "Transmission Front" (``rmtxop``, ``cm_loadBTDF``); rtrace traces
from the room and reads "Transmission Back" through reciprocity (``src/rt/m_bsdf.c``). Before
the crown XML was made reciprocal patch by patch
(:func:`radtree.engines.radiance.bsdf.reciprocal_patches`) its two blocks were independent
Monte Carlo estimates (10 rays a patch here) and the chain read 0.966 of rtrace (0.970
turned round); the same XML with only its front block: 0.995.

The same room with the window turned round (its material's normal to the sky: the light
enters through the XML's back side, as it leaves a free crown's envelope from the inside):
the chain with :func:`~radtree.engines.radiance.threephase.turned_xml` against rtrace.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.conftest import needs_radiance

WINDOW = np.array([[1.0, 0.0, 0.8], [3.0, 0.0, 0.8], [3.0, 0.0, 2.4], [1.0, 0.0, 2.4]])
SENSORS = [(x, y, 0.8) for x in (1.0, 2.0, 3.0) for y in (1.0, 2.0, 3.0)]
CLAIM = 0.03


def _poly(mod: str, name: str, pts) -> str:
    flat = " ".join(f"{v:g}" for p in pts for v in p)
    return f"{mod} polygon {name}\n0\n0\n{3 * len(pts)} {flat}\n"


def room_text() -> str:
    """Materials and the room without its window (the south wall cut around it), ground."""
    out = ["void plastic floor_m\n0\n0\n5 0.2 0.2 0.2 0 0\n",
           "void plastic wall_m\n0\n0\n5 0.5 0.5 0.5 0 0\n",
           "void plastic ceiling_m\n0\n0\n5 0.7 0.7 0.7 0 0\n",
           "void plastic ground_m\n0\n0\n5 0.2 0.2 0.2 0 0\n",
           _poly("floor_m", "floor", [(0, 0, 0), (0, 4, 0), (4, 4, 0), (4, 0, 0)]),
           _poly("ceiling_m", "ceiling", [(0, 0, 3), (4, 0, 3), (4, 4, 3), (0, 4, 3)]),
           _poly("wall_m", "north", [(0, 4, 0), (0, 4, 3), (4, 4, 3), (4, 4, 0)]),
           _poly("wall_m", "west", [(0, 0, 0), (0, 0, 3), (0, 4, 3), (0, 4, 0)]),
           _poly("wall_m", "east", [(4, 0, 0), (4, 4, 0), (4, 4, 3), (4, 0, 3)])]
    for k, pts in enumerate([[(0, 0, 0), (4, 0, 0), (4, 0, 0.8), (0, 0, 0.8)],
                             [(0, 0, 2.4), (4, 0, 2.4), (4, 0, 3), (0, 0, 3)],
                             [(0, 0, 0.8), (1, 0, 0.8), (1, 0, 2.4), (0, 0, 2.4)],
                             [(3, 0, 0.8), (4, 0, 0.8), (4, 0, 2.4), (3, 0, 2.4)]]):
        out.append(_poly("wall_m", f"south{k}", pts))
    out.append(_poly("ground_m", "ground", [(-100, -100, -0.001), (100, -100, -0.001),
                                            (100, -0.01, -0.001), (-100, -0.01, -0.001)]))
    return "\n".join(out)


def window_tris() -> np.ndarray:
    """The window as two triangles wound so their normal points into the room (+y)."""
    a, b, c, d = WINDOW
    tris = np.array([[a, d, c], [a, c, b]])
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    assert np.all(n[:, 1] > 0)
    return tris


@pytest.fixture(scope="module")
def crown_xml(tmp_path_factory) -> Path:
    from radtree.config import load_project
    from radtree.pipeline.crown_bsdf import scenario_xmls
    from radtree.verify.threephase import write_project

    project = load_project(write_project(tmp_path_factory.mktemp("crown")))
    return Path(scenario_xmls(project, project.scenario("with"))[0][2])


def rtrace_reference(folder: Path, xml: Path, back: bool = False) -> np.ndarray:
    """Work-plane irradiance per unit sky radiance with the BSDF window; ``back``: the
    material's normal to the sky (the XML's back side outside)."""
    from radtree.engines.radiance.binaries import FIXED_SEED, monte_carlo_options, run

    tris = window_tris()[:, ::-1] if back else window_tris()
    win = (f"void BSDF crown_m\n6 0 {xml} 0 0 1 .\n0\n0\n"
           + "".join(_poly("crown_m", f"win{k}", t) for k, t in enumerate(tris)))
    sky = ("void glow sky_m\n0\n0\n4 1 1 1 0\n\nsky_m source sky\n0\n0\n4 0 0 1 180\n")
    (folder / "ref.rad").write_text(room_text() + "\n" + win + "\n" + sky)
    oct_ = folder / "ref.oct"
    run(["oconv", str(folder / "ref.rad")], stdout_path=oct_)
    pts = "".join(f"{x} {y} {z} 0 0 1\n" for x, y, z in SENSORS)
    out = run(["rtrace", "-h", "-I", FIXED_SEED, *monte_carlo_options(6, 4096, 1e-4), str(oct_)],
              stdin=pts.encode())
    rgb = np.array(out.decode().split(), float).reshape(-1, 3)
    return rgb.mean(axis=1)


def radtree_chain(folder: Path, xml: Path, turned: bool = False) -> np.ndarray:
    from radtree.engines.radiance import threephase as rad3
    from radtree.engines.radiance.binaries import FIXED_SEED

    tris, normal = window_tris(), np.array([0.0, 1.0, 0.0])
    oct_ = rad3.octree(folder, "room", room_text())
    pts = "".join(f"{x} {y} {z} 0 0 1\n" for x, y, z in SENSORS)
    receivers = (rad3.group_receivers_text([(tris, normal)]) + "\n"
                 + rad3.sky_receivers_text(1))
    v = rad3.view_matrix(folder, oct_, pts, len(SENSORS), receivers,
                         [FIXED_SEED, "-ab", "6", "-ad", "4096", "-lw", "1e-4", "-aa", "0"], 1)
    vf = rad3.write_matrix(folder / "v.vmx", v[:, :145])
    d = rad3.daylight_matrix(folder, oct_, "w", rad3.sender_text(tris, normal), 1, 1000,
                             [FIXED_SEED, "-ab", "2", "-ad", "2", "-aa", "0"], 1)
    t = rad3.turned_xml(xml, folder / "turned.xml") if turned else xml
    dc = rad3.multiply(vf, t, d) + v[:, 145:]
    return dc[:, 1:, :].sum(axis=1).mean(axis=1)


def frads_chain(folder: Path, xml: Path) -> np.ndarray:
    from frads.matrix import load_matrix
    from frads.methods import ThreePhaseMethod, WorkflowConfig

    room = folder / "frads_room.rad"
    room.write_text(room_text())
    window = "".join(_poly("crown_m", f"win{k}", t) for k, t in enumerate(window_tris()))
    cfg = WorkflowConfig.from_dict({
        "settings": {"method": "3phase", "sky_basis": "r1", "save_matrices": False,
                     "num_processors": 1, "output_directory": str(folder),
                     "sensor_window_matrix": ["-ab", "6", "-ad", "4096", "-lw", "1e-4",
                                              "-aa", "0"],
                     "daylight_matrix": ["-ab", "2", "-c", "1000"]},
        "model": {"scene": {"files": [room]},
                  "materials": {"bytes": b"void plastic crown_m\n0\n0\n5 0 0 0 0 0\n",
                                "matrices": {"crown": {"matrix_file": str(xml)}}},
                  "windows": {"w": {"bytes": window.encode(), "matrix_name": "crown"}},
                  "sensors": {"s": {"data": [[x, y, z, 0, 0, 1] for x, y, z in SENSORS]}}}})
    with ThreePhaseMethod(cfg) as m:
        m.generate_matrices(view_matrices=False)
        v = np.asarray(m.sensor_window_matrices["s"].array[0])    # (sensors, 145, 3)
        d = np.asarray(m.daylight_matrices["w"].array)              # (145, 146, 3)
        t = np.asarray(load_matrix(xml))                            # (145, 145, 3)
    total = np.zeros(len(SENSORS))
    for ch in range(3):
        total += v[:, :, ch] @ t[:, :, ch] @ d[:, 1:, ch].sum(axis=1)
    return total / 3.0


@needs_radiance
def test_three_phase_chain_agrees_with_frads_and_rtrace(crown_xml, tmp_path):
    pytest.importorskip("frads")
    ref = rtrace_reference(tmp_path, crown_xml)
    ours = radtree_chain(tmp_path, crown_xml)
    theirs = frads_chain(tmp_path, crown_xml)
    assert ref.min() > 0
    r_ours, r_frads = ours.mean() / ref.mean(), theirs.mean() / ref.mean()
    print(f"room with a crown-BSDF window, uniform sky, mean of 9 sensors: rtrace "
          f"{ref.mean():.5f}, radtree chain {ours.mean():.5f} ({r_ours:.4f}), frads "
          f"{theirs.mean():.5f} ({r_frads:.4f})")
    assert r_ours == pytest.approx(1.0, abs=CLAIM)
    assert r_frads == pytest.approx(1.0, abs=CLAIM)
    assert ours.mean() / theirs.mean() == pytest.approx(1.0, abs=CLAIM)


@needs_radiance
def test_turned_xml_carries_light_entering_the_back_side(crown_xml, tmp_path):
    ref = rtrace_reference(tmp_path, crown_xml, back=True)
    turned = radtree_chain(tmp_path, crown_xml, turned=True)
    ratio = turned.mean() / ref.mean()
    print(f"window turned round: rtrace {ref.mean():.5f}, chain with the turned XML "
          f"{turned.mean():.5f} ({ratio:.4f})")
    assert ratio == pytest.approx(1.0, abs=CLAIM)
