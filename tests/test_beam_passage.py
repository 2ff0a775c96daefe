"""The forward passage of a parallel beam (radtree.engines.forward.passage), behind the
EnergyPlus schedule's *total* definition, on layers whose passage is known exactly."""

from __future__ import annotations

import numpy as np
import pytest

from radtree.engines.forward.passage import beam_passage
from radtree.optics import Plastic, Trans
from radtree.scene import quad

DOWN = np.array([[0.0, 0.0, -1.0]])


def _layer(z: float, name: str = "leaf"):
    return quad(f"{name}{z}", name, np.array([[-50, -50, z], [50, -50, z], [50, 50, z],
                                              [-50, 50, z]], float))


def _starts(n: int = 40_000) -> list[np.ndarray]:
    g = np.random.default_rng(2)
    return [np.column_stack([g.uniform(-1, 1, n), g.uniform(-1, 1, n), np.full(n, 5.0)])]


def test_one_translucent_layer():
    """Total T_s + T_d = 0.5, beam T_s = 0.2 (the beam part is exact: no event is random)."""
    total, beam = beam_passage([_layer(0.0)], {"leaf": Trans("leaf", 0.1, 0.3, 0.2)}, DOWN,
                               _starts())
    assert beam[0] == pytest.approx(0.2, abs=0.006)
    assert total[0] == pytest.approx(0.5, abs=0.008)


def test_two_layers_with_interreflection():
    """Two wide parallel diffuse layers (R, T): what passes both, summing the bounces between
    them (adding method, van de Hulst 1980): T² / (1 − R²) = 0.09 / 0.91 = 0.0989."""
    leaf = Trans("leaf", 0.3, 0.3, 0.0)
    total, beam = beam_passage([_layer(0.0), _layer(-0.01)], {"leaf": leaf}, DOWN, _starts(),
                               max_bounces=40)
    assert beam[0] == 0.0
    assert total[0] == pytest.approx(0.09 / 0.91, rel=0.03)


def test_opaque_and_open():
    blocked, _ = beam_passage([_layer(0.0, "wall")], {"wall": Plastic("wall", 0.5)}, DOWN,
                              _starts(2000))
    assert blocked[0] == 0.0
    with pytest.raises(ValueError, match="one non-empty set"):
        beam_passage([_layer(0.0, "wall")], {"wall": Plastic("wall", 0.5)}, DOWN, [])
