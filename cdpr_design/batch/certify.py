"""``certify`` on the sweeps' workers: each level of the branch-and-prune spread over a local
process pool or a Dask cluster.

The boxes of a level are independent: they are cut into blocks, each block classified by a
worker (:class:`CertifyJob`, on one kernel thread) and the codes put back at the block's place,
so the paving is the one :func:`cdpr_design.workspaces.certify.certify` makes in this process,
box for box and in the same order.  The workers are those of ``sweep``: the process pool of
:func:`cdpr_design.batch.local.pool_session` (started with ``spawn``, stop signals held until
they are ready) and the Dask LocalCluster or scheduler of
:func:`cdpr_design.batch.dask.dask_session`, kept for the whole paving.
"""

from __future__ import annotations

import contextlib
import math

import numpy as np

from cdpr_design.batch.dask import dask_session
from cdpr_design.batch.local import default_workers, pool_session
from cdpr_design.errors import InputError
from cdpr_design.kernels import parallel

#: fewest boxes a task classifies (a task's round trip costs more than a few hundred boxes)
MIN_BLOCK = 256


class CertifyJob:
    """What a worker needs to classify boxes: the certified robot and the test's settings (the
    arguments of :class:`cdpr_design.workspaces.certify.Classifier`)."""

    def __init__(self, robot, min_margin: float, tolerance_outlets=None, tolerance_attachments=None):
        self.args = (robot, min_margin, tolerance_outlets, tolerance_attachments)
        self._classify = None

    def __getstate__(self):
        return {"args": self.args}  # the classifier is built again where the job lands

    def __setstate__(self, state):
        self.args, self._classify = state["args"], None

    def prepared(self) -> "CertifyJob":
        """A worker set up: one kernel thread (the parallelism is across workers), the kernels
        loaded."""
        parallel.set_threads(1)
        self.run_chunk([(0, *(np.zeros((1, self.args[0].design.motion.dim)),) * 2)])
        return self

    def run_chunk(self, items) -> list[tuple[int, np.ndarray]]:
        """(start, status codes) of each (start, lower, upper) block of boxes [m]."""
        if self._classify is None:
            from cdpr_design.workspaces.certify import Classifier

            self._classify = Classifier(*self.args)
        return [(start, self._classify(lo, hi)) for start, lo, hi in items]


class LevelClassifier:
    """The box test of a paving as a callable ``(lower, upper) -> status``, each call's boxes
    cut into blocks run by ``run_parts`` (a pool's or Dask's) on ``workers`` workers."""

    def __init__(self, run_parts, workers: int):
        self.run_parts, self.workers = run_parts, workers

    def __call__(self, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
        k = lower.shape[0]
        size = max(MIN_BLOCK, math.ceil(k / (4 * self.workers)))
        status = np.zeros(k, np.int8)

        def emit(results):
            for start, st in results:
                status[start:start + st.size] = st

        self.run_parts([[(s, lower[s:s + size], upper[s:s + size])] for s in range(0, k, size)], emit)
        return status


def backend(workers: int | None = None, scheduler: str | None = None) -> tuple[str, int]:
    """(name, workers) of the backend :func:`classifier` runs on; ``workers`` None: one per core."""
    w = default_workers() if workers is None else workers
    if w < 1:
        raise InputError(f"--workers: expected at least 1, got {w}")
    if scheduler:
        return ("dask LocalCluster" if scheduler == "local" else f"dask {scheduler}"), w
    return ("serial", 1) if w == 1 else ("processes (spawn)", w)


def classifier(workers: int | None = None, scheduler: str | None = None, connect_timeout: float = 10.0):
    """The ``classifier`` argument of :func:`cdpr_design.workspaces.certify.certify` for ``workers``
    processes (None: one per core; 1 and no scheduler: None, the paving runs in this process) or
    the Dask ``scheduler`` (``"local"``: a LocalCluster of ``workers`` processes on 127.0.0.1; else
    a running scheduler's address)."""
    name, w = backend(workers, scheduler)
    if name == "serial":
        return None

    @contextlib.contextmanager
    def make(*args):
        job = CertifyJob(*args)
        if scheduler:
            with dask_session(job, scheduler, w, connect_timeout) as (nthreads, run_parts):
                yield LevelClassifier(run_parts, nthreads)
        else:
            with pool_session(job, w) as run_parts:
                yield LevelClassifier(run_parts, w)

    return make
