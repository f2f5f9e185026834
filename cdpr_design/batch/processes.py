"""Worker processes that a stop signal never catches half-started: the pools of ``sweep`` and ``optimize``.

A worker process takes a second or more to start (a new interpreter
importing numpy and the package).  Ctrl-C in a terminal reaches every process
of the foreground group, and a run that stops interrupts its workers; a
worker hit while it was still importing printed Python's KeyboardInterrupt
traceback under the run's own clean ``interrupted``.

So a worker is started with the stop signals (SIGINT, SIGTERM, SIGHUP)
*blocked* -- the signal mask is inherited through ``fork`` and ``exec``, as
multiprocessing starts its own resource tracker -- and unblocks them only
once its handlers are set, first thing in the pool's initializer
(:func:`_ready`): a stop signal that came meanwhile is delivered to those
handlers, not to Python's start-up.  In a worker:

- SIGTERM keeps its default action: the run ends a worker it no longer needs
  at once and silently (``Process.terminate``);
- SIGINT and SIGHUP end a worker quietly (exit status 130) -- unless it is
  inside :func:`stop_raises` (an optimize trial being evaluated), where the
  first one raises :class:`KeyboardInterrupt`, so that the trial is recorded
  as interrupted, and later ones are ignored while that runs.

The run itself (the parent) decides what an interruption means: it stops
or ends its workers and exits 130 (:mod:`cdpr_design.cli.signals`).  Two
things would still let a worker speak after the run's own ``interrupted``:

- a stop signal handled in the parent while it hands a new worker its
  start-up data (the pickled process object, down a pipe): the
  :class:`KeyboardInterrupt` cut the data short and the worker, reading it,
  failed with ``EOFError``.  So a worker is started with the stop signals
  held in the parent too (:func:`~cdpr_design.io.locks.signals_held`): the
  interrupt is raised once the worker has all its data;
- a worker still starting when the run exits: it rebuilt the run's
  semaphores after the run had removed them (``FileNotFoundError``).  So an
  interrupted run ends its workers with :func:`end` -- killed (a starting
  worker holds every catchable signal) and waited for -- before it shuts its
  pool down and exits (:func:`end_pool`).
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import signal
from concurrent.futures import ProcessPoolExecutor
from multiprocessing.context import ForkContext, ForkProcess, SpawnContext, SpawnProcess
from typing import Callable

from cdpr_design.errors import STOP_SIGNALS
from cdpr_design.io.locks import signals_held

#: A worker's exit status when a stop signal ended it outside :func:`stop_raises`.
EXIT_INTERRUPTED = 130


@contextlib.contextmanager
def _blocked():
    """The stop signals blocked in this thread (a process started here inherits the mask)."""
    old = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


class _QuietSpawnProcess(SpawnProcess):
    def start(self):
        with signals_held(), _blocked():
            super().start()


class _QuietForkProcess(ForkProcess):
    def start(self):
        with signals_held(), _blocked():
            super().start()


class _QuietSpawnContext(SpawnContext):
    Process = _QuietSpawnProcess


class _QuietForkContext(ForkContext):
    Process = _QuietForkProcess


_CONTEXTS = {"spawn": _QuietSpawnContext, "fork": _QuietForkContext}


def pool(workers: int, start_method: str = "spawn", initializer: Callable | None = None,
         initargs: tuple = ()) -> ProcessPoolExecutor:
    """A process pool of ``workers`` started with ``start_method`` (``spawn`` or ``fork`` quietly, see the
    module; another method as multiprocessing does it); ``initializer(*initargs)`` runs in each
    worker once its signal handlers are set."""
    ctx = _CONTEXTS[start_method]() if start_method in _CONTEXTS else mp.get_context(start_method)
    return ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_ready,
                               initargs=(initializer, initargs))


def end(processes, timeout_s: float = 10.0) -> None:
    """End worker ``processes`` at once (SIGKILL: a worker still starting holds every other
    signal) and wait up to ``timeout_s`` seconds for them to be gone, so that none outlives the
    run that stops them.  A process already gone is skipped."""
    processes = list(processes)
    for p in processes:
        with contextlib.suppress(Exception):
            p.kill()
    for p in processes:
        with contextlib.suppress(Exception):
            p.join(timeout_s)


def end_pool(ex: ProcessPoolExecutor, before, stop: Callable = end) -> None:
    """End the pool ``ex`` of an interrupted run: its worker processes first (the children not in
    ``before``, the set of ``multiprocessing.active_children()`` from before the pool, handed to
    ``stop``: :func:`end`, or a gentler stop that ends with it), then the pool shut down without
    waiting.  In this order because until it is shut down the pool holds the queues whose
    semaphores a worker still starting rebuilds: a worker started just before the interrupt is
    known to no other part of the pool yet."""
    stop([p for p in mp.active_children() if p not in before])
    ex.shutdown(wait=False, cancel_futures=True)


class _Stop:
    armed = 0  # inside stop_raises
    raised = False  # a stop signal raised KeyboardInterrupt there already


def _on_stop(signum, frame) -> None:
    if _Stop.armed:
        if not _Stop.raised:
            _Stop.raised = True
            raise KeyboardInterrupt(signal.Signals(signum).name)
        return
    os._exit(EXIT_INTERRUPTED)  # no work of its own under way: nothing to clean, nothing to say


def _ready(initializer: Callable | None, initargs: tuple) -> None:
    """A worker's first step: its stop-signal handlers set, then the signals unblocked."""
    for s in STOP_SIGNALS:
        signal.signal(s, signal.SIG_DFL if s == getattr(signal, "SIGTERM", None) else _on_stop)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, STOP_SIGNALS)
    if initializer is not None:
        initializer(*initargs)


@contextlib.contextmanager
def stop_raises():
    """Within the block (in a worker of :func:`pool`) the first SIGINT or SIGHUP raises
    :class:`KeyboardInterrupt` instead of ending the worker."""
    _Stop.armed += 1
    try:
        yield
    finally:
        _Stop.armed -= 1
