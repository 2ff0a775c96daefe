"""Generate the SYNTHETIC readings of campaign-rich.toml (run from the repository root):

    python examples/mendoza-street/make_campaign_rich.py

Truth: scenario A plus a clear Perez sky of 15 000 lx diffuse horizontal (what `radtree
diagnose` fits on the real data), traced with the NumPy engine (seed 101, 1024
rays per sensor) on every day, hour and sensor of the campaign; each reading × (1 + noise · N(0, 1)),
noise from the campaign, numpy seed 2024. Writes data/campaign-rich/<group>_<day>.csv in the
`time,sensor,lux` shape of radtree.measurements.load_measured.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from radtree.config import load_project
from radtree.diagnose.campaign import load_campaign
from radtree.diagnose.campaign_sim import CampaignSimulator
from radtree.diagnose.effects import EffectContext, get_effect
from radtree.fileio import write_text

HERE = Path(__file__).resolve().parent
TRUTH_SKY_LUX = 15000.0
TRACE_SEED = 101
TRACE_RAYS = 1024   # the readings' rays (the campaign's own `rays` sets how it is diagnosed)
NOISE_SEED = 2024


def main() -> None:
    project = load_project(HERE)
    campaign = load_campaign(HERE / "campaign-rich.toml", project)
    sim = CampaignSimulator(project, (), None, TRACE_RAYS, TRACE_SEED, campaign=campaign)
    ctx = EffectContext(project)
    truth = get_effect("sky_diffuse").switch_on(ctx, project.scenario("A"), TRUTH_SKY_LUX)
    run = sim.run(truth)
    rng = np.random.default_rng(NOISE_SEED)
    values = run.lux * (1.0 + campaign.noise * rng.standard_normal(len(run.lux)))
    assert sim.layout is not None
    files: dict[tuple[str, str], list[str]] = {}
    for obs, v in zip(sim.layout.observations, values):
        files.setdefault((obs.group, obs.day), []).append(f"{obs.time},{obs.sensor},{v:.1f}\n")
    for (group, day), lines in files.items():
        path = HERE / "data" / "campaign-rich" / f"{group}_{day}.csv"
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text(path, f"# SYNTHETIC readings ({path.name}): make_campaign_rich.py, truth = "
                   f"scenario A + {TRUTH_SKY_LUX:,.0f} lx clear sky, noise "
                   f"{campaign.noise:.0%}, seeds {TRACE_SEED}/{NOISE_SEED}\n# Units: lux\n"
                   "time,sensor,lux\n" + "".join(lines))
        print(path)


if __name__ == "__main__":
    main()
