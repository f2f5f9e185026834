"""The jit options of every kernel, set once.

``cache=True`` so users pay the compile time once per machine (numba's on-disk
cache), ``nogil`` so sweeps run their blocks of poses on threads
(:mod:`cdpr_design.kernels.parallel`; no kernel uses ``parallel=True``), ``error_model='numpy'`` so a
division by zero gives inf/NaN as in numpy instead of raising.
"""

from __future__ import annotations

import numba as nb

JIT = dict(cache=True, nogil=True, error_model="numpy")
njit = nb.njit(**JIT)
#: Reassociation (vectorised reductions) without giving up NaN/inf semantics.
FAST = {"reassoc", "contract", "arcp"}
njit_fast = nb.njit(fastmath=FAST, **JIT)
#: Small helpers of the hot loops, inlined into their callers (no call, no reference counting per call).
njit_inline = nb.njit(fastmath=FAST, inline="always", **JIT)
