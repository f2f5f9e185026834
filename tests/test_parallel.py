"""Blocks of rows on threads (kernels/parallel.py): the split, results independent of the thread
count, errors and interruption, nesting, fork."""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import pytest

from cdpr_design import workspaces as ws
from cdpr_design.kernels import parallel
from cdpr_design.model import spec
from cdpr_design.statics.robot import resolve

from .helpers import PLANAR2


@pytest.fixture(autouse=True)
def _threads_back():
    with parallel.threads_kept():
        yield


@pytest.mark.parametrize("count", [0, 1, 7, 255, 256, 257, 1000, 100_003])
@pytest.mark.parametrize("grain, nthreads", [(1, 1), (1, 2), (256, 2), (4096, 3), (16, 8)])
def test_blocks_cover_the_rows_once_in_order(count, grain, nthreads):
    parts = parallel.blocks(count, grain, nthreads)
    assert [k for k0, k1 in parts for k in range(k0, k1)] == list(range(count))
    assert all(k1 > k0 for k0, k1 in parts)
    assert len(parts) <= max(1, nthreads * parallel.BLOCKS_PER_THREAD)
    if parts:  # no block under the grain but the last, unless that would leave a thread idle
        assert all(k1 - k0 >= min(grain, count // len(parts)) for k0, k1 in parts[:-1])


@pytest.mark.slow
@pytest.mark.parametrize("path, step", [("designs/ipanema3.yaml", 0.25), (PLANAR2, 0.01),
                                        ("designs/crane4.yaml", 0.25)])
def test_results_do_not_depend_on_the_thread_count(path, step):
    d = spec.load(path)
    if "crane4" in str(path):  # its hanging search runs on the kernels' threads, in blocks
        from cdpr_design.workspaces.hanging import Hanger

        robot = resolve(d)
        assert Hanger(robot, d.default_orientation_full()).threaded
    rows = []
    for n in (1, 2, 3, 8):
        got = []
        parallel.set_threads(n)
        ws.run(d, ws.Analysis(engine="numba"), step=step, on_chunk=got.append, chunk=2000)  # more than one chunk each
        rows.append(got)
    ref = rows[0]
    assert sum(len(c.feasible) for c in ref) > 1000 and len(ref) > 1
    for other in rows[1:]:
        for a, b in zip(ref, other, strict=True):
            np.testing.assert_array_equal(a.feasible, b.feasible)
            np.testing.assert_array_equal(a.margin, b.margin)  # NaN where NaN, bit for bit elsewhere
            np.testing.assert_array_equal(a.tensions, b.tensions)
            np.testing.assert_array_equal(a.lengths, b.lengths)
            assert a.extra.keys() == b.extra.keys()  # crane4: the hanging tilt and orientation
            for name in a.extra:
                np.testing.assert_array_equal(a.extra[name], b.extra[name])


def test_every_block_runs_on_the_pool_and_fills_its_rows():
    parallel.set_threads(3)
    out = np.zeros(10_000, dtype=np.int64)
    names = set()

    def block(k0, k1, out):
        names.add(threading.current_thread().name)
        out[k0:k1] += np.arange(k0, k1) + 1

    parallel.run_blocks(block, out.size, out, grain=100)
    assert np.array_equal(out, np.arange(1, 10_001))  # each row written exactly once
    assert names and all(n.startswith("cdpr-kernel") for n in names)


def test_one_thread_runs_in_the_caller():
    parallel.set_threads(1)
    names = set()
    parallel.run_blocks(lambda k0, k1: names.add(threading.current_thread().name), 100_000, grain=10)
    assert names == {threading.current_thread().name}


def test_an_error_in_a_block_is_raised_and_no_block_runs_afterwards():
    parallel.set_threads(2)
    running = []
    started = []

    def block(k0, k1):
        started.append(k0)
        running.append(1)
        try:
            if k0 == 0:
                raise ArithmeticError("block 0")
            time.sleep(0.02)
        finally:
            running.pop()

    with pytest.raises(ArithmeticError, match="block 0"):
        parallel.run_blocks(block, 16 * 100, grain=100)
    assert running == []  # the blocks still running had finished when the error reached the caller
    assert len(started) < 16  # the blocks not begun were dropped


INTERRUPTED = """
import os, signal, threading, time
from cdpr_design.kernels import parallel
parallel.set_threads(2)
started = []
def block(k0, k1):
    started.append(k0)
    time.sleep(0.05)
threading.Timer(0.08, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
t0 = time.perf_counter()
try:
    parallel.run_blocks(block, 16 * 10, grain=10)
except KeyboardInterrupt:
    print(len(started), time.perf_counter() - t0)
"""


def test_interrupt_while_waiting_drops_the_blocks_not_begun():
    """Ctrl-C reaches the waiting caller (in its own process: signals go to the main thread) within
    a block's time, and the blocks not begun are dropped."""
    import subprocess
    import sys

    from .helpers import subprocess_env

    r = subprocess.run([sys.executable, "-c", INTERRUPTED], capture_output=True, text=True, timeout=120,
                       env=subprocess_env())
    assert r.returncode == 0 and r.stdout, r.stderr
    started, seconds = r.stdout.split()
    assert int(started) < 16 and float(seconds) < 0.6  # 16 blocks of 0.05 s on two threads take 0.4 s


def test_a_block_that_runs_blocks_does_not_wait_for_the_pool():
    parallel.set_threads(2)
    out = np.zeros(400)

    def inner(k0, k1, out):
        out[k0:k1] += 1

    def outer(k0, k1, out):
        parallel.run_blocks(lambda a, b, o: inner(k0 + a, k0 + b, o), k1 - k0, out, grain=1)

    parallel.run_blocks(outer, out.size, out, grain=10)  # would deadlock if the inner runs queued on the pool
    assert np.array_equal(out, np.ones(400))


@pytest.mark.skipif(not hasattr(os, "fork"), reason="fork")
def test_a_forked_child_runs_kernels_after_the_parent_used_the_pool():
    """The parent's pool threads do not exist in a fork: the child starts its own pool (a stale one
    would wait forever for threads that are not there)."""
    d = spec.load("designs/ipanema3.yaml")
    parallel.set_threads(2)
    ref = ws.run(d, ws.Analysis(engine="numba"), step=0.3).summary()["feasible"]
    pid = os.fork()
    if pid == 0:  # the child: a sweep on two threads, then out without running the parent's tests
        code = 1
        try:
            out = np.zeros(1000)

            def block(k0, k1, out):
                out[k0:k1] = 1

            parallel.run_blocks(block, out.size, out, grain=10)
            r = ws.run(d, ws.Analysis(engine="numba"), step=0.3).summary()
            code = 0 if out.all() and r["feasible"] == ref else 1
        finally:
            os._exit(code)
    end = time.time() + 120
    while time.time() < end:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            assert os.waitstatus_to_exitcode(status) == 0
            return
        time.sleep(0.05)
    os.kill(pid, 9)
    os.waitpid(pid, 0)
    pytest.fail("the forked child hung in run_blocks")


def test_thread_setting_is_checked_and_restored():
    with pytest.raises(ValueError, match="threads"):
        parallel.set_threads(0)
    parallel.set_threads(3)
    with parallel.threads_kept():
        parallel.set_threads(1)
        assert parallel.threads() == 1
    assert parallel.threads() == 3
    parallel.set_threads(None)
    import numba

    assert parallel.threads() == numba.config.NUMBA_NUM_THREADS


def test_fewer_threads_after_more_are_honoured():
    """The pool only grows; a later, smaller setting still runs at most that many blocks at once."""
    lock = threading.Lock()
    state = {"active": 0, "peak": 0}

    def block(k0, k1):
        with lock:
            state["active"] += 1
            state["peak"] = max(state["peak"], state["active"])
        time.sleep(0.005)
        with lock:
            state["active"] -= 1

    for n in (4, 2):
        parallel.set_threads(n)
        state["peak"] = 0
        parallel.run_blocks(block, 10_000, grain=1)
        assert state["peak"] <= n


def test_raising_the_thread_count_while_other_threads_run_blocks():
    """A bigger pool replaces the old one (shut down) while other threads submit: never
    'cannot schedule new futures after shutdown'."""
    errors = []
    stop = threading.Event()

    def runner():
        out = np.zeros(1000)
        while not stop.is_set():
            try:
                parallel.run_blocks(lambda k0, k1, o: o.__setitem__(slice(k0, k1), 1), out.size, out, grain=1)
            except Exception as exc:  # noqa: BLE001
                errors.append(exc)
                return

    parallel.set_threads(2)
    ts = [threading.Thread(target=runner) for _ in range(3)]
    for t in ts:
        t.start()
    try:
        for n in range(3, 60):
            parallel.set_threads(n)
            time.sleep(0.002)
    finally:
        stop.set()
        for t in ts:
            t.join()
    assert errors == []


def test_a_numba_block_not_compiled_yet_runs_its_first_block_in_the_caller():
    import numba

    names = []

    @numba.njit(nogil=True)
    def fill(k0, k1, out):
        for k in range(k0, k1):
            out[k] = k

    def block(k0, k1, out):
        names.append(threading.current_thread().name)
        fill(k0, k1, out)

    block.signatures = fill.signatures  # [] until the first call: as a dispatcher that has not run
    parallel.set_threads(2)
    out = np.zeros(10_000)
    parallel.run_blocks(block, out.size, out, grain=10)
    assert names[0] == threading.current_thread().name and np.array_equal(out, np.arange(10_000))
