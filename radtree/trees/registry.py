"""Crown models by name, shaped like the engine registry (:mod:`radtree.engines.registry`).

The declarations — name, one-line summary, capabilities, ``"module:function"`` per
representation — are :data:`radtree.config.crown_models.REGISTRY` (plain data: the schema
checks ``scenario.model`` against it when a project loads). This module resolves them: the
builder of a model and representation is imported on first use, so building a homogeneous
shell never imports the louvers or turbid code. Adding a crown model is one new module in
:mod:`radtree.trees` and one line in that registry; :func:`radtree.trees.build.build_crown`,
the schema's choices, ``radtree calibrate --model`` and the docs' reference
(:func:`crown_model_rows`) follow.

Every builder is called as ``build(tree, sensors=, street=, frame=, form=, source=) ->
TreeModel`` (lengths in metres, x east, y north, z up; ``frame``: the façade frame the crown is
built in; ``source``: the project file, for error messages).
"""

from __future__ import annotations

from collections.abc import Callable
from importlib import import_module
from typing import Any

from radtree.config.crown_models import CROWN_MODELS, REGISTRY, CrownModel
from radtree.errors import ConfigError

__all__ = ["CROWN_MODELS", "CrownModel", "calibrated_models", "crown_builder", "crown_model",
           "crown_model_rows"]

#: builder(tree, *, sensors, street, frame, form, source) -> TreeModel
Builder = Callable[..., Any]


def crown_model(name: str, source: str | None = None) -> CrownModel:
    """The declaration of crown model ``name``; an unknown name → ConfigError naming
    ``source`` and ``scenario.model``."""
    if name not in REGISTRY:
        raise ConfigError(f"got {name!r}, expected one of {', '.join(CROWN_MODELS)}",
                          source=source, field="scenario.model")
    return REGISTRY[name]


def crown_builder(name: str, representation: str = "explicit",
                  source: str | None = None) -> Builder:
    """The function building model ``name`` in ``representation`` (imported now); a
    representation the model does not build itself → its ``explicit`` builder."""
    declared = crown_model(name, source)
    target = declared.builders.get(representation, declared.builders["explicit"])
    module, _, function = target.partition(":")
    return getattr(import_module(module), function)  # type: ignore[no-any-return]


def calibrated_models() -> tuple[str, ...]:
    """The models ``radtree calibrate`` fits (what ``--model`` accepts)."""
    return tuple(n for n, m in REGISTRY.items() if m.calibrated)


def crown_model_rows() -> list[tuple[str, str, dict[str, object]]]:
    """(name, summary, capabilities) of every registered crown model, for the docs'
    reference (capabilities: ``forms``, ``representations``, ``calibrated``)."""
    return [(m.name, m.summary, m.capabilities()) for m in REGISTRY.values()]
