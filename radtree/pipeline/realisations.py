"""Crown realisations: a louvers crown with ``louvers.realisations`` N > 1 (a perforated crown
with ``perforated.realisations`` N > 1: random gap patterns) is traced as N random crowns
``<name>@1`` … ``<name>@N`` (seeds ``<table>.seed`` … + N − 1, and engine seeds
``engine.seed`` … + N − 1, so that each crown is also an independent Monte Carlo sample) and
averaged back into ``<name>``; ``lux_stderr`` becomes the standard error over the crowns."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario
from radtree.config.switches import effective_project
from radtree.errors import ConfigError

REALISATION_MARK = "@"   # "F@3": the third random crown of scenario F


#: crown models with random realisations and the table holding their ``seed``/``realisations``
RANDOM_CROWNS = {"louvers": "louvers", "perforated": "perforated"}


def realisations_of(project: Project, sc: Scenario) -> list[Scenario]:
    """The scenario as traced: itself or, for a louvers crown with ``louvers.realisations``
    (a perforated crown with ``perforated.realisations``) N > 1, N copies named ``<name>@k``
    whose ``<table>.seed`` is seed + k − 1 (k = 1…N); ``simulate`` averages them back into
    ``<name>``. A perforated crown made from a photo has one fixed pattern: N > 1 is an error."""
    table = RANDOM_CROWNS.get(sc.model)
    if table is None:
        return [sc]
    from radtree.trees.build import apply_switches

    tree, _ = apply_switches(project.tree, dict(sc.switches), source=str(project.source))
    params = getattr(tree, table)
    n = params.realisations
    if n <= 1:
        return [sc]
    if table == "perforated" and (tree.perforated.photo is not None or tree.photo is not None):
        raise ConfigError(f"scenario {sc.name}: perforated.realisations = {n} draws random gap "
                          "patterns, but the crown's gaps come from a photo (one fixed pattern): "
                          "set perforated.realisations = 1 or remove the photo",
                          source=str(project.source), field="tree.perforated.realisations")
    # each crown its own engine seed too: with one seed the crowns' paths share their random
    # numbers (the first directions and, path by path, every later draw), which correlates
    # their Monte Carlo errors and leaves part of the mean's error out of the spread
    engine_seed = effective_project(project, sc).engine.seed
    return [replace(sc, name=f"{sc.name}{REALISATION_MARK}{k}",
                    switches={**sc.switches, f"{table}.seed": params.seed + k - 1,
                              f"{table}.realisations": 1, "engine.seed": engine_seed + k - 1})
            for k in range(1, n + 1)]


def parent_name(name: str) -> str:
    """``F@3`` → ``F``; other names unchanged."""
    return str(name).partition(REALISATION_MARK)[0]


def is_later_realisation(name: str) -> bool:
    """True for ``F@2``, ``F@3``, …: crowns after the first (maps and checks use the first)."""
    return str(name).partition(REALISATION_MARK)[2] not in ("", "1")


def selected(project: Project, names: list[str] | None) -> list[Scenario]:
    """The scenarios to build or trace, each expanded into its crown realisations; a name may
    also pick one realisation (``F@2``)."""
    out: list[Scenario] = []
    for name in names or [sc.name for sc in project.scenarios]:
        parent, mark, k = name.partition(REALISATION_MARK)
        subs = realisations_of(project, project.scenario(parent))
        if not mark:
            out.extend(subs)
        elif k.isdigit() and len(subs) > 1 and 1 <= int(k) <= len(subs):
            out.append(subs[int(k) - 1])
        else:
            raise ConfigError(f"scenario {parent!r} has no realisation {name!r} "
                              f"(it has {len(subs) if len(subs) > 1 else 'no'} realisations)",
                              source=str(project.source), field="scenario")
    return out


def merge_realisations(table: pd.DataFrame, hashes: dict[str, str]
                       ) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """Average the rows of ``<name>@k`` realisations into ``<name>``: ``lux``/``lux_traced`` are
    the means over realisations, ``lux_stderr`` the standard error over them (s.d./√n, which
    includes the tracing noise), ``lux_realisation_sd`` and ``realisations`` are added; a grid
    traced in one realisation only (the dense map) keeps its values. ``hashes`` maps a parent
    name to its parameter hash. Returns (merged table, the per-realisation rows or None)."""
    names = table["scenario"].astype(str)
    is_sub = names.str.contains(REALISATION_MARK, regex=False)
    if not is_sub.any():
        return table, None
    sub = table[is_sub].copy()
    parts = names[is_sub].str.partition(REALISATION_MARK)
    sub["scenario"] = parts[0]
    sub["realisation"] = parts[2].astype(int)
    keys = ["scenario", "time", "grid", "sensor"]
    g = sub.groupby(keys, sort=False)
    stats = pd.DataFrame({"lux": g["lux"].mean(), "lux_traced": g["lux_traced"].mean(),
                          "sd": g["lux"].std(ddof=1), "n": g["lux"].size()})
    merged = (sub.sort_values("realisation").drop_duplicates(keys).drop(columns="realisation")
              .set_index(keys))
    stats = stats.reindex(merged.index)
    merged["lux"] = stats["lux"]
    merged["lux_traced"] = stats["lux_traced"]
    several = stats["n"] > 1
    merged["lux_stderr"] = np.where(several, stats["sd"] / np.sqrt(stats["n"]),
                                    merged["lux_stderr"])
    merged["lux_realisation_sd"] = np.where(several, stats["sd"], np.nan)
    merged["realisations"] = stats["n"]
    merged = merged.reset_index()
    merged["params_hash"] = merged["scenario"].map(hashes).fillna(merged["params_hash"])
    return pd.concat([table[~is_sub], merged], ignore_index=True), sub
