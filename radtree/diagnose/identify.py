"""Identifiability: which effects can a measured data set tell apart, and how well is each
fitted strength known?

Pure NumPy on small matrices, no simulation. The inputs are the effects' *signatures* on the
measured quantities — column j of the signature matrix S (observations × effects, lux) is the
change effect j makes to every measured value at its reference strength — and the noise of
each measured value, σ_i (lux; instrument noise and Monte Carlo error). Then:

* the **correlation** of two effects is the uncentred correlation (cosine) of their
  *whitened* signatures S_ij / σ_i: the fits have no intercept, so this is what decides
  whether one amplitude can stand in for another (the attribution's ``cosine``);
* the **condition number** of the whitened, column-normalised matrix says how close the set
  is to degenerate (1: orthogonal signatures; ∞: some combination is invisible);
* **groups** are the clusters of effects linked by |correlation| ≥ ``GROUP_CORR`` (single
  linkage): the data cannot separate the members of one group in a joint fit (an
  anticorrelated pair too: a joint fit trades one amplitude against the other; the loop's
  one-effect-at-a-time, non-negative fit can still tell such a pair apart by the sign of the
  residual, which is why the self-test's rule uses the signed correlation);
* an effect whose whitened signature norm (its SNR, √Σ(S_ij/σ_i)²) is below ``SNR_MIN`` is
  *below the noise*: not identifiable at all with these data;
* the **confidence interval** of a fitted strength is the profile-likelihood interval
  calibrated by the F distribution (exact for a linear strength with Gaussian noise of
  unknown scale): the strengths s with (SSE(s) − SSE_min) / (SSE_min / (n − 1)) ≤ F₁,ₙ₋₁(1−α),
  SSE the noise-weighted sum of squared residuals. With the noise scale known
  (``known_noise``) the χ²₁ quantile on SSE(s) − SSE_min is used instead.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats as sps

from radtree.errors import RadtreeError

#: effects whose whitened signatures correlate at least this much form one group
GROUP_CORR = 0.95
#: a whitened signature norm below this many noise units is "below the noise"
SNR_MIN = 3.0
#: two-sided confidence level of the strength intervals
CONFIDENCE = 0.95
#: relative noise (1 σ) of a measured value when the data do not state theirs
DEFAULT_NOISE = 0.03


def noise_sigma(expected: np.ndarray, mc_stderr: np.ndarray, noise: float = DEFAULT_NOISE,
                noise_lux: float | np.ndarray = 0.0) -> np.ndarray:
    """Noise (1 σ, lux) of a measured-minus-simulated value: the instrument's relative
    ``noise`` of the ``expected`` value, its floor ``noise_lux``, and the Monte Carlo error of
    the measurement's and the model's simulation (``mc_stderr`` each, NaN counts as 0)."""
    se = np.nan_to_num(np.asarray(mc_stderr, float), nan=0.0)
    return np.sqrt((noise * np.asarray(expected, float)) ** 2 + np.asarray(noise_lux) ** 2
                   + 2 * se ** 2)


def whiten(signatures: np.ndarray, sigma: np.ndarray | float | None) -> np.ndarray:
    """Signatures (observations × effects) divided by the noise of each observation."""
    s = np.atleast_2d(np.asarray(signatures, float))
    if sigma is None:
        return s
    sg = np.broadcast_to(np.asarray(sigma, float), (s.shape[0],))
    if np.any(~np.isfinite(sg)) or np.any(sg <= 0):
        raise RadtreeError("identifiability: every observation's noise must be > 0 lx")
    return s / sg[:, None]


def correlation_matrix(signatures: np.ndarray, sigma: np.ndarray | float | None = None
                       ) -> np.ndarray:
    """Uncentred correlation of the whitened signature columns (NaN for a zero column)."""
    w = whiten(signatures, sigma)
    norms = np.linalg.norm(w, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = w / norms[None, :]
    c = u.T @ u
    c[:, norms == 0] = np.nan
    c[norms == 0, :] = np.nan
    return np.clip(c, -1.0, 1.0)


def unique_snr(target: np.ndarray, others: np.ndarray | None,
               sigma: np.ndarray | float | None = None) -> float:
    """The part of ``target`` (one signature, lux per observation) that no combination of the
    columns of ``others`` (observations × k, lux) can reproduce, in noise units over all the
    observations: ‖(I − P) w‖ with w = target / σ and P the least-squares projection on the
    span of the whitened ``others``. Equivalently SNR · √(1 − R²), R² the squared multiple
    correlation of w with the others (1 / the variance inflation factor), and the z-score —
    amplitude ÷ its standard error, noise known — of the target's amplitude in a joint,
    unconstrained fit with every other column free; its square is the χ² that the residual
    signature adds over the noise. No others (or all zero): the plain whitened norm."""
    w = whiten(np.asarray(target, float)[:, None], sigma)[:, 0]
    if others is None or np.size(others) == 0:
        return float(np.linalg.norm(w))
    o = whiten(np.asarray(others, float).reshape(len(w), -1), sigma)
    o = o[:, np.linalg.norm(o, axis=0) > 0]
    if o.shape[1] == 0:
        return float(np.linalg.norm(w))
    u, sv, _ = np.linalg.svd(o, full_matrices=False)
    u = u[:, sv > 1e-10 * sv[0]]
    return float(np.linalg.norm(w - u @ (u.T @ w)))


def nearest_snr(target: np.ndarray, alternatives: np.ndarray,
                sigma: np.ndarray | float | None = None) -> float:
    """How far ``target`` (lux per observation) lies from the nearest of ``alternatives``
    (k × observations, lux: what another explanation can predict), in noise units over all the
    observations: min_k ‖(target − alternative_k) / σ‖ (∞ without alternatives). Fitting the
    target's cause instead of the nearest alternative lowers the noise-weighted sum of squares
    by about this squared (a χ² with that non-centrality)."""
    a = np.atleast_2d(np.asarray(alternatives, float))
    if a.size == 0:
        return math.inf
    t = np.asarray(target, float)
    d = whiten((t[None, :] - a).T, sigma)
    return float(np.min(np.linalg.norm(d, axis=0)))


def condition_number(signatures: np.ndarray, sigma: np.ndarray | float | None = None) -> float:
    """2-norm condition number of the whitened, column-normalised signature matrix (zero
    columns left out; ∞ when the matrix has fewer observations than effects)."""
    w = whiten(signatures, sigma)
    norms = np.linalg.norm(w, axis=0)
    w = w[:, norms > 0] / norms[norms > 0]
    if w.shape[1] == 0:
        return math.nan
    sv = np.linalg.svd(w, compute_uv=False)
    if w.shape[0] < w.shape[1] or sv[-1] <= 1e-12 * sv[0]:
        return math.inf
    return float(sv[0] / sv[-1])


def groups_of(names: Sequence[str], corr: np.ndarray, threshold: float = GROUP_CORR
              ) -> list[list[str]]:
    """Single-linkage clusters of ``names`` with |corr| ≥ ``threshold`` (NaN never links);
    each group in catalogue order, groups ordered by their first member."""
    n = len(names)
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(n):
        for j in range(i + 1, n):
            if np.isfinite(corr[i, j]) and abs(corr[i, j]) >= threshold:
                parent[root(j)] = root(i)
    out: dict[int, list[str]] = {}
    for i in range(n):
        out.setdefault(root(i), []).append(names[i])
    return list(out.values())


@dataclass
class Identifiability:
    """What a data set can tell apart (see the module doc).

    ``signatures``: observations × effects (lux at the reference strengths); ``sigma``: noise
    per observation (lux); ``snr``: whitened signature norm per effect; ``groups``: clusters
    of effects the data cannot separate (singletons included; below-noise effects each alone).
    """

    names: list[str]
    signatures: np.ndarray
    sigma: np.ndarray
    correlation: np.ndarray
    condition: float
    snr: np.ndarray
    groups: list[list[str]]
    threshold: float = GROUP_CORR
    observations: list[str] = field(default_factory=list)

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise RadtreeError(f"identifiability: no effect {name!r} "
                               f"(have {', '.join(self.names)})") from None

    def below_noise(self, name: str) -> bool:
        return not self.snr[self.index(name)] >= SNR_MIN

    def group_of(self, name: str) -> list[str]:
        return next(g for g in self.groups if name in g)

    def partners(self, name: str) -> list[str]:
        """The effects the data cannot separate from ``name``."""
        return [g for g in self.group_of(name) if g != name]

    def separable(self, a: str, b: str) -> bool:
        return b not in self.group_of(a)

    def distinguishable(self, name: str) -> bool:
        """Above the noise and alone in its group."""
        return not self.below_noise(name) and not self.partners(name)

    @property
    def confounded(self) -> list[list[str]]:
        """The groups of two or more effects."""
        return [g for g in self.groups if len(g) > 1]

    def max_abs_corr(self, name: str) -> tuple[float, str]:
        i = self.index(name)
        row = np.abs(self.correlation[i]).copy()
        row[i] = np.nan
        if not np.any(np.isfinite(row)):
            return math.nan, ""
        j = int(np.nanargmax(row))
        return float(row[j]), self.names[j]

    def frame(self) -> pd.DataFrame:
        """The correlation matrix as a labelled DataFrame."""
        return pd.DataFrame(self.correlation, index=self.names, columns=self.names)

    def table(self) -> pd.DataFrame:
        """One row per effect: its group, SNR, strongest correlation, verdict."""
        recs = []
        for k, g in enumerate(self.groups, start=1):
            for name in g:
                c, other = self.max_abs_corr(name)
                i = self.index(name)
                verdict = ("below the noise" if self.below_noise(name) else
                           "separable" if len(g) == 1 else
                           "not separable from " + ", ".join(x for x in g if x != name))
                recs.append({"effect": name, "group": k, "snr": float(self.snr[i]),
                             "max_abs_correlation": c, "most_correlated_with": other,
                             "verdict": verdict})
        return pd.DataFrame(recs, columns=["effect", "group", "snr", "max_abs_correlation",
                                           "most_correlated_with", "verdict"])

    def sentence(self, named: str) -> str:
        """"named X, but X and Y are not separable with these data" (or that X is)."""
        others = self.partners(named)
        if not others:
            return f"named {named}; with these data it is separable from every other candidate"
        every = [named] + others
        listed = ", ".join(every[:-1]) + " and " + every[-1]
        return (f"named {named}, but {listed} are not separable with "
                "these data (whitened signatures correlate ≥ "
                f"{self.threshold:.2f}); the choice among them is the lower CV error only")


def identifiability(names: Sequence[str], signatures: np.ndarray,
                    sigma: np.ndarray | float | None = None, threshold: float = GROUP_CORR,
                    observations: Sequence[str] = ()) -> Identifiability:
    """The identifiability of ``names`` with signatures (observations × effects, lux) and
    noise ``sigma`` (lux per observation; None: unit noise)."""
    s = np.asarray(signatures, float)
    if s.ndim != 2 or s.shape[1] != len(names):
        raise RadtreeError(f"identifiability: signature matrix {s.shape} does not match "
                           f"{len(names)} effect(s)")
    sg = np.ones(s.shape[0]) if sigma is None else np.broadcast_to(
        np.asarray(sigma, float), (s.shape[0],)).copy()
    corr = correlation_matrix(s, sg)
    snr = np.linalg.norm(whiten(s, sg), axis=0)
    above = [n for n, v in zip(names, snr) if v >= SNR_MIN]
    idx = [list(names).index(n) for n in above]
    groups = groups_of(above, corr[np.ix_(idx, idx)], threshold)
    groups += [[n] for n, v in zip(names, snr) if not v >= SNR_MIN]
    order = {n: i for i, n in enumerate(names)}
    groups.sort(key=lambda g: order[g[0]])
    return Identifiability(list(names), s, sg, corr, condition_number(s, sg), snr, groups,
                           threshold, list(observations))


# --------------------------------------------------------------------------- intervals
@dataclass(frozen=True)
class Interval:
    """A fitted strength and its confidence interval (same units as the strength)."""

    estimate: float
    lo: float
    hi: float
    level: float = CONFIDENCE

    def covers(self, value: float) -> bool:
        return self.lo <= value <= self.hi

    def text(self, fmt: Callable[[float], str] = lambda v: f"{v:.3g}") -> str:
        return f"{fmt(self.estimate)} [{fmt(self.lo)}, {fmt(self.hi)}]"


def profile_interval(strengths: np.ndarray, predictions: np.ndarray, residual: np.ndarray,
                     sigma: np.ndarray | float | None = None, known_noise: bool = False,
                     level: float = CONFIDENCE, n_params: int = 1) -> Interval:
    """Profile-likelihood interval of a strength scanned at ``strengths`` (ascending) with
    ``predictions[k]`` the change to the measured values at ``strengths[k]``.

    Unknown noise scale (default): F-calibrated, exact for a linear strength. ``known_noise``:
    ``sigma`` is the true noise, χ²₁ on the weighted SSE. The interval is the span of the
    scanned strengths inside the region (so it stays within the scanned bounds)."""
    xs = np.asarray(strengths, float)
    p = np.atleast_2d(np.asarray(predictions, float))
    r = np.asarray(residual, float)
    sg = np.ones(len(r)) if sigma is None else np.broadcast_to(np.asarray(sigma, float),
                                                               (len(r),))
    sse = (((r[None, :] - p) / sg[None, :]) ** 2).sum(axis=1)
    k = int(np.argmin(sse))
    n = len(r)
    if known_noise:
        inside = sse - sse[k] <= sps.chi2.ppf(level, 1)
    else:
        dof = max(1, n - n_params)
        scale = sse[k] / dof
        inside = (sse - sse[k] <= sps.f.ppf(level, 1, dof) * scale) if scale > 0 else (
            sse <= sse[k])
    return Interval(float(xs[k]), float(xs[inside].min()), float(xs[inside].max()), level)


def linear_interval(signature: np.ndarray, residual: np.ndarray, reference: float,
                    lo: float, hi: float, *, sigma: np.ndarray | float | None = None,
                    known_noise: bool = False, level: float = CONFIDENCE,
                    points: int = 2001) -> Interval:
    """Profile interval of a linear strength (signature at ``reference``) within [lo, hi]."""
    if reference <= 0:
        raise RadtreeError("a linear strength needs a positive reference")
    xs = np.linspace(lo, hi, points)
    x = np.asarray(signature, float)
    return profile_interval(xs, (xs / reference)[:, None] * x[None, :], residual, sigma,
                            known_noise, level)


def joint_intervals(signatures: np.ndarray, residual: np.ndarray,
                    sigma: np.ndarray | float | None = None, level: float = CONFIDENCE
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Every amplitude fitted *together* (weighted least squares, no bounds) and the
    half-width of its interval with the others free (the profile of a linear model: t on the
    diagonal of the covariance). Amplitudes are multiples of the reference strength; an
    effect whose partners can stand in for it gets a very wide (or infinite) half-width."""
    w = whiten(signatures, sigma)
    sg = np.ones(w.shape[0]) if sigma is None else np.broadcast_to(np.asarray(sigma, float),
                                                                   (w.shape[0],))
    y = np.asarray(residual, float) / sg
    n, p = w.shape
    a, *_ = np.linalg.lstsq(w, y, rcond=None)
    dof = n - p
    gram = w.T @ w
    if dof <= 0 or np.linalg.matrix_rank(gram) < p:
        return a, np.full(p, np.inf)
    s2 = float(np.sum((y - w @ a) ** 2) / dof)
    cov = s2 * np.linalg.inv(gram)
    return a, sps.t.ppf(0.5 + level / 2, dof) * np.sqrt(np.clip(np.diag(cov), 0, None))


# --------------------------------------------------------------------------- a diagnosis step
def step_identifiability(att: Any, expected: np.ndarray, mc_stderr: np.ndarray,
                         noise: float = DEFAULT_NOISE, noise_lux: float = 0.0
                         ) -> tuple[Identifiability, dict[str, Interval]]:
    """Identifiability of one step's candidates (an :class:`~.attribution.Attribution`) on its
    measured values (weighted by their noise), and the profile interval of every fitted
    strength — of the loop's own fit: unweighted least squares, noise scale unknown."""
    sigma = np.maximum(noise_sigma(expected, mc_stderr, noise, noise_lux), 1e-9)
    names = list(att.signatures)
    s = (np.column_stack([att.signatures[n].reference_hourly() for n in names]) if names
         else np.zeros((len(att.residual), 0)))
    ident = identifiability(names, s, sigma, observations=[])
    out: dict[str, Interval] = {}
    for n in names:
        sig = att.signatures[n]
        st = sig.strength
        if sig.kind == "binary" or st is None:
            continue
        if sig.kind == "linear":
            out[n] = linear_interval(sig.hourly[0], att.residual, float(sig.strengths[0]),
                                     0.0, st.hi)
        else:
            xs, preds = sig.choices()
            out[n] = profile_interval(xs, preds, att.residual)
    return ident, out
