"""Compile a pose's kernels in two processes at once, on a machine's first run.

numba compiles one function at a time, in the process that needs it: a first run of IPAnema 3
compiled on one core while the other waited.  The functions a sweep's pose
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
processes finish at about the same time (IPAnema 3, docs/performance.md).  For any
other m - n :func:`compile_pose` waits for the other process, and the loop,
compiled next, loads the functions from the cache instead of compiling them: numba caches a
function with the code callers link in, so the loop's machine code is the one it would have had.

Only on a first run: the other process is started, then this one compiles or loads a function of
its share whose code is this m - n's, and the other is kept only if that was a compile (not in
the cache, :func:`_first_run`); started before the answer is known, it imports numba while this
process does.  When it loaded, the other process is stopped: a run that compiled this m - n's QP method
compiled its margins too, as a rule (every cache entry is stamped with the whole package's
sources, :mod:`cdpr_design.kernels._jit`); where it did not, and whatever the other process does
not compile (it failed, or was stopped), this process compiles them itself, as it would without
this.
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
    process when they are not in numba's cache; returns whether that process was kept (a first run).
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
    tensions, _ = pose_kernels(n, m)  # the QP last: its code is this m - n's
    if not tensions:
        return False  # m = n: one small function, nothing to share
    other = _first_run(n, m, *tensions[-1])
    try:
        _compile(tensions[:-1])
        if other and meanwhile is not None:
            meanwhile()
    finally:
        if other:
            other.wait()
    return bool(other)


def _compile_pointers(n: int, m: int, meanwhile: Callable[[], None] | None) -> bool:
    """:func:`compile_pose` for m - n = 1, 2: the pointers of :data:`~cdpr_design.kernels.pointers.HERE`
    here, the others in the other process."""
    six = pointers.pose_functions(n, m)
    other = _first_run(n, m, *six[pointers.HERE[0]])
    if other:
        pointers.expect(n, m, other)
    pointers.pointers(n, m, which=pointers.HERE)
    if other and meanwhile is not None:
        meanwhile()
    return bool(other)


def _first_run(n: int, m: int, dispatcher, sig) -> subprocess.Popen | None:
    """The other process if this is a machine's first run of this m - n, else None.

    The other process is started first, then ``dispatcher`` (of this process's share, one whose
    code is this m - n's own: the tensions' QP or projection) compiled or loaded here for ``sig``:
    the other is kept if that was a compile (not in numba's cache), and stopped if it loaded --
    then so will the rest.  Started before the answer is known, the other process imports numba
    while this one does; on a run that loads, it is stopped after about that, on the other core.
    Nothing is started when this process has ``dispatcher`` already (compiled or loaded by an
    earlier sweep of the same m - n: the functions' types do not depend on n and m)."""
    if tuple(sig.args) in dispatcher.overloads:
        return None
    other = _start(n, m)
    missed = sum(dispatcher.stats.cache_misses.values())
    compiled = False
    try:
        dispatcher.compile(sig.args)
        compiled = sum(dispatcher.stats.cache_misses.values()) > missed
    finally:
        if other and not compiled:  # it loaded (or failed): the other process has nothing to do
            other.kill()
            other.wait()
    return other if other and compiled else None


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
