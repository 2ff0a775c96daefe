"""The NumPy engine's random numbers: one counter-based stream per path.

Every uniform a path uses is a hash of the trace's key, the path's number in its sensor grid
and the draw's place in the program — (bounce, site[, shadow layer]) and the draw's count
there: SplitMix64's finaliser applied to a Weyl sequence, the generator of Steele, Lea &
Flood (2014), "Fast splittable pseudorandom number generators", OOPSLA '14, with the path
number as the sequence position and the site as its offset. A path's numbers therefore do
not depend on which other paths are traced beside it — in which batch, in which part of a
batch, on how many worker threads — so the threads that share a batch trace their parts
without waiting for each other, and ``engine.workers`` and ``batch_paths`` do not change a
result.

Integer arithmetic modulo 2⁶⁴ only: every platform and NumPy version gives the same numbers.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

_MASK = (1 << 64) - 1
_GOLDEN = 0x9E3779B97F4A7C15  # 2⁶⁴ / φ, SplitMix64's increment
_M1, _M2 = 0xBF58476D1CE4E5B9, 0x94D049BB133111EB  # SplitMix64's finaliser (Stafford's Mix13)
_U_GOLDEN, _U_M1, _U_M2 = np.uint64(_GOLDEN), np.uint64(_M1), np.uint64(_M2)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_TO_UNIT = 1.0 / (1 << 53)

# Places of the draws made outside the bounce loop (bounce 0); the loop's own are
# (bounce ≥ 1, site 0–4), a shadow ray's roulette appends the layer crossed. Distinct places
# give independent numbers, so no two sites may share one.
FIRST_DIRECTIONS = (0, 4)      # cosine samples of the first directions (no Sobol' net given)
SUN_DISC = (0, 5)              # a sensor's direction into the sampled sun disc
SENSOR_SUN_ROULETTE = (0, 6)   # the roulette of a sensor's own shadow ray


def mix64(x: int) -> int:
    """SplitMix64's finaliser of one 64-bit integer (a Python int)."""
    x &= _MASK
    x = ((x ^ (x >> 30)) * _M1) & _MASK
    x = ((x ^ (x >> 27)) * _M2) & _MASK
    return x ^ (x >> 31)


def site_offset(key: int, tag: tuple[int, ...]) -> int:
    """The 64-bit offset of the draw labelled ``tag`` in the stream ``key``: the finaliser
    chained over the tag's numbers (each + 1, times the golden increment)."""
    s = mix64(key)
    for t in tag:
        s = mix64(s ^ (((int(t) + 1) * _GOLDEN) & _MASK))
    return s


def uniforms(ids: np.ndarray, offset: int) -> np.ndarray:
    """Uniform doubles in [0, 1), one per path number in ``ids`` (uint64): the top 53 bits of
    SplitMix64's finaliser of ``ids · golden + offset`` (mod 2⁶⁴)."""
    h = np.multiply(ids, _U_GOLDEN, dtype=np.uint64)
    h += np.uint64(offset)
    h ^= h >> _S30
    h *= _U_M1
    h ^= h >> _S27
    h *= _U_M2
    h ^= h >> _S31
    h >>= _S11
    return h * _TO_UNIT


class Draws(Protocol):
    """Uniforms for a set of paths at one place in the program (see the module docstring)."""

    def random(self, size: int) -> np.ndarray:
        """``size`` uniform doubles in [0, 1): one per path of this set, in its order."""
        ...

    def rows(self, rows: np.ndarray | None, *tag: int) -> Draws:
        """The draws of the paths at ``rows`` of this set (None: all), at the place ``tag``
        (appended to this set's own)."""
        ...


class PathStreams:
    """The streams of the paths numbered ``ids`` (uint64, one per row of a batch or part),
    at the place ``tag`` of the program; each :meth:`random` there is the next draw."""

    def __init__(self, key: int, ids: np.ndarray, tag: tuple[int, ...] = ()):
        self.key = int(key) & _MASK
        self.ids = np.asarray(ids, dtype=np.uint64)
        self.tag = tuple(tag)
        self.count = 0

    def rows(self, rows: np.ndarray | None, *tag: int) -> PathStreams:
        ids = self.ids if rows is None else self.ids.take(rows)
        return PathStreams(self.key, ids, self.tag + tag)

    def random(self, size: int) -> np.ndarray:
        if size != len(self.ids):
            raise ValueError(f"{size} draws asked of {len(self.ids)} paths")
        self.count += 1
        return uniforms(self.ids, site_offset(self.key, (*self.tag, self.count)))


class GeneratorDraws:
    """A NumPy ``Generator`` as :class:`Draws`: the plain stream, whatever the rows or the
    place (one thread drawing in a fixed order, e.g. the sensors' own direct sun)."""

    def __init__(self, rng: np.random.Generator):
        self.rng = rng

    def rows(self, rows: np.ndarray | None, *tag: int) -> GeneratorDraws:
        return self

    def random(self, size: int) -> np.ndarray:
        return self.rng.random(size)


def as_draws(rng: Draws | np.random.Generator) -> Draws:
    """``rng`` as :class:`Draws` (a ``Generator`` wrapped in :class:`GeneratorDraws`)."""
    return GeneratorDraws(rng) if isinstance(rng, np.random.Generator) else rng


def stream_key(rng: np.random.Generator) -> int:
    """A 64-bit stream key drawn from ``rng`` (one draw)."""
    return int(rng.integers(0, 1 << 64, dtype=np.uint64))
