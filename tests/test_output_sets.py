"""A command's outputs are put in place together or not at all, one command at a time (issue 40, 6-8).

Every test leaves the output folder holding either the earlier run's files or
the new run's, whole, with the record ``.cdpr-design-outputs`` listing them,
and a failure is one line with exit status 2.  The file-system failures are
real: a file-size limit (RLIMIT_FSIZE) set in the command's own process, a
path too long for the temporary names, an immutable file (``chattr +i``), a
rename refused half-way through the commit, a commit killed half-way through.
Concurrent commands are ordered by the folder's lock, which the test holds
first: no test depends on which process is faster.
"""

from __future__ import annotations

import hashlib
import json
import os
import queue
import resource
import signal
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import pytest

from .helpers import PLANAR2, invoke, light_spec, subprocess_env

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX file systems and signals")

MANIFEST = ".cdpr-design-outputs"
LOCK = ".cdpr-design.lock"
#: The numpy engine and no picture helper: nothing numba would have to compile (and cache) under a limit.
ENV = {"CDPR_DESIGN_PICTURE_WORKER": "0", "CDPR_DESIGN_ENGINE": "numpy"}


def cli(*args, limit: int | None = None, **kw) -> subprocess.CompletedProcess:
    """The real command line in a child process; ``limit``: its RLIMIT_FSIZE [bytes]."""
    def preexec():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return subprocess.run([sys.executable, "-m", "cdpr_design", *map(str, args)], capture_output=True, text=True,
                          timeout=600, env=subprocess_env(**ENV), preexec_fn=preexec if limit else None, **kw)


def snapshot(folder: Path) -> dict[str, str]:
    """name -> digest of every file in ``folder`` but the lock files (whose contents name their holder)."""
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())
            if p.is_file() and not p.name.endswith(".lock")}


def record(folder: Path) -> set[str]:
    return set((folder / MANIFEST).read_text().split()) if (folder / MANIFEST).exists() else set()


def leftovers(folder: Path) -> list[str]:
    """Temporary files, backups and commit lists: none may stay after a command ended."""
    return sorted(p.name for p in folder.iterdir()
                  if p.name.endswith(".tmp") or p.name in (".cdpr-design-commit", ".cdpr-design-rollback"))


def one_error_line(stderr: str) -> str:
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in stderr, stderr
    return lines[0]


def consistent_workspace(folder: Path) -> None:
    """summary.json describes the workspace.csv beside it (one run's set, not two)."""
    rows = (folder / "workspace.csv").read_text().count("\n") - 1
    assert json.loads((folder / "summary.json").read_text())["poses"] == rows


# -- 6: write failures --------------------------------------------------------------------------


def test_a_file_size_limit_during_workspace_leaves_the_old_outputs_and_one_line(tmp_path):
    out = tmp_path / "o"
    old = cli("workspace", PLANAR2, "--step", "0.05", "--out", out, "--quiet")
    assert old.returncode == 0, old.stderr
    before = snapshot(out)
    # the new table (22,801 rows, 2 MB) passes 1 MB; the old files (under 200 kB each) would not
    new = cli("workspace", PLANAR2, "--step", "0.01", "--out", out, "--quiet", limit=1_000_000)
    assert new.returncode == 2, new.stderr  # was 1 with a traceback
    line = one_error_line(new.stderr)
    assert "workspace.csv" in line and "File too large" in line, line
    assert snapshot(out) == before and leftovers(out) == []
    consistent_workspace(out)


def test_a_file_size_limit_during_sweep_keeps_the_old_tables(tmp_path):
    out = tmp_path / "o"
    args = ["sweep", PLANAR2, "--step", "0.05", "--workers", "1", "--out", out, "--quiet"]
    old = cli(*args, "--vary", "effector.mass=0.5,1")
    assert old.returncode == 0, old.stderr
    before = snapshot(out)
    new = cli(*args, "--vary", "effector.mass=0.5:2:40", limit=20_000)
    assert new.returncode == 2, new.stderr
    line = one_error_line(new.stderr)
    assert "File too large" in line and str(out) in line, line
    after = snapshot(out)
    for name in ("sweep.csv", "sweep_best.csv", "sweep.png"):  # the outputs: the old ones, whole
        assert after[name] == before[name], name
    assert leftovers(out) == [] and {"sweep.csv", "sweep_best.csv", "sweep.png"} <= record(out)


def test_a_file_size_limit_during_optimize_leaves_no_study(tmp_path):
    spec = light_spec(tmp_path)
    out = tmp_path / "o"
    r = cli("optimize", spec, "--vary", "cables.0.outlet.0=-0.5:0.5", "--maximize", "task_min_margin",
            "--trials", "3", "--no-picture", "--quiet", "--out", out, limit=16_384)
    assert r.returncode == 2, r.stderr  # was 1 with SQLAlchemy's schema
    line = one_error_line(r.stderr)
    assert "optimize.db" in line and "SQLite" in line, line
    assert not any(p.name.startswith("optimize.") for p in out.iterdir()), sorted(os.listdir(out))
    assert "optimize.db" not in record(out) and leftovers(out) == []


def test_an_out_path_too_long_for_the_temporary_names_is_refused_before_any_work(tmp_path):
    # a folder that exists, whose files' temporary names would pass PATH_MAX (4096 bytes)
    folder = tmp_path
    while len(os.fsencode(str(folder))) < 4096 - 240:
        folder = folder / ("d" * 200)
    folder = folder / ("e" * (4096 - 40 - len(os.fsencode(str(folder)))))
    folder.mkdir(parents=True)
    r = invoke("workspace", PLANAR2, "--step", "0.05", "--out", folder, "--quiet")
    assert r.exit_code == 2, r.output  # was 1: ENAMETOOLONG's traceback from the first temporary file
    line = one_error_line(r.output)
    assert "--out" in line and "too long" in line, line
    assert list(folder.iterdir()) == []


def _chattr(flag: str, path: Path) -> bool:
    try:
        return subprocess.run(["chattr", flag, str(path)], capture_output=True).returncode == 0
    except OSError:
        return False


def test_an_immutable_output_leaves_the_old_set_and_one_line(tmp_path):
    out = tmp_path / "o"
    assert cli("workspace", PLANAR2, "--step", "0.05", "--out", out, "--quiet").returncode == 0
    if not _chattr("+i", out / "summary.json"):
        pytest.skip("chattr +i is not permitted here (the next test makes a rename fail in-process)")
    try:
        before = snapshot(out)
        r = cli("workspace", PLANAR2, "--step", "0.02", "--out", out, "--quiet")
        assert r.returncode == 2, r.stderr
        line = one_error_line(r.stderr)
        assert "summary.json" in line and "Operation not permitted" in line, line
        assert snapshot(out) == before and leftovers(out) == []  # was: the new table beside the old summary
        consistent_workspace(out)
    finally:
        _chattr("-i", out / "summary.json")


def test_a_rename_refused_half_way_through_the_commit_is_undone(tmp_path, monkeypatch):
    """The renames run in order (the record first); the one of summary.json fails after others were
    done: those are put back from their backups."""
    out = tmp_path / "o"
    r = invoke("workspace", PLANAR2, "--step", "0.05", "--out", out, "--quiet")
    assert r.exit_code == 0, r.output
    before = snapshot(out)
    real = os.replace
    done = []

    def replace(src, dst, **kw):
        if Path(dst).name == "summary.json" and Path(src).name.endswith(".tmp") and "_old" not in Path(src).name:
            raise PermissionError(1, "Operation not permitted", str(dst))
        done.append(Path(dst).name)
        return real(src, dst, **kw)

    monkeypatch.setattr(os, "replace", replace)
    r = invoke("workspace", PLANAR2, "--step", "0.02", "--out", out, "--quiet")
    monkeypatch.setattr(os, "replace", real)
    assert r.exit_code == 2, r.output
    assert "cannot replace" in one_error_line(r.output) and "summary.json" in r.output
    assert {MANIFEST, "workspace.csv"} <= set(done)  # some files were in place before the failure
    assert snapshot(out) == before and leftovers(out) == []
    consistent_workspace(out)


def test_a_commit_killed_half_way_is_finished_by_the_next_command(tmp_path):
    """SIGKILL (here: the process ends itself) after two of the commit's renames; the next command
    opening the folder completes the renames before anything else: the new set, whole."""
    out = tmp_path / "o"
    out.mkdir()
    for name in ("a.txt", "b.txt", "c.txt"):
        (out / name).write_text("old " + name)
    (out / MANIFEST).write_text("a.txt\nb.txt\nc.txt\n")
    script = textwrap.dedent(f"""
        import os
        from cdpr_design.io.files import OutputDir
        out = OutputDir({str(out)!r})
        real, calls = os.replace, []
        def replace(src, dst):
            src, dst = os.fspath(src), os.fspath(dst)
            if ".cdpr-design-tmp." in os.path.basename(src) and not dst.endswith(".cdpr-design-commit"):
                calls.append(dst)
                if len(calls) == 3:
                    os._exit(9)  # killed mid-commit
            return real(src, dst)
        os.replace = replace
        with out:
            for name in ("a.txt", "b.txt", "c.txt", "d.txt"):
                out.write_text(name, "new " + name)
    """)
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=subprocess_env(),
                       timeout=120)
    assert r.returncode == 9, r.stderr
    assert (out / ".cdpr-design-commit").exists()  # the list of renames a killed commit leaves
    texts = {n: (out / n).read_text() for n in ("a.txt", "b.txt", "c.txt")}
    assert sorted(texts.values()) == ["new a.txt", "old b.txt", "old c.txt"]  # the one window of a mix

    from cdpr_design.io.files import OutputDir

    OutputDir(out)  # opening the folder finishes the commit
    assert {n: (out / n).read_text() for n in ("a.txt", "b.txt", "c.txt", "d.txt")} == {
        n: "new " + n for n in ("a.txt", "b.txt", "c.txt", "d.txt")}
    assert record(out) == {"a.txt", "b.txt", "c.txt", "d.txt"}
    assert leftovers(out) == []


# -- 7: two commands on one folder ----------------------------------------------------------------


class Started:
    """A command in a child process whose stderr is read line by line (without blocking the test)."""

    def __init__(self, *args):
        self.proc = subprocess.Popen([sys.executable, "-m", "cdpr_design", *map(str, args)], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, env=subprocess_env(**ENV))
        self.lines: queue.Queue = queue.Queue()
        self.err: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stderr:
            self.err.append(line)
            self.lines.put(line)
        self.lines.put(None)

    def next_line(self, timeout: float = 300.0) -> str | None:
        return self.lines.get(timeout=timeout)

    def finish(self) -> int:
        self.proc.wait(timeout=600)
        self.proc.stdout.read()
        return self.proc.returncode


def test_workspace_and_size_motors_on_one_folder_both_end_with_a_correct_record(tmp_path):
    from cdpr_design.io.locks import owned

    out = tmp_path / "o"
    out.mkdir()
    with owned(out / LOCK):  # the test writes the folder: both commands must wait for it
        a = Started("workspace", PLANAR2, "--step", "0.02", "--out", out)
        note = a.next_line()
        assert note is not None and "waiting for" in note and f"pid {os.getpid()}" in note, (note, a.err)
        b = Started("size-motors", PLANAR2, "--out", out)
        note = b.next_line()
        assert note is not None and "waiting for" in note and f"pid {os.getpid()}" in note, (note, b.err)
        assert not any(out.glob("*.csv"))  # neither has written anything
    assert a.finish() == 0, "".join(a.err)
    assert b.finish() == 0, "".join(b.err)
    outputs = {"workspace.csv", "workspace.png", "tension_map.png", "tilt_map.png", "summary.json",
               "boundary.csv", "frame_loads.csv", "frame_loads.png", "motor_sizing.csv"}
    assert record(out) == outputs  # was: motor_sizing.csv dropped out of the record
    assert {p.name for p in out.iterdir()} == outputs | {MANIFEST, LOCK}
    consistent_workspace(out)
    # and the record lets each command replace its own file again
    assert cli("size-motors", PLANAR2, "--out", out, "--quiet").returncode == 0


def test_a_second_sweep_on_a_folder_a_sweep_is_writing_waits_for_it_naming_it(tmp_path):
    """Commands sharing an --out take turns: the second sweep says whom it waits for, writes nothing
    meanwhile, and runs once the first is over."""
    from cdpr_design.io.locks import owned

    out = tmp_path / "o"
    out.mkdir()
    with owned(out / ".sweep.lock"):
        b = Started("sweep", PLANAR2, "--vary", "effector.mass=0.5,1", "--step", "0.05", "--workers", "1",
                    "--out", out)
        note = b.next_line()
        assert note is not None and "waiting for" in note and f"pid {os.getpid()}" in note, (note, b.err)
        assert sorted(os.listdir(out)) == [".sweep.lock"]  # nothing written while it waits
    assert b.finish() == 0, "".join(b.err)
    assert {"sweep.csv", "sweep.journal.jsonl"} <= record(out)


# -- 8: optimize interrupted ----------------------------------------------------------------------


def _starting_worker(pid: int) -> bool:
    """Whether a worker process of ``pid`` (multiprocessing's ``spawn_main``) has an interpreter that
    catches SIGINT already (Python's own handler, set before it imports anything): from then on it
    spends a second or more importing, the start-up a signal must not catch."""
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
                if int(stat.rsplit(")", 1)[1].split()[1]) != pid or b"spawn_main" not in (d / "cmdline").read_bytes():
                    continue
                caught = next(ln for ln in (d / "status").read_text().splitlines() if ln.startswith("SigCgt:"))
                if int(caught.split()[1], 16) >> (signal.SIGINT - 1) & 1:
                    return True
            except (OSError, ValueError, IndexError, StopIteration):
                pass
    return False


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="finds the worker through /proc")
@pytest.mark.parametrize("how", ["SIGTERM", "Ctrl-C"])
def test_optimize_interrupted_while_its_worker_starts_prints_no_traceback(tmp_path, how):
    """The signal lands while the worker process is still starting (importing); the worker then
    holds it until its handlers are set, and ends quietly."""
    spec = light_spec(tmp_path)
    proc = subprocess.Popen([sys.executable, "-m", "cdpr_design", "optimize", str(spec), "--vary",
                             "cables.0.outlet.0=-0.5:0.5", "--maximize", "task_min_margin", "--trials", "50",
                             "--workers", "2", "--no-picture", "--quiet", "--out", str(tmp_path / "o")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env=subprocess_env(**ENV), start_new_session=True)
    try:
        while not _starting_worker(proc.pid):
            assert proc.poll() is None, proc.stderr.read()
        if how == "SIGTERM":
            proc.send_signal(signal.SIGTERM)
        else:  # a terminal's Ctrl-C reaches the whole foreground group, the worker too
            os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err  # was the worker's traceback, 7 of 7
    assert err.strip() == "interrupted", err


def test_a_damaged_study_is_refused_and_nothing_is_created_beside_it(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    db = out / "optimize.db"
    # an SQLite file in WAL mode (file format bytes 18-19 = 2, as optuna's studies are) with a damaged schema
    import sqlite3

    con = sqlite3.connect(db)
    con.execute("PRAGMA journal_mode=WAL")
    con.execute("CREATE TABLE studies (study_id INTEGER PRIMARY KEY, study_name TEXT)")
    con.commit()
    con.close()
    data = bytearray(db.read_bytes())
    for k in range(100, len(data), 7):
        data[k] = 0x5A
    db.write_bytes(bytes(data))
    (out / MANIFEST).write_text("optimize.db\n")
    before = snapshot(out)
    r = invoke("optimize", PLANAR2, "--vary", "cables.0.outlet.0=-0.5:0.5", "--maximize", "task_min_margin",
               "--trials", "2", "--resume", "--out", out, "--quiet")
    assert r.exit_code == 2, r.output
    assert "left as it is" in one_error_line(r.output)
    assert snapshot(out) == before  # was: optimize.db-shm and optimize.db-wal beside it
    assert sorted(os.listdir(out)) == [MANIFEST, "optimize.db"]


def test_a_certify_whose_summary_cannot_be_put_in_place_leaves_the_old_paving(tmp_path, monkeypatch):
    """certify's boxes, picture and summary go in together: a refused rename of summary.json puts
    the new boxes.csv back out (the folder keeps the earlier paving whole)."""
    out = tmp_path / "o"
    r = invoke("certify", PLANAR2, "--resolution", "0.1", "--out", out, "--quiet")
    assert r.exit_code == 0, r.output
    before = snapshot(out)
    real = os.replace

    def replace(src, dst, **kw):
        if Path(dst).name == "summary.json" and Path(src).name.endswith(".tmp") and "_old" not in Path(src).name:
            raise PermissionError(1, "Operation not permitted", str(dst))
        return real(src, dst, **kw)

    monkeypatch.setattr(os, "replace", replace)
    r = invoke("certify", PLANAR2, "--resolution", "0.02", "--out", out, "--quiet")
    monkeypatch.setattr(os, "replace", real)
    assert r.exit_code == 2, r.output
    assert "summary.json" in one_error_line(r.output)
    after = snapshot(out)
    for name in ("boxes.csv", "certify.png", "summary.json"):  # the outputs: the old ones, whole
        assert after[name] == before[name], name  # (the run's journal, kept for --resume, is new)
    assert leftovers(out) == []
    boxes = (out / "boxes.csv").read_text().count("\n") - 1
    assert sum(json.loads((out / "summary.json").read_text())["counts"].values()) == boxes
