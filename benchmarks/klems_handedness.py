"""Klems frames of the three-phase chain against rtrace: one 1 × 1 m window (normal down, into
the room below, ``BSDF`` up +Y) in a black ceiling, a glow patch 45° up on the −X side, two
irradiance sensors 1 m below the window and 1 m to either side (x = −1, +1).

The XML passes light only when both its incident and its outgoing Klems patch have local
x > 0 (azimuth within ±80°), 1/π sr⁻¹, in both transmission blocks (unchanged by reciprocity).
rtrace applies it to the window; the chain is ``rmtxop V T D`` with the radtree/tutorial
convention (receiver ``h=kf``, sender ``h=-kf``, both ``u=+Y``) and, for comparison, with the
sender ``h=kf``, and with the receiver ``h=-kf``. Prints the two sensors' irradiance per unit
radiance for each.

Run: ``nice .venv/bin/python benchmarks/klems_handedness.py --xml KLEMS.xml [--work DIR]``.

Measured 8 December 2026 04:29 UTC (load ≈ 3, 2 cores): rtrace 0.0000 / 0.0161 (``-u+``:
0.0168, 0.0173), chain (receiver ``h=kf``) sender ``h=-kf`` 0.0171 / 0.0000, sender ``h=kf``
0 / 0; receiver and sender ``h=-kf`` 0.0000 / 0.0171, rtrace's. rtrace lights the
sensor on the far side (light keeps its horizontal direction: Radiance indexes incident and
outgoing patches in one frame, ``bsdf_m.c``), the chain the near one: ``h=-kf`` and ``h=kf``
take opposite x axes (``rfluxmtx.c`` ``prepare_sampler``, ``klems_full.cal`` ``kbin``), so
V·T·D mirrors the transmitted light left/right about the up vector (see
``benchmarks/threephase_closure.py``'s docstring). Fixed for free crowns (their outward
sender ``h=+kf``, :func:`radtree.engines.radiance.threephase.sender_text`); the dome keeps the
tutorial convention.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radtree.bsdf.klems import DIRECTIONS, read_klems  # noqa: E402
from radtree.engines.radiance.binaries import find_radiance  # noqa: E402

WINDOW = "-.5 -.5 1  -.5 .5 1  .5 .5 1  .5 -.5 1"
GLOW = "sg polygon s1 0 0 12  -3.6 2 7.4   -3.6 -2 7.4   -6.4 -2 4.6   -6.4 2 4.6\n"
CEILING = "void plastic blk 0 0 5 0 0 0 0 0\n" + "".join(
    f"blk polygon c{k} 0 0 12 {v}\n" for k, v in enumerate([
        "-50 -50 1.001  -50 50 1.001  -.5 50 1.001  -.5 -50 1.001",
        ".5 -50 1.001  .5 50 1.001  50 50 1.001  50 -50 1.001",
        "-.5 .5 1.001  -.5 50 1.001  .5 50 1.001  .5 .5 1.001",
        "-.5 -50 1.001  -.5 -.5 1.001  .5 -.5 1.001  .5 -50 1.001"]))
POINTS = "-1 0 0 0 0 1\n1 0 0 0 0 1\n"


def write_xml(template: Path, dest: Path) -> None:
    """The template's Klems basis with every block replaced by the x > 0 pass-through."""
    k = read_klems(template)
    n = len(k.lambdas)
    counts = np.unique(k.theta_deg, return_counts=True)[1]
    phi = np.concatenate([np.arange(c) * 360.0 / c for c in counts])
    xpos = ((phi < 80) | (phi > 280)) & (np.arange(n) > 0)
    t = np.where(xpos[:, None] & xpos[None, :], 1 / np.pi, 0.0)
    body = "\n".join(" ".join(f"{v:.6g}" for v in row) for row in t)

    def block(m: re.Match[str]) -> str:
        key = DIRECTIONS[re.search(r"<WavelengthDataDirection>\s*(.*?)\s*<", m.group(0))
                         .group(1)]
        data = body if key in ("tf", "tb") else " ".join(["0"] * (n * n))
        return re.sub(r"<ScatteringData>.*?</ScatteringData>",
                      lambda _: f"<ScatteringData>\n{data}\n</ScatteringData>", m.group(0),
                      flags=re.S)

    dest.write_text(re.sub(r"<WavelengthDataBlock>.*?</WavelengthDataBlock>", block,
                           template.read_text(), flags=re.S))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", type=Path, default=Path("/tmp/klems_handedness"))
    ap.add_argument("--xml", type=Path, required=True,
                    help="any Klems-full XML (e.g. a crown BSDF of radtree bsdf): its basis "
                         "and header are kept, its data replaced")
    args = ap.parse_args()
    inst = find_radiance()
    if inst is None:
        sys.exit("no Radiance")
    env = inst.env()
    w = args.work
    w.mkdir(parents=True, exist_ok=True)
    write_xml(args.xml, w / "tio.xml")
    files = {
        "src.rad": "void glow sg 0 0 4 1 1 1 0\n" + GLOW,
        "ceil.rad": CEILING,
        "win.rad": f"void BSDF wmat 6 0 tio.xml 0 1 0 . 0 0\nwmat polygon win 0 0 12 {WINDOW}\n",
        "recv.rad": f"#@rfluxmtx h=kf u=+Y\nvoid glow wg 0 0 4 1 1 1 0\n"
                    f"wg polygon win 0 0 12 {WINDOW}\n",
        "sky.rad": "#@rfluxmtx h=u u=+Y\nvoid glow sg 0 0 4 1 1 1 0\n" + GLOW,
    }
    for sign in ("-", "+"):
        files[f"send{sign}.rad"] = f"#@rfluxmtx h={sign}kf u=+Y\nvoid polygon win 0 0 12 {WINDOW}\n"
    for name, text in files.items():
        (w / name).write_text(text)

    def sh(cmd: str, stdin: str | None = None) -> str:
        return subprocess.run(cmd, shell=True, cwd=w, env=env, input=stdin, text=True,
                              capture_output=True, check=True).stdout

    sh("oconv src.rad ceil.rad win.rad > ref.oct; oconv ceil.rad > e.oct")
    for u in ("-u-", "-u+"):
        out = sh(f"rtrace -I -h -ab 2 -ad 40000 -lw 1e-7 -aa 0 {u} ref.oct", POINTS)
        print(f"rtrace {u}: " + " / ".join(f"{float(r.split()[0]):.4f}"
                                           for r in out.splitlines()))
    (w / "recv-.rad").write_text(files["recv.rad"].replace("h=kf", "h=-kf"))
    for rs in ("", "-"):
        sh(f"rfluxmtx -I+ -y 2 -ab 1 -ad 40000 -lw 1e-7 -aa 0 -faf - recv{rs}.rad -i e.oct "
           f"> V{rs}.mtx", POINTS)
    for rs, sign in (("", "-"), ("", "+"), ("-", "-")):
        sh(f"rfluxmtx -c 4000 -ff -ab 0 send{sign}.rad sky.rad -i e.oct > D{sign}.mtx")
        out = sh(f"rmtxop -fa V{rs}.mtx tio.xml D{sign}.mtx").strip().splitlines()[-2:]
        print(f"chain, receiver h={rs or '+'}kf, sender h={sign}kf: "
              + " / ".join(f"{float(r.split()[0]):.4f}" for r in out))


if __name__ == "__main__":
    main()
