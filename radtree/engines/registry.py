"""Engines by name: ``radiance`` (rtrace on the build folder), ``numpy`` (built-in Monte Carlo),
``forward`` (forward light tracing to patch detectors).

``get_engine("auto")`` is Radiance when its binaries are found, else the NumPy engine. A new
estimator is one class registered here; nothing else in radtree names an engine.
"""

from __future__ import annotations

from importlib import import_module

from radtree.engines.base import Engine
from radtree.errors import ConfigError, RadtreeError

#: name → "module:Class" (imported on first use: Radiance's lookup costs nothing until asked)
ENGINES: dict[str, str] = {
    "radiance": "radtree.engines.radiance.interface:RadianceEngine",
    "numpy": "radtree.engines.numpy.interface:NumpyEngine",
    "forward": "radtree.engines.forward.interface:ForwardEngine",
}
#: ``auto`` tries these in order
AUTO_ORDER = ("radiance", "numpy")
#: what ``--engine`` accepts
ENGINE_CHOICES = ("auto", *ENGINES)


def engine_class(name: str, source: str | None = None) -> type[Engine]:
    """The registered class of engine ``name`` (``source``: the file that named it)."""
    if name not in ENGINES:
        raise ConfigError(f"unknown engine {name!r} (expected one of {', '.join(ENGINE_CHOICES)})",
                          source=source, field="engine.name")
    module, _, cls = ENGINES[name].partition(":")
    return getattr(import_module(module), cls)


def get_engine(name: str = "auto", source: str | None = None) -> Engine:
    """An engine instance; ``auto`` → the first available of :data:`AUTO_ORDER`; an unknown
    name → ConfigError naming ``source`` and ``engine.name``."""
    if name == "auto":
        for candidate in AUTO_ORDER:
            if engine_class(candidate).available():
                return engine_class(candidate)()
        raise RadtreeError("no engine available")
    cls = engine_class(name, source)
    if not cls.available():
        raise RadtreeError(f"engine {name!r} asked for, but {cls.missing_hint}")
    return cls()


def available_engines() -> list[Engine]:
    """Every registered engine that can run here."""
    return [engine_class(n)() for n in ENGINES if engine_class(n).available()]


def photon_engines() -> list[str]:
    """Names of the registered engines with a photon budget (:attr:`Engine.photon_budget`:
    forward light tracing, noise set by ``engine.photons``)."""
    return [n for n in ENGINES if engine_class(n).photon_budget]


def folder_engine() -> Engine:
    """The engine whose inspectable build folders ``radtree build`` writes (Radiance)."""
    for name in ENGINES:
        cls = engine_class(name)
        if cls.uses_build_folder:
            return cls()
    raise RadtreeError("no registered engine writes build folders")


def seeded_engine() -> Engine:
    """The first registered seeded engine (common random numbers for a fixed seed): what
    calibration and diagnosis use unless told otherwise (the NumPy engine)."""
    for name in ENGINES:
        cls = engine_class(name)
        if cls.seeded and cls.available():
            return cls()
    raise RadtreeError("no seeded engine available")


def attributing_engine() -> Engine | None:
    """The first available registered engine that attributes light to trees
    (:attr:`Engine.attributes_trees`), or None."""
    for name in ENGINES:
        cls = engine_class(name)
        if cls.attributes_trees and cls.available():
            return cls()
    return None


def engine_named(name: str | None) -> Engine:
    """``get_engine(name)``, or the seeded engine when ``name`` is None."""
    return seeded_engine() if name is None else get_engine(name)


#: capability flags an engine class declares (:class:`radtree.engines.base.Engine`), as the
#: reference pages name them
CAPABILITIES = ("uses_build_folder", "seeded", "instancing", "ladder_in_one_trace",
                "attributes_trees", "photon_budget")


def engine_rows() -> list[tuple[str, str, str]]:
    """``(name, summary, capabilities)`` per registered engine, for the reference pages
    (summary: the class docstring's first sentence; capabilities: the flags it sets)."""
    rows = []
    for name in ENGINES:
        cls = engine_class(name)
        doc = " ".join((cls.__doc__ or "").split())
        summary = doc.split(". ")[0].rstrip(".")
        caps = [c for c in CAPABILITIES if getattr(cls, c, False)]
        rows.append((name, summary, ", ".join(caps) or "-"))
    return rows
