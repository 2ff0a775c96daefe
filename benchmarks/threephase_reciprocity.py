"""The three-phase chain against a direct rtrace on the frads room of
``tests/test_frads_crosscheck.py``, with the crown XML as radtree writes it (reciprocal patch
by patch, :func:`radtree.engines.radiance.bsdf.reciprocal_patches`) and as it was before
(the two rfluxmtx passes' blocks left apart, only the ring exchanges reciprocal).

Why it matters: rmtxop (the chain) reads the XML's "Transmission Front" as it stands
(Radiance ``src/util/cmbsdf.c``, ``cm_loadBTDF``); rtrace's ``BSDF`` material traces from the
room and looks the pair up in the block of the side the ray arrives from — "Transmission
Back" for the window of the frads room — assuming reciprocity (``src/rt/m_bsdf.c``,
``sample_sdf``; ``src/common/bsdf_m.c`` maps WINDOW's front to Radiance's back). Each
variant prints rtrace (``-as 0``, :func:`radtree.engines.radiance.binaries.
monte_carlo_options`, ``-ab 6 -lw 1e-4``, at two ``-ad``), the chain and the ratio, mean of
the 9 sensors, window as in the test (material normal into the room) and turned round.

Measured 8 Dec 2026, load 1.2–1.3 on 2 cores (``python benchmarks/threephase_reciprocity.py``,
17 s; chain/rtrace at ``-ad 4096`` / ``-ad 65536``, the range of the 9 sensors at 65536)::

    reciprocal (now)          as in the test  0.9998 / 1.0076 (a sensor 0.957–1.083)
    reciprocal (now)          turned round    0.9924 / 0.9890 (a sensor 0.946–1.055)
    before                    as in the test  0.9663 / 0.9757 (a sensor 0.893–1.092)
    before                    turned round    0.9702 / 0.9654 (a sensor 0.880–1.125)
    before, front block only  as in the test  0.9950 / 0.9885 (a sensor 0.947–1.073)
    before, front block only  turned round    0.9965 / 0.9890 (a sensor 0.946–1.113)

rtrace with ``-u+ -ad 16384``, 6 runs, of the reciprocal XML: 0.14067 ± 0.00035 (s.e.) and
0.17644 ± 0.00033 turned round: chain/rtrace 0.991 and 0.998. ``-ad`` above 65536 gives the
same numbers as 65536.
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests import test_frads_crosscheck as room  # noqa: E402


def old_xml(folder: Path, dest: Path) -> Path:
    """The XML of ``folder`` (a chord-envelope sample: ``ring<k>/*.dat`` raw rfluxmtx flux)
    assembled as before: ring exchanges reciprocal, patches not (wrapBSDF of the result)."""
    from radtree.engines.radiance.bsdf import KEYS, klems_patch_rings, reciprocal_rings, wrap_klems

    ring, _ = klems_patch_rings()
    flux = {key: np.zeros((145, 145)) for key in KEYS}
    for k in range(9):
        for key in KEYS:
            flux[key][:, ring == k] = np.loadtxt(folder / f"ring{k}" / f"{key}.dat")[:, ring == k]
    dest.mkdir(parents=True, exist_ok=True)
    for key, m in reciprocal_rings(flux).items():
        np.savetxt(dest / f"{key}.dat", m, fmt="%.7e", delimiter="\t")
    return wrap_klems(dest, "old", 0.1, 1.0, 1.0)


def front_only(xml: Path, dest: Path) -> Path:
    """``xml`` without its "Transmission Back" block: rtrace then applies reciprocity to the
    front block, the one the chain reads."""
    text = xml.read_text()
    for block in re.findall(r"<WavelengthData>.*?</WavelengthData>", text, flags=re.S):
        if re.search(r"<WavelengthDataDirection>\s*Transmission Back", block):
            text = text.replace(block, "")
    dest.write_text(text)
    return dest


def rtrace(folder: Path, xml: Path, back: bool, ad: int) -> np.ndarray:
    from radtree.engines.radiance.binaries import FIXED_SEED, monte_carlo_options, run

    room.rtrace_reference(folder, xml, back=back)           # writes ref.oct
    pts = "".join(f"{x} {y} {z} 0 0 1\n" for x, y, z in room.SENSORS)
    out = run(["rtrace", "-h", "-I", FIXED_SEED, *monte_carlo_options(6, ad, 1e-4),
               str(folder / "ref.oct")], stdin=pts.encode())
    return np.array(out.decode().split(), float).reshape(-1, 3).mean(axis=1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ad", type=int, default=65536, help="rtrace -ad of the second reference")
    args = ap.parse_args()
    from radtree.config import load_project
    from radtree.pipeline.crown_bsdf import scenario_xmls
    from radtree.verify.threephase import write_project

    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        (work / "crown").mkdir()
        project = load_project(write_project(work / "crown"))
        xml = Path(scenario_xmls(project, project.scenario("with"))[0][2])
        variants = {"reciprocal (now)": xml,
                    "before": old_xml(xml.parent, work / "old"),
                    "before, front block only": front_only(work / "old" / "old.xml",
                                                           work / "front.xml")}
        for label, x in variants.items():
            for back in (False, True):
                sub = work / f"{label[:6].strip()}_{back}_{len(label)}"
                sub.mkdir()
                r1, r2 = rtrace(sub, x, back, 4096), rtrace(sub, x, back, args.ad)
                per = room.radtree_chain(sub, x, turned=back)
                chain, lo, hi = float(per.mean()), min(per / r2), max(per / r2)
                side = "turned round" if back else "as in the test"
                print(f"{label:26s} {side:15s} rtrace -ad 4096 {r1.mean():.5f}, -ad {args.ad} "
                      f"{r2.mean():.5f}; chain {chain:.5f}: {chain / r1.mean():.4f} / "
                      f"{chain / r2.mean():.4f} (a sensor {lo:.3f}–{hi:.3f})", flush=True)


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).parent))
    from _common import print_resources_at_exit

    print_resources_at_exit()
    main()
