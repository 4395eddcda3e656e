"""How the world's kernels are compiled (numba): one decorator per way a kernel is called.

``kernel`` (called from Python, compiled on its own), ``inlined`` (copied into its compiled
callers) and ``leaf`` (linked into each caller, no CPython wrapper); all cached on disk, numpy's
error model, no parallelism, no fast-math: the same numbers, a shorter first compile.

Design: docs/design/modules.md (Compiling the world's kernels)
"""

from __future__ import annotations

from numba import njit

_OPTIONS = {"cache": True, "error_model": "numpy", "no_cfunc_wrapper": True}

kernel = njit(**_OPTIONS)
inlined = njit(**_OPTIONS, inline="always")
leaf = njit(**_OPTIONS, no_cpython_wrapper=True)
