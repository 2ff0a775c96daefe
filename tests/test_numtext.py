"""Vectorised number text (radtree.engines.radiance.numtext): the same bytes as printf."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from radtree.engines.radiance.numtext import format_rows


def _printf(prefix: str, values: np.ndarray, spec: str) -> str:
    n, k = values.shape
    return ((prefix + (" " + spec) * k + "\n") * n) % tuple(values.ravel().tolist())


def test_awkward_values_match_printf() -> None:
    """Signed zeros, values rounding to zero, exact binary ties (1/64 = 0.015625 rounds to
    even), decimal near-ties whose scaled product lands on a half, carries into the integer
    part and large magnitudes."""
    v = np.array([[-0.0, 0.0, -1e-9], [1e-9, 0.000005, -0.000005], [0.015625, -0.046875, 2.5],
                  [999.999995, -999.999995, 12345.678915], [0.123455, 1.000005, 9.999999],
                  [1e7 + 0.5, -3e6 - 1e-5, 7.0], [1e12, -3e13 + 0.25, 123456789012.345]])
    assert format_rows("v", v, 5) == _printf("v", v, "%.5f")


def test_decimal_near_ties_match_printf() -> None:
    """4 × 10⁴ values with six decimals (each a near-tie at five places) and as many binary
    ties, in more rows than one chunk."""
    rng = np.random.default_rng(3)
    near = np.round(rng.normal(0.0, 40.0, (20000, 2)), 6)
    ties = np.round(rng.normal(0.0, 40.0, (20000, 2)) * 64) / 64
    for v in (near, ties):
        assert format_rows("v", v, 5) == _printf("v", v, "%.5f")


@settings(max_examples=200, deadline=None)
@given(arrays(np.float64, st.tuples(st.integers(1, 30), st.integers(1, 4)),
              elements=st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)),
       st.integers(0, 7))
def test_floats_match_printf(values: np.ndarray, decimals: int) -> None:
    assert format_rows("v", values, decimals) == _printf("v", values, f"%.{decimals}f")


@settings(max_examples=100, deadline=None)
@given(arrays(np.int64, st.tuples(st.integers(1, 30), st.integers(1, 4)),
              elements=st.integers(-10**12, 10**12)))
def test_integers_match_printf(values: np.ndarray) -> None:
    assert format_rows("f", values, 0) == _printf("f", values, "%d")


def test_bad_input_is_named() -> None:
    with pytest.raises(ValueError, match="2-D"):
        format_rows("v", np.zeros(3), 5)
    with pytest.raises(ValueError, match="finite"):
        format_rows("v", np.array([[np.nan, 0.0]]), 5)
    assert format_rows("v", np.zeros((0, 3)), 5) == ""
