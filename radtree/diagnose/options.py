"""The options every diagnosis-family run shares: :class:`DiagnoseOptions`.

``diagnose`` (:mod:`.run`), ``selftest`` (:mod:`.hidden`) and ``next_measurement``
(:mod:`.design`) start from a scenario, simulate on one engine (the seeded engine by default:
``rays`` per sensor, one ``seed`` for every switched run — common random numbers), consider a
set of effects, may follow a measurement campaign, and write into one folder
(``PROJECT/diagnose`` by default). One frozen, checked dataclass holds those choices::

    from radtree.diagnose import DiagnoseOptions, diagnose
    diagnose("examples/mendoza-street", options=DiagnoseOptions(scenario="B", rays=512))

A value out of bounds raises :class:`radtree.config.SchemaError` (a ConfigError) naming the
field, e.g. ``diagnose.margin``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar

from radtree.config.spec import Checked, meta
from radtree.diagnose.attribution import DEFAULT_MARGIN
from radtree.diagnose.loop import DEFAULT_MAX_STEPS, LoopOptions

if TYPE_CHECKING:
    from radtree.diagnose.campaign import Campaign
    from radtree.diagnose.effect import Effect


@dataclass(frozen=True)
class DiagnoseOptions(Checked):
    """``scenario``: where to start (None: the project's first). ``engine``: a registered
    engine name (None: the seeded engine); ``rays`` per sensor (None: the engine's default,
    1024 for the NumPy engine) and ``seed`` (None: the project's ``engine.seed``) of every
    run. ``margin``: relative cross-validated RMSE improvement a step must bring, in [0, 1).
    ``max_steps``: steps of the loop at most. ``effects``: the effects to consider (the
    candidates of a diagnosis, the effects a self-test hides; None: the whole catalogue).
    ``campaign``: a measurement campaign to follow (None: the project's façade grid mean at
    its hours). ``out_dir``: output folder (None: ``PROJECT/diagnose``); ``write``: write
    the outputs at all. ``workers``: processes tracing ahead (None: the usable cores, at most
    4; 1: everything in this process — the same numbers either way)."""

    TABLE: ClassVar[str] = "diagnose"

    scenario: str | None = None
    engine: str | None = None
    rays: int | None = field(default=None, metadata=meta(1))
    seed: int | None = None
    margin: float = field(default=DEFAULT_MARGIN, metadata=meta(0.0, 1.0, hi_open=True))
    max_steps: int = field(default=DEFAULT_MAX_STEPS, metadata=meta(1))
    effects: tuple[Effect, ...] | None = None
    campaign: Campaign | None = None
    out_dir: Path | None = None
    write: bool = True
    workers: int | None = field(default=None, metadata=meta(1))

    def check(self) -> None:
        if self.effects is not None:
            object.__setattr__(self, "effects", tuple(self.effects))
        if self.out_dir is not None:
            object.__setattr__(self, "out_dir", Path(self.out_dir))

    def loop(self, *, catalogue: tuple[Effect, ...] | None = None,
             first_step_signatures: bool = False) -> LoopOptions:
        """The loop's options (``catalogue``: default :attr:`effects`, else the catalogue)."""
        from radtree.diagnose.effects import EFFECTS

        return LoopOptions(self.margin, self.max_steps,
                           catalogue or self.effects or EFFECTS, first_step_signatures)

    def folder(self, root: Path) -> Path:
        """Where the outputs go: :attr:`out_dir`, else ``root / "diagnose"``."""
        return self.out_dir if self.out_dir is not None else root / "diagnose"


#: the options of a call that gives none
DEFAULT_OPTIONS = DiagnoseOptions()
