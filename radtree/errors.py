"""One error type for people: every failure radtree expects ends up as a RadtreeError.

The command line maps them to exit codes (:mod:`radtree.cli.errors`): :class:`EngineError` → 3,
any other :class:`RadtreeError` (:class:`ConfigError`, unreadable input files) → 2,
:class:`Terminated` → 143, other :class:`KeyboardInterrupt` → 130, anything else (a bug) → 1.
"""

from __future__ import annotations


class RadtreeError(Exception):
    """A failure with a message meant for the user (no traceback needed).

    Pickled with its message and attributes (``field``, ``source``, ``command``, …), so an
    error raised in a worker process reads the same where it is re-raised."""

    def __reduce__(self) -> tuple:
        return (_restore, (type(self), str(self), dict(self.__dict__)))


def _restore(cls: type[RadtreeError], message: str, state: dict) -> RadtreeError:
    exc = cls.__new__(cls)
    Exception.__init__(exc, message)
    exc.__dict__.update(state)
    return exc


class ConfigError(RadtreeError):
    """A project file or option is invalid; the message names file, field, value and expectation."""

    def __init__(self, message: str, *, source: str | None = None, field: str | None = None):
        self.source = source
        self.field = field
        where = []
        if source:
            where.append(str(source))
        if field:
            where.append(f"field '{field}'")
        prefix = ": ".join([", ".join(where)]) + ": " if where else ""
        super().__init__(prefix + message)


class EngineError(RadtreeError):
    """An external program (Radiance) failed; carries the command and its stderr."""

    def __init__(self, message: str, *, command: list[str] | None = None, stderr: str = ""):
        self.command = command or []
        self.stderr = stderr
        text = message
        if command:
            text += f"\n  command: {' '.join(command)}"
        if stderr.strip():
            text += f"\n  stderr: {stderr.strip()[-2000:]}"
        super().__init__(text)


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM (raised by the command line's signal handler).

    A :class:`KeyboardInterrupt` so that every cleanup written for Ctrl-C (cancel pending
    work, remove temporary files, keep finished parts) runs for SIGTERM too.
    """

    def __init__(self, signum: int = 15):
        self.signum = signum
        super().__init__(f"terminated by signal {signum}")


def install_extra(extra: str) -> str:
    """How to install radtree's optional ``extra`` (the text every "missing extra" message
    ends with): ``make demo`` installs radtree without its extras, ``make install`` with all."""
    return f"pip install 'radtree[{extra}]' (in a source checkout: make install)"
