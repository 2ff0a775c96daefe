"""``radtree doctor``: which engines are usable, with versions."""

from __future__ import annotations

import click

from radtree.cli.options import CONTEXT
from radtree.errors import EngineError


@click.command("doctor", context_settings=CONTEXT)
def doctor_command() -> None:
    """Which engines are usable, with versions. Exits 3 only when none is."""
    from radtree.engines.registry import ENGINES, engine_class

    usable = 0
    for name in ENGINES:
        cls = engine_class(name)
        if not cls.available():
            click.echo(f"{name}: not available — {cls.missing_hint}")
            continue
        engine = cls()
        runnable = engine.version() is not None
        usable += runnable
        click.echo(f"{name}: {engine.describe()}" + ("" if runnable else " (found but not runnable)"))
        for line in engine.details():
            click.echo(f"  {line}")
    if not usable:
        raise EngineError("no usable engine")
