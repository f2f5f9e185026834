"""The functions a grid pose of m - n = 1 or 2 calls, as C function pointers, and the blocks of the
loops that call them so.

numba compiles a function together with everything it calls: the grid sweep's loop for m - n = 2
linked the functions its pose calls (:func:`~cdpr_design.kernels.pose.eval_small`) into its own
code, optimised them again with it, and so could only compile once they were compiled.  On a
machine's first run of IPAnema 3 that put the loop's compile after the margins' (in
the other process, :mod:`cdpr_design.kernels.warm`), each on the critical path.  Here the loop
takes six functions as arguments of numba's first-class function type -- ``eval_small``'s five
and the structure matrix (:func:`~cdpr_design.kernels.geometry.structure_matrix`) -- given
pointers to them (the C wrappers numba makes of the compiled functions themselves,
:func:`pointers`): it compiles on its own, while the other process still compiles its share
(:data:`HERE`, :data:`THERE`), once for m - n = 1 and 2, and nothing is compiled twice (the loops
that call the six directly link the same compiled functions).  It is also given only the twelve
scratch arrays its pose works in (:func:`~cdpr_design.kernels.pose.small_scratch`): an indirect
call a function, six a pose, the outputs identical (first-run figures: docs/performance.md).

The pointers are passed as six arguments, not a tuple: a tuple of functions makes numba warn that
first-class functions are experimental, separate arguments do not.  Under ``NUMBA_DISABLE_JIT``
the loops are Python functions and are given the Python functions themselves.
"""

from __future__ import annotations

import subprocess
import threading

import numba
import numpy as np

from cdpr_design.kernels._jit import pointer
from cdpr_design.kernels.geometry import structure_matrix
from cdpr_design.kernels.pose import pose_kernels, row_buffers, small_scratch

#: the pointers made in this process, by (function, signature)
_made: dict = {}
#: the other process compiling the margins' pointers (kernels.warm), by (n, m)
_pending: dict[tuple[int, int], subprocess.Popen] = {}
_lock = threading.Lock()


def expect(n: int, m: int, process: subprocess.Popen) -> None:
    """Note that ``process`` compiles the margins' pointers of ``n`` DOF and ``m`` cables into the
    cache: :func:`pointers` waits for it before making them here (loaded, not compiled again)."""
    with _lock:
        _pending[(n, m)] = process


#: positions in :func:`pointers` of the functions a first run compiles in this process (the tensions'
#: projection, first: the one of the two whose code differs between m - n = 1 and 2, and the basis
#: factorisation) and in the other (the null basis, the margins' setup and facets, the structure
#: matrix; :mod:`cdpr_design.kernels.warm`): about the same time each
HERE = (4, 0)
THERE = tuple(k for k in range(6) if k not in HERE)


def pointers(n: int, m: int, wreq=None, tmax=None, which=(0, 1, 2, 3, 4, 5)) -> list:
    """Pointers to the grid pose's functions of ``n`` DOF and ``m`` cables (m - n = 1, 2) for a
    sweep's ``wreq`` and ``tmax``: those at the positions ``which`` of :func:`pose_functions`' six
    (:data:`HERE`, :data:`THERE`).  Each is compiled, or loaded from numba's cache, once per
    process; those of :data:`THERE` after the other process compiling them finished
    (:func:`expect`).  Under ``NUMBA_DISABLE_JIT``, the Python functions."""
    six = pose_functions(n, m, wreq, tmax)
    if any(k in THERE for k in which):
        with _lock:
            other = _pending.pop((n, m), None)
        if other is not None:
            other.wait()
    if numba.config.DISABLE_JIT:
        return [six[k][0] for k in which]
    out = []
    for k in which:
        with _lock:
            if six[k] not in _made:
                _made[six[k]] = pointer(*six[k])
            out.append(_made[six[k]])
    return out


def pose_functions(n: int, m: int, wreq=None, tmax=None) -> list:
    """The six (dispatcher, signature) a grid pose calls, in the order of the grid loop's arguments:
    :func:`~cdpr_design.kernels.pose.pose_kernels`' five in the order of
    :func:`~cdpr_design.kernels.pose.eval_small`'s, then the structure matrix for the grid's types
    (C-contiguous float64 arrays Rb, A (m, 3) [m], W (n, m), L (m,) [m], the int64 rows)."""
    from numba import typeof, types

    tensions, margins = pose_kernels(n, m, wreq, tmax)
    f8, vec, mat = types.float64, typeof(np.empty(1)), typeof(np.empty((1, 1)))
    structure = (structure_matrix, types.boolean(f8, f8, f8, mat, mat, typeof(np.empty(1, dtype=np.int64)), mat, vec))
    return tensions[:2] + margins + tensions[2:] + [structure]


def signature_types(n: int, m: int, wreq=None, tmax=None) -> tuple:
    """The numba types of the six :func:`pointers`, in their order: what a loop taking them is compiled for."""
    from numba import types

    return tuple(types.FunctionType(sig) for _, sig in pose_functions(n, m, wreq, tmax))


class PointerBlock:
    """Rows k0..k1-1 of a sweep whose loop takes the pose's functions as pointers (m - n = 1, 2): the
    block's buffers (:func:`~cdpr_design.kernels.pose.row_buffers`, the scratch as its
    :func:`~cdpr_design.kernels.pose.small_scratch`), then ``loop(*pointers, k0, k1, *args, W, t, L, lo, scr)``.

    ``parts(*args)`` gives (n, m, nv, wreq, tmax) from the block's arguments (``wreq`` (nv, n) a
    pose's required wrenches), ``extra(m)`` more work arrays after the scratch, if any (as
    :class:`~cdpr_design.kernels.pose.RowBlock`'s).  The first call
    compiles the loop for the pointers' types before it asks for them (:func:`pointers`), so on a
    machine's first run the loop compiles while the other process compiles the margins.  Python,
    as :class:`~cdpr_design.kernels.pose.RowBlock`.
    """

    def __init__(self, loop, parts, extra=None):
        self.loop, self.parts, self.extra = loop, parts, extra
        self._fns: dict = {}

    @property
    def signatures(self) -> list:
        """The loop's compiled signatures (:func:`~cdpr_design.kernels.parallel.run_blocks` runs the
        first block of a loop not compiled yet on the calling thread)."""
        return self.loop.signatures

    def __call__(self, k0, k1, *args):
        n, m, nv, wreq, tmax = self.parts(*args)
        W, t, L, lo, scr = row_buffers(n, m, nv)
        buffers = (W, t, L, lo, small_scratch(scr)) + (() if self.extra is None else self.extra(m))
        key = (n, m, numba.typeof(wreq), numba.typeof(tmax))
        fns = self._fns.get(key)
        if fns is None:
            if not numba.config.DISABLE_JIT:
                from numba import typeof, types

                self.loop.compile(signature_types(n, m, wreq, tmax) + (types.int64, types.int64)
                                  + tuple(typeof(a) for a in args + buffers))
            fns = self._fns[key] = tuple(pointers(n, m, wreq, tmax))
        self.loop(*fns, k0, k1, *args, *buffers)
