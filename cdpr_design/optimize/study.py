"""The optuna study: storage, sampler, trials claimed and evaluated by one or several processes, resuming.

Storage
-------
One SQLite file (``optimize.db`` in the output folder) through optuna's
``RDBStorage``.  SQLite is transactional, so a run killed at any instant
(SIGKILL included) leaves a consistent study; every worker process opens the
same file, and SQLite serialises their writes (a busy writer is waited for up
to :data:`BUSY_TIMEOUT_S`, never an error under this load: a few writes per
trial, each well under a second).

Exactly N trials
----------------
A run ends when N trials have finished (``complete``, ``infeasible`` or
``failed``).  Workers *claim* a trial under an exclusive file lock
(``.optimize.claim``): count the study's trials that are not interrupted, and
create one only while that count is below N.  So several workers never
overshoot N, and a resumed run stops at the same total.

Interrupted trials
------------------
A trial stopped by SIGINT (or SIGTERM, SIGHUP) is told ``FAIL`` with the user attribute
``interrupted``; one stopped by SIGKILL stays ``RUNNING`` in the file.  A
resumed run (which holds ``.optimize.lock``, so no other run is using the
study) marks the latter failed-and-interrupted too, and queues every
interrupted trial's parameters again: each point is evaluated once, and
interrupted trials do not count towards N nor appear in the results.

Samplers
--------
TPE (Bergstra et al. 2011), multivariate (Falkner et al. 2018), for one
objective; multi-objective TPE (Ozaki et al. 2020, 2022; optuna models its
keys independently) for several; both with optuna's constraint handling (the limits' violations,
:mod:`cdpr_design.optimize.objectives`).  See ``docs/optimize.md`` for the
choice.  With ``seed`` and one worker a run is deterministic; a resumed run
seeds its sampler with ``seed`` plus the trials already in the study (so its
random start-up points are not the first run's again).
"""

from __future__ import annotations

import contextlib
import os
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from cdpr_design.batch.local import prepare_worker
from cdpr_design.batch.processes import EXIT_INTERRUPTED, end as end_workers, end_pool, pool, stop_raises
from cdpr_design.kernels import parallel
from cdpr_design.errors import InputError, WriteError
from cdpr_design.io.locks import flock, one_run, signals_held
from cdpr_design.model.limits import SEED_LIMIT
from cdpr_design.optimize.problem import Problem, evaluate

#: The study's file, its name inside it, the lock files (in the output folder).
DB = "optimize.db"
STUDY = "cdpr-design optimize"
RUN_LOCK = ".optimize.lock"
WORKERS_LOCK = ".optimize.workers"
#: Seconds a new run waits for the worker processes of a killed run to finish their trial and exit.
ORPHAN_WAIT_S = 120.0
CLAIM_LOCK = ".optimize.claim"
#: Seconds a writer waits for SQLite's lock before giving up.
BUSY_TIMEOUT_S = 300.0
#: Random trials before TPE models the results (optuna's default).
STARTUP_TRIALS = 10
#: Candidates TPE draws per trial (optuna's default is 24; docs/optimize.md: 64 converges more surely on
#: the sharp-ridged margins of outlet placement).
EI_CANDIDATES = 64


@dataclass
class RunStats:
    """How a run went: trials requested, finished before, evaluated now, interrupted ones re-queued."""

    requested: int
    resumed: int = 0
    evaluated: int = 0
    requeued: int = 0
    workers: int = 1
    elapsed_s: float = 0.0
    stopped_by_timeout: bool = False
    notes: list[str] = field(default_factory=list)


def _optuna():
    import optuna

    optuna.logging.set_verbosity(optuna.logging.ERROR)
    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    return optuna


def _sqlite_pragmas(dbapi_connection, connection_record) -> None:
    """Write-ahead log, synced at checkpoints (``synchronous=NORMAL``): a commit is no fsync, and
    readers do not wait for the writer.  Still atomic and consistent when a process is killed
    (SQLite's documentation, "Write-Ahead Logging"); only a power cut may lose the last commits."""
    cur = dbapi_connection.cursor()
    cur.execute("PRAGMA journal_mode=WAL")
    cur.execute("PRAGMA synchronous=NORMAL")
    cur.close()


def storage(folder: Path):
    """The study's SQLite storage in ``folder``."""
    import sqlalchemy

    optuna = _optuna()
    url = f"sqlite:///{(Path(folder) / DB).resolve()}"
    st = optuna.storages.RDBStorage(url, engine_kwargs={"connect_args": {"timeout": BUSY_TIMEOUT_S}})
    sqlalchemy.event.listen(st.engine, "connect", _sqlite_pragmas)
    st.engine.dispose()  # the connections opened while creating the tables: reopened with the pragmas
    return st


def check_file(folder: Path, resume: bool) -> None:
    """Refuse, before any work, an ``optimize.db`` in ``folder`` that is no usable study file (exit 2
    naming it): a folder, a file that is not an SQLite database or a damaged one, another SQLite
    database, or (without ``resume``) a study.  It is never replaced, even with ``--overwrite``:
    a study is moved away by hand.  Read only; no file is created."""
    path = Path(folder) / DB
    if not path.exists():
        return
    if not path.is_file():
        raise InputError(f"{path}: not a file; move it away or choose another --out")
    tables, names = _contents(path)
    if tables and "studies" not in tables:
        raise InputError(f"{path}: an SQLite database but not an optuna study; move it away or choose another --out")
    if STUDY in names and not resume:
        _refuse_existing(path)


def _contents(path: Path) -> tuple[set[str], set[str]]:
    """(tables, study names) of the SQLite file ``path``, opened read-only; exit 2 naming it when it
    is not an SQLite database, is damaged or cannot be read.

    Nothing is created beside it: without a write-ahead log (``-wal``) beside the file there is
    nothing newer than the file to read, and SQLite is told the file does not change (``immutable``),
    so it makes no ``-wal`` or ``-shm`` of its own (a damaged file is left exactly as it was).  With
    a log there, the file is read with it, as SQLite reads a study another run left."""
    import sqlite3

    flags = "mode=ro" if Path(f"{path}-wal").exists() else "mode=ro&immutable=1"
    try:
        con = sqlite3.connect(f"{path.resolve().as_uri()}?{flags}", uri=True, timeout=BUSY_TIMEOUT_S)
        try:
            if con.execute("PRAGMA quick_check(1)").fetchone() != ("ok",):
                raise sqlite3.DatabaseError("database disk image is malformed")
            tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
            names = {r[0] for r in con.execute("SELECT study_name FROM studies")} if "studies" in tables else set()
        finally:
            con.close()
    except sqlite3.Error as exc:
        raise InputError(f"{path}: not a readable optuna study ({exc}); it is left as it is: move it away "
                         "or choose another --out") from None
    return tables, names


def _refuse_existing(path: Path) -> None:
    """Exit 2: ``path`` holds a study and ``--resume`` was not given (it is never replaced)."""
    raise InputError(f"--resume: {path} already holds a study; pass --resume to continue it, or choose another --out")


def load(folder: Path):
    """The study in ``folder`` (after a run)."""
    optuna = _optuna()
    return optuna.load_study(study_name=STUDY, storage=storage(folder))


def make_sampler(seed: int | None):
    """TPE (several objectives: multi-objective TPE); optuna's defaults otherwise (multivariate for one
    objective, independent for several); the limits reach it as the trials' constraints."""
    optuna = _optuna()
    seed = None if seed is None else seed % SEED_LIMIT  # a resumed run's or a worker's offset may pass the top
    return optuna.samplers.TPESampler(seed=seed, n_startup_trials=STARTUP_TRIALS, n_ei_candidates=EI_CANDIDATES,
                                      constant_liar=True)


def _interrupted(t) -> bool:
    return bool(t.user_attrs.get("interrupted"))


def interrupted_count(study) -> int:
    """Interrupted trials (failed and marked so); constant during a run (an interruption ends it)."""
    optuna = _optuna()
    return sum(_interrupted(t) for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.FAIL,)))


def _n_trials(study, store, states=None) -> int:
    """The study's trials (in ``states``): one COUNT query of its storage ``store`` (optuna's storage
    API, ``get_n_trials``) rather than loading the trials."""
    return store.get_n_trials(store.get_study_id_from_name(study.study_name), state=states)


def counted(study, store, interrupted: int | None = None) -> int:
    """Trials that count towards the total: every trial but the interrupted ones (``interrupted``:
    their number if known); ``store`` the study's storage (:func:`storage`)."""
    if interrupted is None:
        interrupted = interrupted_count(study)
    return _n_trials(study, store) - interrupted


def finished(study) -> list:
    """The finished trials that count (complete, infeasible, failed; not interrupted), by number."""
    optuna = _optuna()
    states = (optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.FAIL)
    return [t for t in study.get_trials(deepcopy=False, states=states) if not _interrupted(t)]


def done_count(study, store, interrupted: int) -> int:
    """Finished trials that count (one COUNT query of ``store``; ``interrupted``: their number,
    constant in a run)."""
    TS = _optuna().trial.TrialState
    return _n_trials(study, store, (TS.COMPLETE, TS.FAIL)) - interrupted


def _claim(study, store, total: int, lock: Path, interrupted: int):
    """A new trial (``Study.ask``: a queued trial taken, or a new row) while fewer than ``total``
    trials count, else None.

    Only the count and ``ask`` are under the lock: optuna samples a trial's parameters (TPE over
    every trial so far, the slow part) at its first ``suggest``, outside it, so workers sample in
    parallel."""
    with flock(lock):
        if counted(study, store, interrupted) >= total:
            return None
        return study.ask()


def _tell(study, trial, problem: Problem, outcome, seconds: float, worker: int) -> None:
    """Record the outcome (one user attribute, ``result``), the limits' violations as one constraint (their
    positive sum, else the largest), and tell optuna (failed: ``FAIL``, else the objective values)."""
    optuna = _optuna()
    trial.set_user_attr("result", {"state": outcome.state, "reason": outcome.reason, "figures": outcome.figures,
                                   "seconds": round(seconds, 6), "worker": worker})
    if outcome.violations:
        # optuna's TPE ranks trials by the summed positive violation only: one constraint carries it
        over = sum(v for v in outcome.violations if v > 0)
        trial.set_constraint("limits", over if over > 0 else max(outcome.violations))
    if outcome.state == "failed":
        study.tell(trial, state=optuna.trial.TrialState.FAIL)
    else:
        study.tell(trial, outcome.values)


def work(problem: Problem, folder: Path, total: int, seed: int | None, deadline: float | None,
         worker: int = 0, single_thread: bool = False, on_trial: Callable[[], None] | None = None,
         parent: int | None = None, store=None) -> int:
    """Claim and evaluate trials until ``total`` count or ``deadline`` (time.time()) passes; the
    number evaluated here.  A KeyboardInterrupt marks the trial under way interrupted and propagates.
    ``parent``: the process id of the run; a worker whose run has died stops after its trial.
    ``store``: the storage already open in this process (default: open it)."""
    optuna = _optuna()
    store = store or storage(folder)
    study = optuna.load_study(study_name=STUDY, storage=store, sampler=make_sampler(seed))
    interrupted = interrupted_count(study)
    job = problem.job()
    lock = Path(folder) / CLAIM_LOCK
    done = 0
    if single_thread:
        prepare_worker()  # the kernels on one thread: parallelism is across processes
    while deadline is None or time.time() < deadline:
        if parent is not None and os.getppid() != parent:
            break  # the run was killed: leave the rest to a resumed run
        trial = None
        try:
            with signals_held():  # a trial created is a trial in hand
                trial = _claim(study, store, total, lock, interrupted)
            if trial is None:
                break
            values = {p.key: p.suggest(trial) for p in problem.space.params}
            t0 = time.perf_counter()
            outcome = evaluate(problem, job, trial.number, values)
            with signals_held():  # told whole
                _tell(study, trial, problem, outcome, time.perf_counter() - t0, worker)
        except BaseException:
            if trial is not None:
                with signals_held(raise_after=False), contextlib.suppress(Exception):
                    trial.set_user_attr("interrupted", True)
                    study.tell(trial, state=optuna.trial.TrialState.FAIL)
            raise
        done += 1
        if on_trial is not None:
            on_trial()
    return done


def _worker_main(problem: Problem, folder: str, total: int, seed: int | None, deadline: float | None,
                 worker: int, parent: int) -> int:
    """A worker process: holds a shared lock on ``.optimize.workers`` while it works (a later run
    waits for it, :func:`_wait_for_orphans`); a stop signal interrupts its trial (which is recorded
    so), one before or after that ends the process quietly (:mod:`cdpr_design.batch.processes`)."""
    try:
        with stop_raises(), flock(Path(folder) / WORKERS_LOCK, shared=True), _db_errors(Path(folder)):
            done = work(problem, Path(folder), total, seed, deadline, worker, single_thread=True, parent=parent)
    except KeyboardInterrupt:
        # the trial is recorded interrupted and the lock released: the run that stops this worker
        # waits for it to be gone (:func:`_stop`), not for a pool worker idle after its one task
        os._exit(EXIT_INTERRUPTED)
    if os.getppid() != parent:
        os._exit(0)  # the run was killed: nobody will hand this pool worker more work or collect it
    return done


@contextlib.contextmanager
def _db_errors(folder: Path):
    """SQLite's failures on the study (a full disk or a file-size limit: "disk I/O error", "database
    or disk is full") as a :class:`WriteError` naming ``optimize.db``, on one line."""
    import sqlite3

    try:
        yield
    except sqlite3.Error as exc:
        raise _db_error(folder, exc) from None
    except Exception as exc:
        orig = getattr(exc, "orig", None)  # SQLAlchemy's DBAPIError around sqlite3's error
        if isinstance(orig, sqlite3.Error):
            raise _db_error(folder, orig) from None
        raise


def _db_error(folder: Path, exc: BaseException) -> WriteError:
    return WriteError(f"cannot write {Path(folder) / DB}: {' '.join(str(exc).split())} (SQLite)")


def _drop_new_study(folder: Path, exc: WriteError) -> WriteError:
    """After a write error on a study this run created: the file and its SQLite companions removed
    when no trial finished in it (the folder as it was), else kept for ``--resume`` (the message
    says so)."""
    path = Path(folder) / DB
    try:
        tables, _ = _contents(path)
        kept = 0
        if "trials" in tables:
            import sqlite3

            con = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True)
            try:
                kept = con.execute("SELECT COUNT(*) FROM trials WHERE state IN ('COMPLETE', 'FAIL')").fetchone()[0]
            finally:
                con.close()
    except Exception:  # noqa: BLE001 - unreadable: nothing in it to keep
        kept = 0
    if kept:
        return WriteError(f"{exc}; the {kept} trial(s) finished are kept in it (--resume continues)")
    for suffix in ("", "-wal", "-shm", "-journal"):
        with contextlib.suppress(OSError):
            os.unlink(f"{path}{suffix}")
    return exc


def _wait_for_orphans(folder: Path, log: Callable[[str], None]) -> None:
    """Wait until no worker of an earlier, killed run is still evaluating (each ends after its trial)."""
    end = time.time() + ORPHAN_WAIT_S
    told = False
    while True:
        with flock(folder / WORKERS_LOCK, blocking=False) as free:
            if free:
                return
        if time.time() > end:
            raise InputError(f"--out: worker processes of an earlier run still use {folder}; "
                             "wait for them to end or choose another --out")
        if not told:
            log("waiting for the workers of an interrupted run to finish their trials")
            told = True
        time.sleep(0.2)


def open_study(problem: Problem, folder: Path, resume: bool, log: Callable[[str], None]):
    """The study in ``folder``: created, or (``resume``) loaded after checking it is this problem's,
    its interrupted trials re-queued.  (study, trials already finished, trials re-queued)."""
    optuna = _optuna()
    st = storage(folder)
    names = optuna.get_all_study_names(st)
    if STUDY in names and not resume:
        _refuse_existing(Path(folder) / DB)
    if STUDY not in names:
        if resume:
            log(f"--resume: no study in {folder}; starting one")
        study = optuna.create_study(study_name=STUDY, storage=st, directions=problem.directions)
        study.set_user_attr("fingerprint", problem.fingerprint())
        study.set_user_attr("problem", problem.describe())
        return study, st, 0, 0
    study = optuna.load_study(study_name=STUDY, storage=st)
    if study.user_attrs.get("fingerprint") != problem.fingerprint():
        raise InputError(f"--resume: the study in {folder} is from another search (other spec, keys, ranges, "
                         "objectives, limits or options); run without --resume and another --out to start over")
    requeued = requeue_interrupted(study, st)
    return study, st, len(finished(study)), requeued


def requeue_interrupted(study, store) -> int:
    """Mark trials left RUNNING (a killed run) interrupted, and queue every interrupted trial's
    parameters again, once (the study's user attribute ``requeued`` lists the trials queued again).
    ``store``: the study's storage.  The number queued now."""
    optuna = _optuna()
    TS = optuna.trial.TrialState
    study_id = store.get_study_id_from_name(study.study_name)
    done = set(study.user_attrs.get("requeued") or ())
    n = 0
    for t in study.get_trials(deepcopy=False, states=(TS.RUNNING, TS.FAIL)):
        if t.state == TS.RUNNING:
            trial_id = store.get_trial_id_from_study_id_trial_number(study_id, t.number)
            store.set_trial_user_attr(trial_id, "interrupted", True)
            store.set_trial_state_values(trial_id, TS.FAIL)
        elif not _interrupted(t) or t.number in done:
            continue
        done.add(t.number)
        if t.params:
            study.enqueue_trial(t.params, user_attrs={"requeued_from": t.number})
            n += 1
    study.set_user_attr("requeued", sorted(done))
    return n


def run(problem: Problem, folder: Path, total: int, *, workers: int = 1, seed: int | None = None,
        timeout: float | None = None, resume: bool = False, progress: Callable[[int, int], None] | None = None,
        log: Callable[[str], None] | None = None, start_method: str = "spawn") -> RunStats:
    """Run the study in ``folder`` until ``total`` trials have finished (or ``timeout`` [s] passed).

    ``workers`` processes share the study (1: this process); ``progress(done, total)``.
    """
    log = log or (lambda msg: None)
    folder = Path(folder)
    t0 = time.perf_counter()
    created = not (folder / DB).exists()
    with one_run(folder / RUN_LOCK, "optimize"):
        try:
            with _db_errors(folder):
                return _run(problem, folder, total, workers, seed, timeout, resume, progress, log, start_method, t0)
        except WriteError as exc:
            if not created:
                raise
            raise _drop_new_study(folder, exc) from None


def _run(problem, folder, total, workers, seed, timeout, resume, progress, log, start_method, t0) -> RunStats:
    """:func:`run` under the run's lock."""
    _wait_for_orphans(folder, log)
    study, store, before, requeued = open_study(problem, folder, resume, log)
    stats = RunStats(requested=total, resumed=before, requeued=requeued, workers=workers)
    if resume and before:
        log(f"resuming: {before} of {total} trials already done"
            + (f", {requeued} interrupted trial(s) queued again" if requeued else ""))
    if seed is not None:
        seed = seed + len(study.get_trials(deepcopy=False))
    deadline = time.time() + timeout if timeout is not None else None
    done = [before]

    def tick():
        done[0] += 1
        if progress is not None:
            progress(min(done[0], total), total)

    if progress is not None:
        progress(min(before, total), total)
    if workers == 1:
        stats.evaluated = work(problem, folder, total, seed, deadline, on_trial=tick, store=store)
    else:
        stats.evaluated = _run_pool(problem, folder, total, workers, seed, deadline, study, store, progress,
                                    start_method)
    stats.elapsed_s = time.perf_counter() - t0
    stats.stopped_by_timeout = len(finished(study)) < total
    return stats


def _run_pool(problem, folder, total, workers, seed, deadline, study, store, progress, start_method) -> int:
    """This process as worker 0 (set up already: it starts evaluating at once) and ``workers - 1``
    worker processes, each running :func:`work` on the shared study; progress by counting its trials."""
    import multiprocessing as mp
    from concurrent.futures import FIRST_EXCEPTION, wait

    before = set(mp.active_children())
    ex = pool(workers - 1, start_method)  # workers a Ctrl-C does not catch half-started
    interrupted = interrupted_count(study)

    def tick():
        for f in futures:
            if f.done():
                f.result()  # a worker's error surfaces here
        if progress is not None:
            progress(min(done_count(study, store, interrupted), total), total)

    try:
        futures = [ex.submit(_worker_main, problem, str(folder), total,
                             None if seed is None else seed + k, deadline, k, os.getpid())
                   for k in range(1, workers)]
        with parallel.threads_kept():  # this process's trials ran on one thread, the command goes on as before
            here = work(problem, folder, total, seed, deadline, 0, single_thread=True, on_trial=tick,
                        store=store)
        pending = set(futures)
        while pending:
            _, pending = wait(pending, timeout=0.5, return_when=FIRST_EXCEPTION)
            tick()
        ex.shutdown(wait=True)
        return here + sum(f.result() for f in futures)
    except BaseException:
        end_pool(ex, before, _stop)
        raise


def _stop(processes, grace_s: float = 10.0) -> None:
    """Interrupt worker processes (each marks its trial interrupted), then end those still running."""
    import signal

    for p in processes:
        with contextlib.suppress(Exception):
            os.kill(p.pid, signal.SIGINT)
    end = time.time() + grace_s
    for p in processes:
        p.join(max(0.0, end - time.time()))
    end_workers([p for p in processes if p.is_alive()])  # killed and waited for: none outlives the run
