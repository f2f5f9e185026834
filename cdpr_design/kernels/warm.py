"""Compile a pose's kernels in two processes at once, on a machine's first run.

numba compiles one function at a time, in the process that needs it: a first run of IPAnema 3
compiled for about 20 CPU-s on one core while the other waited.  The functions a sweep's pose
calls (:func:`~cdpr_design.kernels.pose.pose_kernels`) fall into two independent sets of about
the same cost, the margins' and the tensions': :func:`compile_pose` compiles the margins' in a
new process (:func:`main`, run by ``python -c``) while this one compiles the
tensions', both into numba's on-disk cache (``cache=True``; numba's cache files are written
atomically, one per function).

For m - n = 1, 2 they are pointers (:mod:`cdpr_design.kernels.pointers`), with the structure
matrix, and the grid sweep's loop compiles without them: this process compiles the basis
factorisation and the tensions' projection (:data:`~cdpr_design.kernels.pointers.HERE`), the
other the null basis, the margins' setup and facets and the structure matrix
(:data:`~cdpr_design.kernels.pointers.THERE`), then the chunk statistics; :func:`compile_pose`
returns once this process has its share (and the CSV formatter, ``meanwhile``), the loop
compiles while the other process still works, and the sweep's block waits for it only when it
needs the other's pointers, then loads them from the cache.  The shares are chosen so that both
processes finish at about the same time (IPAnema 3, ``scripts/bench_first_run.py``).  For any
other m - n :func:`compile_pose` waits for the other process, and the loop,
compiled next, loads the functions from the cache instead of compiling them: numba caches a
function with the code callers link in, so the loop's machine code is the one it would have had.

Only on a first run: the other process starts when one of the tensions' functions was not in
the cache (compiled, not loaded).  When they all loaded, nothing is started: a run that
compiled this m - n's QP method compiled its margins too, as a rule (every cache entry is
stamped with the whole package's sources, :mod:`cdpr_design.kernels._jit`); where it did not,
and whatever the other process does not compile (it failed, or was stopped), this process
compiles them itself, as it would without this.
"""

from __future__ import annotations

import os
import subprocess
import sys
from typing import Callable

import numba

from cdpr_design.kernels import pointers
from cdpr_design.kernels.pose import pose_kernels
from cdpr_design.kernels.sweep import compile_chunk_stats

#: the folder holding the ``cdpr_design`` package, first on the other process's path
_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _compile(functions) -> None:
    for dispatcher, sig in functions:
        dispatcher.compile(sig.args)


def compile_pose(n: int, m: int, meanwhile: Callable[[], None] | None = None) -> bool:
    """Compile (or load) the pose kernels for ``n`` DOF and ``m`` cables, the margins' in another
    process when they are not in numba's cache; returns whether that process was started.
    ``meanwhile`` is called, when it was, while the other runs: more to compile in this process
    (the CSV formatter).

    For m - n = 1, 2 the kernels are pointers (:mod:`cdpr_design.kernels.pointers`) and the grid
    loop does not need them to compile: this returns without waiting, and the sweep's block,
    having compiled its loop, waits for the other process when it asks for that process's
    pointers.  For any other m - n this waits for it."""
    if numba.config.DISABLE_JIT:
        return False  # plain Python functions: nothing to compile
    if m - n in (1, 2):
        return _compile_pointers(n, m, meanwhile)
    tensions, margins = pose_kernels(n, m)
    other = None
    try:
        for dispatcher, sig in tensions:
            missed = sum(dispatcher.stats.cache_misses.values())
            dispatcher.compile(sig.args)
            if other is None and sum(dispatcher.stats.cache_misses.values()) > missed:
                other = _start(n, m)
        if other and meanwhile is not None:
            meanwhile()
    finally:
        if other:
            other.wait()
    return bool(other)


def _compile_pointers(n: int, m: int, meanwhile: Callable[[], None] | None) -> bool:
    """:func:`compile_pose` for m - n = 1, 2: the pointers of :data:`~cdpr_design.kernels.pointers.HERE`
    here, the others in the other process, started as soon as the first of this one's was not in
    the cache."""
    six = pointers.pose_functions(n, m)
    other = None
    for k in pointers.HERE:
        dispatcher = six[k][0]
        missed = sum(dispatcher.stats.cache_misses.values())
        pointers.pointers(n, m, which=(k,))
        if other is None and sum(dispatcher.stats.cache_misses.values()) > missed:
            other = _start(n, m)
            if other:
                pointers.expect(n, m, other)
    if other and meanwhile is not None:
        meanwhile()
    return bool(other)


def _start(n: int, m: int) -> subprocess.Popen | bool:
    """The other process, compiling the margins' functions; False if it cannot be started (then
    the sweep's loop compiles them, as without it)."""
    # this process's environment is inherited (NUMBA_CACHE_DIR with it); the child puts this
    # checkout first on its path, as the picture worker does
    code = f"import sys; sys.path.insert(0, {_ROOT!r}); from {__name__} import main; main({n}, {m})"
    try:
        return subprocess.Popen([sys.executable, "-c", code],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        return False


def main(n: int, m: int) -> None:
    """The other process: compile the margins' functions of ``n`` DOF and ``m`` cables (for m - n = 1, 2
    the pointers of :data:`~cdpr_design.kernels.pointers.THERE`), then the chunk statistics, into the cache."""
    if m - n in (1, 2):
        pointers.pointers(n, m, which=pointers.THERE)
    else:
        _compile(pose_kernels(n, m)[1])
    compile_chunk_stats()


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]))
