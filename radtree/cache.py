"""The build cache: built crowns and their OBJ text kept between builds, keyed by all that
shapes them.

A crown (:class:`~radtree.trees.model.TreeModel`) depends on its model and form, the
``[tree]`` tables after the scenario's switches (input files such as the fisheye photo by
their path *and* content), the sensors, the street and the façade frame — and on the code
that builds it. The key is the SHA-256 of all of these plus a fingerprint of the installed
radtree package (every file's bytes) and of the numerical libraries' versions, so a code edit
or an upgrade never serves an old crown. The photo crowns (the photo's analysis, mask check
and cut: 2.5–4 s each) load in milliseconds on the next build, ``--fresh`` ones included;
a large mesh's Wavefront OBJ text (``"%.5f"`` formatting of up to 10⁵ vertices) is copied
instead of formatted again, keyed by its name, material, vertex and face bytes; a build
folder's ``model.png`` is copied when its crown and scene are the same to the byte.

Where: ``$RADTREE_CACHE_DIR`` (``off`` turns the cache off), else
``$XDG_CACHE_HOME/radtree``, else ``~/.cache/radtree``. Size: at most ``$RADTREE_CACHE_MB``
(default 2048) MB; the least recently used entries go first. ``radtree cache`` shows it,
``radtree cache --clear`` empties it.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import pickle
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from radtree.fileio import atomic_path, file_sha256_cached, make_folder

__all__ = ["CacheInfo", "cache_dir", "cache_info", "cached_file", "cached_object",
           "clear_cache", "content_key", "has_object"]

#: libraries whose numbers a crown depends on (a new version may change the last bit)
_LIBRARIES = ("numpy", "shapely", "scikit-image", "scipy", "pillow", "matplotlib")
#: what the cache holds: ``<key>.pickle`` (crowns), ``<key>.obj`` (mesh text) and
#: ``<key>.png`` (a build folder's picture of its crown)
_SUFFIXES = (".pickle", ".obj", ".png")
DEFAULT_MB = 2048


def cache_dir() -> Path | None:
    """The build cache folder, or None when ``RADTREE_CACHE_DIR=off``."""
    env = os.environ.get("RADTREE_CACHE_DIR", "").strip()
    if env.lower() in ("off", "0", "no", "none"):
        return None
    if env:
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME", "").strip()
    return (Path(base) if base else Path.home() / ".cache") / "radtree"


def _limit_bytes() -> int:
    raw = os.environ.get("RADTREE_CACHE_MB", "").strip()
    try:
        mb = float(raw) if raw else DEFAULT_MB
    except ValueError:
        mb = DEFAULT_MB
    return int(max(mb, 0.0) * 1e6)


@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """SHA-256 of the radtree package's files and its shipped ``materials/`` and
    ``templates/`` (a checkout keeps them beside the package; paths and bytes) and the
    numerical libraries' versions: any edit or upgrade gives new keys."""
    from importlib import metadata

    import radtree
    from radtree.resources import FOLDERS, folder

    root = Path(radtree.__file__).parent
    h = hashlib.sha256(radtree.__version__.encode())
    tops = [root] + [Path(str(folder(name))) for name in FOLDERS]
    for top in dict.fromkeys(t for t in tops if t.is_dir()):
        for f in sorted(top.rglob("*")):
            if f.is_file() and "__pycache__" not in f.parts and f.suffix not in (".pyc", ".pyo"):
                h.update(str(f.relative_to(top.parent)).encode())
                h.update(f.read_bytes())
    for lib in _LIBRARIES:
        try:
            h.update(f"{lib}={metadata.version(lib)}".encode())
        except metadata.PackageNotFoundError:
            h.update(f"{lib}=-".encode())
    return h.hexdigest()


def _plain(obj: Any, located: bool) -> Any:
    """JSON-able form of a dataclass tree; a file counts by its content, and by its resolved
    path too when ``located`` (what is built records where its input came from)."""
    from dataclasses import fields, is_dataclass

    if is_dataclass(obj) and not isinstance(obj, type):
        return {"@": type(obj).__name__, **{f.name: _plain(getattr(obj, f.name), located)
                                             for f in fields(obj)}}
    if isinstance(obj, dict):
        return {str(k): _plain(v, located) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_plain(v, located) for v in obj]
    if isinstance(obj, Path):
        p = obj.resolve()
        return {"path": str(p) if located else p.name,
                "sha256": file_sha256_cached(p) if p.is_file() else None}
    return obj


def content_key(*arrays: Any, located: tuple[str, ...] = (), **parts: Any) -> str:
    """The cache key of what is made from ``parts`` (dataclasses, strings, numbers, paths)
    and ``arrays`` (their bytes), by radtree's code as installed. Files count by name and
    content; in the parts named in ``located`` by their full path too (a crown made from a
    photo records the photo's path)."""
    text = json.dumps({"code": code_fingerprint(),
                       **{k: _plain(v, k in located) for k, v in parts.items()}},
                      sort_keys=True, default=repr)
    h = hashlib.sha256(text.encode())
    for a in arrays:
        h.update(f"{a.dtype}{a.shape}".encode())
        h.update(memoryview(a).cast("B") if a.flags.c_contiguous else a.tobytes())
    return h.hexdigest()


def cached_object(key: str, build: Callable[[], Any]) -> tuple[Any, bool]:
    """``(object, True)`` from the cache when ``key`` is there, else ``(build(), False)`` with
    the object stored. An unreadable entry is rebuilt; a cache that cannot be written is
    skipped (the build goes on, slower)."""
    folder = cache_dir()
    if folder is None:
        return build(), False
    path = folder / f"{key}.pickle"
    try:
        with path.open("rb") as f:
            crown = pickle.load(f)
        os.utime(path)                      # recently used: evicted last
        return crown, True
    except FileNotFoundError:
        pass
    except (OSError, pickle.UnpicklingError, EOFError, AttributeError, ImportError, ValueError):
        path.unlink(missing_ok=True)        # unreadable (e.g. a half-copied file): rebuilt
    obj = build()
    _store(path, lambda tmp: tmp.write_bytes(pickle.dumps(obj, protocol=5)))
    return obj, False


def has_object(key: str) -> bool:
    """True when the cache holds the object of ``key`` (:func:`cached_object`)."""
    folder = cache_dir()
    return folder is not None and (folder / f"{key}.pickle").is_file()


def cached_file(key: str, suffix: str, make: Callable[[Path], Any], dest: Path) -> bool:
    """Make the file ``dest`` (atomically): copied from the cache entry ``key`` when there
    (True), else written by ``make(path)`` and stored (False)."""
    folder = cache_dir()
    path = None if folder is None else folder / f"{key}{suffix}"
    if path is not None and path.is_file():
        try:
            with atomic_path(dest) as tmp:
                shutil.copyfile(path, tmp)
            os.utime(path)
            return True
        except FileNotFoundError:           # evicted by another process meanwhile
            pass
    with atomic_path(dest) as tmp:
        make(tmp)
    if path is not None:
        _store(path, lambda t: shutil.copyfile(dest, t))
    return False


def _store(path: Path, write: Callable[[Path], Any]) -> None:
    """Put an entry in the cache (atomically), then keep the cache within its size."""
    try:
        make_folder(path.parent)
        with atomic_path(path) as tmp:
            write(tmp)
        _evict(path.parent, _limit_bytes(), keep=path)
    except OSError:
        pass                                # a read-only or full cache slows, never fails


def _entries(folder: Path) -> list[tuple[float, int, Path]]:
    out = []
    for p in (p for suffix in _SUFFIXES for p in folder.glob(f"*{suffix}")):
        try:
            st = p.stat()
        except OSError:
            continue
        out.append((st.st_mtime, st.st_size, p))
    return sorted(out)


def _evict(folder: Path, limit: int, keep: Path) -> None:
    """Delete the least recently used entries until the folder holds at most ``limit`` bytes
    (``keep``, the entry just written, stays)."""
    entries = _entries(folder)
    total = sum(size for _, size, _ in entries)
    for _, size, p in entries:
        if total <= limit:
            break
        if p != keep:
            p.unlink(missing_ok=True)
            total -= size


@dataclass(frozen=True)
class CacheInfo:
    """What the build cache holds: its folder (None: off), entries, bytes, limit in bytes."""

    folder: Path | None
    entries: int
    bytes: int
    limit: int
    oldest: float | None     # last use of the least recently used entry (Unix time, s)

    def describe(self) -> str:
        if self.folder is None:
            return "build cache: off (RADTREE_CACHE_DIR=off)"
        age = ("" if self.oldest is None else
               f", least recently used {(time.time() - self.oldest) / 86400:.1f} days ago")
        return (f"build cache: {self.folder}\n  {self.entries} entries (crowns, mesh OBJ text), "
                f"{self.bytes / 1e6:.1f} MB "
                f"of {self.limit / 1e6:.0f} MB (RADTREE_CACHE_MB){age}")


def cache_info() -> CacheInfo:
    folder = cache_dir()
    entries = [] if folder is None or not folder.is_dir() else _entries(folder)
    return CacheInfo(folder, len(entries), sum(s for _, s, _ in entries), _limit_bytes(),
                     entries[0][0] if entries else None)


def clear_cache() -> int:
    """Delete every cache entry; return how many."""
    folder = cache_dir()
    if folder is None or not folder.is_dir():
        return 0
    entries = _entries(folder)
    for _, _, p in entries:
        p.unlink(missing_ok=True)
    return len(entries)
