"""A crown BSDF as a "tree screen": the XML of `radtree bsdf` in a plain window's Radiance
``BSDF`` material (written with honeybee-radiance's BSDF modifier), in a box room.

    PYTHONPATH=. python examples/tree-screen/run.py [--xml leaf_on.xml] [--samples 200]

Without ``--xml`` it computes the leaf-on and leaf-off BSDFs of the Mendoza sensor dome's slat
stack (scenario B) with ``--samples`` rays per Klems patch (cached in ``out/``). The room:
4 m wide, 6 m deep (y from −6 to 0), 3 m high, its north wall at y = 0 a 3.6 × 2.6 m
window looking north (towards the sun in Mendoza); work plane 0.8 m,
1 m grid. Sky: ``gensky`` clear sky with sun for Mendoza, 22 December 12:30. Prints the
work-plane mean with clear glazing (τ 0.8, honeybee ``Glass``) and with the window carrying
the crown BSDF, leaf-on and leaf-off. The window polygon's normal points into the room:
the XML's back side (its front, the crown's outside, faces the street), up = +z.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
from pathlib import Path

import numpy as np
from honeybee_radiance.geometry import Polygon
from honeybee_radiance.modifier.material import BSDF, Glass, Plastic

import radtree.log
from radtree.bsdf.run import compute_crown_bsdfs
from radtree.config import load_project
from radtree.engines.radiance.binaries import require_radiance
from radtree.light.units import PHOTOPIC_RGB, WHITE_EFFICACY

HERE = Path(__file__).resolve().parent
ROOM_W, ROOM_D, ROOM_H = 4.0, 6.0, 3.0


def room_text(window) -> str:
    """The box room (walls ρ 0.5, floor 0.2, ceiling 0.7) with ``window`` in its north wall."""
    wall, floor, ceil = (Plastic.from_single_reflectance(n, r) for n, r in
                         (("wall", 0.5), ("floor", 0.2), ("ceiling", 0.7)))
    w, d, h = ROOM_W, ROOM_D, ROOM_H
    x0, x1, z0, z1 = 0.2, w - 0.2, 0.2, h - 0.2
    quads = {  # each polygon's normal points into the room
        "floor": (floor, [(0, 0, 0), (w, 0, 0), (w, d, 0), (0, d, 0)]),
        "ceiling": (ceil, [(0, 0, h), (0, d, h), (w, d, h), (w, 0, h)]),
        "south": (wall, [(0, d, 0), (w, d, 0), (w, d, h), (0, d, h)]),
        "east": (wall, [(w, 0, 0), (w, 0, h), (w, d, h), (w, d, 0)]),
        "west": (wall, [(0, 0, 0), (0, d, 0), (0, d, h), (0, 0, h)]),
        "north_below": (wall, [(0, 0, 0), (0, 0, z0), (w, 0, z0), (w, 0, 0)]),
        "north_above": (wall, [(0, 0, z1), (0, 0, h), (w, 0, h), (w, 0, z1)]),
        "north_left": (wall, [(0, 0, z0), (0, 0, z1), (x0, 0, z1), (x0, 0, z0)]),
        "north_right": (wall, [(x1, 0, z0), (x1, 0, z1), (w, 0, z1), (w, 0, z0)]),
        "window": (window, [(x0, 0, z0), (x0, 0, z1), (x1, 0, z1), (x1, 0, z0)]),
    }
    mods = {m.identifier: m for m, _ in quads.values()}
    out = [m.to_radiance() for m in mods.values()]
    # built with the window wall at y = 0 and the room at y > 0, then mirrored (y → −y, the
    # vertex order reversed to keep the normals inside): the window looks north, to the sun
    out += [Polygon(name, [(x, -y, z) for x, y, z in verts[::-1]], mod).to_radiance()
            for name, (mod, verts) in quads.items()]
    return "\n".join(out) + "\n"


def sky_text() -> str:
    """gensky: Mendoza (−32.89°, 68.83° W, meridian 45° W), 22 December 12:30, clear with sun."""
    out = subprocess.run(["gensky", "12", "22", "12.5", "+s", "-a", "-32.89", "-o", "68.83",
                          "-m", "45"], capture_output=True, text=True, check=True,
                         env=require_radiance().env()).stdout
    return out + ("skyfunc glow sky_glow\n0\n0\n4 1 1 1 0\nsky_glow source sky\n0\n0\n"
                  "4 0 0 1 180\nskyfunc glow ground_glow\n0\n0\n4 1 1 1 0\n"
                  "ground_glow source ground\n0\n0\n4 0 0 -1 180\n")


def workplane() -> bytes:
    xs = np.arange(0.5, ROOM_W, 1.0)
    ys = np.arange(0.5, ROOM_D, 1.0)
    return "".join(f"{x} {-y} 0.8 0 0 1\n" for y in ys for x in xs).encode()


def trace(folder: Path, name: str, window) -> float:
    """Mean work-plane illuminance (lux) with ``window`` (rtrace -I -ab 4 -ad 512)."""
    env = require_radiance().env()
    (folder / f"{name}.rad").write_text(room_text(window) + sky_text())
    with open(folder / f"{name}.oct", "wb") as oct_file:
        subprocess.run(["oconv", f"{name}.rad"], cwd=folder, stdout=oct_file, check=True,
                       env=env)
    res = subprocess.run(["rtrace", "-h", "-I", "-ab", "4", "-ad", "512", "-lw", "1e-3",
                          f"{name}.oct"], cwd=folder, input=workplane(), capture_output=True,
                         check=True, env=env)
    rgb = np.array(res.stdout.split(), float).reshape(-1, 3)
    return float((WHITE_EFFICACY * rgb @ np.array(PHOTOPIC_RGB)).mean())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--xml", type=Path, nargs="*", help="crown BSDF XML file(s) to use")
    ap.add_argument("--samples", type=int, default=200, help="rays per Klems patch")
    args = ap.parse_args()
    out = HERE / "out"
    out.mkdir(exist_ok=True)
    xmls = list(args.xml or [])
    if not xmls:
        proj = load_project(HERE.parent / "mendoza-street",
                            overrides={"tree.bsdf.samples": args.samples})
        radtree.log.enable(progress=False)   # the rfluxmtx commands as they run
        result = compute_crown_bsdfs(proj, proj.scenario("B"), out / "bsdf")
        xmls = [r.xml for r in result.runs.values()]
    clear = trace(out, "clear", Glass.from_single_transmittance("clear_glass", 0.8))
    print(f"clear glazing (τ 0.8):          work plane mean {clear:8.1f} lx")
    for xml in xmls:
        local = out / Path(xml).name
        if Path(xml).resolve() != local.resolve():
            shutil.copyfile(xml, local)
        screen = BSDF(str(local), identifier=f"tree_screen_{local.stem}",
                      up_orientation=(0.0, 0.0, 1.0))
        lux = trace(out, local.stem, screen)
        print(f"tree screen {local.name:18s} work plane mean {lux:8.1f} lx "
              f"({100 * lux / clear:.1f} % of clear glazing)")


if __name__ == "__main__":
    main()
