"""Where the five-phase sun loses the surroundings' reflected sun (issue 40 item 2): the paths
of the reflected sun through the office example's leaf-on crown, BSDF shell against the explicit
slats.

Reuses the project copy of ``benchmarks/threephase.py`` (``--work DIR``: ``DIR/3phase``, its
crown XMLs cached there; ``--samples`` must be that run's, else the XMLs are recomputed) and
traces with ``rtrace -I`` (``-ab 6``, no ambient cache, ``-u+``; each figure the mean of
``--repeats`` runs, ± its standard error) on the leaf-on scenes: the BSDF-crown scene (the
aBSDF shell, as the ``fivephase`` sun runs) and the explicit crown (the slats, as the default
method), their materials varied:

1. **Reflected sun by surface** — one unit sun at Reinhart patch (alt 54°, az 0°: the patch
   with the largest leaf-on reflected sun on both grids), the surroundings black but one
   surface (or all): the reflected part (minus the all-black run) on the façade grid;
2. **(a) sun → crown → ground** — the ground irradiance of that sun, surroundings black, on a
   1 m grid of the street (under/behind the crowns, y < 8 m; beyond, y ≥ 8 m);
3. **(b) ground → crown → façade** — the ground a uniform glow (radiance 1), all else black:
   façade sum, for the whole street and its two strips;
4. **(c) light sent back by the crown** — in (1): the façade paint the only reflector;
5. **direction** — a 20° glow cone in the north at elevation e (no ground, all else black):
   façade sum, below (e < 0, the street's light) and above the horizon;
6. **position** — the same cones at points inside the central crown (x 0.4, y 3 m) at
   heights 4–11.5 m (its base 3 m, centre 7.75 m, top 12.5 m), facing the cone.

Measured 2026-12-07 (``--work`` a copy of the 16:58 run's ``3phase`` folder, ``--samples
50``, ``--repeats 2``; steps 1–5 22:23–22:31 UTC at load 2.8–3.1, steps 6–8 with ``--only 6,7``
22:34–22:36 at load 1.4–2.5; 2 cores):

* The 0.71 of issue 40 is both grids together: summed over sensors and the 80 patch suns of the
  cached runs the façade reads 0.68, the work plane 0.94 (the façade's reflected sun is 7 × the
  work plane's).
* step 1: façade, unit sun at patch alt 54° az 0°, reflected by all surroundings: BSDF 1.80e-5,
  explicit 2.67e-5 — **0.673**; by the ground alone 1.39e-5 / 2.21e-5 — **0.627** (± 2 %);
  step 4 (c): by the façade paint alone 1.08e-6 / 1.04e-6 (1.04 ± 0.14; 1.43 in a first scratch
  run) — the ground holds the deficit.
* step 2: (a) the sun on the street through the crown: y < 8 m **0.996**, y ≥ 8 m (in the opposite
  building's shadow) 0.925 — the sun reaches the ground right.
* step 3: (b) glowing street → façade: **0.613** (y < 8 m 0.610, beyond 0.598).
* step 5: cones below the horizon e −50, −30, −15°: 0.649, 0.585, 0.490; above, e +45°: 0.925
  (scratch, same settings: −70° 0.52, +20° 0.85; the whole upper hemisphere 1.45, the lower
  0.61).
* step 6: inside the crown, from below (e −50°): 0.143, 1.11, 1.57 at z 4, 7.75, 11.5 m; from
  above (e +50°): 2.37, 1.45, 0.265. The explicit crown's field varies 16–17 × from base to
  top, the shell's within 2 ×.
* step 7: facets: every band's upper facet and its mirrored lower twin within 2.5 % (e.g. b1
  0.0400 / 0.0409, 0.1635 / 0.1634); step 8, the wall cap, up +z: from +60, +20, −20, −60°:
  τ 0.115, 0.227, 0.521, 0.841 — dark towards the crown's top, as its depth table says (up
  −z mirrors it; in the whole scene, scratch, that reads 4.8 × above, 0.48 × below).
* Straight-line depth (scratch, ``radtree.pipeline.wall_cap`` functions): from the façade
  sensors through the cap and the far facet the shell's depth is within 0.35 m of the
  envelope's for −50…+70° (−30°: 3.44 vs 3.66 m); at −70° 3.4 vs 1.6 m (the cap's one-slat
  floor).

Cause: the representation's limit, not a defect. A BSDF shell holds the crown's depth at its
surface, so the light inside it does not depend on where the receiver sits; the office's
window (3.75–6.25 m) lies in the lower third of a crown that reaches the wall (base 3 m,
centre 7.75 m). Light from the sunlit street enters through the crown's base 1–2 m below the
window and in the real crown reaches it through little foliage; in the shell it first crosses
the base facet's whole half chord (R cos θ). The cap's per-patch depth makes straight lines
from one point right, not light scattered inside the crown.

Work plane (scratch scripts: the 16:58 run's cached sun coefficients replayed hour by hour
with the dc sky and the leaf dates): five-phase − explicit UDI <100
+4.5, 100–300 −4.7 pp; the explicit reflected sun × the BSDF's per-patch ratio (0.72–1.09)
alone +2.5 / −2.0; two more realisations of (1) and (2) (``rcontrib`` replicates, same
settings) +3.3 / −3.1 and +4.9 / −4.7, the three's mean +4.3 / −3.9 against the one explicit
realisation. Per sensor and patch one realisation's s.d. is 64 % of the mean explicit value
(two explicit runs differ by ± 34 % per point, 3.5 pp of UDI < 100:
``benchmarks/threephase.py``), so at the sun runs'
``-ad 512`` the work plane's 3 pp is not resolved by one explicit run.

Run: ``nice -n 10 .venv/bin/python benchmarks/fivephase_paths.py --work /tmp/threephase_bench``
(≈ 10 min at load 3).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radtree.annual.coefficients import scene_text  # noqa: E402
from radtree.annual.run import AnnualOptions, plan_annual, with_season  # noqa: E402
from radtree.annual.threephase import _scene_with, crown_models, state_xmls  # noqa: E402
from radtree.config import load_project  # noqa: E402
from radtree.engines.radiance.binaries import find_radiance  # noqa: E402
from radtree.optics import Plastic, with_reflectance  # noqa: E402
from radtree.scene import Scene  # noqa: E402

LUM = np.array([0.265, 0.67, 0.065])
SUN_SR = 2 * math.pi * (1 - math.cos(math.radians(0.533 / 2)))
PATCH_SUN = (0.0, 0.587785, 0.809017)   # Reinhart MF 1 patch at alt 54°, az 0°


def scenes(work: Path, samples: int) -> tuple[Scene, Scene, float, set[str]]:
    """(BSDF-crown scene, explicit scene, ground reflectance, names of the surroundings'
    materials) of the leaf-on state."""
    from radtree.pipeline.assemble import make_scene

    project = load_project(work / "3phase", overrides={"tree.bsdf.samples": samples})
    plan = plan_annual(project, with_season(project, AnnualOptions(method="3phase")),
                       crown_notes=False)
    models, _ = crown_models(project, plan.with_sc, state_xmls(project, plan.with_sc))
    bare = make_scene(project, replace(plan.with_sc, model="none"), dense_grid=False).scene
    return (_scene_with(bare, models["leaf_on"]), plan.scenes["leaf_on"], plan.rho,
            set(bare.materials))


def variant(scene: Scene, bare_names: set[str], keep: set[str] | None, rho: float) -> Scene:
    """``scene`` with the ground's reflectance ``rho`` and the surroundings' plastics
    (``bare_names``) black but ``keep`` (None: all kept)."""
    mats = dict(scene.materials)
    g = scene.ground_material
    if isinstance(mats.get(g), Plastic):
        mats[g] = with_reflectance(mats[g], rho)
    for name in bare_names:
        m = mats.get(name)
        if isinstance(m, Plastic) and keep is not None and name not in keep:
            mats[name] = Plastic(name, 0.0)
    return replace(scene, materials=mats)


class Tracer:
    """Writes scene variants and extra sources to a folder and runs ``rtrace -I``. The
    repeats are separate processes (``-u+``); two runs started within the same second were
    seen to give the same values, so :meth:`Paths.inside` traces six copies of each point and
    takes its standard error over them."""

    def __init__(self, folder: Path, rho: float, repeats: int):
        self.folder, self.rho, self.repeats = folder, rho, repeats
        self.env = {**os.environ, **find_radiance().env()}
        self.n = 0

    def octree(self, text: str, extra: str = "", no_ground: bool = False) -> Path:
        if no_ground:
            text = re.sub(r"\n# ground:.*?(?=\n# )", "\n", text, count=1, flags=re.S)
        self.n += 1
        rad, oct_ = self.folder / f"s{self.n}.rad", self.folder / f"s{self.n}.oct"
        rad.write_text(text + "\n" + extra)
        with open(oct_, "wb") as fh:
            subprocess.run(["oconv", str(rad)], stdout=fh, check=True, env=self.env)
        return oct_

    def trace(self, octree: Path, pts: str, ab: int = 6, ad: int = 1024) -> np.ndarray:
        """(repeats, points) irradiance (photopic, W/m² per unit source radiance)."""
        cmd = ["rtrace", "-h", "-I+", "-ab", str(ab), "-ad", str(ad), "-as", "0", "-aa", "0",
               "-lw", "1e-4", "-dj", "0", "-dc", "1", "-dt", "0", "-u+", str(octree)]
        out = [subprocess.run(cmd, input=pts.encode(), capture_output=True, check=True,
                              env=self.env).stdout for _ in range(self.repeats)]
        return np.array([np.array(o.split(), float).reshape(-1, 3) @ LUM for o in out])


def sun_text(d: tuple[float, float, float], radiance: float = 1e6) -> str:
    return (f"void light sun\n0\n0\n3 {radiance:g} {radiance:g} {radiance:g}\n\n"
            f"sun source sun_src\n0\n0\n4 {d[0]:.6f} {d[1]:.6f} {d[2]:.6f} 0.533\n")


def cone_text(el_deg: float, angle: float = 20.0) -> str:
    e = math.radians(el_deg)
    return (f"void glow cone\n0\n0\n4 1 1 1 0\n\ncone source cone_src\n0\n0\n"
            f"4 0 {math.cos(e):.6f} {math.sin(e):.6f} {angle:g}\n")


def glow_zone(x0: float, x1: float, y0: float, y1: float) -> str:
    """An upward-facing glowing rectangle 2 mm above the ground (radiance 1)."""
    return (f"void glow zone\n0\n0\n4 1 1 1 0\n\nzone polygon zone_p\n0\n0\n12 {x0} {y0} 0.002 "
            f"{x1} {y0} 0.002 {x1} {y1} 0.002 {x0} {y1} 0.002\n")


def ratio_line(label: str, b: np.ndarray, x: np.ndarray) -> str:
    se = lambda a: a.std(ddof=1) / math.sqrt(len(a)) if len(a) > 1 else float("nan")  # noqa: E731
    return (f"  {label:44s} BSDF {b.mean():.4g} ± {se(b):.2g}  explicit {x.mean():.4g} ± "
            f"{se(x):.2g}  ratio {b.mean() / x.mean():.3f}")


class Paths:
    """The measurements of the module text on one pair of scenes."""

    def __init__(self, bsdf: Scene, explicit: Scene, rho: float, names: set[str],
                 tracer: Tracer):
        self.crowns = {"bsdf": bsdf, "explicit": explicit}
        self.rho, self.names, self.t = rho, names, tracer
        self.facade = bsdf.grids["facade"].to_pts()

    def text(self, crown: str, keep: set[str] | None) -> str:
        return scene_text(variant(self.crowns[crown], self.names, keep, self.rho), None)

    def pair(self, keep: set[str] | None, extra: str, pts: str, *, no_ground: bool = False,
             ab: int = 6, ad: int = 1024, total: bool = True) -> dict[str, np.ndarray]:
        """{crown: (repeats,) sums over ``pts`` (or (repeats, points) with total False)}."""
        out = {}
        for crown in self.crowns:
            v = self.t.trace(self.t.octree(self.text(crown, keep), extra, no_ground), pts,
                             ab=ab, ad=ad)
            out[crown] = v.sum(axis=1) if total else v
        return out

    def by_surface(self) -> None:
        sun = sun_text(PATCH_SUN)
        print("1. façade sum, unit sun at patch alt 54° az 0° (÷ 1e6): reflected by")
        black = self.pair(set(), sun, self.facade)
        for label, keep in (("all surroundings", None), ("the ground only", {"ground"}),
                            ("the façade paint only (c)", {"facade_paint"})):
            v = self.pair(keep, sun, self.facade)
            print(ratio_line(label, (v["bsdf"] - black["bsdf"].mean()) / 1e6,
                             (v["explicit"] - black["explicit"].mean()) / 1e6))

    def ground_sun(self) -> None:
        xs, ys = np.arange(-12.0, 12.1, 1.0), np.arange(0.5, 20.0, 1.0)
        g = np.array([(x, y) for y in ys for x in xs])
        pts = "".join(f"{x} {y} 0.001 0 0 1\n" for x, y in g)
        v = self.pair(set(), sun_text(PATCH_SUN), pts, ab=4, ad=256, total=False)
        free = 1e6 * SUN_SR * PATCH_SUN[2]
        print(f"2. (a) ground irradiance of that sun, surroundings black (÷ open sun {free:.4g})")
        for label, m in (("y < 8 m (under/behind the crowns)", g[:, 1] < 8),
                         ("y >= 8 m", g[:, 1] >= 8)):
            print(ratio_line(label, v["bsdf"][:, m].mean(axis=1) / free,
                             v["explicit"][:, m].mean(axis=1) / free))

    def glowing_ground(self) -> None:
        print("3. (b) glowing ground (radiance 1), all else black: façade sum")
        for label, z in (("whole street", (-40, 40, 0, 20)), ("y 0-8 m, |x| < 12", (-12, 12, 0, 8)),
                         ("y 8-20 m, |x| < 12", (-12, 12, 8, 20))):
            v = self.pair(set(), glow_zone(*z), self.facade)
            print(ratio_line(label, v["bsdf"], v["explicit"]))

    def cones(self) -> None:
        print("5. 20° glow cone in the north at elevation e, no ground, all else black: façade")
        for el in (-50, -30, -15, 45):
            v = self.pair(set(), cone_text(el), self.facade, no_ground=True, ad=2048)
            print(ratio_line(f"e {el:+d}°", v["bsdf"], v["explicit"]))

    def inside(self) -> None:
        print("6. the cones at points inside the central crown (x 0.4, y 3 m), facing them")
        for el in (-50, 50):
            e = math.radians(el)
            for z in (4.0, 7.75, 11.5):
                pts = f"0.4 3 {z} 0 {math.cos(e):.6f} {math.sin(e):.6f}\n" * 6
                v = self.pair(set(), cone_text(el), pts, no_ground=True, ad=2048, total=False)
                print(ratio_line(f"e {el:+d}°, z {z:g} m", v["bsdf"].ravel(),
                                 v["explicit"].ravel()))


def panel_tau(tracer: Tracer, material: str, n_out: np.ndarray, source: np.ndarray) -> float:
    """Transmittance of a 120 m square of ``material`` (Radiance text of a material named
    ``panel``) whose outward normal is ``n_out`` (the polygon's normal inwards, −n_out, as the
    shell's), for a sun at ``source``: irradiance 5 cm behind it (away from the sun), facing it, over the
    sun's irradiance on the panel."""
    t1 = np.array([1.0, 0.0, 0.0])
    t2 = np.cross(n_out, t1)
    vs = [-60 * t1 - 60 * t2, 60 * t1 - 60 * t2, 60 * t1 + 60 * t2, -60 * t1 + 60 * t2]
    if np.dot(np.cross(vs[1] - vs[0], vs[2] - vs[0]), -n_out) < 0:
        vs = vs[::-1]
    d = source / np.linalg.norm(source)
    text = (material + "\npanel polygon panel_p\n0\n0\n12 " +
            " ".join(f"{v:.5f}" for q in vs for v in q) + "\n" + sun_text(tuple(d)))
    side = math.copysign(1.0, float(np.dot(d, n_out)))   # the point opposite the sun
    c, f = -side * n_out * 0.05, side * n_out
    pt = f"{c[0]} {c[1]} {c[2]} {f[0]} {f[1]} {f[2]}\n"
    e = tracer.trace(tracer.octree(text), pt, ab=1, ad=8192).mean()
    return float(e / (1e6 * SUN_SR * abs(np.dot(d, n_out))))


def shell_checks(bsdf: Scene, tracer: Tracer) -> None:
    """7. the lower facets against the upper ones mirrored; 8. the wall cap's orientation."""
    print("7. one facet's transmittance (sun ±30° from its normal in the vertical plane): "
          "upper band / its mirrored lower twin")
    bands = sorted(n for n in bsdf.materials if re.fullmatch(r"crown_bsdf_b\d", n))
    for k, name in enumerate(bands):
        e = math.radians((k + 0.5) * 90.0 / len(bands))
        for off in (30, -30):
            taus = []
            for s, suffix in ((1, ""), (-1, "_low")):
                m = bsdf.materials[name + suffix]
                n_out = np.array([0.0, math.cos(e), s * math.sin(e)])
                a = e + math.radians(off)
                src = np.array([0.0, math.cos(a), s * math.sin(a)])
                up = " ".join(f"{u:g}" for u in m.up)
                taus.append(panel_tau(tracer, f"void aBSDF panel\n5 {m.xml} {up} .\n0\n0\n",
                                      n_out, src))
            print(f"  {name} (normal ±{math.degrees(e):.0f}°), sun {off:+d}° from the normal "
                  f"(+: towards the zenith, mirrored for the twin): {taus[0]:.4f} / {taus[1]:.4f}")
    cap = bsdf.materials.get("crown_bsdf_wall")
    if cap is None:
        return
    print("8. the wall cap (vertical, normal into the crown), sun on the crown side")
    for up in ("0 0 1", "0 0 -1"):
        taus = [panel_tau(tracer, f"void aBSDF panel\n5 {cap.xml} {up} .\n0\n0\n",
                          np.array([0.0, -1.0, 0.0]),
                          np.array([0.0, math.cos(math.radians(el)), math.sin(math.radians(el))]))
                for el in (60, 20, -20, -60)]
        print(f"  up {up}: from elevation +60, +20, −20, −60°: "
              + ", ".join(f"{t:.3f}" for t in taus))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", type=Path, default=Path("/tmp/threephase_bench"))
    ap.add_argument("--samples", type=int, default=50, help="tree.bsdf.samples of that run")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--only", default="", help="comma-separated steps (1, 2, 3, 5, 6, 7: 7 and 8), default all")
    args = ap.parse_args()
    print(f"five-phase reflected-sun paths on {args.work / '3phase'}; load {os.getloadavg()}")
    bsdf, explicit, rho, names = scenes(args.work, args.samples)
    with tempfile.TemporaryDirectory(prefix="fivephase_paths_") as tmp:
        p = Paths(bsdf, explicit, rho, names, Tracer(Path(tmp), rho, args.repeats))
        steps = {"1": p.by_surface, "2": p.ground_sun, "3": p.glowing_ground, "5": p.cones,
                 "6": p.inside, "7": lambda: shell_checks(bsdf, p.t)}
        for key, step in steps.items():
            if not args.only or key in args.only.split(","):
                step()
                sys.stdout.flush()
    print(f"load {os.getloadavg()}")


if __name__ == "__main__":
    main()
