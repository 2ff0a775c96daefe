"""How radtree talks to the user: :mod:`logging` per module, progress bars on request.

Every module logs to its own logger, ``log = logging.getLogger(__name__)``, under the
``radtree`` logger. Library calls are **quiet by default**: the ``radtree`` logger has only a
:class:`logging.NullHandler`, and :func:`progress` hands back the plain iterable. The command
line installs the handler and the progress bars (:func:`enable`, from ``radtree -v|-q``) and
removes them when the command ends. A notebook or script turns the same messages on with::

    import radtree.log
    radtree.log.enable()                 # INFO messages and progress bars on stderr
    radtree.log.enable(logging.DEBUG, progress=False)

Levels: ``INFO`` is what a command prints as it goes (what is built, traced, written);
``WARNING`` is something the user should act on; ``DEBUG`` is detail for a bug report.
Messages are printed without a prefix (``warning:`` for warnings), one per line, through
:func:`tqdm.tqdm.write` so that they never break a running progress bar.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Iterable
from typing import IO, Any

__all__ = ["enable", "disable", "enabled", "progress", "ROOT"]

#: the logger every radtree module's logger descends from
ROOT = "radtree"
logging.getLogger(ROOT).addHandler(logging.NullHandler())

_state: dict[str, Any] = {"handler": None, "progress": False}


class _Formatter(logging.Formatter):
    """The message alone; warnings and errors prefixed with their level in lower case."""

    def format(self, record: logging.LogRecord) -> str:
        msg = record.getMessage()
        if record.levelno >= logging.WARNING:
            msg = f"{record.levelname.lower()}: {msg}"
        return msg


class _TqdmHandler(logging.Handler):
    """Writes through ``tqdm.write`` to the stream current at the time of the message (so
    that a test runner or a notebook that swaps ``sys.stdout`` sees it)."""

    def __init__(self, stream: IO[str] | None, level: int) -> None:
        super().__init__(level)
        self.stream = stream
        self.setFormatter(_Formatter())

    def emit(self, record: logging.LogRecord) -> None:
        try:
            from tqdm import tqdm

            tqdm.write(self.format(record), file=self.stream or sys.stdout)
        except Exception:   # noqa: BLE001 — logging must never raise into the caller
            self.handleError(record)


def enable(level: int = logging.INFO, *, progress: bool = True,
           stream: IO[str] | None = None) -> None:
    """Print radtree's messages at ``level`` and above to ``stream`` (default: the current
    ``sys.stdout`` at each message) and show progress bars on stderr when ``progress``.
    Calling it again replaces the previous settings."""
    disable()
    handler = _TqdmHandler(stream, level)
    root = logging.getLogger(ROOT)
    root.addHandler(handler)
    root.setLevel(level)
    _state.update(handler=handler, progress=progress)


def disable() -> None:
    """Back to quiet: remove the handler :func:`enable` installed and the progress bars."""
    root = logging.getLogger(ROOT)
    if _state["handler"] is not None:
        root.removeHandler(_state["handler"])
    root.setLevel(logging.NOTSET)
    _state.update(handler=None, progress=False)


def enabled() -> bool:
    """Whether :func:`enable` is in force (messages are printed)."""
    return _state["handler"] is not None


class _Quiet:
    """What :func:`progress` returns without items when bars are off: accepts a bar's calls."""

    def update(self, n: int = 1) -> None:
        return None

    def set_postfix_str(self, s: str, refresh: bool = True) -> None:
        return None

    def close(self) -> None:
        return None

    def __enter__(self) -> _Quiet:
        return self

    def __exit__(self, *exc: object) -> None:
        return None


def progress(items: Iterable | None = None, *, desc: str, total: int | None = None,
             unit: str = "hour") -> Any:
    """A tqdm progress bar on stderr over ``items`` (or one of ``total`` steps to ``update``)
    when :func:`enable` turned bars on; else ``items`` itself (or an object that accepts a
    bar's ``update``/``close`` and does nothing)."""
    if not _state["progress"]:
        return _Quiet() if items is None else items
    from tqdm import tqdm

    if items is None:
        return tqdm(total=total, desc=desc, unit=unit, leave=False)
    return tqdm(items, desc=desc, unit=unit, leave=False, total=total)

