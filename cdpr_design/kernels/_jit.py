"""The jit options of every kernel, set once.

``cache=True`` so users pay the compile time once per machine (numba's on-disk
cache), ``nogil`` so sweeps run their blocks of poses on threads
(:mod:`cdpr_design.kernels.parallel`; no kernel uses ``parallel=True``), ``error_model='numpy'`` so a
division by zero gives inf/NaN as in numpy instead of raising.  Only numba's documented
options are used.

Where numba caches the kernels, and why a change to any kernel module needs a new
folder, is :mod:`cdpr_design.kernels.cache`'s part.
"""

from __future__ import annotations

import numba as nb
from numba.extending import register_jitable

JIT = dict(cache=True, nogil=True, error_model="numpy")
njit = nb.njit(**JIT)
#: Reassociation (vectorised reductions) without giving up NaN/inf semantics.
FAST = {"reassoc", "contract", "arcp"}
njit_fast = nb.njit(fastmath=FAST, **JIT)
#: Small helpers of the hot loops, inlined into their callers in numba's IR: no call, and no
#: array passed per call (numba counts a reference to every array a function binds).
njit_inline = nb.njit(fastmath=FAST, inline="always", **JIT)
#: A function with a single caller, inlined into it in numba's IR with the caller's own options:
#: a separately compiled function is optimised by LLVM again, with everything it calls, in the
#: module of every function that calls it, so each level of a chain of calls costs its whole
#: depth again (the sagging cables' fixed point).
njit_folded = nb.njit(inline="always", **JIT)


def jitable(func):
    """``func`` itself, a plain Python function, and compiled into the kernels that call it
    (``numba.extending.register_jitable``).

    For the functions that only allocate a kernel's arrays (:func:`~cdpr_design.kernels.hsm.make_scratch`):
    called from Python, numpy allocates them and nothing is compiled.
    """
    return register_jitable(func)

