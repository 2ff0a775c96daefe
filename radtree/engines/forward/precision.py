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
1.29); on the reference-case louvers dome, scenario A at 12:30 with *rounds of 50 000 photons* (1 600
a batch) and a 5 % target, 50 runs give z s.d. 1.51 and |z| > 3 in 6 %: with that few photons
a batch the error is understated by about half. The default rounds (1 M photons, 31 250 a
batch) were not put through the same 50 repeats on this machine.

**Stopping.** After the first round the photons still needed are predicted from the standard
error's 1/√N law, N_total = N · (r / target)² with r the worst grid's relative error, plus 10 %
(rounded up to whole rounds, at least one, at most up to the cap), traced as one *leg*, and the
target checked again; few looks keep the optional-stopping bias of the reported error small.
A grid whose batches all read 0 lux (no light reaches it) counts as reached (0 ± 0). At the cap
the run stops and :class:`PrecisionWarning` states the relative error reached per grid.
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

    def next_leg(self, traced: int, rel: float) -> int:
        """Photons of the next leg (whole rounds) after ``traced`` photons gave the worst
        relative error ``rel``; 0 when the target is reached, there is none, or the cap is."""
        if self.target is None or rel <= self.target or traced >= self.cap:
            return 0
        if math.isfinite(rel):
            need = traced * (rel / self.target) ** 2 * MARGIN - traced
        else:
            need = traced  # nothing seen yet: double
        rounds = max(1, math.ceil(need / self.round_photons))
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
