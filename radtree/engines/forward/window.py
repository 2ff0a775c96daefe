"""The weight window: photons too heavy for where they are split into lighter copies.

**Why** (reference street, scenario B at 12:30, defaults, seed 1, every patch crossing of the
counted rounds recorded: benchmarks/forward.py ``--crossings``): the focused launch gives the
outer rings (16–48 m from the focus) few photons for their area, so each starts with hundreds
of lumens against ~26 lm for the median crossing photon. The flux photons bring to the façade
patches is therefore spread over five decades: the 1 % of crossings carrying more than 10 ×
the mean crossing made 23 % of the scattered façade light (their launched flux: median 222 lm),
those above 30 × (27 of 14 981) 10 %, the largest single crossing 1 %: 14 981 crossings worth
1 316 equal ones. The weights were *not* grown by the guide (a heavy crossing's flux was at
most 1.6 × its launched flux, most at the roulette floor 0.05 ×); they came with the launch
and reached the façade through the five slat layers (4–7 specular events after 1–3 diffuse
ones). A mean of a few such crossings is the skewed estimate whose batch error is low exactly
when they are missing (z s.d. 1.26, |z| > 3 in 2 % over 50 seeds before this module). With the
window (same seed): 31 740 crossings worth 12 442 equal ones, none above 10 × the mean, the
largest 0.03 % of the total.

**What** (the weight-window method of MCNP: Booth 1982, "Automatic importance estimation in
forward Monte Carlo calculations", Trans. Am. Nucl. Soc. 41, 308, and Booth & Hendricks 1984,
Nucl. Technol./Fusion 5, 90 — both cited from memory; the technique as documented by Geant4's
biasing notes, "Weight window technique", and TOPAS's ``WeightWindow``): at every surface event
a photon whose flux w exceeds the window's upper bound W(p) at the event point p is split into
n = ⌈w / W(p)⌉ copies (at most ``max_split``), each carrying w / n and 1 / n of the roulette's
reference flux (so the roulette below the window does not undo the split). Each copy then
draws its own event direction. Splitting keeps every expected tally (the copies' fluxes sum to
w and each is traced as the photon would be): the estimate stays unbiased for any window.

The bound follows the importance of a point for the patches. A diffuse event at distance d
from the target grid's centre reaches the sphere of radius r around it with a share ∝ (r/d)²
of its flux (the guide's cone, :mod:`.guide`), so

    W(p) = level · max(1, (d / r)²),

``level`` (lm) = ``factor`` × the mean flux per patch crossing. With the focused launch it is
predicted from the pilot's crossings as the first round's allocation will make them
(:func:`radtree.engines.forward.strata.predicted_crossings`), so every round — the sizing round
too — traces with the window; otherwise it comes from the hour's first round, traced without
it. Every later round uses the same level, so whether a photon splits never depends on the
round it belongs to. Near the patches a photon may carry at most ``factor`` mean crossings;
far away proportionally more, since only (r/d)² of it can arrive.

**Why from the pilot** (2026-12-07): a sizing round without the window read a 2–4 × larger
error than the windowed rounds after it, so it predicted 2–4 × the photons needed (B 12:30:
runs ended at 0.7–1.9 % for the 2 % target, 20 of 50 at the 15 M cap; F 12:30 with the
roulette of :mod:`.tracer` fixed: 4–5 M photons for 0.5–0.9 %). With the level from the pilot
F and B 12:30 reach 2 % in their first round (0.9 M photons counted; F: 47 of 50 seeds).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MAX_SPLIT = 64
"""Copies at most per photon and event (TOPAS's ``MaximumSplitNumber`` defaults to 100)."""


@dataclass(frozen=True)
class WeightWindow:
    """Split photons heavier than ``level`` · max(1, (d / ``radius``)²) lm at distance d (m)
    from ``target`` (m)."""

    target: np.ndarray
    radius: float
    level: float
    max_split: int = MAX_SPLIT

    def bound(self, points: np.ndarray) -> np.ndarray:
        """The window's upper bound (lm) at ``points`` (k, 3), m."""
        d = np.linalg.norm(points - self.target, axis=1)
        return self.level * np.maximum(1.0, (d / self.radius) ** 2)

    def aimed(self, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
        """Rays (``origins`` m, unit ``dirs``) that pass within ``radius`` of ``target``
        ahead of their origin."""
        rel = self.target - origins
        t = np.einsum("ij,ij->i", rel, dirs)
        miss = np.linalg.norm(rel - t[:, None] * dirs, axis=1)
        return (t > 0) & (miss <= self.radius)

    def aimed_copies(self, origins: np.ndarray, dirs: np.ndarray, flux: np.ndarray
                     ) -> np.ndarray:
        """Copies of photons leaving ``origins`` along ``dirs`` with ``flux`` (lm): those
        aimed at the sphere are held to ``level`` itself (their importance does not fall
        with distance: they arrive unless the surfaces on the way stop them)."""
        n = np.where(self.aimed(origins, dirs), np.ceil(flux / self.level), 1.0)
        return np.clip(n, 1, self.max_split).astype(np.int64)

    def copies(self, points: np.ndarray, flux: np.ndarray) -> np.ndarray:
        """Copies of each photon of ``flux`` (lm) at ``points``: ⌈flux / bound⌉ in
        1 … ``max_split``."""
        n = np.ceil(flux / self.bound(points))
        return np.clip(n, 1, self.max_split).astype(np.int64)


def window_level(factor: float, crossed_flux: float, crossings: float) -> float | None:
    """The window's ``level`` (lm): ``factor`` × the mean flux per patch crossing
    (``crossed_flux`` lm over ``crossings``); None (no window) without crossings or factor."""
    if factor <= 0 or crossings <= 0 or crossed_flux <= 0:
        return None
    return factor * crossed_flux / crossings
