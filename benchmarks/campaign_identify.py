"""Which of the catalogue's effects a campaign can tell apart — signatures only, no loop.

    python benchmarks/campaign_identify.py examples/mendoza-street CAMPAIGN.toml [-s A] [--rays N]

For every effect of the catalogue that applies to the scenario: its signature on the
campaign's observations (effects off in the scenario: switched on at the reference strength
minus the scenario; effects on: the scenario minus the scenario with the effect off), the
noise of every observation (the campaign's noise and twice the Monte Carlo variance, as the
self-test), then on noise-weighted values: the signal in noise units over all observations
(‖s/σ‖), the part of it outside the span of every other effect's signature (``joint``,
radtree.diagnose.identify.unique_snr) and the per-value RMS; "distinguishable" here is
joint ≥ SNR_MIN and RMS ≥ the loop's margin (radtree.diagnose.hidden.margin_snr) — stricter
than the self-test's rule (≥ SNR_MIN from each other effect's best fit, which this
signatures-only check does not fit), so a sufficient condition. Also the joint-fit groups at
|corr| ≥ 0.95. Prints one line per effect and the count.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from radtree.config import load_project
from radtree.diagnose.attribution import DEFAULT_MARGIN
from radtree.diagnose.campaign import load_campaign
from radtree.diagnose.campaign_sim import CampaignSimulator
from radtree.diagnose.effects import EFFECTS, EffectContext
from radtree.diagnose.hidden import margin_snr
from radtree.diagnose.identify import identifiability, noise_sigma, unique_snr
from radtree.diagnose.outcome import SNR_MIN


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("project")
    ap.add_argument("campaign")
    ap.add_argument("-s", "--scenario", default=None)
    ap.add_argument("--rays", type=int, default=None)
    a = ap.parse_args()
    t0, c0 = time.perf_counter(), time.process_time()
    proj = load_project(a.project)
    sc = proj.scenario(a.scenario) if a.scenario else proj.scenarios[0]
    camp = load_campaign(a.campaign, proj)
    sim = CampaignSimulator(proj, (), None, a.rays, None, campaign=camp)
    ctx = EffectContext(proj)
    base = sim.run(sc)
    names, cols = [], []
    for e in EFFECTS:
        if e.applies(ctx, sc):
            continue
        if e.is_on(ctx, sc):
            sig = base.lux - sim.run(e.switch_off(ctx, sc)).lux
        else:
            sig = sim.run(e.switch_on(ctx, sc, e.reference(ctx, sc))).lux - base.lux
        names.append(e.name)
        cols.append(sig)
    S = np.column_stack(cols)
    sigma = np.maximum(noise_sigma(base.lux, base.stderr, camp.noise, camp.noise_lux), 1e-9)
    w = S / sigma[:, None]
    ident = identifiability(names, S, sigma)
    n_ok = 0
    print(f"{camp.summary()}: {len(sim.labels)} observations, scenario {sc.name}, "
          f"{sim.rays} rays/sensor")
    for j, n in enumerate(names):
        snr = float(np.sqrt(np.mean(w[:, j] ** 2)))
        corr = ident.correlation[j].copy()
        corr[j] = np.nan
        k = int(np.nanargmax(corr))
        joint = unique_snr(S[:, j], np.delete(S, j, axis=1), sigma)
        ok = joint >= SNR_MIN and snr >= margin_snr(DEFAULT_MARGIN)
        n_ok += ok
        print(f"  {n:26s} {np.linalg.norm(w[:, j]):7.1f} σ, joint {joint:6.1f} σ, RMS "
              f"{snr:5.2f} σ, max corr {corr[k]:+.2f} ({names[k]})  "
              f"{'distinguishable' if ok else 'not distinguishable'}")
    print(f"distinguishable: {n_ok} of {len(names)}; groups at |corr| ≥ 0.95: "
          + ("; ".join(" ~ ".join(g) for g in ident.confounded) or "none")
          + f"  ({time.perf_counter() - t0:.0f} s wall, {time.process_time() - c0:.0f} s CPU)")


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
