"""The diagnose self-test checked (``radtree verify``, path *diagnose self-test*).

* :func:`fit_checks` — the attribution's fit alone: synthetic hourly residuals made of a
  linear effect's signature at a known strength plus seeded Gaussian noise σ; the strength
  :func:`radtree.diagnose.attribution.fit_candidate` recovers against the one injected. The
  least-squares amplitude of a signature x under noise σ has standard error σ / ‖x‖ (ordinary
  least squares, one regressor through the origin), so the claim is 3 of those standard errors.
* :func:`selftest_checks` — the whole loop (:func:`radtree.diagnose.selftest`): effects hidden
  in synthetic measurements of the Mendoza example (its own simulations with the effect on, a
  different seed, 3 % noise), the loop run from the base; every effect the self-test declares
  distinguishable must be named at the first step (exact), and the loop must shrink the gap.
"""

from __future__ import annotations

import logging
import math
import shutil
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from radtree.verify.checks import Check

log = logging.getLogger(__name__)

#: hourly façade means of a day (lx): the shape of the injected signature
SHAPE = np.array([200.0, 210, 190, 180, 190, 200, 215])
SELFTEST_EFFECTS = "more_stages,sky_diffuse,unfiltered_ground"


def fit_checks(strength: float = 18000.0, noise_lux: float = 20.0, seed: int = 1
               ) -> list[Check]:
    """Inject ``sky_diffuse`` at ``strength`` (lx of diffuse sky; its signature
    :data:`SHAPE` at the reference 12 000 lx) under ``noise_lux`` noise; recover it."""
    from radtree.config import Scenario, load_project
    from radtree.diagnose.attribution import Signature, fit_candidate
    from radtree.diagnose.effects import EffectContext, get_effect
    from radtree.verify.compare import MENDOZA

    project = load_project(MENDOZA)
    ctx, effect = EffectContext(project), get_effect("sky_diffuse")
    ref = 12000.0
    base = effect.strength(ctx, Scenario("x", "louvers"))
    if base is None:
        raise RuntimeError("sky_diffuse has no strength to fit")
    st = replace(base, mode="linear", grid=(ref,), reference=ref)
    sig = Signature(effect, "linear", st, np.array([ref]), SHAPE[None, :], np.zeros((1, 3)),
                    ["higher", "intermediate", "lower"], [], ref)
    rng = np.random.default_rng(seed)
    residual = SHAPE * strength / ref + noise_lux * rng.standard_normal(len(SHAPE))
    fit = fit_candidate(sig, residual, ctx, project.scenario("A"), None)
    se = ref * noise_lux / float(np.linalg.norm(SHAPE))
    got = math.nan if fit.strength is None else float(fit.strength)
    return [Check(f"diagnose attribution: sky_diffuse injected at {strength:g} lx into 7 "
                  f"synthetic hourly residuals (σ {noise_lux:g} lx), strength recovered (lx)",
                  "-", strength, got, 3.0 * se, 3.0 * se,
                  "the strength injected; least-squares amplitude SE σ/‖x‖ (3 SE)")]


def selftest_checks(folder: Path | None = None, *, scenario: str = "B", rays: int = 128,
                    effects: str = SELFTEST_EFFECTS, noise: float = 0.03) -> list[Check]:
    """The hidden-effect self-test on a copy of the Mendoza example (7 hours, façade grid
    only, ``rays`` per sensor, NumPy), ``effects`` hidden in ``scenario``."""
    from radtree.config import load_project
    from radtree.diagnose import DiagnoseOptions, selftest
    from radtree.diagnose.effects import parse_effects
    from radtree.verify.compare import MENDOZA

    with tempfile.TemporaryDirectory(prefix="radtree-verify-diagnose-") as tmp:
        root = Path(folder or tmp) / "mendoza"
        shutil.copytree(MENDOZA, root, ignore=shutil.ignore_patterns(
            "build", "results", "report", "diagnose", "sweep"))
        project = load_project(root, overrides={"engine.rays": rays, "sensors.dense_grid": False,
                                                "sensors.dense_hours": []})
        res = selftest(project, noise=noise, options=DiagnoseOptions(
            scenario=scenario, effects=parse_effects(effects), max_steps=2, workers=1))
    out = []
    what = (f"diagnose self-test: effect hidden in Mendoza {scenario} (7 h, {rays} rays, "
            f"{noise:.0%} noise)")
    ref = "the effect hidden in the synthetic measurement"
    for c in res.cases:
        rec = c.record()
        log.info(f"{what}: {c.effect}: distinguishable {c.distinguishable}, named "
                 f"{c.named!r}, nRMSE {rec['rmse_before']:.3f} → {rec['rmse_after']:.3f}")
        if c.distinguishable:
            out.append(Check(f"{what}: {c.effect} named at the first step", "-", 1.0,
                             float(c.correct), 0.0, 0.0, ref))
        out.append(Check(f"{what}: {c.effect}, every step of the loop shrinks the gap", "-", 1.0,
                         float(c.gap_shrinks), 0.0, 0.0, ref))
    return out
