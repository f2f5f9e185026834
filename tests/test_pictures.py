"""The picture worker: PNGs drawn in a child process equal those drawn in-process."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import pytest

from cdpr_design.cli import env
from cdpr_design.plots import worker as pw
from cdpr_design.errors import InputError
from cdpr_design.io.files import OutputDir
from cdpr_design.jobs.common import save_pictures
from cdpr_design.jobs.workspace import workspace_pictures
from cdpr_design.plots import workspace as wsplots
from cdpr_design.model import spec
from cdpr_design import workspaces as ws

from .helpers import PLANAR2, ROOT


@pytest.fixture(scope="module")
def result():
    return ws.run(spec.load(PLANAR2))


def jobs(result):
    return [("workspace.png", wsplots.workspace_figure, (result,)),
            ("tension_map.png", wsplots.tension_figure, (result,))]


#: The two ways a child starts: a copy of this process, a new interpreter.
HOW = pytest.mark.parametrize("fork", [True, False], ids=["forked", "new"])


@HOW
def test_worker_draws_the_same_bytes(result, fork):
    local = pw.PictureWorker(enabled=False).render(jobs(result))
    with pw.PictureWorker(force=True, fork=fork) as worker:
        assert isinstance(worker.proc, pw.ForkedChild) == fork
        remote = worker.render(jobs(result))
        again = worker.render(jobs(result)[1:])  # the worker serves several requests
    assert [n for n, _ in remote] == ["workspace.png", "tension_map.png"]
    assert remote == local
    assert again == local[1:]
    assert remote[0][1][:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.skipif(not hasattr(os, "getpriority"), reason="POSIX priorities")
def test_worker_runs_at_its_parents_cpu_priority(result):
    """No lowered priority: on a busy machine a niced worker waits behind every other process
    (planar4's command 5x slower beside three busy processes, see the module's description)."""
    mine = os.getpriority(os.PRIO_PROCESS, 0)
    with pw.PictureWorker(force=True) as worker:
        assert worker.render(jobs(result)[:1])[0][0] == "workspace.png"  # warmed up and drawn
        assert os.getpriority(os.PRIO_PROCESS, worker.proc.pid) == mine


@pytest.mark.slow
@pytest.mark.parametrize("case", ["planar2", "orientations", "hanging"])
def test_the_worker_warms_up_with_what_a_request_needs_and_without_numba(case, result):
    """The worker's child (:func:`~cdpr_design.plots.worker.main`) warms up before any request
    comes (here: with none, it warms up and ends at the end of its input); then a workspace
    request (plain, of an orientation sweep, of a hanging spatial design) unpickles without
    importing anything, the child answers it with its pictures, and numba is never loaded (the
    child forks to draw only without it)."""
    code = """if True:
        import io, sys
        from cdpr_design.plots import worker as pw
        message = sys.stdin.buffer.read()
        pw.main(io.BytesIO(), io.BytesIO())  # the warm-up; no request
        before = set(sys.modules)
        pw.read_message(io.BytesIO(message))
        imported = sorted(set(sys.modules) - before)
        out = io.BytesIO()
        pw.main(io.BytesIO(message), out)
        out.seek(0)
        status, pngs = pw.read_message(out)
        print(status, len(pngs), all(p[1][:4] == b"\\x89PNG" for p in pngs), imported, "numba" in sys.modules)
    """
    from cdpr_design.jobs.workspace import workspace_pictures

    from .helpers import DESIGNS

    if case == "orientations":
        d = spec.load(DESIGNS / "planar4.yaml")
        result = ws.run(d, ws.Analysis(orientations="total"), grid=ws.make_grid(d, 0.25))
    elif case == "hanging":
        result = ws.run(spec.load(DESIGNS / "crane4.yaml"), step=0.6)
    jobs = workspace_pictures(result)
    message = io.BytesIO()
    pw.write_message(message, pw.request(jobs))
    r = subprocess.run([sys.executable, "-c", code], input=message.getvalue(), capture_output=True, cwd=ROOT,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)), timeout=300)
    assert r.returncode == 0, r.stderr.decode()[-2000:]
    assert r.stdout.decode().split() == ["ok", str(len(jobs)), "True", "[]", "False"]


@HOW
def test_error_in_worker_is_raised_in_process(fork):
    """A figure that fails in the child is drawn again here, so the real error surfaces."""
    with pw.PictureWorker(force=True, fork=fork) as worker:
        with pytest.raises(AttributeError):
            worker.render([("x.png", wsplots.workspace_figure, (None,))])
        assert worker.proc is None  # not trusted again


@HOW
def test_dead_worker_falls_back(result, fork):
    with pw.PictureWorker(force=True, fork=fork) as worker:
        worker.proc.kill()
        worker.proc.wait()
        out = worker.render(jobs(result)[:1])
    assert out == pw.PictureWorker(enabled=False).render(jobs(result)[:1])


def test_disabled_by_environment(monkeypatch):
    monkeypatch.setenv("CDPR_DESIGN_PICTURE_WORKER", "0")
    monkeypatch.delitem(sys.modules, "matplotlib.pyplot", raising=False)
    assert pw.PictureWorker(enabled=env.picture_worker_enabled()).proc is None


def _children() -> set[int]:
    """The process ids of this process's children (Linux's /proc)."""
    return {int(pid) for f in Path("/proc/self/task").glob("*/children") for pid in f.read_text().split()}


def test_prestart_take_discard(monkeypatch):
    """A picture command's worker is started before the command line is read (prestart), handed
    over once (take), and stopped -- its process gone -- when no command takes it (discard)."""
    assert pw.wanted(["workspace", "designs/planar2.yaml"])
    assert pw.wanted(["report", "x.yaml", "--json"])
    assert not pw.wanted(["workspace", "x.yaml", "--help"])
    assert not pw.wanted(["pose", "x.yaml"])
    assert not pw.wanted([])
    monkeypatch.delitem(sys.modules, "matplotlib.pyplot", raising=False)
    monkeypatch.delenv("CDPR_DESIGN_PICTURE_WORKER", raising=False)
    before = _children()
    pw.prestart()
    started = pw.take()
    assert started.proc is not None and started.proc.poll() is None  # the prestarted child, running
    assert pw.take(enabled=False) is not started  # handed over once: the next take makes a new one
    proc = started.proc
    started.close(kill=True)
    assert proc.poll() is not None
    linux = Path("/proc/self/task").is_dir()
    pw.prestart()
    assert not linux or _children() - before  # a child is running
    pw.discard()
    assert pw.take(enabled=False).proc is None  # nothing prestarted is left to take
    assert not linux or not _children() - before  # and its process is gone


@pytest.mark.slow
def test_command_output_identical_with_and_without_worker(tmp_path):
    """The real console entry: files byte-identical whether the worker drew or not."""
    outs = {}
    for flag in ("1", "0"):
        out = tmp_path / f"w{flag}"
        env = {**os.environ, "CDPR_DESIGN_PICTURE_WORKER": flag}
        subprocess.run([sys.executable, "-m", "cdpr_design", "workspace", str(PLANAR2), "--out", str(out),
                        "--quiet", "--json"], check=True, env=env, capture_output=True, cwd=tmp_path)
        outs[flag] = {p.name: p.read_bytes() for p in out.iterdir() if p.suffix in (".png", ".csv")}
    # planar2 is under-constrained: its tilt map comes with the workspace
    assert set(outs["1"]) == {"workspace.png", "tension_map.png", "tilt_map.png", "workspace.csv", "boundary.csv",
                              "frame_loads.csv", "frame_loads.png"}
    assert outs["1"] == outs["0"]


def test_worker_refuses_foreign_file_before_drawing(tmp_path, result):
    out = OutputDir(tmp_path)
    (tmp_path / "tension_map.png").write_text("mine")
    with pytest.raises(InputError, match="was not written by cdpr-design"):
        save_pictures(out, workspace_pictures(result))
    assert not (tmp_path / "workspace.png").exists()
    assert (tmp_path / "tension_map.png").read_text() == "mine"


@pytest.mark.slow
@HOW
def test_hung_worker_is_given_up(result, fork):
    """A child that does not answer in time is killed and the pictures are drawn here."""
    import signal

    with pw.PictureWorker(force=True, fork=fork) as worker:
        worker.timeout = 0.5
        os.kill(worker.proc.pid, signal.SIGSTOP)  # frozen, not dead
        proc = worker.proc
        out = worker.render(jobs(result)[:1])
        assert worker.proc is None and proc.poll() is not None
    assert out == pw.PictureWorker(enabled=False).render(jobs(result)[:1])


def _noisy_figure():
    """A figure function that writes to the standard streams (a library's warning, a print)."""
    from cdpr_design.plots._style import pyplot

    print("NOISE on stdout", flush=True)
    print("NOISE on stderr", file=sys.stderr, flush=True)
    os.write(1, b"NOISE on fd 1")
    return pyplot().figure(figsize=(1, 1))


def test_a_forked_child_writes_nothing_to_its_parents_streams(capfd):
    """The copy's standard streams are /dev/null, as a new child's stderr is: nothing it prints
    reaches the command's output (its --json on stdout), and it holds no copy of the parent's
    stdout, whose reader would otherwise wait for the child too."""
    with pw.PictureWorker(force=True, fork=True) as worker:
        out = worker.render([("a.png", _noisy_figure, ())])
        assert worker.proc is not None  # drawn by the child, not again here
    assert out[0][1][:8] == b"\x89PNG\r\n\x1a\n"
    captured = capfd.readouterr()
    assert "NOISE" not in captured.out + captured.err


def _process_state(pid: int) -> str | None:
    """The state letter of process ``pid`` (``Z``: ended, not yet collected), None once collected."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0]
    except FileNotFoundError:
        return None


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the child's state in /proc")
def test_a_forked_child_let_go_of_is_reaped():
    """A closed worker's forked child ends at the end of its input (exit status 0) and is
    collected, at the latest when the next worker closes, not left a zombie for the rest of a
    long-lived process."""
    import time

    worker = pw.PictureWorker(force=True, fork=True)
    child = worker.proc
    worker.close()
    deadline = time.monotonic() + 60
    while _process_state(child.pid) not in ("Z", None) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _process_state(child.pid) in ("Z", None)  # it ended
    with pw.PictureWorker(force=True, fork=True) as other:
        last = other.proc
    assert _process_state(child.pid) is None and child.returncode == 0
    with pytest.raises(ChildProcessError):
        os.waitpid(child.pid, os.WNOHANG)  # collected already
    assert last.wait() == 0  # the next one ends too (collected here: this test leaves no zombie)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="it forks for real once the conditions hold")
def test_a_copy_is_made_only_where_it_is_safe():
    """No fork with another thread running, with numba loaded, or beside another live child; the
    worker then starts a new interpreter (``fork=None``, the default).  In a fresh process, where
    each condition is made for real (a thread started, numba imported), nothing patched."""
    code = """if True:
        import subprocess, threading
        from cdpr_design.plots import worker as pw
        out = [pw.can_fork()]
        with pw.PictureWorker(force=True) as first:
            out += [isinstance(first.proc, pw.ForkedChild), pw.can_fork()]
            with pw.PictureWorker(force=True) as second:  # the first's request pipe: no second copy
                out.append(isinstance(second.proc, subprocess.Popen))
        out.append(pw.can_fork())
        stop = threading.Event()
        t = threading.Thread(target=stop.wait)
        t.start()
        out.append(pw.can_fork())
        stop.set()
        t.join()
        out.append(pw.can_fork())
        import numba
        out.append(pw.can_fork())
        print(out)
    """
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=300,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.split("\n")[-2] == str([True, True, False, True, True, False, True, False])
