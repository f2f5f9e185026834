"""SIGTERM and SIGHUP behave like Ctrl-C; what a killed run leaves is cleaned by the next (issue 19).

Each test runs the real command line in a subprocess and signals it once its
first temporary file exists (the sweep is streaming rows into it).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .helpers import PLANAR2, planar2_raw, subprocess_env, write_spec

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")


def start(*args, cwd=None) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "cdpr_design", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=cwd,
                            env=subprocess_env(CDPR_DESIGN_PICTURE_WORKER="0", CDPR_DESIGN_ENGINE="numpy"))


def wait_for(cond, proc: subprocess.Popen, timeout: float = 60.0) -> None:
    t0 = time.monotonic()
    while not cond():
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"the command ended (exit {proc.returncode}) before the signal: {err[-2000:]}")
        if time.monotonic() - t0 > timeout:
            proc.kill()
            pytest.fail("timed out waiting for the command to start writing")
        time.sleep(0.02)


def temps(folder: Path) -> list[Path]:
    return sorted(folder.glob(".*.tmp"))


#: 2.25 M poses of planar2 (0.001 m): a few seconds of streaming into workspace.csv
BIG = ["workspace", PLANAR2, "--step", "0.001", "--quiet"]


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT], ids=lambda s: s.name)
def test_a_signal_during_workspace_exits_130_and_removes_its_temporary_files(tmp_path, sig):
    out = tmp_path / "out"
    proc = start(*BIG, "--out", out)
    wait_for(lambda: out.is_dir() and any(p.stat().st_size > 0 for p in temps(out)), proc)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err  # was -15 / -1: killed, 70-110 MB of .tmp left behind
    assert "interrupted" in err and "Traceback" not in err
    assert temps(out) == [] and not (out / "workspace.csv").exists()


@pytest.mark.slow
def test_a_run_in_the_same_out_removes_what_a_killed_run_left(tmp_path):
    out = tmp_path / "out"
    proc = start(*BIG, "--out", out)
    wait_for(lambda: out.is_dir() and any(p.stat().st_size > 0 for p in temps(out)), proc)
    proc.kill()  # SIGKILL: nothing runs, the temporary file stays
    proc.communicate(timeout=60)
    left = temps(out)
    assert left, "SIGKILL left no temporary file to clean"
    foreign = [out / ".notes.tmp", out / f".thesis.{proc.pid}.v2.tmp"]  # not ours (no marker), even with a dead pid
    for p in foreign:
        p.write_text("mine")
    done = subprocess.run([sys.executable, "-m", "cdpr_design", "workspace", PLANAR2, "--step", "0.05", "--out",
                           out, "--quiet"], capture_output=True, text=True, timeout=120,
                          env=subprocess_env(CDPR_DESIGN_PICTURE_WORKER="0"))
    assert done.returncode == 0, done.stderr
    assert temps(out) == sorted(foreign) and (out / "workspace.csv").is_file()


def dead_pid() -> str:
    """The id of a process that has ended."""
    return subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True).stdout.strip()


def test_stale_temporary_files_of_live_processes_are_kept(tmp_path):
    from cdpr_design.io.files import OutputDir
    from cdpr_design.io.preflight import remove_stale

    gone = dead_pid()
    dead = tmp_path / f".workspace.csv.cdpr-design-tmp.{gone}.abcd1234.tmp"
    live = tmp_path / f".workspace.csv.cdpr-design-tmp.{os.getppid()}.efgh5678.tmp"  # our parent runs
    for p in (dead, live):
        p.write_text("partial")
    OutputDir(tmp_path).write_text("x.txt", "x")  # the first write cleans
    assert not dead.exists() and live.exists()
    assert remove_stale(tmp_path) == []


def test_hidden_files_of_the_user_with_a_number_in_the_name_are_kept(tmp_path):
    """Only names with cdpr-design's marker are leftovers: a user's ``.thesis.<n>.v2.tmp`` is not,
    whether or not a process ``n`` runs (such files were deleted)."""
    from cdpr_design.io.files import OutputDir
    from cdpr_design.io.preflight import remove_stale

    gone = dead_pid()
    mine = [tmp_path / f".thesis.{gone}.v2.tmp", tmp_path / f".editor-swap.{gone}.x.tmp",
            tmp_path / f".workspace.csv.{gone}.abcd1234.tmp"]
    for p in mine:
        p.write_text("precious")
    OutputDir(tmp_path).write_text("x.txt", "x")  # the first write cleans
    assert remove_stale(tmp_path) == []
    assert [p.read_text() for p in mine] == ["precious"] * 3


@pytest.mark.slow
def test_sigterm_during_a_sweep_keeps_the_journal_and_resume_is_identical(tmp_path):
    # 48 variants of about 50 ms each (numpy engine, 0.005 m): the signal, sent once the first variant is in
    # the journal, lands seconds before the end. (With 6 variants of 6 ms the whole sweep could finish between
    # two polls and write sweep.csv before the signal arrived: CI failed on that race.)
    args = ["sweep", PLANAR2, "--vary", "effector.mass=0.5:2:48", "--step", "0.005", "--workers", "1",
            "--no-picture", "--quiet"]
    ref = subprocess.run([sys.executable, "-m", "cdpr_design", *map(str, args), "--out", tmp_path / "ref"],
                         capture_output=True, text=True, timeout=300, env=subprocess_env(CDPR_DESIGN_PICTURE_WORKER="0"))
    assert ref.returncode == 0, ref.stderr
    out = tmp_path / "out"
    journal = out / "sweep.journal.jsonl"
    proc = start(*args, "--out", out)
    wait_for(lambda: journal.is_file() and journal.read_text().count("\n") >= 2, proc)  # a variant is in
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert journal.is_file() and temps(out) == [] and not (out / "sweep.csv").exists()
    res = subprocess.run([sys.executable, "-m", "cdpr_design", *map(str, args), "--out", out, "--resume"],
                         capture_output=True, text=True, timeout=300, env=subprocess_env(CDPR_DESIGN_PICTURE_WORKER="0"))
    assert res.returncode == 0, res.stderr
    assert (out / "sweep.csv").read_bytes() == (tmp_path / "ref" / "sweep.csv").read_bytes()


def test_interruptible_turns_sigterm_into_keyboardinterrupt_once():
    from cdpr_design.cli.signals import Interrupted, interruptible

    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(KeyboardInterrupt) as info:
        with interruptible():
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)  # the handler raises here
    assert isinstance(info.value, Interrupted) and info.value.signum == signal.SIGTERM
    assert signal.getsignal(signal.SIGTERM) == before


def _trial_states(db: Path) -> list[str]:
    import sqlite3

    if not db.is_file():
        return []
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as con:
            return [s for (s,) in con.execute("SELECT state FROM trials")]
    except sqlite3.Error:  # the tables are being created
        return []


@pytest.mark.slow
def test_sigterm_during_optimize_exits_130_and_the_study_resumes(tmp_path):
    """SIGTERM behaves like Ctrl-C for optimize: exit 130, no table written, no trial left RUNNING,
    and --resume completes the study."""
    raw = planar2_raw()
    raw["winch"].pop("motor")
    for k in ("max_speed", "max_acceleration"):
        raw["requirements"].pop(k)
    spec = write_spec(tmp_path, raw, "light.yaml")
    out = tmp_path / "opt"
    args = ["optimize", spec, "--vary", "cables.0.outlet.0=-0.5:0.5", "--maximize", "task_min_margin",
            "--no-picture", "--quiet", "--seed", "1", "--out", out]
    proc = start(*args, "--trials", 500)
    wait_for(lambda: _trial_states(out / "optimize.db").count("COMPLETE") >= 2, proc, timeout=120)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted" in err and "Traceback" not in err
    states = _trial_states(out / "optimize.db")
    assert "RUNNING" not in states and not (out / "optimize.csv").exists() and temps(out) == []
    total = states.count("COMPLETE") + 3  # (an interrupted trial is marked failed and not counted)
    res = subprocess.run([sys.executable, "-m", "cdpr_design", *map(str, args), "--trials", str(total), "--resume",
                          "--json"], capture_output=True, text=True, timeout=300,
                         env=subprocess_env(CDPR_DESIGN_PICTURE_WORKER="0"))
    assert res.returncode in (0, 1), res.stderr
    assert json.loads(res.stdout)["trials_done"] == total and (out / "optimize.csv").is_file()


def test_optimize_holds_every_stop_signal_through_a_trials_record():
    """SIGTERM (like SIGINT) during a trial's creation or record is delivered after it, to the
    handler in place (here one raising Stop), so no trial is left RUNNING; with raise_after=False
    it is dropped."""
    from cdpr_design.io.locks import signals_held as _signals_held

    class Stop(Exception):
        pass

    def stop(signum, frame):
        raise Stop(signum)

    old = signal.signal(signal.SIGTERM, stop)
    try:
        done = []
        with pytest.raises(Stop):
            with _signals_held():
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(0.05)  # the handler would run here, were the signal not held
                done.append("recorded")
        assert done == ["recorded"]
        with _signals_held(raise_after=False):
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)
        assert signal.getsignal(signal.SIGTERM) is stop
    finally:
        signal.signal(signal.SIGTERM, old)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=lambda s: s.name)
def test_an_interrupt_a_finaliser_swallowed_is_raised_again(sig):
    """The handler may run inside a finaliser (optuna's storage torn down: SQLAlchemy's weakref
    callback), where Python prints "Exception ignored" and drops the KeyboardInterrupt; the command
    must still end interrupted, not run on."""
    from cdpr_design.cli.signals import interruptible

    class Finalised:
        def __del__(self):
            os.kill(os.getpid(), sig)
            time.sleep(0.01)  # the handler raises here, inside __del__

    ran_on = []
    with pytest.raises(KeyboardInterrupt):
        with interruptible():
            obj = Finalised()
            del obj
            for _ in range(500):  # 5 s: the interrupt must come back well before
                time.sleep(0.01)
            ran_on.append(True)
    assert not ran_on


#: A pool whose first worker is interrupted while the run hands it its start-up data (``size`` bytes of
#: job): a thread of the run sends the run SIGINT as soon as the worker process exists.
_POOL_RUN = '''
import os, signal, sys, threading, time
from pathlib import Path


class Job:
    def __init__(self, size):
        self.payload = b"x" * size

    def prepared(self):
        return self

    def run_chunk(self, items):
        return items


def watch(me):
    while True:
        for c in Path(f"/proc/{me}/task/{me}/children").read_text().split():
            try:
                if b"spawn_main" in Path(f"/proc/{c}/cmdline").read_bytes():
                    os.kill(me, signal.SIGINT)
                    return
            except OSError:
                pass
        time.sleep(0.001)


if __name__ == "__main__":
    from job import Job
    from cdpr_design.batch.local import pool_session

    threading.Thread(target=watch, args=(os.getpid(),), daemon=True).start()
    try:
        with pool_session(Job(int(sys.argv[1])), 2) as run:
            run([[1], [2]], lambda rows: None)
            time.sleep(60)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(130)
'''


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="finds the worker through /proc")
@pytest.mark.parametrize("size", [1_000, 100_000, 5_000_000])
def test_a_run_interrupted_while_it_starts_a_worker_prints_one_line(tmp_path, size):
    """The interrupt lands while the run is still handing its new worker the start-up data (or just
    after: a worker still starting when the run exits).  The run says "interrupted" and nothing
    comes after it: not the worker's ``EOFError`` (its data cut short), nor a ``FileNotFoundError``
    rebuilding a semaphore the run had removed on exit."""
    (tmp_path / "job.py").write_text(_POOL_RUN)
    for _ in range(3):
        r = subprocess.run([sys.executable, str(tmp_path / "job.py"), str(size)], capture_output=True, text=True,
                           timeout=120, cwd=tmp_path, env=subprocess_env(PYTHONPATH=f"{tmp_path}{os.pathsep}"
                                                                                    f"{subprocess_env()['PYTHONPATH']}"))
        assert r.returncode == 130 and r.stderr == "interrupted\n", r.stderr[-3000:]  # was: EOFError, every time
