"""The crown shell's ``aBSDF`` material (``tree.bsdf.material``, default): Radiance's peak
extraction passes the sun through the XML's straight-through Klems patch as a ray.

A synthetic Klems XML with an exact answer: front and back transmission F[o, i] = τ_p δ_oi +
τ_d Λ_o / π (a straight-through peak τ_p = 0.4 in every patch plus a Lambertian τ_d = 0.2), no
reflection, on a 120 m square 1 m above nine upward sensors, the sun (0.533°, radiance 10⁶)
30° from the zenith. The plane is near-infinite, so the sensors' irradiance is the
transmitted flux: E_sun cos 30° (τ_p + τ_d); the direct (``-ab 0``) part is the peak patch's
flux E_sun cos 30° (τ_p + τ_d Λ_i / π)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from radtree.engines.radiance.binaries import monte_carlo_options, run
from radtree.engines.radiance.bsdf import wrap_flux
from radtree.engines.radiance.materials import material_text
from radtree.optics import KLEMS_FULL_RINGS, Bsdf
from tests.conftest import needs_radiance

TAU_PEAK, TAU_DIFFUSE = 0.4, 0.2
SUN_ZENITH_DEG = 30.0


def klems_lambdas() -> np.ndarray:
    """Projected solid angle of each of the 145 Klems patches (sr, summing to π)."""
    out: list[float] = []
    for lo, hi, _, n in KLEMS_FULL_RINGS:
        s = math.sin(math.radians(hi)) ** 2 - math.sin(math.radians(lo)) ** 2
        out += [math.pi * s / n] * n
    return np.array(out)


def peak_xml(folder: Path) -> Path:
    lam = klems_lambdas()
    f = TAU_PEAK * np.eye(145) + TAU_DIFFUSE * (lam / math.pi)[:, None] * np.ones((1, 145))
    zero = np.zeros((145, 145))
    return wrap_flux(folder, {"tf": f, "tb": f, "rf": zero, "rb": zero}, "peak", 0.01, 1.0, 1.0)


def sensor_lux(folder: Path, material: Bsdf, ab: int) -> np.ndarray:
    """Irradiance (photopic channel, W/m²) of nine upward sensors under the plane."""
    z = math.radians(SUN_ZENITH_DEG)
    scene = (material_text(material)
             + f"{material.name} polygon plane\n0\n0\n12 -60 -60 0  -60 60 0  60 60 0  60 -60 0\n"
             "void light solar\n0\n0\n3 1e6 1e6 1e6\n"
             f"solar source sun\n0\n0\n4 {math.sin(z):.9f} 0 {math.cos(z):.9f} 0.533\n")
    (folder / "s.rad").write_text(scene)
    run(["oconv", "s.rad"], cwd=folder, stdout_path=folder / "s.oct")
    pts = "".join(f"{x} {y} -1 0 0 1\n" for x in (-1, 0, 1) for y in (-1, 0, 1))
    out = run(["rtrace", "-h", "-I", "-u-", *monte_carlo_options(ab, 4096, 1e-5), "s.oct"],
              cwd=folder, stdin=pts.encode()).decode().split()
    return np.array(out, float).reshape(-1, 3)[:, 1]


def test_absdf_material_text():
    m = Bsdf("crown_bsdf_b0", "/x/b0.xml", (0.0, 0.0, -1.0), peak=True)
    assert material_text(m) == "void aBSDF crown_bsdf_b0\n5 /x/b0.xml 0 0 -1 .\n0\n0\n"
    with pytest.raises(ValueError, match="no thickness"):
        Bsdf("b", "b.xml", thickness=0.1, peak=True)


@needs_radiance
def test_absdf_passes_the_sun_through_the_klems_peak(tmp_path):
    """Measured (Radiance of the pyradiance 1.2.4 wheel): BSDF passes no sun at ``-ab 0``
    and at ``-ab 1`` (4096 rays) reads 32.5–35.3 (mean −4 %); aBSDF 23.549 at ``-ab 0``
    (the peak patch's flux, 23.633, −0.4 %: the XML's 4 significant digits) and 35.321 at
    ``-ab 1`` at every sensor (35.317 exact)."""
    xml = peak_xml(tmp_path)
    e_sun = 1e6 * 2 * math.pi * (1 - math.cos(math.radians(0.533 / 2)))
    e_h = e_sun * math.cos(math.radians(SUN_ZENITH_DEG))
    lam_i = klems_lambdas()[1 + 8 + 16]          # the 25–35° ring's patches
    plain = Bsdf("shade", str(xml), (0.0, 1.0, 0.0))
    peak = Bsdf("shade", str(xml), (0.0, 1.0, 0.0), peak=True)
    assert np.all(sensor_lux(tmp_path, plain, 0) == 0.0)   # the sun only by ambient sampling
    np.testing.assert_allclose(sensor_lux(tmp_path, peak, 0),
                               e_h * (TAU_PEAK + TAU_DIFFUSE * lam_i / math.pi), rtol=0.01)
    total = sensor_lux(tmp_path, peak, 1)
    np.testing.assert_allclose(total, e_h * (TAU_PEAK + TAU_DIFFUSE), rtol=0.005)
    assert total.std() < 1e-3 * total.mean()            # deterministic: no disc to find


def test_three_phase_matrices_see_the_plain_bsdf():
    """The chain applies the XML as it is: its daylight and view scenes carry the shell as
    ``BSDF`` (``_scene_with(..., peak=False)``); the sun runs' scene keeps the ``aBSDF``."""
    from radtree.annual.coefficients import scene_text
    from radtree.annual.threephase import _scene_with
    from radtree.scene import Mesh, Scene
    from radtree.trees.bsdf_shell import BSDF_SHELL
    from radtree.trees.model import TreeModel

    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    model = TreeModel(meshes=[Mesh("s", BSDF_SHELL, v, np.array([[0, 1, 2]]))],
                      materials={BSDF_SHELL: Bsdf(BSDF_SHELL, "/x/crown.xml", peak=True)},
                      notes=[], recommended_ab=6, form="free", model="louvers")
    bare = Scene([], {}, {}, [])
    assert "void aBSDF crown_bsdf\n5 /x/crown.xml" in scene_text(_scene_with(bare, model), 0.2)
    plain = scene_text(_scene_with(bare, model, peak=False), 0.2)
    assert "void BSDF crown_bsdf\n6 0 /x/crown.xml" in plain and "aBSDF" not in plain
