"""Plant area density along each beam's own path: voxel traversal of the laser beams.

For scans whose beams are not vertical (airborne lines seen off nadir, overlapping strips
whose beams cross, terrestrial scans from a point), each beam is followed from its origin to
its return through the voxel grid (the exact cell walk of Amanatides & Woo 1987, "A fast voxel
traversal algorithm for ray tracing", Eurographics '87: the crossings of the grid's planes
along the beam, sorted, give every cell it passes and the length inside it). Per voxel:

* entering beams N (weighted, below);
* intercepted beams I: those whose return lies in the voxel and is vegetation (not ground,
  not below ``ground_m``);
* the beams' mean optical path per unit density, l̄_G = Σ G(μ_b)·l_b / N, with l_b the length
  of beam b's line inside the voxel (for an intercepted beam the whole chord, as if it went
  on: the path it was exposed to) and G(μ_b) the plant elements' mean projection for its
  direction (|cos zenith| = μ_b).

Beer–Lambert's law over the voxel (MacArthur & Horn 1969; the voxel form with the beams'
mean path length of Béland et al. 2014, Agric. For. Meteorol. 184:82–97, and of AMAPVox,
Vincent et al. 2017, doi:10.18167/DVN1/6WHPRN) gives

    PAD = −ln( (n·(1 − I/N) + ½) / (n + ½) ) / l̄_G           (m²/m³)

with the same correction of the log of a binomial proportion as the vertical column inversion
(:mod:`radtree.lidar.voxels`), which this is exactly when every beam is vertical (l_b = Δz,
G constant) and every weight 1; n = (Σ w)² / Σ w² is the effective number of beams entering
(Kish's effective sample size of a weighted mean, cited from memory), N itself when every
weight is 1, so the ½ is added in units of whole beams: with the weights of a multi-return
scan (below) N counts many partial pulses as few beams, and the ½ added to N would read the
gap high (on the dense crown of ``tests/test_lidar_beams.py``, 16 sub-rays a pulse, seeds
1–4: leaf area −6.1 … −7.3 % with ½ added to N, −3.8 … −5.0 % with it added to n; one ray a
pulse −3.4 … −5.8 %). The 5-beam minimum of :mod:`radtree.lidar.voxels` counts n too. Not the maximum-likelihood I / Σ G·l_b over the beams' free paths (Pimont et al.
2018, Remote Sens. Environ. 215:343–370): on the synthetic street's crowns it blew up where one
or two beams reach a crown's occluded base and stop just inside a voxel (S14: +37 % leaf
area, a single such voxel > 5 m²). Beams whose path is occluded before a voxel do not enter
it (a voxel no beam reached keeps PAD 0). A pulse with several returns counts as that many
sub-beams, sub-beam k running to return k with the weight of
:func:`radtree.lidar.voxels.echo_weights`: by default its intensity over the summed
intensities of the pulse's returns (the share of the pulse's energy it stopped; AMAPVox's
``RelativeEchoWeight``, weight(echo) = intensity(echo) / Σ intensity(pulse), umr-amap/AMAPVox
``amapvox.core/src/main/java/org/amapvox/shot/weight/RelativeEchoWeight.java``), or
1/(number of returns) (``"equal"``, AMAPVox's ``EqualEchoWeight``). On the synthetic street
(``benchmarks/lidar_roundtrip.py``, 16 sub-rays a pulse, seeds 0–5) the equal weights read
the crowns 5.7 % low on average (104 of 120 within 10 %, against +1.0 % and 116 by
intensity): a pulse's first return, which stopped most of its footprint, counts as half a
beam when a second return follows. With one thin beam per pulse every pulse is one beam.

Heights: the grid stands on the terrain (heights above ground, cell k spans k·size …); each
beam is shifted down by the terrain under its return, so the terrain is taken locally flat
along one beam. Units: metres; x east, y north, z up.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: beams handled per block of the traversal (memory: ~ block × planes × 8 bytes × 4)
BLOCK = 20_000


@dataclass(frozen=True)
class Beams:
    """Beams of a scan in the grid's frame (heights above ground, m): ``origin`` (n, 3),
    ``end`` (n, 3) the return, ``hit`` whether the return is an interception by the crown,
    ``weight`` (1/number of returns)."""

    origin: np.ndarray
    end: np.ndarray
    hit: np.ndarray
    weight: np.ndarray


def traverse(origin: np.ndarray, *, end: np.ndarray, lo: np.ndarray, size: float,
             shape: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cells each segment origin → end crosses in the grid of ``shape`` cells of
    ``size`` from corner ``lo`` (x, y, z): (segment index, flat cell index, length m) for
    every piece (module text)."""
    seg, cell, length = [], [], []
    for b0 in range(0, len(origin), BLOCK):
        o, e = origin[b0:b0 + BLOCK], end[b0:b0 + BLOCK]
        s, c, ln = _traverse_block(o, e=e, lo=lo, size=size, shape=shape)
        seg.append(s + b0)
        cell.append(c)
        length.append(ln)
    if not seg:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    return np.concatenate(seg), np.concatenate(cell), np.concatenate(length)


def _traverse_block(o: np.ndarray, *, e: np.ndarray, lo: np.ndarray, size: float,
                    shape: tuple[int, int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    d = e - o
    total = np.linalg.norm(d, axis=1)
    ts = [np.zeros((len(o), 1)), np.ones((len(o), 1))]
    for ax in range(3):
        planes = lo[ax] + size * np.arange(shape[ax] + 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (planes[None, :] - o[:, ax:ax + 1]) / d[:, ax:ax + 1]
        ts.append(np.where((t > 0) & (t < 1), t, np.nan))
    t = np.sort(np.hstack(ts), axis=1)                      # NaN sort last
    t0, t1 = t[:, :-1], t[:, 1:]
    ok = np.isfinite(t1) & (t1 > t0)
    row, col = np.nonzero(ok)
    a, b = t0[row, col], t1[row, col]
    mid = o[row] + 0.5 * (a + b)[:, None] * d[row]
    ijk = np.floor((mid - lo) / size).astype(np.int64)
    inside = np.all((ijk >= 0) & (ijk < np.array(shape)), axis=1)
    row, ijk = row[inside], ijk[inside]
    ln = (b - a)[inside] * total[row]
    return row, np.ravel_multi_index(ijk.T, shape), ln


def chord_beyond(end: np.ndarray, *, d: np.ndarray, lo: np.ndarray, size: float) -> np.ndarray:
    """Length (m) from each return ``end`` along the unit direction ``d`` to the exit of
    the voxel holding it."""
    cell = np.floor((end - lo) / size)
    face = lo + (cell + (d > 0)) * size
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(np.abs(d) > 1e-12, (face - end) / d, np.inf)
    return np.clip(t.min(axis=1), 0.0, None)


def beam_density(beams: Beams, *, lo: np.ndarray, size: float, shape: tuple[int, int, int],
                 g_of_mu: Callable[[np.ndarray], np.ndarray],
                 beyond_max: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(pad, entering beams, intercepted beams) on the grid, each of ``shape`` (module
    text); ``g_of_mu`` gives G for |cos zenith| of the beams. ``beyond_max`` (m, one per
    beam): how far an intercepted beam's chord may run on past its return (the crown
    envelope's exit, :mod:`radtree.lidar.envelope`); unbounded when None."""
    c = beam_counts(beams, lo=lo, size=size, shape=shape, g_of_mu=g_of_mu,
                    beyond_max=beyond_max)
    return density(c.entering, c.hits, c.optical, c.effective()), c.entering, c.hits


@dataclass(frozen=True)
class BeamCounts:
    """Per voxel (arrays of the grid's shape): the beams entering N and intercepted I
    (weighted), their summed optical path per unit density Σ w·G(μ)·l (m) and the sum of the
    entering beams' squared weights Σ w² (None: every weight 1)."""

    entering: np.ndarray
    hits: np.ndarray
    optical: np.ndarray
    entering_sq: np.ndarray | None = None

    def effective(self) -> np.ndarray:
        """:func:`effective_beams` of the entering beams."""
        return effective_beams(self.entering, self.entering_sq)


def effective_beams(weights: np.ndarray, squares: np.ndarray | None) -> np.ndarray:
    """The effective number of beams n = (Σ w)² / Σ w² from their summed ``weights`` and
    summed squared weights (Kish 1965, *Survey Sampling*, cited from memory): Σ w itself
    when ``squares`` is None (every weight 1); 0 where no beam."""
    if squares is None:
        return weights
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(squares > 0, weights**2 / squares, 0.0)


def density(entering: np.ndarray, hits: np.ndarray, optical: np.ndarray,
            effective: np.ndarray | None = None) -> np.ndarray:
    """PAD (m²/m³) = −ln((n·(1 − I/N) + ½)/(n + ½)) / l̄_G with l̄_G = optical / N and n the
    effective number of beams (``effective``; N when None: −ln((N − I + ½)/(N + ½)), module
    text); 0 where no beam entered."""
    n = entering if effective is None else effective
    with np.errstate(divide="ignore", invalid="ignore"):
        gap_w = np.maximum(entering - hits, 0.0) / entering
        gap = (n * gap_w + 0.5) / (n + 0.5)   # module text
        path = optical / entering
        return np.where((entering > 0) & (path > 0), -np.log(np.minimum(gap, 1.0)) / path,
                        0.0)


def beam_counts(beams: Beams, *, lo: np.ndarray, size: float, shape: tuple[int, int, int],
                g_of_mu: Callable[[np.ndarray], np.ndarray],
                beyond_max: np.ndarray | None = None) -> BeamCounts:
    """The counts of :func:`beam_density` per voxel (:class:`BeamCounts`)."""
    d = beams.end - beams.origin
    d /= np.maximum(np.linalg.norm(d, axis=1), 1e-12)[:, None]
    w = beams.weight
    g = np.asarray(g_of_mu(np.abs(d[:, 2])), float) * w
    seg, cell, length = traverse(beams.origin, end=beams.end, lo=lo, size=size, shape=shape)
    n = int(np.prod(shape))
    optical = np.bincount(cell, weights=g[seg] * length, minlength=n)
    k = np.floor((beams.end - lo) / size).astype(np.int64)
    ok = beams.hit & np.all((k >= 0) & (k < np.array(shape)), axis=1)
    hit_cell = np.ravel_multi_index(k[ok].T, shape)
    hits = np.bincount(hit_cell, weights=w[ok], minlength=n)
    # an intercepted beam was exposed to its whole chord through the voxel
    beyond = chord_beyond(beams.end[ok], d=d[ok], lo=lo, size=size)
    if beyond_max is not None:
        beyond = np.minimum(beyond, np.asarray(beyond_max, float)[ok])
    optical += np.bincount(hit_cell, weights=g[ok] * beyond, minlength=n)
    # entering: every beam with a piece in the voxel (an intercepted one has, up to its return)
    first = np.ones(len(seg), bool)
    pair = seg * n + cell
    first[1:] = pair[1:] != pair[:-1]
    entering = np.bincount(cell[first], weights=w[seg[first]], minlength=n)
    entering_sq = np.bincount(cell[first], weights=w[seg[first]] ** 2, minlength=n)
    return BeamCounts(entering.reshape(shape), hits.reshape(shape), optical.reshape(shape),
                      entering_sq.reshape(shape))
