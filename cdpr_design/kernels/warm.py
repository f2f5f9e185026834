"""Compile a pose's kernels in two processes at once, on a machine's first run.

numba compiles one function at a time, in the process that needs it: a first run of IPAnema 3
compiled for about 20 CPU-s on one core while the other waited.  The functions a sweep's pose
calls (:func:`~cdpr_design.kernels.pose.pose_kernels`) fall into two independent sets of about
the same cost, the margins' and the tensions': :func:`compile_pose` compiles the margins' in a
new process (:func:`main`, run by ``python -c``) while this one compiles the
tensions', both into numba's on-disk cache (``cache=True``; numba's cache files are written
atomically, one per function), and waits for it.  The sweep's own loop, compiled next, then
loads them from the cache instead of compiling them: numba caches a function with the code
callers link in, so the loop's machine code is the one it would have had.

Only on a first run: the other process starts when one of the tensions' functions was not in
the cache (compiled, not loaded).  When they all loaded, nothing is started: a run that
compiled this m - n's QP method compiled its margins too, as a rule (every cache entry is
stamped with the whole package's sources, :mod:`cdpr_design.kernels._jit`); where it did not,
and whatever the other process does not compile (it failed, or was stopped), the loop
compiles itself, as it would without this.
"""

from __future__ import annotations

import os
import subprocess
import sys
from typing import Callable

import numba

from cdpr_design.kernels.pose import pose_kernels

#: the folder holding the ``cdpr_design`` package, first on the other process's path
_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _compile(functions) -> None:
    for dispatcher, types in functions:
        dispatcher.compile(types)


def compile_pose(n: int, m: int, meanwhile: Callable[[], None] | None = None) -> bool:
    """Compile (or load) the pose kernels for ``n`` DOF and ``m`` cables, the margins' in another
    process when they are not in numba's cache; returns whether that process ran.  ``meanwhile``
    is called, when it did, before waiting for it: more to compile in this process (the CSV
    formatter), while the other finishes."""
    if numba.config.DISABLE_JIT:
        return False  # plain Python functions: nothing to compile
    tensions, margins = pose_kernels(n, m)
    other = None
    try:
        for dispatcher, types in tensions:
            missed = sum(dispatcher.stats.cache_misses.values())
            dispatcher.compile(types)
            if other is None and sum(dispatcher.stats.cache_misses.values()) > missed:
                other = _start(n, m)
        if other and meanwhile is not None:
            meanwhile()
    finally:
        if other:
            other.wait()
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
    """The other process: compile the margins' functions of ``n`` DOF and ``m`` cables into the cache."""
    _compile(pose_kernels(n, m)[1])


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]))
