"""How the world's kernels are compiled (numba): one decorator per way a kernel is called.

A fresh clone compiles every kernel of the traffic step before the first simulated chunk exists,
so these options keep that compile short without changing a number:

* ``kernel``: called from Python; compiled on its own and cached on disk.
* ``inlined``: called from compiled kernels only, at one or two places: numba copies its code into
  the caller before typing it, so it is compiled once with its caller instead of once on its own
  and again inside every caller's module. Its operations and their order are the same. Called
  from Python (tests, or ``commit`` after the exact overlap check), it compiles on its own.
* ``leaf``: a small helper called from compiled kernels only: compiled once and linked into each
  caller, with no CPython wrapper (numba builds one for every function Python may call).

All: cached on disk, numpy's error model, no C callback wrapper (nothing takes their address), no
parallelism, no fast-math. Numpy's error model: a division by zero gives inf or NaN, as in the
numpy statement of the rules these replaced, instead of a zero check and a ZeroDivisionError branch
at every division (numba's default, Python's model): the same numbers wherever that model did not
raise, and less code to compile.
"""

from __future__ import annotations

from numba import njit

_OPTIONS = {"cache": True, "error_model": "numpy", "no_cfunc_wrapper": True}

kernel = njit(**_OPTIONS)
inlined = njit(**_OPTIONS, inline="always")
leaf = njit(**_OPTIONS, no_cpython_wrapper=True)
