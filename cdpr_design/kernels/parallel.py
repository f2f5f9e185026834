"""Rows in blocks on threads: the one form of parallelism of the kernels.

A parallel kernel is a compiled, ``nogil`` *block* function that fills rows
``k0 .. k1-1`` of its outputs, each row on its own (no row reads another's
result), and a thin Python function of the old name that calls
:func:`run_blocks`.  The blocks run on a pool of threads that lives as long as
the process; numba releases the GIL inside the block, so the threads run on
separate cores.  A plain Python block whose work is numpy's (stacked linear algebra,
einsum: they release the GIL on large arrays) can share them too, in few large blocks
(:func:`cdpr_design.workspaces.hanging._hang_in_blocks`).

Why threads here rather than numba's ``prange``:

- compile time: a ``parallel=True`` function is compiled again around its
  whole call chain (numba re-optimises every function it links in), which cost
  about a quarter of a cold start (docs/performance.md);
- fork safety: numba's threading layer is often GNU OpenMP, which a
  ``fork`` after a parallel region can deadlock; with no ``prange`` it is
  never started;
- interruption: Ctrl-C reaches the waiting main thread at once, and the blocks
  not yet started are dropped.

The speed is the same: rows are independent and blocks are large (a block's
dispatch is small beside its work).  Results
do not depend on the thread count or on the block size.

The thread count is ``numba.config.NUMBA_NUM_THREADS`` (numba's own setting:
the available cores, or the ``NUMBA_NUM_THREADS`` environment variable)
unless :func:`set_threads` sets it for this process (a batch worker runs its
kernels on one thread: parallelism is across variants there).  This module
does not import numba until a kernel runs.
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait
from typing import Callable

#: Blocks handed out per thread (dynamic balance: grid regions differ in cost per row).
BLOCKS_PER_THREAD = 8

_PREFIX = "cdpr-kernel"
_threads: int | None = None
_pool: ThreadPoolExecutor | None = None
_pool_size = 0
_lock = threading.Lock()


def set_threads(n: int | None) -> None:
    """Run the kernels of this process on ``n`` threads (>= 1); None: numba's setting again."""
    global _threads
    if n is not None and n < 1:
        raise ValueError(f"threads must be >= 1, got {n}")
    _threads = n


@contextlib.contextmanager
def threads_kept():
    """The thread setting back to what it was before the ``with`` block, whatever the block set."""
    global _threads
    before = _threads
    try:
        yield
    finally:
        _threads = before


def threads() -> int:
    """The number of threads the kernels run on in this process (:func:`set_threads`)."""
    if _threads is not None:
        return _threads
    import numba  # already loaded: a kernel is about to run

    return max(1, int(numba.config.NUMBA_NUM_THREADS))


def _forget_pool() -> None:
    """In a forked child: the parent's pool threads do not exist here; the next run starts a new pool."""
    global _pool, _pool_size, _lock
    _pool, _pool_size, _lock = None, 0, threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool)


def _executor(n: int) -> ThreadPoolExecutor:
    """The pool, with at least ``n`` threads; the caller holds ``_lock`` (and submits under it: a
    pool replaced by a bigger one is shut down, and takes no new work)."""
    global _pool, _pool_size
    if _pool is None or _pool_size < n:
        if _pool is not None:
            _pool.shutdown(wait=False)  # its queued work still runs
        _pool = ThreadPoolExecutor(max_workers=n, thread_name_prefix=_PREFIX)
        _pool_size = n
    return _pool


def blocks(count: int, grain: int, nthreads: int) -> list[tuple[int, int]]:
    """Split rows 0 .. count-1 into contiguous blocks (k0, k1): at most ``BLOCKS_PER_THREAD`` per
    thread, none smaller than ``grain`` rows unless the rows run out."""
    if count <= 0:
        return []
    n = max(1, min(nthreads * BLOCKS_PER_THREAD, math.ceil(count / max(grain, 1))))
    size = math.ceil(count / n)
    return [(k0, min(count, k0 + size)) for k0 in range(0, count, size)]


def run_blocks(block: Callable, count: int, *args, grain: int = 256) -> None:
    """Call ``block(k0, k1, *args)`` over rows 0 .. count-1 in blocks of at least ``grain`` rows.

    One block runs in the calling thread; several run on at most :func:`threads` pool threads
    (each takes the next block not begun) and this waits for all of them.  An error in a block is
    raised here (the first one); if this thread is interrupted (Ctrl-C), the blocks not yet
    started are dropped and the running ones finish before the exception goes on, so no thread
    writes into the outputs after this returns.  A numba block not compiled yet runs its first
    block here: the compile (or the load from numba's cache) happens where Ctrl-C reaches it.
    """
    nthreads = threads()
    parts = blocks(count, grain, nthreads)
    # one block, one thread, or already on a pool thread (a block never waits for the pool)
    if len(parts) <= 1 or nthreads == 1 or threading.current_thread().name.startswith(_PREFIX):
        for k0, k1 in parts:
            block(k0, k1, *args)
        return
    if getattr(block, "signatures", None) == []:  # a numba dispatcher that has not run yet
        k0, k1 = parts.pop(0)
        block(k0, k1, *args)
    todo = iter(parts)
    take = threading.Lock()
    stop = threading.Event()

    def runner():
        while not stop.is_set():
            with take:
                part = next(todo, None)
            if part is None:
                return
            try:
                block(part[0], part[1], *args)
            except BaseException:
                stop.set()  # the other runners begin no further block
                raise

    futures = []
    try:
        with _lock:  # no pool is replaced between taking it and submitting to it
            pool = _executor(nthreads)
            futures = [pool.submit(runner) for _ in range(min(nthreads, len(parts)))]
        pending = set(futures)
        while pending:  # short waits: a signal's handler (Ctrl-C) runs between them
            done, pending = wait(pending, timeout=0.05, return_when=FIRST_EXCEPTION)
            for f in done:
                f.result()
    except BaseException:
        stop.set()
        for f in futures:
            f.cancel()
        wait(futures)
        raise
