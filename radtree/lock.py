"""One writer per output folder: an advisory lock file beside it, ``.radtree.FOLDER.lock``.

A command that writes a project's ``results/``, ``build/``, ``report/`` or ``diagnose/``
folder holds that folder's lock while it runs. The lock is an ``fcntl.flock`` on the file, so
the kernel releases it when the holder dies (``kill -9``, a crash, a lost machine): a lock left
by a dead process is never in the way. The file carries the holder's pid, host and command
line, so a second run is refused with one message naming them (or, with ``wait=True``, waits
for them to finish). Within one process the lock is re-entrant (``simulate`` → ``build``).

    with folder_lock(project.results_dir, "radtree simulate my-street"):
        ...
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import logging
import os
import socket
import threading
from collections.abc import Iterator
from datetime import datetime, timezone
from pathlib import Path

from radtree.errors import RadtreeError

log = logging.getLogger(__name__)

LOCK_NAME = ".lock"    # the suffix: PROJECT/results → PROJECT/.radtree.results.lock
#: held briefly by a writer while it replaces a folder's finished files (exclusive) and by a
#: reader while it reads them (shared), so a reader sees one writer's files, not a mix
PUBLISH_NAME = ".publish.lock"

_held: dict[str, list[int]] = {}   # resolved lock path → [fd, depth] held by this process
_guard = threading.Lock()


class LockHeld(RadtreeError):
    """Another process holds the folder's lock; ``holder`` is what its lock file says."""

    def __init__(self, folder: Path, holder: dict):
        self.folder, self.holder = folder, holder
        super().__init__(f"{folder} is in use by {describe(holder)}; wait for it to finish "
                         f"(or rerun with --wait), or stop that process")


def describe(holder: dict) -> str:
    """``pid 123 (radtree simulate proj) on host, since 2026-12-01T20:00:00+00:00``."""
    if not holder.get("pid"):
        return "another radtree process"
    text = f"pid {holder['pid']}"
    if holder.get("command"):
        text += f" ({holder['command']})"
    if holder.get("host") and holder["host"] != socket.gethostname():
        text += f" on {holder['host']}"
    if holder.get("since"):
        text += f", since {holder['since']}"
    return text


def read_holder(path: Path) -> dict:
    """What the lock file at ``path`` says (``{}`` when absent, empty or unreadable)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def pid_alive(pid: int) -> bool:
    """True when a process ``pid`` exists on this machine."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def lock_path(folder: str | os.PathLike, name: str = LOCK_NAME) -> Path:
    """``PARENT/.radtree.FOLDER.lock`` for ``PARENT/FOLDER`` (beside the folder, so taking the
    lock creates nothing; a failed command leaves no empty output folder)."""
    folder = Path(folder)
    return folder.parent / f".radtree.{folder.name}{name}"


def _left_by_dead_process(holder: dict) -> bool:
    """True when a lock file names a process of this machine that is no longer running."""
    try:
        pid = int(holder.get("pid") or 0)
    except (TypeError, ValueError):
        return False
    same_host = holder.get("host") in (None, socket.gethostname())
    return pid > 0 and same_host and not pid_alive(pid)


@contextlib.contextmanager
def _holding(key: str, fd: int) -> Iterator[None]:
    """Record this process as holding the lock ``key`` (file descriptor ``fd``) while inside,
    so that a nested :func:`folder_lock` of the same file re-enters it."""
    with _guard:
        _held[key] = [fd, 1]
    try:
        yield
    finally:
        with _guard:
            del _held[key]


@contextlib.contextmanager
def folder_lock(folder: str | os.PathLike, command: str, wait: bool = False, *,
                name: str = LOCK_NAME, shared: bool = False) -> Iterator[Path]:
    """Hold the lock file ``.radtree.FOLDER<name>`` beside ``folder`` (:func:`lock_path`; neither
    the folder nor its parent is created) while inside.

    Another process holding it → :class:`LockHeld` naming its pid and command, or with
    ``wait`` a message (logged) and a blocking wait. A lock file left by a process that
    is gone is taken over (logged). ``shared``: several readers may hold it at once
    (they do not sign the file)."""
    path = lock_path(folder, name)
    key = str(path.resolve())
    with _guard:
        if key in _held:
            _held[key][1] += 1
            reentered = True
        else:
            reentered = False
    if reentered:
        try:
            yield path
        finally:
            with _guard:
                _held[key][1] -= 1
        return
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except PermissionError:
        if not shared:
            raise
        yield path            # a reader of a read-only folder: no writer can be there
        return
    mode = fcntl.LOCK_SH if shared else fcntl.LOCK_EX
    try:
        try:
            fcntl.flock(fd, mode | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = read_holder(path)
            if not wait:
                raise LockHeld(Path(folder), holder) from None
            log.info("waiting for %s to release %s", describe(holder), folder)
            fcntl.flock(fd, mode)
        if shared:
            with _holding(key, fd):
                yield path
            return
        previous = read_holder(path)
        if _left_by_dead_process(previous):
            log.info("note: %s was locked by pid %s (%s), which is no longer running; lock "
                     "taken over", folder, previous["pid"], previous.get("command", "?"))
        record = json.dumps({"pid": os.getpid(), "host": socket.gethostname(),
                             "command": command,
                             "since": datetime.now(timezone.utc).isoformat(timespec="seconds")})
        os.ftruncate(fd, 0)
        os.pwrite(fd, record.encode(), 0)
        try:
            with _holding(key, fd):
                yield path
        finally:
            os.ftruncate(fd, 0)   # released: an empty file names no holder
    finally:
        os.close(fd)
