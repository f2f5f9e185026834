"""Running a sweep: every variant of a plan evaluated, in this process, a process pool or on Dask.

See :mod:`cdpr_design.batch.local` for the evaluation of a variant and the
process pool, :mod:`cdpr_design.batch.dask` for Dask; this module chooses the
backend and counts the rows.
"""

from __future__ import annotations

import time
from typing import Callable, Iterable

from cdpr_design.batch.dask import run_dask
from cdpr_design.batch.local import Job, Options, RunStats, default_workers, run_pool, run_serial, with_catalogue
from cdpr_design.batch.variants import Plan
from cdpr_design.errors import InputError


def run(plan: Plan, options: Options | None = None, *, workers: int | None = None,
        scheduler: str | None = None, skip: Iterable[int] = (),
        on_record: Callable[[dict], None] | None = None,
        progress: Callable[[int, int], None] | None = None,
        chunk: int | None = None, start_method: str = "spawn",
        connect_timeout: float = 10.0, pool: bool | None = None) -> RunStats:
    """Evaluate every variant of ``plan`` not in ``skip``; rows go to ``on_record`` as they finish.

    Parameters
    ----------
    plan : Plan
    options : Options
    workers : int, optional
        Processes (default: one per core).  1 runs in this process.  With a
        scheduler: the LocalCluster's worker count (``"local"``), ignored for
        an existing cluster (its thread count is used to size the chunks).
    scheduler : str, optional
        ``"local"`` starts a :class:`distributed.LocalCluster` on 127.0.0.1;
        anything else is the address of a running Dask scheduler.
    skip : variant indices already done (``--resume``).
    on_record : callback(record)
        Called in this process, in completion order, once per variant.
    progress : callback(done, total)
        Variants done (including skipped) out of all.
    chunk : int, optional
        Variants per task (default :func:`chunk_size`).
    start_method : str
        How pool workers start (``spawn``; see the module notes on ``fork``).
    connect_timeout : float
        Seconds to wait for a Dask scheduler at an address.
    pool : bool, optional
        True: a process pool even for one worker (benchmarks); default: one
        worker runs in this process.

    Returns
    -------
    RunStats
    """
    options = options or Options()
    skip = set(skip)
    total = len(plan)
    todo = list(plan.variants(skip))
    stats = RunStats(variants=total, skipped=total - len(todo))
    t0 = time.perf_counter()
    done = [stats.skipped]

    def emit(recs):
        for r in recs:
            stats.evaluated += 1
            if r["error"]:
                stats.errors += 1
            if on_record is not None:
                on_record(r)
        done[0] += len(recs)
        if progress is not None:
            progress(done[0], total)

    if progress is not None:
        progress(done[0], total)
    if options.catalogue is None:
        from cdpr_design.model import spec

        options = with_catalogue(options, spec.load_catalogue())
    w = workers if workers is not None else default_workers()
    if w < 1:
        raise InputError(f"--workers: expected at least 1, got {w}")
    job = Job(plan, options)
    if scheduler:
        run_dask(job, todo, scheduler, w, chunk, emit, stats, connect_timeout)
    elif not pool and (w == 1 or len(todo) <= 1):
        stats.backend, stats.workers, stats.chunk = "serial", 1, 1
        if todo:
            run_serial(job, todo, emit)
    else:
        run_pool(job, todo, w, chunk, emit, stats, start_method)
    stats.elapsed_s = time.perf_counter() - t0
    return stats
