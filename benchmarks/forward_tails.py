"""Where the forward engine's heavy tail comes from: every patch crossing, or every launched
photon's whole contribution (its lineage), of runs at the project's defaults.

Run through ``benchmarks/forward.py`` (``--crossings SEED …`` and ``--lineage SEED …``, with
``--hours`` and ``--scenarios``); the figures are in that module's docstring.

* :func:`crossings`: each patch crossing with its flux, launched flux and events, split by
  source (sun / sky), path (specular only, 1 or more diffuse events) and where the crossing
  segment started. A weight window's identical copies cross as several light crossings, so
  this view can hide a heavy *photon*:
* :func:`lineage`: one round at the defaults (after the pilot, the window open as the run opens
  it) traced with one tally row per launched photon, per launch ring: the ring's contribution
  and its standard error, the share of photons that reach the patches, the share of the
  ring's light its ten largest photons carry and the kurtosis of the per-photon estimates —
  the heavy tail of the estimate itself.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from radtree.config import effective_project
from radtree.engines.forward import ForwardSettings, trace_forward


def crossings(cases, seeds: list[int], window: float) -> None:  # type: ignore[no-untyped-def]
    """Every patch crossing of runs at the project's defaults (``window``: the weight-window
    factor; with a window only the rounds it applies to, without one every main round),
    recorded with the crossing photon's flux, launched flux (its ring: the focused
    launch gives each ring's photons an equal share of the ring's flux) and events: where the
    heavy tail of the façade estimate comes from. The tracer is subclassed here (each segment
    tallied once more into a row per photon), so the runs are slower than plain ones."""
    from radtree.engines.forward import run as forward_run
    from radtree.engines.forward.tracer import ForwardTracer

    rec: list[np.ndarray] = []

    class Recording(ForwardTracer):
        counted = False
        sky = 0.0   # 1 while tracing a launch that did not start as the sun's beam

        def run(self, photons):  # type: ignore[no-untyped-def]
            # the sun's photons all travel one way (the sky's: each its own direction)
            self.sky = 0.0 if len(photons) > 1 and np.ptp(photons.d, axis=0).max() < 1e-12 \
                else 1.0
            return super().run(photons)

        def _advance(self, ph):  # type: ignore[no-untyped-def]
            seen = ph if not ph.direct.any() else ph.take(~ph.direct)
            tri, t = self.geo.caster.first_hit(seen.o, seen.d)   # (explicit surfaces only)
            t = np.where(tri < 0, np.inf, t)
            rows = np.zeros((len(seen), self.det.count))
            self.det.tally(seen.o, seen.d, t, seen.w, np.arange(len(seen)), rows)
            c = rows.sum(axis=1)
            hit = np.flatnonzero(c > 0)
            if len(hit) and self.counted and (window <= 0 or self.window is not None):
                dist = np.linalg.norm(seen.o[hit] - self.det_centre, axis=1)
                rec.append(np.column_stack([c[hit], seen.w[hit], seen.w0[hit],
                                            seen.ndiff[hit], seen.nspec[hit],
                                            np.full(len(hit), self.sky), dist]))
            return super()._advance(ph)

    def tracer(h, batches):  # type: ignore[no-untyped-def]
        s = h.settings
        tr = Recording(h.geo, h.optics, h.det, batches, threshold=s.threshold,
                       splitting=s.splitting, max_bounces=s.max_bounces,
                       max_specular=s.max_specular, chunk=s.chunk, rng=h.rng,
                       splitting_near=h.near, guide=h.guide,
                       guided_roulette=s.guided_roulette)
        tr.counted = batches > 1   # the pilot's scout traces one batch: not recorded
        tr.det_centre = h.target
        return tr

    forward_run._tracer = tracer  # type: ignore[assignment]
    for proj, name, hour, built, st in cases:
        s = replace(ForwardSettings.from_params(proj.engine, built.ab), window=window)
        for k in seeds:
            rec.clear()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                r = trace_forward(built.scene, st, replace(s, seed=k), ["facade"], workers=1)
            m, se = r.grid_mean("facade")
            a = np.vstack(rec)
            c, w, w0 = a[:, 0], a[:, 1], a[:, 2]
            mc = c.mean()
            print(f"  {name} {hour} seed {k} window {window:g}: {m:.1f} ± {se:.1f} lx, "
                  f"{(r.photons + r.sizing_photons) / 1e6:.1f} M photons (sizing round "
                  f"included), {len(c)} crossings, effective {c.sum() ** 2 / (c ** 2).sum():.0f}"
                  f"; largest {c.max() / c.sum():.2%} of the total", flush=True)
            for f in (10, 30, 100):
                big = c > f * mc
                print(f"    crossings > {f:3d} × mean: {big.sum():5d} carry {c[big].sum() / c.sum():6.1%}"
                      f"; their launched flux median {np.median(w0[big]) if big.any() else 0:7.1f}"
                      f" lm (all: {np.median(w0):.1f}), flux / launched max "
                      f"{(w / w0)[big].max() if big.any() else 0:.2f}", flush=True)
            _crossing_classes(a, mc)


def _crossing_classes(a: np.ndarray, mean_crossing: float) -> None:
    """Per class of crossing (source; diffuse/specular events before it; where its segment
    started): its share of the crossings' flux, of the heavy crossings (> 10 × the mean) and
    the equal crossings it is worth (Σc)² / Σc²."""
    c, nd, ns, sky, dist = a[:, 0], a[:, 3], a[:, 4], a[:, 5], a[:, 6]
    total = c.sum()
    classes = {
        "sky, no event": (sky == 1) & (nd == 0) & (ns == 0),
        "sky, specular only": (sky == 1) & (nd == 0) & (ns > 0),
        "sky, diffuse": (sky == 1) & (nd > 0),
        "sun, specular only": (sky == 0) & (nd == 0),
        "sun, 1 diffuse": (sky == 0) & (nd == 1),
        "sun, ≥ 2 diffuse": (sky == 0) & (nd >= 2),
        "segment from < 0.5 m": dist < 0.5,
        "segment from 0.5–2 m": (dist >= 0.5) & (dist < 2.0),
        "segment from ≥ 2 m": dist >= 2.0,
    }
    big = c > 10 * mean_crossing
    for label, m in classes.items():
        if not m.any():
            continue
        cm = c[m]
        print(f"    {label:22s}: {m.sum():7d} crossings, {cm.sum() / total:6.1%} of the flux, "
              f"worth {cm.sum() ** 2 / (cm ** 2).sum():8.0f}; > 10 × mean: {(m & big).sum():4d} "
              f"({c[m & big].sum() / total:5.1%} of the flux), largest {cm.max() / total:.2%}",
              flush=True)



def lineage(cases, seeds: list[int], guided: bool = True) -> None:  # type: ignore[no-untyped-def]
    """Per launch ring, one round's photons each with its own tally row (module text); the
    scenario's own settings (its switches applied); ``guided`` False: the roulette's reference
    stays the launched flux (``ForwardSettings.guided_roulette``, the behaviour before)."""
    from radtree.engines.forward import run as forward_run
    from radtree.engines.forward.sources import EnvironmentSource

    for proj, name, hour, built, st in cases:
        eff = effective_project(proj, proj.scenario(name)).engine
        for seed in seeds:
            s = replace(ForwardSettings.from_params(eff, built.ab), seed=seed,
                        guided_roulette=guided)
            h = forward_run._plan(built.scene, st, s, ["facade"], backend="auto", workers=1,
                                  label=None)
            tr = forward_run._tracer(h, s.batches)
            strata, _, _ = forward_run._focus(h)
            assert strata is not None, "the lineage view needs the focused launch"
            forward_run._window_from_pilot(h, tr, strata)
            at = forward_run._at_points(h)
            sky = forward_run._sky_rows(h)
            sky_lux = 0.0 if sky is None else float(sky.mean())
            level = "none" if tr.window is None else f"{tr.window.level:.3g} lm"
            print(f"  {name} {hour} seed {seed}: direct sun at the points {at.mean():.1f} lx, "
                  f"unscattered sky at the points {sky_lux:.1f} lx, window level {level}, "
                  f"guided roulette {s.guided_roulette}", flush=True)
            rows = [_ring(h, tr, st_) for st_ in strata]
            var = sum(r[2] ** 2 for r in rows)
            print(f"   one round: {sum(r[1] for r in rows):.1f} ± {var ** 0.5:.1f} lx (the rest of "
                  f"the façade mean)", flush=True)
            for st_, (n, mu, se, hit, top, kurt) in zip(strata, rows):
                kind = "sky" if isinstance(h.sources[st_.source], EnvironmentSource) else "sun"
                print(f"   {kind} ring {st_.a:5.1f}–"
                      f"{st_.b:5.1f} m: {n:7d} photons, {mu:8.2f} ± {se:6.2f} lx (variance share "
                      f"{se * se / var if var > 0 else 0:6.1%}), reach {hit:.4f}, ten largest "
                      f"{top:.3f}, kurtosis {kurt:.0f}", flush=True)


def _ring(h, tr, st_) -> tuple[int, float, float, float, float, float]:  # type: ignore[no-untyped-def]
    """One ring's photons, one tally row each: photons, the ring's contribution (lux) and its
    standard error, the share reaching the patches, the ten largest photons' share, kurtosis."""
    from radtree.engines.forward.tracer import Photons

    det, m = h.det, st_.photons
    src = h.sources[st_.source]
    ys = []
    for c0 in range(0, m, 65536):
        k = min(65536, m - c0)
        launch = src.ring_launch(k, st_.a, st_.b, h.target, h.rng)
        launch.flux *= k / m
        tr.tally = np.zeros((k, det.count))
        tr.run(Photons.start(launch, np.arange(k), st_.source in h.direct))
        ys.append(tr.tally.sum(axis=1) / (det.count * det.area))
    y = np.concatenate(ys) * m     # each photon's estimate of the ring's contribution (lux)
    mu, sd = float(y.mean()), float(y.std(ddof=1))
    top = float(np.sort(y)[::-1][:10].sum() / y.sum()) if y.sum() > 0 else 0.0
    kurt = float(np.mean((y - mu) ** 4) / sd ** 4) if sd > 0 else 0.0
    return m, mu, sd / np.sqrt(m), float(np.mean(y > 0)), top, kurt
