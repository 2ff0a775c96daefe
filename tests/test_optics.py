import math

import pytest

from radtree.engines.radiance.materials import material_text
from radtree.optics import Glass, Hole, Plastic, Trans, transmissivity_from_transmittance


def test_plastic_text():
    assert material_text(Plastic("facade_paint", 0.9)) == (
        "void plastic facade_paint\n0\n0\n5 0.9 0.9 0.9 0 0\n")


def test_trans_leaf_text_from_spec():
    # R 0.11, T_d 0.50 all diffuse: C = 0.61, trans = 0.8197, tspec = 0 (SPEC.md)
    assert material_text(Trans("leaf", 0.11, 0.50)) == (
        "void trans leaf\n0\n0\n7 0.61 0.61 0.61 0 0 0.8197 0\n")


def test_trans_with_specular_part():
    t = Trans("slat", 0.11, 0.25, 0.25)
    c, trans, tspec = t.coefficients
    assert c == pytest.approx(0.61)
    assert trans == pytest.approx(0.5 / 0.61)
    assert tspec == pytest.approx(0.5)
    # Radiance splits C·trans·tspec into specular transmission: must give T_s back
    assert c * trans * tspec == pytest.approx(0.25)
    assert c * (1 - trans) == pytest.approx(0.11)


@pytest.mark.parametrize("tn, expected, text", [
    (0.06, 0.0654, "0.0655"), (0.5, 0.5452, "0.5452"), (0.88, 0.9584, "0.9584")])
def test_glass_from_transmittance(tn, expected, text):
    g = Glass.from_transmittance("glazing", tn)
    # SPEC.md rounds 0.065455 down to 0.0654; radtree writes 4 decimals, rounded
    assert g.transmissivity == pytest.approx(expected, abs=1.5e-4)
    assert material_text(g) == f"void glass glazing\n0\n0\n3 {text} {text} {text}\n"
    assert g.transmittance == pytest.approx(tn, abs=1e-6)  # the converter's inverse


@pytest.mark.parametrize("bad", [0.0, -0.1, 0.92, 1.0, float("nan")])
def test_converter_rejects_outside_domain(bad):
    with pytest.raises(ValueError, match="transmittance"):
        transmissivity_from_transmittance(bad)


def test_converter_upper_edge_is_near_one():
    assert transmissivity_from_transmittance(0.9183) == pytest.approx(1.0, abs=2e-4)


@pytest.mark.parametrize("args", [(-0.1, 0.5, 0.0), (0.6, 0.5, 0.0), (0.11, math.nan, 0.0),
                                  (0.11, 0.5, 0.5)])
def test_trans_rejects_bad_optics(args):
    with pytest.raises(ValueError, match="material 'leaf'"):
        Trans("leaf", *args)


def test_hole_writes_nothing():
    assert material_text(Hole("gap")) == ""
    assert Hole("gap").transmittance == 1.0
