"""Attribution: which missing effect explains the residual?

For every candidate effect (applies to the scenario and is off in it) the *signature* is the
change the effect makes to the simulated hourly grid means — and to the per-row daily means —
when switched on: ``run(scenario + effect) − run(scenario)`` with the same seed (common random
numbers). The residual r = measured − simulated is then fitted by each signature:

* on/off effects: the signature itself (nothing is fitted);
* ``linear`` strengths: a non-negative amplitude a of the signature at the reference strength
  (strength = a × reference, clipped to the bounds);
* ``search`` strengths: a 1-D search over the strengths, the signature re-simulated at a few
  strengths and interpolated linearly between them (integer strengths: only the simulated whole
  numbers); the strength "off" (no change) is among the choices.

Candidates are ranked by the **leave-one-hour-out cross-validated RMSE**: the strength is fitted
on n − 1 hours and predicts the left-out hour, for every hour, so a flexible effect cannot win
by bending through seven points. The current model (no change) has CV RMSE = its RMSE. The
winner must lower the CV RMSE by more than ``margin`` (relative, default 5 %). Its *explained
fraction* is 1 − Σ(r − fit)² / Σ r² with the strength fitted on all hours.

A **tie** is declared when another candidate that also beats the margin has a signature whose
uncentred correlation (cosine similarity — the fit has no intercept, so this is what decides
whether two amplitudes can stand in for each other) with the winner's exceeds ``TIE_CORR``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from radtree.config import Scenario
from radtree.diagnose.effects import EFFECTS, Effect, EffectContext, Strength, candidates
from radtree.diagnose.simulate import Run, Simulator

log = logging.getLogger(__name__)

TIE_CORR = 0.9
DEFAULT_MARGIN = 0.05
_FINE = 201  # strengths scanned by a continuous 1-D search


def cosine(a: np.ndarray, b: np.ndarray) -> float:
    """Uncentred correlation Σab / (|a||b|); NaN when either vector is zero."""
    na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    if na == 0 or nb == 0:
        return math.nan
    return float(np.dot(a, b) / (na * nb))


@dataclass
class Signature:
    """An effect's change to the hourly means (and row daily means) vs the base run.

    ``strengths``: simulated strengths (ascending; ``[nan]`` for on/off effects); ``hourly``:
    (k, hours) lx; ``rows``: (k, rows) lx; ``scenarios``: the switched scenarios.
    """

    effect: Effect
    kind: str
    strength: Strength | None
    strengths: np.ndarray
    hourly: np.ndarray
    rows: np.ndarray
    row_names: list[str]
    scenarios: list[Scenario]
    reference: float | None

    def reference_hourly(self) -> np.ndarray:
        """The signature at the reference strength (on/off: the signature)."""
        if self.kind == "binary" or self.reference is None:
            return self.hourly[0]
        return self.at(self.reference)[0]

    def at(self, s: float | None) -> tuple[np.ndarray, np.ndarray]:
        """(hourly, rows) change at strength ``s`` (interpolated; linear: scaled)."""
        if self.kind == "binary" or s is None:
            return self.hourly[0], self.rows[0]
        if self.kind == "linear":
            f = float(s) / float(self.strengths[0])
            return f * self.hourly[0], f * self.rows[0]
        xs = np.concatenate([[0.0], self.strengths])
        hs = np.vstack([np.zeros(self.hourly.shape[1]), self.hourly])
        rs = np.vstack([np.zeros(self.rows.shape[1]), self.rows])
        s = float(np.clip(s, xs[0], xs[-1]))
        h = np.array([np.interp(s, xs, hs[:, j]) for j in range(hs.shape[1])])
        r = np.array([np.interp(s, xs, rs[:, j]) for j in range(rs.shape[1])])
        return h, r

    def choices(self) -> tuple[np.ndarray, np.ndarray]:
        """For a search: strengths scanned and the hourly signature at each (rows)."""
        assert self.strength is not None
        if self.strength.integer:
            xs = np.concatenate([[0.0], self.strengths])
        else:
            xs = np.linspace(0.0, float(self.strengths[-1]), _FINE)
        return xs, np.array([self.at(x)[0] for x in xs])


@dataclass
class CandidateFit:
    """One candidate's fit to the residual (lux unless named ``n…``)."""

    effect: str
    title: str
    kind: str
    strength: float | None
    strength_text: str
    change: str
    prediction: np.ndarray
    row_prediction: np.ndarray
    explained_fraction: float
    rmse_fit_lux: float
    cv_rmse_lux: float
    cv_strengths: list[float | None]
    row_rms_after_lux: float = math.nan
    corr_with_winner: float = math.nan
    improves: bool = False


@dataclass
class Attribution:
    """The ranking of one diagnosis step."""

    residual: np.ndarray
    mean_measured: float
    baseline_cv_lux: float
    fits: list[CandidateFit]
    signatures: dict[str, Signature]
    not_candidates: dict[str, str]
    margin: float
    winner: CandidateFit | None = None
    tie_with: list[str] = field(default_factory=list)
    similarity: pd.DataFrame | None = None

    def table(self) -> pd.DataFrame:
        """Ranked candidates (normalised RMSEs = lux / mean measured)."""
        mm = self.mean_measured
        rows = []
        for rank, f in enumerate(self.fits, start=1):
            rows.append({
                "rank": rank, "effect": f.effect, "kind": f.kind,
                "strength": f.strength, "strength_text": f.strength_text,
                "explained_fraction": f.explained_fraction,
                "nrmse_fit": f.rmse_fit_lux / mm, "cv_nrmse": f.cv_rmse_lux / mm,
                "cv_gain": 1.0 - f.cv_rmse_lux / self.baseline_cv_lux
                if self.baseline_cv_lux > 0 else math.nan,
                "improves": f.improves, "corr_with_winner": f.corr_with_winner,
                "row_rms_after_lux": f.row_rms_after_lux, "change": f.change,
            })
        return pd.DataFrame(rows)


# --------------------------------------------------------------------------- signatures
def compute_signatures(sim: Simulator, ctx: EffectContext, base: Scenario, base_run: Run,
                       effects: Iterable[Effect]) -> dict[str, Signature]:
    """Simulate each effect switched on at its strengths; return the signatures."""
    out: dict[str, Signature] = {}
    row_names = list(base_run.rows.columns)
    base_rows = base_run.row_daily().to_numpy(float)
    effects = tuple(effects)
    sim.trace_ahead(signature_scenarios(ctx, base, effects))
    for e in effects:
        st = e.strength(ctx, base)
        kind = "binary" if st is None else st.mode
        pts = _points(st)
        hourly, rows, scs = [], [], []
        for p in pts:
            sc = e.switch_on(ctx, base, p)
            run = sim.run(sc)
            if run.seconds > 0.05:
                log.debug("    %s%s: simulated in %.1f s", e.name,
                         "" if p is None or st is None else f" @ {st.text(p)}", run.seconds)
            hourly.append(run.lux - base_run.lux)
            rows.append(run.row_daily().reindex(row_names).to_numpy(float) - base_rows)
            scs.append(sc)
        strengths = np.array([np.nan if p is None else float(p) for p in pts])
        out[e.name] = Signature(e, kind, st, strengths, np.array(hourly), np.array(rows),
                                row_names, scs, None if st is None else st.reference)
    return out


def _points(st: Strength | None) -> list[float | None]:
    return [None] if st is None else list(st.search_points())


def signature_scenarios(ctx: EffectContext, base: Scenario, effects: Iterable[Effect]
                        ) -> list[Scenario]:
    """The switched scenarios :func:`compute_signatures` simulates (to trace them ahead)."""
    return [e.switch_on(ctx, base, p) for e in effects for p in _points(e.strength(ctx, base))]


# --------------------------------------------------------------------------- fitting
def _fit(sig: Signature, r: np.ndarray, idx: np.ndarray) -> tuple[float | None, np.ndarray]:
    """Strength fitted on hours ``idx`` and the hourly prediction at it (all hours)."""
    if sig.kind == "binary" or sig.strength is None:
        return None, sig.hourly[0]
    st = sig.strength
    if sig.kind == "linear":
        x = sig.hourly[0]
        den = float(np.dot(x[idx], x[idx]))
        a = float(np.dot(r[idx], x[idx]) / den) if den > 0 else 0.0
        ref = float(sig.strengths[0])
        a = float(np.clip(a, 0.0, st.hi / ref))
        return a * ref, a * x
    xs, preds = sig.choices()
    sse = ((r[idx][None, :] - preds[:, idx]) ** 2).sum(axis=1)
    k = int(np.argmin(sse))  # ties → the smallest strength
    return float(xs[k]), preds[k]


def fit_candidate(sig: Signature, r: np.ndarray, ctx: EffectContext, base: Scenario,
                  row_residual: np.ndarray | None) -> CandidateFit:
    """In-sample fit (all hours) and leave-one-hour-out CV of one signature."""
    n = len(r)
    all_idx = np.arange(n)
    s_all, pred = _fit(sig, r, all_idx)
    st = sig.strength
    if s_all is not None and st is not None:
        s_all = float(st.round(s_all)) if s_all > 0 else 0.0
        pred = sig.at(s_all)[0]
    cv_res, cv_s = np.zeros(n), []
    for i in range(n):
        idx = np.delete(all_idx, i)
        s_i, p_i = _fit(sig, r, idx)
        cv_res[i] = r[i] - p_i[i]
        cv_s.append(s_i)
    row_pred = sig.at(s_all)[1] if s_all is not None else sig.rows[0]
    ss = float(np.sum(r ** 2))
    explained = 1.0 - float(np.sum((r - pred) ** 2)) / ss if ss > 0 else math.nan
    effect = sig.effect
    if s_all is None:
        stext, change = "on", effect.describe(ctx, base, None)
    elif s_all <= 0:
        stext, change = "off (0)", "(no change)"
    else:
        assert st is not None
        stext, change = st.text(s_all), effect.describe(ctx, base, s_all)
    fit = CandidateFit(effect.name, effect.title, sig.kind, s_all, stext, change, pred,
                       row_pred, explained, float(np.sqrt(np.mean((r - pred) ** 2))),
                       float(np.sqrt(np.mean(cv_res ** 2))), cv_s)
    if row_residual is not None and len(row_residual) == len(row_pred):
        fit.row_rms_after_lux = float(np.sqrt(np.mean((row_residual - row_pred) ** 2)))
    return fit


def attribute(sim: Simulator, *, ctx: EffectContext, base: Scenario, base_run: Run,
              measured: np.ndarray, row_residual: np.ndarray | None = None,
              catalogue: Iterable[Effect] = EFFECTS, margin: float = DEFAULT_MARGIN,
              exclude: Iterable[str] = (), reuse: dict[str, Signature] | None = None
              ) -> Attribution:
    """Rank the candidate effects of ``base`` against the residual measured − base (lx).

    ``reuse``: signatures kept from an earlier step (by effect name) are taken from it instead
    of being simulated on ``base``, and the ones simulated are added to it."""
    r = np.asarray(measured, float) - base_run.lux
    cands, why = candidates(ctx, base, catalogue)
    skip = set(exclude)
    for e in [c for c in cands if c.name in skip]:
        why[e.name] = "left out (tried at this step and rejected)"
    cands = [c for c in cands if c.name not in skip]
    if reuse is None:
        sigs = compute_signatures(sim, ctx, base, base_run, cands)
    else:
        reuse.update(compute_signatures(sim, ctx, base, base_run,
                                        [c for c in cands if c.name not in reuse]))
        sigs = {c.name: reuse[c.name] for c in cands}
    fits = [fit_candidate(sigs[c.name], r, ctx, base, row_residual) for c in cands]
    baseline = float(np.sqrt(np.mean(r ** 2)))
    for f in fits:
        f.improves = (f.cv_rmse_lux < (1.0 - margin) * baseline
                      and (f.strength is None or f.strength > 0))
    fits.sort(key=lambda f: (f.cv_rmse_lux, f.effect))
    att = Attribution(r, float(np.mean(measured)), baseline, fits, sigs, why, margin)
    att.similarity = similarity_matrix(sigs)
    choose_winner(att)
    return att


def choose_winner(att: Attribution, skip: Iterable[str] = ()) -> None:
    """Set ``winner`` (best improving candidate not in ``skip``) and its tie partners."""
    skip = set(skip)
    att.winner, att.tie_with = None, []
    for f in att.fits:
        f.corr_with_winner = math.nan
    passing = [f for f in att.fits if f.improves and f.effect not in skip]
    if not passing:
        return
    w = passing[0]
    att.winner = w
    wv = w.prediction if np.any(w.prediction) else att.signatures[w.effect].reference_hourly()
    for f in att.fits:
        v = f.prediction if np.any(f.prediction) else \
            att.signatures[f.effect].reference_hourly()
        f.corr_with_winner = cosine(wv, v)
        if f is not w and f in passing and f.corr_with_winner > TIE_CORR:
            att.tie_with.append(f.effect)


def similarity_matrix(sigs: dict[str, Signature]) -> pd.DataFrame:
    """Cosine similarity of the reference signatures (hourly)."""
    names = list(sigs)
    mat = np.array([[cosine(sigs[a].reference_hourly(), sigs[b].reference_hourly())
                     for b in names] for a in names]) if names else np.zeros((0, 0))
    return pd.DataFrame(mat, index=names, columns=names)
