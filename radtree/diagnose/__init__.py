"""Model–measurement discrepancy workflow (reference case §6): ``radtree diagnose``.

Find where simulation and measurement disagree (by hour, by sensor row, by sun altitude), name
the physical effect most likely missing, add it to the model, re-simulate, and show the gap
shrink — and prove the workflow on synthetic data in which a known effect was hidden.

    from radtree.diagnose import diagnose, selftest, EFFECTS
    opts = DiagnoseOptions(scenario="B")
    res = diagnose("examples/mendoza-street", options=opts)   # → PROJECT/diagnose/
    res.steps                                                 # steps.csv as a DataFrame
    st = selftest("examples/mendoza-street", noise=0.03, options=opts)
    st.passed, st.table()

Library calls are quiet; ``radtree.log.enable()`` prints their progress messages.

Modules: :mod:`.effects` (the catalogue), :mod:`.simulate` (cached, seeded façade-grid runs),
:mod:`.residuals` (disagreement map and its rules), :mod:`.attribution` (signatures, fits,
leave-one-hour-out ranking), :mod:`.measured` (the measured side), :mod:`.loop` (the loop),
:mod:`.options` (:class:`DiagnoseOptions`), :mod:`.run` (:func:`diagnose` and its outputs),
:mod:`.hidden` (the self-test), :mod:`.design` (the next measurement), :mod:`.registry` (the
effects by name), :mod:`.report`; the step project files are written by
:mod:`radtree.config.step_project`.
"""

from __future__ import annotations

import importlib
from typing import Any

# Lazy exports (PEP 562): ``import radtree.diagnose.cli`` stays light for ``radtree --help``.
_EXPORTS = {
    "Attribution": "attribution", "CandidateFit": "attribution", "Signature": "attribution",
    "attribute": "attribution",
    "EFFECTS": "effects", "EFFECT_NAMES": "effects", "EffectContext": "effects", "Effect": "effects",
    "Strength": "effects", "candidates": "effects", "catalogue_lines": "effects",
    "get_effect": "effects", "parse_effects": "effects",
    "LoopOptions": "loop", "LoopResult": "loop", "Step": "loop", "run_loop": "loop",
    "Measured": "measured", "load_measurements": "measured",
    "DiagnoseOptions": "options", "next_measurement": "design", "Design": "design",
    "effect_rows": "registry", "EFFECT_REGISTRY": "registry",
    "DisagreementMap": "residuals", "disagreement_map": "residuals",
    "DiagnoseResult": "run", "diagnose": "run",
    "HiddenCase": "hidden", "SelftestResult": "hidden", "selftest": "hidden",
    "Run": "simulate", "Simulator": "simulate",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'radtree.diagnose' has no attribute {name!r}")
    return getattr(importlib.import_module(f"radtree.diagnose.{module}"), name)


def __dir__() -> list[str]:
    return sorted(list(globals()) + __all__)
