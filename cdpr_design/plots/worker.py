"""Pictures drawn in a child process, so importing matplotlib overlaps a command's work.

Importing matplotlib and drawing the first figure costs about a second on
one core; the numbers behind the pictures take a fraction of that for a
typical design.  A command that ends with pictures starts a
:class:`PictureWorker` first thing: the child imports matplotlib on the other
core while the parent reads the spec and sweeps, then :meth:`PictureWorker.render`
hands it the figure functions and their data and gets PNG bytes back.  The
parent writes the files itself (atomic, manifest-checked, see
:class:`cdpr_design.io.files.OutputDir`).

The child runs at its parent's CPU priority.  It once lowered its own
(``nice`` +10), so that the parent's sweep threads went first where the two
overlap, a few percent on an idle machine.  But a lowered priority is
lowered against every other process too: with busy processes beside it, the
pictures waited behind them (docs/performance.md).

Whenever the child cannot be used (it failed to start, died, or a figure
raised there) ``render`` draws in-process instead, so errors surface exactly
as without the worker.  No child is started when matplotlib is already
imported in this process (nothing to hide) or when the caller disables it
(``enabled=False``; the command line does so for
``CDPR_DESIGN_PICTURE_WORKER=0``).

The child is a copy of the parent (``os.fork``) where that is safe
(:func:`can_fork`: Linux, one thread, numba not loaded, no other child
alive), else a new interpreter.  A copy starts with what the parent has
imported: the command line starts the worker (:func:`prestart`) once numpy
is imported and before typer, rich and pydantic, so its child skips Python's
start-up, its site and numpy.
This module imports nothing heavy itself.

Protocol on the child's pipes (a new interpreter's stdin/stdout): length-prefixed pickles.  A request is
a list of jobs ``(name, builder, args, dpi)``; the answer is
``("ok", [(name, png_bytes), ...])`` or ``("error", text)``.  End of input
ends the child.
"""

from __future__ import annotations

import gc
import io
import os
import pickle
import signal
import struct
import subprocess
import sys
import threading
from pathlib import Path

_LEN = struct.Struct("<Q")

#: zlib level of the PNGs: 3 encodes faster than PIL's default 6, the files somewhat larger
#: (docs/performance.md)
PNG_COMPRESSION = 3


def read_message(stream):
    """One length-prefixed pickle from ``stream``, or None at end of input."""
    head = stream.read(_LEN.size)
    if len(head) < _LEN.size:
        return None
    size = _LEN.unpack(head)[0]
    data = stream.read(size)
    if len(data) < size:
        return None
    return pickle.loads(data)


def write_message(stream, obj) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(_LEN.pack(len(data)))
    stream.write(data)
    stream.flush()


def draw_parallel(jobs) -> list[tuple[str, bytes]]:
    """:func:`draw`, the second half of the jobs in a forked copy of this process.

    Used in the worker only: it runs no threads and has not loaded numba's
    OpenMP runtime (checked), so forking it is safe; the parent command waits idle
    meanwhile, leaving both cores to the drawing.  Falls back to drawing in
    turn where ``fork`` does not exist or fails.
    """
    if len(jobs) < 2 or not hasattr(os, "fork") or "numba" in sys.modules:
        return draw(jobs)
    half = (len(jobs) + 1) // 2
    first, second = jobs[:half], jobs[half:]
    rfd, wfd = os.pipe()
    try:
        pid = os.fork()
    except OSError:
        os.close(rfd)
        os.close(wfd)
        return draw(jobs)
    if pid == 0:  # the copy: draw the second half, send it back, leave without cleanup
        code = 0
        try:
            os.close(rfd)
            try:
                answer = ("ok", draw(second))
            except Exception as exc:
                answer = ("error", f"{type(exc).__name__}: {exc}")
            with os.fdopen(wfd, "wb") as fh:
                write_message(fh, answer)
        except BaseException:
            code = 1
        finally:
            os._exit(code)
    os.close(wfd)
    try:
        out = draw(first)
    finally:
        with os.fdopen(rfd, "rb") as fh:
            answer = read_message(fh)
        os.waitpid(pid, 0)
    if answer is None or answer[0] != "ok":
        raise RuntimeError(f"drawing in the forked worker failed: {answer[1] if answer else 'no answer'}")
    return out + answer[1]


def draw(jobs) -> list[tuple[str, bytes]]:
    """PNG bytes of each job ``(name, builder, args, dpi)``; figures are closed.  A builder
    returning text instead of a figure (the HTML report) gives that text, UTF-8 encoded."""
    from cdpr_design.plots._style import pyplot

    out = []
    for name, builder, args, dpi in jobs:
        fig = builder(*args)
        if isinstance(fig, str):
            out.append((name, fig.encode("utf-8")))
            continue
        plt = pyplot()
        try:
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=dpi, pil_kwargs={"compress_level": PNG_COMPRESSION})
        finally:
            plt.close(fig)
        out.append((name, buf.getvalue()))
    return out


class PictureWorker:
    """A child process drawing PNGs (see the module's description).

    Parameters
    ----------
    enabled : bool
        False: never start a child; :meth:`render` draws in-process.
    force : bool
        Start a child even though matplotlib is imported here already (tests).
    fork : bool or None
        How the child starts: True, a copy of this process (``os.fork``), which has
        Python, its site and whatever this process imported so far (numpy, which a child
        started afresh imports before matplotlib); False, a
        new interpreter.  None: a copy where that is safe (:func:`can_fork`), else new.
    """

    #: seconds to wait for the child's pictures before drawing them here instead
    timeout: float = 300.0

    def __init__(self, enabled: bool = True, force: bool = False, fork: bool | None = None):
        self.proc = None
        # the child's pipes are used by one thread at a time: the request in flight (its writer
        # and reader threads) until it has ended, then whoever takes `proc` under this lock to
        # close them (see close)
        self._lock = threading.Lock()
        self._inflight: threading.Thread | None = None  # the thread of a submitted request
        if not enabled or (not force and "matplotlib.pyplot" in sys.modules):
            return
        try:
            self.proc = ForkedChild() if (can_fork() if fork is None else fork) else _new_child()
        except OSError:
            self.proc = None
        if self.proc is not None:
            _alive.add(self.proc)

    def render(self, jobs) -> list[tuple[str, bytes]]:
        """PNG bytes of each job ``(name, builder, args)``; builder: a figure function of
        :mod:`cdpr_design.plots` (or any importable function returning a figure)."""
        jobs = request(jobs)
        pngs = self._render_remote(jobs)
        return pngs if pngs is not None else draw(jobs)

    def submit(self, jobs) -> "Pending":
        """Start :meth:`render` and return at once: the child draws while the caller works on
        (writes its tables); :meth:`Pending.result` waits for the PNG bytes.  Without a child
        the pictures are drawn in this process when the result is asked for."""
        return Pending(self, request(jobs))

    def _render_remote(self, jobs):
        """The child's PNGs of ``jobs`` (with dpi), or None when it cannot draw them."""
        proc = self.proc
        if proc is None:
            return None
        # the request is written by a thread (it may exceed the pipe's buffer) while this
        # one waits for the answer; a child that hangs is given up on after `timeout`
        sent: list[BaseException] = []
        writer = threading.Thread(target=_send, args=(proc.stdin, jobs, sent), daemon=True)
        writer.start()
        try:
            answer = read_message(proc.stdout) if _readable(proc.stdout, self.timeout) else None
        except (OSError, ValueError, EOFError, pickle.PickleError, AttributeError, TypeError):
            answer = None
        if sent:  # the request could not be sent (pickling it failed, or the child died)
            answer = None
        if answer is not None and answer[0] == "ok":
            writer.join()
            return answer[1]
        # give up on the child: stop it (a writer blocked on the full pipe then fails), wait for
        # the writer, and only then close the pipes (see close)
        _stop(proc)
        writer.join()
        self.close()
        return None

    def close(self, kill: bool = False) -> None:
        """Let the child go: it ends at end of input.  ``kill``: stop it now (it may be busy).

        The pipes are closed once a submitted request's thread has ended (at once when the child
        is killed): a buffered stream closed by one thread while another writes to or reads from
        it can fail in that other thread with a ValueError, as CPython's ``flush()`` checks for
        *closed* before it takes the stream's lock and then writes from the buffer ``close()``
        freed ("PyMemoryView_FromBuffer(): info->buf must not be NULL")."""
        with self._lock:
            proc, self.proc = self.proc, None
        if proc is None:
            return
        _alive.discard(proc)
        if kill:
            _stop(proc)
        inflight = self._inflight
        if inflight is not None and inflight is not threading.current_thread():
            inflight.join()
        for stream in (proc.stdin, proc.stdout):
            try:
                stream.close()
            except OSError:
                pass
        if isinstance(proc, ForkedChild):
            _reap(proc)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        # after an error the child may still be importing: stop it rather than wait
        self.close(kill=exc_type is not None)
        return False


def _stop(proc) -> None:
    """Kill the child ``proc`` if it still runs, and wait for it to end."""
    if proc.poll() is None:
        proc.kill()
        proc.wait()


def _new_child() -> subprocess.Popen:
    """A child in a new interpreter, running :func:`main` on its standard input and output."""
    # the child imports this very package, whatever the working folder holds
    pkg_root = str(Path(__file__).resolve().parents[2])
    code = (f"import sys; sys.path.insert(0, {pkg_root!r}); "
            "from cdpr_design.plots.worker import main; main()")
    return subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL)


def can_fork() -> bool:
    """Whether a copy of this process can be the child: on Linux (macOS's system libraries are
    not safe to use in a copy that does not exec), with no other thread running (a copy has
    only the thread that forked: a lock another one held stays locked there), numba not
    loaded (its threading layer) and no other child of this module alive (a copy would hold
    that child's request pipe open, which then never sees its end of input)."""
    return (sys.platform.startswith("linux") and hasattr(os, "fork") and threading.active_count() == 1
            and "numba" not in sys.modules and not _alive)


class ForkedChild:
    """The child as a copy of this process (``os.fork``) running :func:`main` on two pipes; what
    :class:`PictureWorker` uses of a :class:`subprocess.Popen`: ``pid``, ``stdin`` (requests),
    ``stdout`` (answers), :meth:`poll`, :meth:`kill`, :meth:`wait`.  The copy's standard
    streams, descriptors and Python objects, are /dev/null; it leaves by ``os._exit`` (none of
    this process's exit handlers run twice)."""

    def __init__(self):
        req_r, req_w = os.pipe()
        ans_r, ans_w = os.pipe()
        try:
            self.pid = os.fork()
        except OSError:
            for fd in (req_r, req_w, ans_r, ans_w):
                os.close(fd)
            raise
        if self.pid == 0:
            code = 1
            try:
                os.close(req_w)
                os.close(ans_r)
                null = os.open(os.devnull, os.O_RDWR)
                for fd in (0, 1, 2):
                    os.dup2(null, fd)
                # the parent's Python-level streams may not be those descriptors (a notebook's)
                sys.stdin = sys.stdout = sys.stderr = open(os.devnull, "r+")
                main(os.fdopen(req_r, "rb"), os.fdopen(ans_w, "wb"))
                code = 0
            finally:
                os._exit(code)
        os.close(req_r)
        os.close(ans_w)
        self.stdin = os.fdopen(req_w, "wb")
        self.stdout = os.fdopen(ans_r, "rb")
        self.returncode = None

    def poll(self) -> int | None:
        """The child's exit status, or None while it runs."""
        if self.returncode is None:
            try:
                pid, status = os.waitpid(self.pid, os.WNOHANG)
            except ChildProcessError:
                self.returncode = -1
                return self.returncode
            if pid:
                self.returncode = os.waitstatus_to_exitcode(status)
        return self.returncode

    def kill(self) -> None:
        if self.poll() is None:
            try:
                os.kill(self.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass

    def wait(self) -> int:
        if self.returncode is None:
            try:
                self.returncode = os.waitstatus_to_exitcode(os.waitpid(self.pid, 0)[1])
            except ChildProcessError:
                self.returncode = -1
        return self.returncode


#: The children of open workers (:meth:`PictureWorker.close` lets go of them).
_alive: set = set()
#: Forked children let go of and not yet seen to end (each :func:`_reap` looks again).
_leaving: list[ForkedChild] = []


def _reap(child: ForkedChild | None = None) -> None:
    """Collect the exit status of the let-go forked children that have ended (``child`` is one
    more), so that none stays a zombie for the rest of a long-lived process."""
    if child is not None:
        _leaving.append(child)
    _leaving[:] = [c for c in _leaving if c.poll() is None]


class Pending:
    """Pictures being drawn by a :class:`PictureWorker`'s child (:meth:`PictureWorker.submit`)."""

    def __init__(self, worker: PictureWorker, jobs):
        self.jobs = jobs
        self._pngs = None
        self._thread = None
        if worker.proc is not None:
            # a thread of this process waits for the child's answer; it only moves bytes
            self._thread = worker._inflight = threading.Thread(target=self._wait, args=(worker,), daemon=True)
            self._thread.start()

    def _wait(self, worker: PictureWorker) -> None:
        self._pngs = worker._render_remote(self.jobs)

    def result(self) -> list[tuple[str, bytes]]:
        """PNG bytes of each job; drawn here when the child could not (errors surface here)."""
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._pngs is None:
            self._pngs = draw(self.jobs)
        return self._pngs


def request(jobs) -> list:
    """The request :class:`PictureWorker` sends its child for ``jobs`` ``(name, builder, args)``:
    each with the pictures' resolution (what :func:`main` reads, :func:`write_message`)."""
    from cdpr_design.plots._style import DPI

    return [(name, builder, tuple(args), DPI) for name, builder, args in jobs]


def _send(stream, obj, failures: list) -> None:
    """Write a request; a failure is recorded in ``failures`` (the reader then falls back)."""
    try:
        write_message(stream, obj)
    except BaseException as exc:  # noqa: BLE001 - reported to the waiting thread
        failures.append(exc)
        try:
            stream.close()  # the child sees end of input and ends
        except OSError:
            pass


def _readable(stream, timeout: float) -> bool:
    """Whether ``stream`` has data (or end of input) within ``timeout`` seconds.
    Where pipes cannot be polled (Windows) it answers True and the read blocks."""
    import selectors

    try:
        with selectors.DefaultSelector() as sel:
            sel.register(stream, selectors.EVENT_READ)
            return bool(sel.select(timeout))
    except (OSError, ValueError):
        return True


_prestarted: PictureWorker | None = None

#: commands that end with pictures drawn through :func:`take`
PICTURE_COMMANDS = ("workspace", "report")


def wanted(argv) -> bool:
    """Whether the command line ``argv`` (without the program) runs a picture command."""
    return bool(argv) and argv[0] in PICTURE_COMMANDS and not {"-h", "--help"} & set(argv)


def prestart(enabled: bool = True) -> None:
    """Start a worker now, for the command about to run (:func:`take` hands it over).

    ``enabled=False``: start none (the commands then draw in-process)."""
    global _prestarted
    if _prestarted is None:
        _prestarted = PictureWorker(enabled=enabled)


def take(enabled: bool = True) -> PictureWorker:
    """The worker :func:`prestart` started, else a new one (``enabled`` as for :class:`PictureWorker`)."""
    global _prestarted
    worker, _prestarted = _prestarted, None
    return worker if worker is not None else PictureWorker(enabled=enabled)


def discard() -> None:
    """Stop a prestarted worker no command took."""
    global _prestarted
    worker, _prestarted = _prestarted, None
    if worker is not None:
        worker.close(kill=True)


# ----------------------------------------------------------------------------
# The child
# ----------------------------------------------------------------------------


#: What a request of the ``workspace`` and ``report`` commands unpickles: its result's classes
#: (the design, the grid, an orientation sweep's maps) and the figure functions.
#: :func:`_warm_up` imports them while the parent still sweeps, not once the request is there
#: (then on the command's critical path).  None of them imports numba
#: (:func:`draw_parallel` forks only without it).
PRELOAD = ("cdpr_design.workspaces.grid", "cdpr_design.workspaces.orientation", "cdpr_design.plots.workspace",
           "cdpr_design.plots.hanging")


def _warm_up() -> None:
    """Import matplotlib, :data:`PRELOAD`, and load the font the pictures' text needs; then put
    everything loaded so far (modules, fonts, caches: about 120,000 objects that live as long as
    the worker) out of the cyclic garbage collector's sight (:func:`gc.freeze`), so that no
    collection walks them again.  Frozen objects are still freed when their reference counts
    drop to zero.  The warm-up's cyclic garbage (about 2,800 objects, the warm-up figure's
    among them) is frozen with the rest rather than collected first: a collection there walks
    every one of those objects, on the worker's CPU while the command starts up."""
    import importlib

    from cdpr_design.plots._style import pyplot

    plt = pyplot()
    for name in PRELOAD:
        importlib.import_module(name)
    fig = plt.figure(figsize=(1, 1))
    fig.text(0.5, 0.5, "x [m]")
    fig.savefig(io.BytesIO(), format="png", dpi=20)
    plt.close(fig)
    gc.freeze()


def main(inp=None, outp=None) -> None:
    """The child: warm up, then answer requests from ``inp`` on ``outp`` (binary streams;
    default this process's standard input and output) until the end of input."""
    if inp is None:
        inp, outp = sys.stdin.buffer, sys.stdout.buffer
        sys.stdout = sys.stderr  # nothing but answers on the pipe
    try:
        _warm_up()
        while True:
            jobs = read_message(inp)
            if jobs is None:
                return
            write_message(outp, answer(jobs))
            gc.collect()  # the request's garbage, while the parent writes the pictures
    except (KeyboardInterrupt, BrokenPipeError):
        return


def answer(jobs) -> tuple:
    """The worker's answer to a request (see the module's description), drawn with the cyclic
    garbage collector paused: a figure is thousands of objects in reference cycles, and the
    collections they triggered while drawing (each walking every live object) cost up to a
    fifth of a picture's CPU time; :func:`main` collects once the answer is sent.  Meanwhile the
    request's closed figures wait in memory: a few MB each (their pixel buffers), a handful
    of figures a request."""
    gc.disable()
    try:
        return ("ok", draw_parallel(jobs))
    except Exception as exc:  # the parent redraws in-process and reports it
        return ("error", f"{type(exc).__name__}: {exc}")
    finally:
        gc.enable()


if __name__ == "__main__":
    main()
