"""Running a sweep on Dask: a LocalCluster started for it, or a running scheduler."""

from __future__ import annotations

import contextlib
import os
import pickle
import threading

from cdpr_design.batch.local import Job, RunStats, chunk_size, chunks, closing, guided_chunks
from cdpr_design.batch.variants import short
from cdpr_design.errors import InputError, quote


#: Settings of the LocalCluster: the nannies hand dask's configuration to
#: their workers, so these reach them too.  Neither dask's statistical profiler
#: nor its GIL monitor, which take the GIL from short Python-heavy tasks; the
#: event-loop health check, memory monitor and system monitor at the intervals
#: below instead of dask's shorter defaults (no dashboard is served, and a
#: sweep's memory is bounded chunk buffers): with two cores shared by the
#: scheduler, the nannies and the workers, they cost CPU on every variant
#: (docs/performance.md).  ``MALLOC_TRIM_THRESHOLD_`` is not set (see
#: :func:`start_local_cluster`).
LOCAL_CLUSTER_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.gil.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
}
#: The workers' own environment (the nannies set it in each worker process):
#: one numba thread per worker, the parallelism is across variants.
LOCAL_WORKER_ENV = {"NUMBA_NUM_THREADS": "1"}

#: A job pickling to fewer bytes goes with every Dask task instead of being scattered.
INLINE_JOB_BYTES = 1_000_000


#: Schemes of Dask addresses that name a host and a TCP port (``tcp://host:8786``).
HOST_PORT_SCHEMES = ("tcp", "tls", "ws", "wss")


def check_scheduler(address: str) -> None:
    """Refuse a ``--scheduler`` value that is neither ``local`` nor a Dask address with a known
    scheme (``tcp://host:port``, a port 1-65535), before any work; whether a scheduler
    answers there is found when the sweep connects."""
    try:
        from distributed.comm import get_address_host_port, parse_address, registry
    except ImportError as exc:  # pragma: no cover - a dependency
        raise InputError(f"--scheduler: dask.distributed is not installed ({exc})") from None
    if address == "local":
        return
    expected = f"--scheduler {quote(address)}: expected 'local' or a Dask scheduler address such as tcp://host:8786"
    try:
        scheme, _ = parse_address(address)
        registry.get_backend(scheme)
        if scheme in HOST_PORT_SCHEMES:
            host, port = get_address_host_port(address)
            if not host or not 0 < port < 65536:
                raise ValueError("no host, or a port outside 1-65535")
    except ValueError as exc:
        raise InputError(f"{expected} ({short(exc)})") from None


def start_local_cluster(LocalCluster, workers: int):
    """A LocalCluster of ``workers`` single-threaded worker processes on 127.0.0.1.

    dask's nannies start workers with ``MALLOC_TRIM_THRESHOLD_=65536``
    (``distributed.nanny.pre-spawn-environ``).  Setting that variable turns off
    glibc's dynamic mmap threshold, so every array above 128 kB is a fresh
    mmap with its page faults: a variant's sweep ran slower than in a pool
    worker (docs/performance.md).  The sweep's memory is bounded chunk buffers, so the workers
    keep glibc's default.

    Before spawning a worker, dask's nanny writes its pre-spawn variables
    (``distributed.nanny.pre-spawn-environ`` and ``PYTHONHASHSEED``) into this
    process's environment (distributed/nanny.py, ``WorkerProcess.start``);
    those variables, and only those, are put back as they were once the
    workers are up.
    """
    import logging

    import dask

    with dask.config.set(LOCAL_CLUSTER_CONFIG):
        written = set(dask.config.get("distributed.nanny.pre-spawn-environ")) | {"PYTHONHASHSEED"}
        saved = {k: os.environ.get(k) for k in written}
        try:
            return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                dashboard_address=None, host="127.0.0.1", env=LOCAL_WORKER_ENV,
                                # a task's error comes back with its future (the variant's row);
                                # what dask logs at ERROR are shut-down races of heartbeats
                                silence_logs=logging.CRITICAL)
        finally:
            for k, v in saved.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v


#: the kinds of job (their classes) a Dask worker process has been set up for
_DASK_READY: set = set()


def _dask_chunk(job, items):
    """A chunk run in a Dask worker by ``job.run_chunk``; the worker process is set up once per
    kind of job (``job.prepared()``: the kernels loaded, one kernel thread)."""
    if type(job) not in _DASK_READY:
        job.prepared()
        _DASK_READY.add(type(job))
    return job.run_chunk(items)


def run_dask(job: Job, todo, scheduler: str, w: int, chunk: int | None, emit, stats: RunStats,
              connect_timeout: float = 10.0) -> None:
    with dask_session(job, scheduler, w, connect_timeout) as (nthreads, run_parts):
        size = chunk or chunk_size(len(todo), nthreads, minimum=10)
        stats.backend = "dask LocalCluster" if scheduler == "local" else f"dask {scheduler}"
        stats.workers, stats.chunk = nthreads, size
        if todo:
            run_parts(chunks(todo, size) if chunk else guided_chunks(todo, size, nthreads, minimum=10), emit)


@contextlib.contextmanager
def dask_session(job, scheduler: str, w: int, connect_timeout: float = 10.0):
    """Dask for the block: a LocalCluster of ``w`` workers (``scheduler == "local"``) or the
    scheduler at that address.  Yields (worker threads, ``run_parts(parts, emit)``): every part
    run by ``job.run_chunk`` on a worker (set up once with ``job.prepared()``), ``emit`` of its
    result here as each completes.  An exception in the block cancels the tasks and closes the
    client and the cluster; otherwise the cluster closes in the background (``wait_closed``)."""
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError as exc:  # pragma: no cover - a dependency
        raise InputError(f"--scheduler: dask.distributed is not installed ({exc})") from None
    cluster = None
    try:
        if scheduler == "local":
            cluster = start_local_cluster(LocalCluster, w)
            client = Client(cluster)
        else:
            try:
                client = Client(scheduler, timeout=f"{connect_timeout}s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise InputError(f"--scheduler: cannot connect to {scheduler}: {exc}") from None
    except BaseException:
        if cluster is not None:
            cluster.close()
        raise
    job_f = []

    def run_parts(parts, emit) -> None:
        if not job_f:
            # a small job (the usual: a few kB) travels with each task, which spares
            # a broadcast round trip before the first task; a big one is sent once
            small = len(pickle.dumps(job, protocol=pickle.HIGHEST_PROTOCOL)) < INLINE_JOB_BYTES
            job_f.append(job if small else client.scatter(job, broadcast=True))
        futures = [client.submit(_dask_chunk, job_f[0], part, pure=False) for part in parts]
        try:
            for fut in as_completed(futures):
                emit(fut.result())
        except BaseException:
            client.cancel(futures)
            raise

    try:
        yield sum(client.nthreads().values()) or w, run_parts
    except BaseException:
        client.close()
        if cluster is not None:
            cluster.close()
        raise
    client.close()
    if cluster is not None:
        # every row is in: the cluster closes (the workers shut down and
        # exit) while the caller goes on; wait_closed() joins it
        closer = threading.Thread(target=cluster.close, name="cdpr-design LocalCluster close")
        closer.start()
        closing(closer)
