"""A real ``radtree`` process held at a known point, so signal tests need no timing.

``python tests/held_run.py K ARGS…`` runs ``radtree ARGS…`` with every engine's ``trace``
(and an engine's own ``trace_many``, which traces several hours at once) wrapped: the first K
hours trace normally; the call that would trace hour K + 1 waits until the process has
received a signal (radtree's own SIGINT/SIGTERM handler has been entered) and then fails, so
it never writes a part. Whatever the machine's speed, exactly K parts exist when the signal arrives and
when the process exits.
"""

from __future__ import annotations

import signal
import sys
import threading

signalled = threading.Event()
_install = signal.signal


def _spy(signum, handler):  # type: ignore[no-untyped-def]
    """Install ``handler`` wrapped so that its first call releases the held hour."""
    if callable(handler):
        def wrapped(s, frame, _h=handler):  # type: ignore[no-untyped-def]
            signalled.set()
            return _h(s, frame)

        return _install(signum, wrapped)
    return _install(signum, handler)


def hold_after(k: int) -> None:
    from radtree.engines.base import Engine
    from radtree.engines.registry import ENGINES, engine_class

    calls = [0]
    lock = threading.Lock()

    def count(hours: int) -> None:
        """Count ``hours`` more; past the first k, wait for the signal and fail."""
        with lock:
            calls[0] += hours
            n = calls[0]
        if n > k:
            signalled.wait(300)
            raise RuntimeError("held hour released by the signal")

    for name in ENGINES:
        cls = engine_class(name)
        original = cls.trace

        def trace(self, plan, label, grids=None, _original=original):  # type: ignore[no-untyped-def]
            count(1)
            return _original(self, plan, label, grids)

        cls.trace = trace  # type: ignore[method-assign]
        if cls.trace_many is not Engine.trace_many:   # the engine's own: count its hours
            many = cls.trace_many

            def trace_many(self, plan, labels, grids=None, _many=many):  # type: ignore[no-untyped-def]
                count(len(labels))
                return _many(self, plan, labels, grids)

            cls.trace_many = trace_many  # type: ignore[method-assign]


if __name__ == "__main__":
    signal.signal = _spy  # type: ignore[assignment]
    hold_after(int(sys.argv[1]))
    from radtree.cli import main

    sys.argv = ["radtree", *sys.argv[2:]]
    main()
