"""Atomic writes: outputs go to a temporary name in the same folder and are renamed into place."""

from __future__ import annotations

import contextlib
import errno
import functools
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

_UMASK = os.umask(0)
os.umask(_UMASK)
FILE_MODE = 0o666 & ~_UMASK      # what open() would give: temporaries start at 0600
FOLDER_MODE = 0o777 & ~_UMASK


def make_folder(folder: str | os.PathLike) -> Path:
    """``mkdir -p folder``; an OSError naming the folder (and a file in its way) otherwise."""
    path = Path(folder)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        block = next((p for p in (path, *path.parents) if p.exists() and not p.is_dir()), path)
        what = "a file of that name is in the way" if block == path else f"{block} is a file"
        raise NotADirectoryError(errno.ENOTDIR, f"cannot create this folder: {what} (move or "
                                 "delete it)", str(path)) from None
    return path


def _unwritten(exc: OSError, target: Path) -> OSError:
    """``exc`` as raised for ``target`` (not its temporary name), saying nothing was replaced."""
    why = exc.strerror or str(exc)
    return type(exc)(exc.errno, f"cannot write: {why} (nothing written; a previous "
                     f"{target.name}, if any, is unchanged)", str(target))


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it to ``path``, else delete it.

    A failing write (disk full, read-only folder) raises an OSError naming ``path``, leaves no
    temporary behind and ``path`` as it was."""
    target = Path(path)
    make_folder(target.parent)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as exc:
        raise _unwritten(exc, target) from exc
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        try:
            yield tmp_path
            if tmp_path.is_file() and not tmp_path.is_symlink():
                os.chmod(tmp_path, FILE_MODE)
            os.replace(tmp_path, target)
        except OSError as exc:
            if exc.filename is not None and Path(exc.filename) not in (tmp_path, target):
                raise              # about another file (e.g. an input read while writing)
            raise _unwritten(exc, target) from exc
    finally:
        if tmp_path.is_symlink() or tmp_path.exists():
            tmp_path.unlink()


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` to ``path`` atomically; return the path."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


@contextlib.contextmanager
def atomic_dir(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary folder beside ``path``; on success it replaces ``path`` whole."""
    target = Path(path)
    make_folder(target.parent)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        yield tmp
        os.chmod(tmp, FOLDER_MODE)
        if target.exists():
            old = target.with_name(f".{target.name}.old")
            if old.exists():
                shutil.rmtree(old)
            os.replace(target, old)
            os.replace(tmp, target)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, target)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def file_sha256(path: str | os.PathLike) -> str:
    """The SHA-256 hex digest of a file's bytes."""
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def file_sha256_cached(path: str | os.PathLike) -> str:
    """:func:`file_sha256`, remembered per process by path, modification time and size (an
    edited file is read again): input files are hashed for every scenario's keys."""
    st = os.stat(path)
    return _sha256_of(str(path), st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=256)
def _sha256_of(path: str, mtime_ns: int, size: int) -> str:
    return file_sha256(path)
