"""Lens projections: known values, both directions, presets, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from radtree.errors import ConfigError
from radtree.hemi.lens import (
    FC_E8_COEFFICIENTS,
    Projection,
    get_lens,
    parse_polynomial,
    polynomial_lens,
    radian_to_x_coefficients,
)

ALL = ["equidistant", "equisolid", "stereographic", "orthographic", "FC-E8", "FC-E9"]


@pytest.mark.parametrize("name", ALL)
def test_ninety_degrees_is_the_mask_radius(name: str) -> None:
    lens = get_lens(name)
    assert lens.radius(np.array([0.0, 90.0])) == pytest.approx([0.0, 1.0], abs=1e-12)
    assert lens.zenith(np.array([0.0, 1.0])) == pytest.approx([0.0, 90.0], abs=1e-9)


def test_closed_forms() -> None:
    z = np.array([30.0, 60.0])
    assert get_lens("equidistant").radius(z) == pytest.approx([1 / 3, 2 / 3])
    assert get_lens("equisolid").radius(z) == pytest.approx(
        np.sin(np.radians(z) / 2) / math.sin(math.pi / 4)
    )
    assert get_lens("stereographic").radius(z) == pytest.approx(np.tan(np.radians(z) / 2))
    assert get_lens("orthographic").radius(z) == pytest.approx([0.5, math.sqrt(3) / 2])


def test_fc_e8_polynomial_normalised_by_p1() -> None:
    a1, a2, a3 = FC_E8_COEFFICIENTS
    p1 = a1 + a2 + a3
    assert p1 == pytest.approx(1.00108)
    x = 0.5
    expected = (a1 * x + a2 * x**2 + a3 * x**3) / p1
    assert get_lens("FC-E8").radius(np.array([45.0]))[0] == pytest.approx(expected, rel=1e-12)


def test_fc_e9_from_hemisfer_radian_coefficients() -> None:
    # Hemisfer: r/R = 0.6427 t + 0.0346 t^2 - 0.024491 t^3 (t in radians), ~1 at 90 degrees
    t = math.radians(60.0)
    raw60 = 0.6427 * t + 0.0346 * t**2 - 0.024491 * t**3
    t90 = math.pi / 2
    raw90 = 0.6427 * t90 + 0.0346 * t90**2 - 0.024491 * t90**3
    assert raw90 == pytest.approx(1.0, abs=1e-3)
    assert get_lens("fce9").radius(np.array([60.0]))[0] == pytest.approx(raw60 / raw90, rel=1e-12)
    assert radian_to_x_coefficients((1.0,)) == pytest.approx((math.pi / 2,))


@settings(max_examples=60, deadline=None)
@given(
    st.sampled_from(ALL),
    st.lists(st.floats(0.0, 90.0, allow_nan=False), min_size=1, max_size=50),
)
def test_round_trip_vectorised(name: str, zeniths: list[float]) -> None:
    lens = get_lens(name)
    z = np.array(zeniths)
    back = lens.zenith(lens.radius(z))
    assert back == pytest.approx(z, abs=1e-7)


@pytest.mark.parametrize("name", ALL)
def test_derivative_matches_finite_difference(name: str) -> None:
    lens = get_lens(name)
    z = np.array([5.0, 30.0, 60.0, 85.0])
    h = 1e-4
    fd = (lens.radius(z + h) - lens.radius(z - h)) / math.radians(2 * h)
    assert lens.derivative(z) == pytest.approx(fd, rel=1e-6)


def test_user_polynomial_and_parse() -> None:
    lens = parse_polynomial("1.0, 0.0, 0.0")
    assert lens.kind == "polynomial"
    z = np.linspace(0, 90, 7)
    assert lens.radius(z) == pytest.approx(z / 90)  # p(x) = x is equidistant
    rad = polynomial_lens([2 / math.pi], unit="rad")
    assert rad.radius(np.array([45.0]))[0] == pytest.approx(0.5)


def test_outside_range_is_nan() -> None:
    assert np.isnan(get_lens("orthographic").zenith(np.array([1.2]))[0])
    assert np.isnan(get_lens("FC-E8").zenith(np.array([1.01]))[0])
    assert np.isnan(get_lens("equidistant").radius(np.array([-1.0]))[0])


def test_invalid_lenses_are_rejected() -> None:
    with pytest.raises(ConfigError, match="not strictly increasing"):
        Projection("polynomial", (1.0, 0.0, -2.0))
    with pytest.raises(ConfigError, match="unknown lens"):
        get_lens("fisheye-9000")
    with pytest.raises(ConfigError, match="unknown projection"):
        Projection("cylindrical")
    with pytest.raises(ConfigError, match="comma-separated"):
        parse_polynomial("1.06;0.1")
