"""Global crown permeability, as the study measured it, and the layer count that matches it.

SPEC.md defines the measured canopy permeability (5–6 %) as *vertical illuminance under the
crown / unobstructed vertical global illuminance*. :func:`global_permeability` computes the
same ratio in the model: the façade sensors' illuminance with the crown, divided by the same
sensors' illuminance in the open street (no crown), both traced with the ground-reflected light
traced, summed over the project's hours. Unlike the direct (specular) permeability of
``radtree calibrate`` it counts every path: diffuse transmission through slats, reflections
between slats and the white wall, and light reflected by the street.

:func:`calibrate_layers` picks the integer number of louvers layers whose global permeability is
closest (in log terms) to the target: this is SPEC's own rule "light must meet about 4 layers
(0.5⁴ ≈ 6 %)", evaluated with every light path instead of the direct one. It uses the measured
permeability only — no hourly façade measurement.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario
from radtree.light import hour_states
from radtree.scenarios import make_scene


def _facade_sum(project: Project, scenario: Scenario, rays: int, seed: int) -> tuple[float, float]:
    from radtree.engines.numpy.engine import trace_hour

    built = make_scene(project, scenario, dense_grid=False)
    params = replace(project.engine, rays=rays, seed=seed)
    total, var = 0.0, 0.0
    for st in hour_states(project, scenario):
        g = trace_hour(built.scene, st, params, grids=["facade"])["facade"]
        total += float(g.lux.mean())
        if g.stderr is not None:
            var += float(np.sum(g.stderr ** 2)) / len(g.lux) ** 2
    return total, math.sqrt(var)


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


def calibrate_layers(project: Project, target: float | None = None,
                     layers: range = range(3, 8), rays: int = 2048,
                     echo: Callable[[str], None] = print) -> LayerCalibration:
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
        echo(f"  {n} layers: global permeability {100 * p:.2f} % ± {100 * se:.2f}")
    table = pd.DataFrame(rows)
    best = table.loc[table["log_distance"].idxmin()]
    return LayerCalibration(target, table, int(best["layers"]), float(best["permeability"]))
