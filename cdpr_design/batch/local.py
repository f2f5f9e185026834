"""Evaluating a sweep's variants: in this process or in a local process pool.

Every variant is rebuilt with :func:`cdpr_design.model.spec.from_dict` (so the spec
rules apply to it) and evaluated by :func:`cdpr_design.design.evaluate.evaluate`, the
code behind ``report``'s ``design_report.csv``: a sweep row *is* the report
row of that variant.  Rows leave through an ``on_record`` callback (the
command line appends them to a journal and writes ``sweep.csv``); a resumed
sweep passes the variant indices already done in ``skip``.  Nothing here
touches files.

Execution backends
------------------
- in-process (``workers=1``);
- a process pool (``workers > 1``, default one per core).  Workers are
  started with ``spawn``, which is safe whatever the parent ran before (its
  threads, its open files, a caller's OpenMP library: a ``fork`` copies the
  process in the middle of all that), with the stop signals held until they
  are ready (:mod:`cdpr_design.batch.processes`).  Workers load the kernels
  from numba's on-disk cache (``cache=True``).
- Dask distributed (:mod:`cdpr_design.batch.dask`).

Parallelism is across variants: each worker runs the kernels on one
thread (:func:`cdpr_design.kernels.parallel.set_threads`), which also avoids
oversubscribing the cores.  Results do not depend on the thread count (each
pose is computed on its own; the reductions are min / max / counts).  Variants travel in chunks
so that scheduling overhead stays small.
"""

from __future__ import annotations

import contextlib
import importlib
import itertools
import math
import os
import threading
from dataclasses import dataclass, field, replace
from typing import Any, Sequence

from cdpr_design.batch.variants import Plan
from cdpr_design.kernels import parallel


JOURNAL_VERSION = 1


@dataclass(frozen=True)
class Options:
    """What :func:`cdpr_design.design.evaluate.evaluate` is asked, besides the design."""

    step: float | None = None
    safety_factor: float | None = None
    motor: str | None = None
    trajectory: str | None = None
    catalogue: Any = None  # a model.catalogue.Catalogue; None: the shipped one
    #: engine of every variant's grid sweeps (:data:`~cdpr_design.statics.robot.ENGINES`; results are
    #: identical: not in the fingerprint)
    engine: str = "auto"
    #: only the figures needed (``evaluate(figures=...)``: the workspace sweep or the sizing is
    #: skipped when neither they nor the spec's checks need it); None: every figure
    figures: frozenset | None = None

    def fingerprint(self) -> dict:
        out = {"step": self.step, "safety_factor": self.safety_factor, "motor": self.motor,
               "trajectory": self.trajectory, "catalogue": repr(self.catalogue)}
        if self.figures is not None:
            out["figures"] = sorted(self.figures)
        return out


@dataclass(frozen=True)
class Job:
    """What a worker needs: the plan and the options (sent once per worker)."""

    plan: Plan
    options: Options

    def prepared(self) -> "Job":
        """Set up a worker process for this job (once, in the worker); the job it then runs
        (with the shipped catalogue loaded there when none was given)."""
        prepare_worker()
        if self.options.catalogue is None:
            from cdpr_design.model import spec

            return Job(self.plan, with_catalogue(self.options, spec.load_catalogue()))
        return self

    def run_chunk(self, items: Sequence[tuple[int, tuple]]) -> list[dict]:
        """The rows of a chunk of (index, values) variants."""
        return evaluate_chunk(self, items)


def record(index: int, values: Sequence, figures: dict | None = None, error: str = "") -> dict:
    """A sweep row as plain data (one journal line)."""
    return {"variant": int(index), "values": list(values), "figures": figures or {}, "error": error}


def evaluate_variant(job: Job, index: int, values: Sequence) -> dict:
    """Build and evaluate one variant; an exception becomes the row's ``error``."""
    from cdpr_design.model import spec

    # by module path: the package's lazy API also has a function named ``evaluate``
    ev = importlib.import_module("cdpr_design.design.evaluate")
    opt = job.options
    try:
        design = spec.from_dict(job.plan.data(values), source=job.plan.source)
        samples = None
        if opt.trajectory is not None:
            from cdpr_design.motion import trajectory as tr
            from cdpr_design.statics.robot import Analysis, resolve

            samples = tr.sample(resolve(design, Analysis(command="motion")), opt.trajectory)
        row = ev.evaluate(design, step=opt.step, catalogue=opt.catalogue, samples=samples,
                          safety_factor=opt.safety_factor, motor=opt.motor, engine=opt.engine,
                          figures=opt.figures)
    except Exception as exc:  # noqa: BLE001 - a failing variant is a row, the sweep goes on
        msg = " ".join(str(exc).split())
        return record(index, values, error=f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__)
    return record(index, values, row)


def evaluate_chunk(job: Job, items: Sequence[tuple[int, tuple]]) -> list[dict]:
    return [evaluate_variant(job, i, v) for i, v in items]


#: the job of this pool worker (any object with ``prepared()`` and ``run_chunk(items)``: a
#: sweep's :class:`Job`, a certification's ``batch.certify.CertifyJob``)
_WORKER_JOB = None


def prepare_worker() -> None:
    """A worker process set up for evaluating designs: one kernel thread (parallelism is across
    processes)."""
    parallel.set_threads(1)


def _init_worker(job) -> None:
    global _WORKER_JOB
    _WORKER_JOB = job.prepared()


def _pool_chunk(items):
    return _WORKER_JOB.run_chunk(items)


def with_catalogue(opt: Options, cat) -> Options:
    return replace(opt, catalogue=cat)


def default_workers() -> int:
    """One worker per core available to this process."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def chunk_size(n: int, workers: int, minimum: int = 1, maximum: int = 200) -> int:
    """Variants per task: about 16 tasks per worker, at least ``minimum``."""
    return max(minimum, min(maximum, math.ceil(n / max(1, 16 * workers))))


def chunks(items: list, size: int) -> list[list]:
    return [items[k:k + size] for k in range(0, len(items), size)]


def guided_chunks(items: list, size: int, workers: int, minimum: int = 1) -> list[list]:
    """Chunks of at most ``size`` that shrink towards the end (guided self-scheduling):
    each about a quarter of what is left per worker, never below ``minimum`` (unless
    ``size`` is smaller), so the
    workers finish together instead of one idling through the other's last big chunk."""
    out = []
    k = 0
    while k < len(items):
        left = len(items) - k
        n = min(size, max(minimum, math.ceil(left / (4 * max(1, workers)))))
        out.append(items[k:k + n])
        k += n
    return out


@dataclass
class RunStats:
    """How a sweep ran."""

    variants: int
    evaluated: int = 0
    skipped: int = 0
    errors: int = 0
    backend: str = ""
    workers: int = 1
    chunk: int = 1
    elapsed_s: float = 0.0
    notes: list[str] = field(default_factory=list)


def run_serial(job: Job, todo, emit) -> None:
    with parallel.threads_kept():
        prepare_worker()
        for i, vals in todo:
            emit([evaluate_variant(job, i, vals)])


def run_pool(job: Job, todo, w: int, chunk: int | None, emit, stats: RunStats, start_method: str) -> None:
    """Evaluate ``todo`` in a process pool of ``w`` workers started with ``start_method``."""
    w = min(w, len(todo))
    size = chunk or chunk_size(len(todo), w)
    stats.backend, stats.workers, stats.chunk = f"processes ({start_method})", w, size
    parts = chunks(todo, size) if chunk else guided_chunks(todo, size, w, minimum=2)
    with pool_session(job, w, start_method) as run_parts:
        run_parts(parts, emit)


@contextlib.contextmanager
def pool_session(job, w: int, start_method: str = "spawn"):
    """A process pool of ``w`` workers, each set up once with ``job.prepared()``, kept for the
    block; yields ``run_parts(parts, emit)``: every part run by ``job.run_chunk`` in a worker,
    ``emit`` of its result in this process as each completes.  An exception (Ctrl-C) in the
    block ends the workers at once; otherwise they exit in the background (:func:`wait_closed`)."""
    import multiprocessing as mp

    from cdpr_design.batch.processes import end_pool, pool

    before = set(mp.active_children())
    ex = pool(w, start_method, _init_worker, (job,))  # workers a Ctrl-C does not catch half-started
    try:
        yield lambda parts, emit: _submit_bounded(ex, parts, 4 * w, emit)
    except BaseException:
        end_pool(ex, before)
        raise
    # every row is in: the workers' exit (interpreter teardown with
    # numba loaded) overlaps the caller's next steps; wait_closed() joins it
    closer = threading.Thread(target=ex.shutdown, kwargs={"wait": True}, name="cdpr-design pool shutdown")
    closer.start()
    closing(closer)


def _submit_bounded(ex, parts, in_flight: int, emit) -> None:
    """Submit ``parts`` keeping at most ``in_flight`` tasks pending (memory stays bounded
    for huge sweeps); ``emit`` each task's rows as it completes."""
    from concurrent.futures import FIRST_COMPLETED, wait

    pending = set()
    it = iter(parts)
    for part in itertools.islice(it, in_flight):
        pending.add(ex.submit(_pool_chunk, part))
    while pending:
        finished, pending = wait(pending, return_when=FIRST_COMPLETED)
        for f in finished:
            emit(f.result())
            nxt = next(it, None)
            if nxt is not None:
                pending.add(ex.submit(_pool_chunk, nxt))


#: threads still shutting down finished sweeps' workers (see :func:`wait_closed`)
_CLOSING: list[threading.Thread] = []


def closing(thread: threading.Thread) -> None:
    """Remember a shut-down under way (and forget those that are over)."""
    _CLOSING[:] = [t for t in _CLOSING if t.is_alive()] + [thread]


def wait_closed() -> None:
    """Wait until the workers of finished sweeps have exited.

    :func:`cdpr_design.batch.run` returns as soon as every row is in; the
    pool's or the LocalCluster's worker processes then exit in the background
    (Python waits for them before this process ends).  Benchmarks call this
    between runs.
    """
    while _CLOSING:
        _CLOSING.pop(0).join()
