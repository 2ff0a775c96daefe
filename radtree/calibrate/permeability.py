"""Global crown permeability, as the study measured it, and the layer count that matches it.

The reference case defines the measured canopy permeability (5–6 %) as *vertical illuminance under the
crown / unobstructed vertical global illuminance*. :func:`global_permeability` computes the
same ratio in the model: the façade sensors' illuminance with the crown, divided by the same
sensors' illuminance in the open street (no crown), both traced with the ground-reflected light
traced, summed over the project's hours. Unlike the direct (specular) permeability of
``radtree calibrate`` it counts every path: diffuse transmission through slats, reflections
between slats and the white wall, and light reflected by the street.

:func:`calibrate_layers` picks the integer number of louvers layers whose global permeability is
closest (in log terms) to the target: this is the reference case's own rule "light must meet about 4 layers
(0.5⁴ ≈ 6 %)", evaluated with every light path instead of the direct one. It uses the measured
permeability only — no hourly façade measurement.

:func:`calibrate_crossings` does the same for the *volume* arrangement of the free crowns
(``louvers.arrangement = "volume"``), whose density is a continuous number: the mean slat
crossings of a vertical line through the crown centre, found by secant / false-position steps
on ln(permeability / target).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario
from radtree.engines.registry import seeded_engine
from radtree.pipeline.trace import facade_total

log = logging.getLogger(__name__)


def _facade_sum(project: Project, scenario: Scenario, rays: int, seed: int) -> tuple[float, float]:
    """Σ_h façade mean (lux) and its s.e., traced as ``simulate`` traces (the scene's -ab, the
    scenario's switches) on the seeded engine (common random numbers across crowns)."""
    return facade_total(project, scenario, seeded_engine(), rays, seed)


def global_permeability(project: Project, model: str = "louvers",
                        switches: dict | None = None, rays: int = 2048,
                        seed: int = 1) -> tuple[float, float]:
    """(permeability, standard error) of the crown: Σ_h E_crown / Σ_h E_open on the façade
    sensors, sun (and sky) as the project lights it, ground-reflected light traced."""
    open_sum, open_se = _facade_sum(project, Scenario("open", "none", "traced"), rays, seed)
    crown_sum, crown_se = _facade_sum(
        project, Scenario("crown", model, "traced", switches=dict(switches or {})), rays, seed)
    p = crown_sum / open_sum
    se = p * math.sqrt((crown_se / crown_sum) ** 2 + (open_se / open_sum) ** 2)
    return p, se


@dataclass
class LayerCalibration:
    target: float
    table: pd.DataFrame          # layers, permeability, stderr, log_distance
    layers: int
    permeability: float

    def summary(self) -> str:
        return (f"Chosen: [tree.louvers] layers = {self.layers} → global permeability "
                f"{100 * self.permeability:.2f} % (target {100 * self.target:.2f} %).")


def calibrate_layers(project: Project, target: float | None = None,
                     layers: range = range(3, 8), rays: int = 2048) -> LayerCalibration:
    """Integer louvers layer count whose global permeability is closest to ``target``
    (default ``tree.homogeneous.permeability``), the other louvers parameters as in the project."""
    target = project.tree.homogeneous.permeability if target is None else target
    if not 0 < target < 1:
        raise ValueError(f"target permeability must be in (0, 1), got {target}")
    rows = []
    for n in layers:
        p, se = global_permeability(project, "louvers", {"louvers.layers": n}, rays)
        rows.append({"layers": n, "permeability": p, "stderr": se,
                     "log_distance": abs(math.log(p / target))})
        log.info("  %d layers: global permeability %.2f %% ± %.2f", n, 100 * p, 100 * se)
    table = pd.DataFrame(rows)
    best = table.loc[table["log_distance"].idxmin()]
    return LayerCalibration(target, table, int(best["layers"]), float(best["permeability"]))


@dataclass
class CrossingsCalibration:
    target: float
    table: pd.DataFrame          # crossings, permeability, stderr, realisation_sd,
    #                              realisation_se, log_ratio (ln p/target)
    crossings: float             # the evaluated crossings closest (in log terms) to the target
    permeability: float
    stderr: float
    realisation_se: float        # nan with one realisation
    converged: bool              # |ln p/target| ≤ max(tol, 2 s.e./p) at ``crossings``
    realisations: int = 1

    def summary(self) -> str:
        return (f"Chosen: [tree.louvers] crossings = {self.crossings:g} → global "
                f"permeability {100 * self.permeability:.2f} % ± "
                f"{100 * self.realisation_se:.2f} over {self.realisations} realisation(s) "
                f"(target {100 * self.target:.2f} %"
                f"{'' if self.converged else '; not converged'}).")


@dataclass(frozen=True)
class CrossingsSearch:
    """How :func:`calibrate_crossings` searches: the two ``start`` crossings, ``rays`` per
    sensor, the tolerance ``tol`` on |ln(p/target)|, at most ``max_iter`` steps after the
    start, iterates rounded to ``decimals`` places, the tracing ``seed`` and the crown
    realisations ``seeds`` (``louvers.seed`` values; empty: the project's)."""

    start: tuple[float, float] = (8.0, 16.0)
    rays: int = 2048
    tol: float = 0.02
    max_iter: int = 10
    decimals: int = 1
    seed: int = 1
    seeds: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", tuple(float(x) for x in self.start))
        object.__setattr__(self, "seeds", tuple(int(s) for s in self.seeds))
        if self.rays < 1 or self.tol <= 0 or self.max_iter < 0 or len(self.start) != 2:
            raise ValueError(f"invalid crossings search {self}")


def calibrate_crossings(project: Project, *, target: float | None = None,
                        switches: dict | None = None,
                        search: CrossingsSearch = CrossingsSearch()) -> CrossingsCalibration:
    """``louvers.crossings`` of the volume arrangement whose global permeability is ``target``
    (default ``tree.homogeneous.permeability``).

    Free crowns, ``louvers.arrangement = "volume"`` (added to ``switches``, which may override
    them or anything else). ln(permeability) falls monotonically with the crossings (up to
    Monte Carlo noise), so the root of ln(p/target) is found by secant steps from
    ``search.start``, then by false position in the tightest bracket (bisecting when two steps
    in a row land on the same side). Iterates are rounded to ``search.decimals`` places
    (values to write in a project file). Stops when |ln(p/target)| ≤ max(tol, 2·s.e./p). The
    open-street façade sum is traced once. Uses the measured permeability only — no hourly
    façade measurement.

    ``search.seeds``: crown realisations (``louvers.seed`` values; default the project's). The
    eight façade sensors sit within 0.25 m, so the slats just in front of them weigh heavily
    and one realisation's permeability scatters by ≈ 14 % (s.d., reference case, crossings
    16); the permeability is the mean over the realisations (the same seeds at every crossings
    value, and a larger crossings adds slats to the same realisation, so the mean curve is
    smooth). ``stderr`` is the tracing (Monte Carlo) error used by the stopping rule;
    ``realisation_se`` = s.d. over realisations / √n is the error of the mean as an estimate
    of the crown's expected permeability."""
    target = project.tree.homogeneous.permeability if target is None else target
    if not 0 < target < 1:
        raise ValueError(f"target permeability must be in (0, 1), got {target}")
    ev = _Evaluator(project, target, switches, search)
    for x in search.start:
        ev(round(float(x), search.decimals))
    same_side = 0
    for _ in range(search.max_iter):
        if any(ev.done(r["log_ratio"], r["stderr"] / r["permeability"]) for r in ev.rows):
            break
        x2 = _next_crossings(ev.rows, same_side, search.decimals)
        if any(r["crossings"] == x2 for r in ev.rows):
            break  # the rounding grid is exhausted
        prev = ev.rows[-1]["log_ratio"] > 0
        f2 = ev(x2)
        same_side = same_side + 1 if (f2 > 0) == prev else 0
    table = pd.DataFrame(ev.rows).sort_values("crossings").reset_index(drop=True)
    best = table.loc[table["log_ratio"].abs().idxmin()]
    return CrossingsCalibration(target, table, float(best["crossings"]),
                                float(best["permeability"]), float(best["stderr"]),
                                float(best["realisation_se"]),
                                ev.done(best["log_ratio"], best["stderr"] / best["permeability"]),
                                len(ev.realisations))


@dataclass
class _Evaluator:
    """The global permeability at a crossings value, mean over the realisations; every
    evaluation is a row of :attr:`rows` and a log line."""

    project: Project
    target: float
    switches: dict | None
    search: CrossingsSearch
    rows: list[dict] = field(default_factory=list)
    realisations: tuple[int, ...] = field(init=False)
    base: dict = field(init=False)
    open_sum: float = field(init=False)
    open_se: float = field(init=False)

    def __post_init__(self) -> None:
        s = self.search
        self.realisations = s.seeds or (self.project.tree.louvers.seed,)
        self.base = {"tree.form": "free", "louvers.arrangement": "volume",
                     **dict(self.switches or {})}
        self.open_sum, self.open_se = _facade_sum(
            self.project, Scenario("open", "none", "traced"), s.rays, s.seed)

    def done(self, f: float, rel_se: float) -> bool:
        return bool(abs(f) <= max(self.search.tol, 2.0 * rel_se))

    def __call__(self, x: float) -> float:
        """ln(p/target) at ``x`` crossings."""
        sums, ses = [], []
        for s in self.realisations:
            sw = {**self.base, "louvers.crossings": x, "louvers.seed": s}
            crown_sum, crown_se = _facade_sum(
                self.project, Scenario("crown", "louvers", "traced", switches=sw),
                self.search.rays, self.search.seed)
            sums.append(crown_sum)
            ses.append(crown_se)
        n = len(sums)
        crown_mean = float(np.mean(sums))
        crown_se = math.sqrt(sum(v * v for v in ses)) / n
        p = crown_mean / self.open_sum
        se = p * math.sqrt((crown_se / crown_mean) ** 2 + (self.open_se / self.open_sum) ** 2)
        sd = float(np.std(np.asarray(sums) / self.open_sum, ddof=1)) if n > 1 else float("nan")
        f = math.log(p / self.target)
        self.rows.append({"crossings": x, "permeability": p, "stderr": se,
                          "realisation_sd": sd, "realisation_se": sd / math.sqrt(n),
                          "log_ratio": f})
        log.info("  crossings %g: global permeability %.3f %% ± %.3f%s", x, 100 * p, 100 * se,
                 f", realisations {n}, s.d. {100 * sd:.2f}" if n > 1 else "")
        return f


def _next_crossings(rows: list[dict], same_side: int, decimals: int) -> float:
    """The next crossings to evaluate: false position in the tightest bracket (bisection
    after two steps on one side), else a secant step from the last two, clamped to ¼–4 ×."""
    above = [r for r in rows if r["log_ratio"] > 0]  # too permeable: more crossings
    below = [r for r in rows if r["log_ratio"] <= 0]
    if above and below:
        a = max(above, key=lambda r: r["crossings"])
        b = min(below, key=lambda r: r["crossings"])
        if same_side >= 2:  # false position stalls on one side: bisect once
            x2 = 0.5 * (a["crossings"] + b["crossings"])
        else:
            x2 = a["crossings"] - a["log_ratio"] * (b["crossings"] - a["crossings"]) / (
                b["log_ratio"] - a["log_ratio"])
    else:
        r0, r1 = rows[-2], rows[-1]
        if r1["log_ratio"] == r0["log_ratio"]:
            x2 = r1["crossings"] * (1.5 if r1["log_ratio"] > 0 else 1.0 / 1.5)
        else:
            x2 = r1["crossings"] - r1["log_ratio"] * (r1["crossings"] - r0["crossings"]) / (
                r1["log_ratio"] - r0["log_ratio"])
        x2 = min(max(x2, 0.25 * r1["crossings"]), 4.0 * r1["crossings"])
    return max(round(x2, decimals), 10.0 ** -decimals)


#: what ``radtree calibrate --global`` prints first
GLOBAL_DEFINITION = ("Global permeability = Σ façade illuminance with the crown / Σ in the open "
                     "street, over the project's hours (seeded engine, every light path).")


def calibrate_global(project: Project, target: float | None = None, form: str | None = None,
                     realisations: int = 1) -> LayerCalibration | CrossingsCalibration:
    """The louvers density from the measured permeability: the volume crossings of free
    ``volume`` crowns (mean over ``realisations`` crowns, 512 rays/sensor), else the integer
    layer count."""
    if (form or project.tree.form) == "free" and project.tree.louvers.arrangement == "volume":
        return calibrate_crossings(project, target=target, search=CrossingsSearch(
            rays=512, seeds=tuple(range(1, realisations + 1))))
    return calibrate_layers(project, target)
