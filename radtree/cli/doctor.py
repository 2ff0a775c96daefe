"""``radtree doctor``: which engines are usable, with versions."""

from __future__ import annotations

import click

from radtree.cli.options import CONTEXT
from radtree.errors import EngineError


@click.command("doctor", context_settings=CONTEXT)
def doctor_command() -> None:
    """Which engines are usable, with versions. Exits non-zero only when none is."""
    from radtree.engines.radiance.binaries import find_radiance, version

    install = find_radiance()
    ok = False
    if install is not None:
        v = version()
        click.echo(f"radiance: {v or 'found but not runnable'} ({install.origin}: {install.bin_dir})")
        click.echo(f"  RAYPATH: {install.raypath}")
        ok = ok or v is not None
    else:
        click.echo("radiance: not found (pip install pyradiance, or put Radiance on PATH)")
    try:
        from radtree.engines.numpy import engine as npe

        click.echo(f"numpy: available ({npe.describe()})")
        ok = True
    except ImportError as exc:
        click.echo(f"numpy: not available ({exc})")
    if not ok:
        raise EngineError("no usable engine")
