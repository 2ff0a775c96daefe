"""The one error handler of the ``radtree`` command line, and its exit codes.

Every command is invoked through :class:`RadtreeGroup`, which turns each kind of failure into
one short message on stderr (the full traceback only with ``radtree --debug``) and one exit code:

====  ==========================================================================================
code  meaning
====  ==========================================================================================
0     success
1     a bug: an unexpected exception (rerun with ``--debug`` and report the traceback); also
      ``diagnose selftest`` when a distinguishable hidden effect was misnamed
2     bad input: the project file or an option (:class:`~radtree.errors.ConfigError`, click's
      usage errors), an input file that cannot be read (images, measurements, weather), or any
      other :class:`~radtree.errors.RadtreeError` that is not an engine failure
3     engine failure (:class:`~radtree.errors.EngineError`): a Radiance program failed or no
      engine is usable; the message names the command and its stderr
130   interrupted (Ctrl-C, SIGINT); finished work is kept, the same command resumes
143   terminated (SIGTERM); as 130, finished work is kept
====  ==========================================================================================

The handlers for SIGINT and SIGTERM are installed by :func:`signal_handlers` while a command
runs, whatever the parent process left them as (a shell's background job ignores SIGINT):
both raise in the main thread so that ``with`` blocks and ``finally`` clauses run, temporary
files are removed and the state on disk stays resumable.
"""

from __future__ import annotations

import signal
import sys
import traceback
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, NoReturn

import click

from radtree.errors import EngineError, RadtreeError, Terminated

OK = 0
BUG = 1
CHECK_FAILED = 1  # diagnose selftest misnamed a hidden effect; verify: a physics check failed
BAD_INPUT = 2
ENGINE_FAILURE = 3
INTERRUPTED = 130
TERMINATED = 128 + signal.SIGTERM  # 143

RESUME_HINT = ("finished hours and cases are kept (results/parts/, sweep/cases/); "
               "run the same command again to resume")


def exit_code(exc: BaseException) -> int:
    """The exit code of a failure (see the table in this module's docstring)."""
    if isinstance(exc, Terminated):
        return TERMINATED
    if isinstance(exc, KeyboardInterrupt):
        return INTERRUPTED
    if isinstance(exc, EngineError):
        return ENGINE_FAILURE
    if isinstance(exc, (RadtreeError, OSError)):
        return BAD_INPUT
    return BUG


def _raise_terminated(signum: int, frame: Any) -> NoReturn:
    raise Terminated(signum)


@contextmanager
def signal_handlers() -> Iterator[None]:
    """SIGINT → KeyboardInterrupt, SIGTERM → :class:`~radtree.errors.Terminated` while inside.

    Installed explicitly (not inherited from the parent) and restored on exit; a no-op outside
    the main thread, where Python cannot install handlers.
    """
    try:
        previous = {signal.SIGINT: signal.signal(signal.SIGINT, signal.default_int_handler),
                    signal.SIGTERM: signal.signal(signal.SIGTERM, _raise_terminated)}
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def _debug(ctx: click.Context) -> bool:
    root = ctx.find_root()
    return bool(isinstance(root.obj, dict) and root.obj.get("debug"))


def fail(ctx: click.Context, exc: BaseException) -> NoReturn:
    """Print one message for ``exc`` (traceback with --debug) and exit with its code."""
    code = exit_code(exc)
    if _debug(ctx):
        traceback.print_exception(exc)
    if code == TERMINATED:
        click.secho(f"terminated: {RESUME_HINT}", fg="yellow", err=True)
    elif code == INTERRUPTED:
        click.secho(f"interrupted: {RESUME_HINT}", fg="yellow", err=True)
    elif code == BUG:
        where = f" in 'radtree {ctx.invoked_subcommand}'" if ctx.invoked_subcommand else ""
        click.secho(f"internal error{where}: {type(exc).__name__}: {exc}", fg="red", err=True)
        if not _debug(ctx):
            click.secho("this is a bug in radtree: rerun with `radtree --debug ...` for the "
                        "traceback and report it", fg="red", err=True)
    elif isinstance(exc, OSError) and not isinstance(exc, RadtreeError):
        name = f"{exc.filename}: " if exc.filename else ""
        click.secho(f"error: {name}{exc.strerror or exc}", fg="red", err=True)
    else:
        click.secho(f"error: {exc}", fg="red", err=True)
    sys.exit(code)


class RadtreeGroup(click.Group):
    """The main group: runs a command under :func:`signal_handlers` and :func:`fail`."""

    def main(self, *args: Any, **kwargs: Any) -> Any:
        with signal_handlers():
            return super().main(*args, **kwargs)

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except (click.exceptions.ClickException, click.exceptions.Exit, click.Abort,
                SystemExit):
            raise  # click's own usage errors (exit 2) and explicit exits
        except BaseException as exc:  # noqa: BLE001 - the one place failures become exit codes
            fail(ctx, exc)
