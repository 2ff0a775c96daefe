"""The in-process engines' optional compiled kernel (``radtree.engines.common._kernel``, built from
``_kernel.c`` at install when a C compiler is at hand).

It runs the shadow-ray loop's per-crossing arithmetic (:mod:`radtree.engines.numpy.shadow`) in
one pass per crossing instead of ≈ 25 NumPy passes: the transmittance products, Russian
roulette, compaction, the next origins past the surfaces crossed and their float32 copy in
Embree's frame. It computes every number exactly as the NumPy code does (the same IEEE
operations in the same order, compiled without contraction into fused multiply-adds); the
NumPy code stays the reference and the fallback.

``RADTREE_KERNEL`` = ``numpy`` forces the NumPy code, ``c`` requires the kernel (an error when
it is not built), ``auto`` (default) uses it when it loads.
"""

from __future__ import annotations

import importlib
import os
from types import ModuleType

import numpy as np

CHOICES = ("auto", "c", "numpy")

_loaded: tuple[ModuleType | None, str] | None = None


def _load() -> tuple[ModuleType | None, str]:
    """The compiled module (None when not built) and why not."""
    global _loaded
    if _loaded is None:
        try:
            # by name (a static ``from … import _kernel`` would put the compiled module in the
            # import graph the layer check walks, tests/test_layers.py; it was a cycle once)
            _kernel = importlib.import_module("radtree.engines.common._kernel")
        except ImportError as exc:
            _loaded = (None, f"not built ({exc})")
        else:
            _loaded = (_kernel, "")
    return _loaded


def choice() -> str:
    """``RADTREE_KERNEL`` (``auto`` | ``c`` | ``numpy``; default ``auto``)."""
    value = os.environ.get("RADTREE_KERNEL", "auto").strip().lower() or "auto"
    if value not in CHOICES:
        raise ValueError(f"RADTREE_KERNEL must be one of {CHOICES}, got {value!r}")
    return value


def kernel() -> ModuleType | None:
    """The compiled kernel when it is to be used, else None (the NumPy code)."""
    want = choice()
    if want == "numpy":
        return None
    mod, why = _load()
    if mod is None and want == "c":
        raise ImportError(f"RADTREE_KERNEL=c but the C kernel is {why}: reinstall radtree "
                          "with a C compiler (pip install -e .)")
    return mod


def name() -> str:
    """Which shadow-ray kernel the engine uses: ``c`` or ``numpy``."""
    return "c" if kernel() is not None else "numpy"


def describe() -> str:
    """One phrase for ``radtree doctor``: which kernel, and why NumPy when it is."""
    want = choice()
    if want == "numpy":
        return "shadow-ray kernel numpy (RADTREE_KERNEL=numpy)"
    mod, why = _load()
    if mod is None:
        return f"shadow-ray kernel numpy (the C kernel is {why})"
    return "shadow-ray kernel c (radtree.engines.common._kernel)"


def triangle_rows(normals: np.ndarray, v0: np.ndarray) -> np.ndarray:
    """The kernel's per-triangle rows (n, 8), zeroed, with the normal in columns 0–2 and the
    first vertex in 3–5 (columns 6–7 for the caller): one 64-byte row a triangle, starting on
    a 64-byte boundary (one cache line a lookup)."""
    n = len(normals)
    raw = np.zeros(8 * n + 8)
    skip = (-raw.ctypes.data % 64) // 8
    rows = raw[skip:skip + 8 * n].reshape(n, 8)
    rows[:, 0:3] = normals
    rows[:, 3:6] = v0
    return rows
