"""What every benchmark prints at the end: peak memory, CPU time, wall time, machine load.

Each script in ``benchmarks/`` calls :func:`print_resources_at_exit` in its
``if __name__ == "__main__":`` block (the script's own directory is on ``sys.path`` when it is
run as ``python benchmarks/NAME.py``, hence ``from _common import ...``). At interpreter exit —
also after ``sys.exit`` or an exception — one line is printed::

    resources: wall 12.3 s; CPU 20.1 s (user + system, this process 18.0 s + children 2.1 s);
    peak RSS 412 MiB (this process), 95 MiB (largest waited-for child); load 1.9 → 2.4 (2 CPUs)

Peak RSS is ``resource.getrusage(...).ru_maxrss`` (KiB on Linux): for ``RUSAGE_CHILDREN`` it
is the largest single terminated, waited-for descendant (an rtrace, a Dask worker), not their
sum; a child forked from a large Python process counts the pages it shared with its parent. The load average is the 1-minute one at the start and at the end: on a shared machine
(the session's 2 cores serve several jobs) wall times are only comparable at equal load, CPU
times and ratios measured back to back in one process more so.
"""

from __future__ import annotations

import atexit
import os
import resource
import sys
import time

_STATE: dict[str, float] = {}


def _load() -> float:
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


def _kib_to_mib(kib: float) -> float:
    # ru_maxrss is in KiB on Linux, in bytes on macOS
    return kib / 1024.0 if sys.platform != "darwin" else kib / 1024.0 ** 2


def peak_rss_mib() -> tuple[float, float]:
    """(this process, largest waited-for child) peak resident set size, MiB."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return _kib_to_mib(own), _kib_to_mib(kids)


def cpu_seconds() -> tuple[float, float]:
    """(this process, waited-for children) user + system CPU time, s."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime, kids.ru_utime + kids.ru_stime


def resources_line() -> str:
    """The one-line summary (see the module docstring) since :func:`print_resources_at_exit`."""
    wall = time.perf_counter() - _STATE.get("t0", time.perf_counter())
    own_cpu, kid_cpu = cpu_seconds()
    own_rss, kid_rss = peak_rss_mib()
    return (f"resources: wall {wall:.1f} s; CPU {own_cpu + kid_cpu:.1f} s (user + system, this "
            f"process {own_cpu:.1f} s + children {kid_cpu:.1f} s); peak RSS {own_rss:.0f} MiB "
            f"(this process), {kid_rss:.0f} MiB (largest waited-for child); load "
            f"{_STATE.get('load0', float('nan')):.1f} → {_load():.1f} ({os.cpu_count()} CPUs)")


def print_resources_at_exit() -> None:
    """Start the clock now and print :func:`resources_line` when the interpreter exits."""
    if "t0" in _STATE:
        return
    _STATE["t0"] = time.perf_counter()
    _STATE["load0"] = _load()
    atexit.register(lambda: print(resources_line(), flush=True))


def seed_list(text: str) -> list[int]:
    """A ``--seeds`` argument as a list: "0-5" → [0, 1, 2, 3, 4, 5]; "0,2" → [0, 2]."""
    out: list[int] = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out.extend(range(int(a), int(b or a) + 1))
    return out
