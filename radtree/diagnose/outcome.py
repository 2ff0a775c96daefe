"""What a diagnosis and a self-test found (the report reads these), and small shared helpers."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.config import Project, Scenario, load_project
from radtree.diagnose.attribution import DEFAULT_MARGIN
from radtree.diagnose.loop import LoopResult
from radtree.diagnose.measured import Measured

#: a hidden effect is distinguishable when its signature lies at least this many noise units
#: (over all values) from every other candidate's best fit (radtree.diagnose.hidden)
SNR_MIN = 3.0
SELFTEST_COLUMNS = ["hidden_effect", "distinguishable", "named_effect", "rmse_before",
                    "rmse_after"]


def resolve_project(project: str | os.PathLike | Project) -> Project:
    return project if isinstance(project, Project) else load_project(Path(project))


def pick_scenario(project: Project, name: str | None) -> Scenario:
    return project.scenario(name) if name else project.scenarios[0]


@dataclass
class DiagnoseResult:
    """What :func:`diagnose` found and wrote."""

    project: Project
    scenario: Scenario
    engine: str
    rays: int | None
    seed: int | None
    measured: Measured
    loop: LoopResult
    out_dir: Path | None
    seconds: float
    simulations: int
    cache_hits: int
    not_candidates: dict[str, str] = field(default_factory=dict)
    files: list[Path] = field(default_factory=list)
    margin: float = DEFAULT_MARGIN

    @property
    def steps(self) -> pd.DataFrame:
        return self.loop.steps_table()


@dataclass
class HiddenCase:
    """One hidden effect: the decision made before the run, then what the loop did."""

    effect: str
    base: Scenario
    truth: Scenario
    strength_true: float | None
    strength_text: str
    signature_rms_lux: float
    noise_rms_lux: float
    max_correlation: float
    most_correlated_with: str
    distinguishable: bool
    reason: str
    #: noise units (over all values) from the nearest other candidate's best fit (or from no
    #: change, if nearer), from no change, and beyond the span of every other candidate
    separation_snr: float = math.nan
    combined_snr: float = math.nan
    joint_snr: float = math.nan
    nearest: str = ""
    loop: LoopResult | None = None
    measured: Measured | None = None

    @property
    def named(self) -> str:
        return self.loop.named() if self.loop is not None else ""

    @property
    def correct(self) -> bool:
        return self.named == self.effect

    @property
    def gap_shrinks(self) -> bool:
        return self.loop is not None and all(s.rmse_after < s.rmse_before
                                             for s in self.loop.steps)

    def record(self) -> dict[str, Any]:
        lp = self.loop
        first = lp.steps[0] if lp is not None and lp.steps else None
        return {
            "hidden_effect": self.effect, "distinguishable": self.distinguishable,
            "named_effect": self.named,
            "rmse_before": lp.start_map.stats["nrmse"] if lp else math.nan,
            "rmse_after": lp.final_map.stats["nrmse"] if lp else math.nan,
            "correct": self.correct,
            "named_or_tied": self.correct or (first is not None
                                              and self.effect in first.tie_with),
            "tie_with": ";".join(first.tie_with) if first else "",
            "steps": " + ".join(s.effect for s in lp.steps) if lp else "",
            "gap_shrinks": self.gap_shrinks,
            "strength_true": self.strength_true if self.strength_true is not None else math.nan,
            "strength_fitted": (first.strength if first is not None and first.strength
                                is not None and first.effect == self.effect else math.nan),
            "signature_rms_lux": self.signature_rms_lux, "noise_rms_lux": self.noise_rms_lux,
            "snr": self.signature_rms_lux / self.noise_rms_lux if self.noise_rms_lux > 0
            else math.nan,
            "separation_snr": self.separation_snr, "nearest_candidate": self.nearest,
            "combined_snr": self.combined_snr, "joint_snr": self.joint_snr,
            "max_correlation": self.max_correlation,
            "most_correlated_with": self.most_correlated_with, "reason": self.reason,
            "base": self.base.name if not self.base.switches else
            self.base.name + " with " + ", ".join(f"{k}={v}" for k, v in
                                                 self.base.switches.items()),
        }


@dataclass
class SelftestResult:
    project: Project
    scenario: Scenario
    noise: float
    cases: list[HiddenCase]
    skipped: dict[str, str]
    seconds: float
    simulations: int
    out_dir: Path | None = None
    files: list[Path] = field(default_factory=list)
    engine: str = ""
    rays: int | None = None
    seed: int | None = None
    campaign: str = ""   # the campaign's summary ("" : the project's façade grid mean)
    margin: float = DEFAULT_MARGIN

    @property
    def passed(self) -> bool:
        return all(c.correct for c in self.cases if c.distinguishable)

    @property
    def misnamed(self) -> list[HiddenCase]:
        return [c for c in self.cases if c.distinguishable and not c.correct]

    def table(self) -> pd.DataFrame:
        recs = [c.record() for c in self.cases]
        if not recs:
            return pd.DataFrame(columns=SELFTEST_COLUMNS)
        cols = SELFTEST_COLUMNS + [k for k in recs[0] if k not in SELFTEST_COLUMNS]
        return pd.DataFrame(recs, columns=cols)
