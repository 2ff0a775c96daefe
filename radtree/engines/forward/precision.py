"""The forward engine's precision target: photons added in legs until every traced grid's mean
reaches a relative standard error, or a stated cap.

**Estimator.** Photons are traced in *rounds* of ``photons`` each, every round split into
``batches`` equal batches; each batch is an independent estimate of every detector's
illuminance (its tally × batches / patch area, lux), so after R rounds there are R × batches
batch estimates x_b of equal size. A grid's mean illuminance is the mean over the batches of the
batch's grid mean, ḡ = (1/B) Σ g_b, and its standard error the *batch-means* error

    SE(ḡ) = s(g_b) / √B,   s the sample standard deviation (ddof 1).

The batches, not the per-sensor errors, give the grid mean's error: overlapping patches share
photons, so the per-sensor errors are correlated and √(Σ SE²)/n understates it.

**Heavy tails.** A batch's grid mean is a sum over many photons of rare contributions; with
enough photons per batch the batch means are near normal, and what remains of the tail is met
by **more batches**: the first round has ``batches`` (default 32 from ``engine.forward_batches``)
and every further round adds as many, so the error estimate's degrees of freedom grow with the
photons (for normal batch means z = (ḡ − g)/SE follows Student's t with B − 1 ≥ 31 degrees of
freedom: s.d. 1.03, P(|z| > 3) = 0.5 %). Measured (benchmarks/forward.py ``--zscores``): on a
translucent shell 60 seeded runs give z s.d. 0.97 (32 batches of 250 photons; 16 batches:
1.29). On the reference street the tail is not the guided weights (bounded by 1/(1 − q) = 5
a diffuse event, and a hit's contribution within a launch ring is at most 6.4× the ring's mean
hit, scenario B at 12:30) but **rare paths from far rings**: photons starting 4–16 m from the
focus reach the façade patches 1–3 times in 10⁴, each hit carrying ~50× the flux of an
inner-ring hit; the pilot (~4 000 photons a ring) saw none, the rings ran on the defensive
floor, and a run's few such hits — or their absence, which lowers the mean and its error
together — made the tail (B at 12:30: −9.5 %, z −5.7 against Radiance). The strata are
therefore **re-allocated before every further round** from all photons so far
(:func:`radtree.engines.forward.strata.reallocate`), and within every round before each of
its ``engine.forward_stages`` stages (default 4; :mod:`radtree.engines.forward.strata`,
*Stages*: B at 12:30, 200 seeds, |z| > 3 in 1.5 % with the round at once, none in 4 stages). What stays is the skew of a mean of
rare, heavy hits: its batch-means error is right on average (a 2 m patch over a sunlit floor,
focused launch, 40 seeds of 100 000 photons: spread of the means / r.m.s. error 1.03) but low
in the runs that missed the heavy hits, so z has a negative tail (same runs: z s.d. 1.30,
min −4.4). Figures on the street: benchmarks/forward.py. The heavy hits left after the
re-allocation came with the launch, not from the guide: the outer rings' photons start with
100–3 000 lm against 4–30 lm in the inner rings, and crossings above 10 × the mean crossing
(~1 % of them) carried 25–30 % of the façade's scattered light. So a **weight window**
(:mod:`radtree.engines.forward.window`, MCNP's method) splits every photon heavier than its
bound into lighter copies, its level predicted from the pilot (every round traces with it).
On the free crowns (F) the tail was the roulette after a guided event: see
:mod:`radtree.engines.forward.tracer`, *Roulette after a guided event*.

**Stopping.** After the first round the photons needed are predicted from the standard
error's 1/√N law, N = N₁ · (r / target)² with r the worst grid's relative error, plus 10 %
(whole rounds, at least one, within the cap). Stopping on the very photons one reports biases
a skewed estimate low: a run that missed the rare heavy hits has a low mean *and* a small
error, so it stops early and keeps both (2 m patch over a sunlit floor, rounds of 5 000 photons
to 3 %, 30 seeds: mean −1.7 %, spread of the means 1.43 × the r.m.s. error, z s.d. 1.49). So the
first round only **sizes** the run, as the first sample of Stein's two-stage procedure sets
the size of the second (Stein 1945, Ann. Math. Statist. 16, 243–258); here its photons are then
set aside: when it misses the target they steer the strata, and the N predicted are traced
afresh and counted (cost: one round, 1 M photons at the defaults, N₁/N of the run). Same
floor runs with it: mean −0.4 %, spread 1.11 × the r.m.s. error, z s.d. 1.14, max |z| 2.9
(rounds of 20 000 to 2 %, 40 seeds: z s.d. 1.52 → 1.33, mean z −0.59 → −0.34). If those still miss the target (the prediction's noise), further legs are predicted the
same way from the counted photons and the target checked again. A grid whose batches all read
0 lux (no light reaches it) counts as reached (0 ± 0). At the cap the run stops and
:class:`PrecisionWarning` states the relative error reached per grid.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

MARGIN = 1.1
"""Factor on the predicted photons of a leg (the prediction's own noise)."""


class PrecisionWarning(UserWarning):
    """The photon cap was hit before the precision target."""


def mean_and_se(batch_means: np.ndarray) -> tuple[float, float]:
    """The mean of equal-size batch estimates (lux) and its batch-means standard error."""
    x = np.asarray(batch_means, float)
    if len(x) < 2:
        raise ValueError("a standard error needs at least 2 batches")
    return float(x.mean()), float(x.std(ddof=1) / math.sqrt(len(x)))


def relative_se(mean: float, se: float) -> float:
    """SE / |mean|; 0 for a grid that reads 0 ± 0 (nothing to resolve), ∞ for 0 ± something."""
    if mean == 0.0:
        return 0.0 if se == 0.0 else math.inf
    return se / abs(mean)


def worst_relative_se(per_grid: dict[str, np.ndarray]) -> tuple[str, float]:
    """The grid with the largest relative standard error of its mean, and that error;
    ``per_grid[name]``: the (batches,) grid means of the batches (lux)."""
    worst = ("", 0.0)
    for name, g in per_grid.items():
        r = relative_se(*mean_and_se(g))
        if r > worst[1] or not worst[0]:
            worst = (name, r)
    return worst


@dataclass(frozen=True)
class Budget:
    """How many photons to trace: rounds of ``round_photons``, until every grid's relative
    standard error ≤ ``target`` (None: one round, no target) or ``cap`` photons."""

    round_photons: int
    target: float | None
    cap: int

    def next_leg(self, traced: int, rel: float, *, spent: int = 0) -> int:
        """Photons of the next leg (whole rounds) after ``traced`` counted photons gave the
        worst relative error ``rel`` (``spent``: photons traced besides, towards the cap); 0
        when the target is reached, there is none, or the cap is."""
        if self.target is None or rel <= self.target or traced + spent >= self.cap:
            return 0
        if math.isfinite(rel):
            need = traced * (rel / self.target) ** 2 * MARGIN - traced
        else:
            need = traced  # nothing seen yet: double
        rounds = max(1, math.ceil(need / self.round_photons))
        room = (self.cap - traced - spent) // self.round_photons
        return int(min(rounds, max(room, 0))) * self.round_photons

    def sized_leg(self, traced: int, rel: float) -> int:
        """Photons (whole rounds) predicted for the target *in all* after a sizing round of
        ``traced`` photons with the worst relative error ``rel``, within the cap left; 0 when
        there is no target, it is met, nothing was seen (∞) or no round fits."""
        if self.target is None or rel <= self.target or not math.isfinite(rel):
            return 0
        rounds = max(1, math.ceil(traced * (rel / self.target) ** 2 * MARGIN
                                  / self.round_photons))
        room = (self.cap - traced) // self.round_photons
        return int(min(rounds, max(room, 0))) * self.round_photons

    def warn_if_short(self, traced: int, per_grid: dict[str, np.ndarray]) -> str | None:
        """A :class:`PrecisionWarning` (and its text) when the target was not reached."""
        if self.target is None:
            return None
        short = {n: relative_se(*mean_and_se(g)) for n, g in per_grid.items()}
        short = {n: r for n, r in short.items() if r > self.target}
        if not short:
            return None
        text = (f"forward engine: photon cap {self.cap:,} reached ({traced:,} traced) before "
                f"the target relative standard error {self.target:.1%}: "
                + ", ".join(f"grid '{n}' {r:.1%}" for n, r in short.items())
                + " (raise engine.max_photons, or accept the reported errors)")
        warnings.warn(text, PrecisionWarning, stacklevel=3)
        return text
