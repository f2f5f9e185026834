"""Locks on files of an output folder, and steps that no stop signal cuts in two.

:func:`flock` is the POSIX ``flock`` of a file: exclusive or shared, waited
for or tried once.  :func:`owned` is an exclusive lock whose file names the
process holding it (``pid 4242: cdpr-design workspace spec.yaml``) while it is
held, so that a command that finds it taken can say by whom; it is tried
once, or waited for up to a number of seconds.  The locks are released by
the kernel when their process ends, however it ends (SIGKILL included).

:func:`signals_held` holds the stop signals (:data:`~cdpr_design.errors.STOP_SIGNALS`)
through a step that must not be cut (the renames that put a command's files
in place, a trial's record in a study) and delivers them after it.
"""

from __future__ import annotations

import contextlib
import os
import shlex
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Callable

from cdpr_design.errors import STOP_SIGNALS, InputError

#: Seconds between two tries of a lock waited for.
POLL_S = 0.05
#: Longest description of a command in a lock file (characters).
COMMAND_WIDTH = 200


class Busy(Exception):
    """An :func:`owned` lock is held by another process (``holder``: what its file says, or None)."""

    def __init__(self, holder: str | None):
        super().__init__(holder or "another process")
        self.holder = holder


@contextlib.contextmanager
def flock(path: str | Path, blocking: bool = True, shared: bool = False):
    """An exclusive (``shared``: shared) lock on ``path``, created if missing (POSIX ``flock``);
    yields False when not ``blocking`` and taken, else True."""
    import fcntl

    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | (0 if blocking else fcntl.LOCK_NB))
        except BlockingIOError:
            yield False
            return
        try:
            yield True
        finally:
            fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)


def this_command() -> str:
    """This process's command line, shortened for a lock file (``cdpr-design`` for the tool's own)."""
    argv = list(sys.argv) or ["python"]
    name = Path(argv[0]).name
    if name in ("__main__.py", "cdpr-design", "cdpr_design"):
        name = "cdpr-design"
    text = shlex.join([name, *argv[1:]])
    return text if len(text) <= COMMAND_WIDTH else text[:COMMAND_WIDTH - 3] + "..."


def holder(path: str | Path) -> str | None:
    """Who holds the :func:`owned` lock ``path``, as its file says (None: it says nothing)."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace").strip()
    except OSError:
        return None
    return " ".join(text.split())[:COMMAND_WIDTH + 20] or None


@contextlib.contextmanager
def owned(path: str | Path, wait_s: float = 0.0, on_wait: Callable[[str | None], None] | None = None):
    """An exclusive lock on ``path`` (created if missing), the file naming this process while it is held.

    Taken at once, or waited for up to ``wait_s`` seconds (``on_wait(holder)`` is called once when
    it must wait); :class:`Busy` when it is still held by another process then.
    """
    import fcntl

    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        end = time.monotonic() + wait_s
        told = False
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                who = holder(path)
                if time.monotonic() >= end:
                    raise Busy(who) from None
                if not told and on_wait is not None:
                    on_wait(who)
                    told = True
                time.sleep(POLL_S)
        try:
            with contextlib.suppress(OSError):  # the name is a courtesy: a full disk does not stop the lock
                os.ftruncate(fd, 0)
                os.pwrite(fd, f"pid {os.getpid()}: {this_command()}\n".encode("utf-8", "replace"), 0)
            yield
        finally:
            with contextlib.suppress(OSError):
                os.ftruncate(fd, 0)
            fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)


@contextlib.contextmanager
def one_run(path: str | Path, command: str, wait_s: float = 0.0,
            on_wait: Callable[[str | None], None] | None = None):
    """The :func:`owned` lock ``path`` of a command whose files change as it runs (a sweep's journal,
    a study), held for the run: a second run of ``command`` on the folder waits for it up to
    ``wait_s`` seconds (``on_wait`` as :func:`owned`'s), then is refused, an :class:`InputError`
    naming ``--out`` and the run holding it."""
    with contextlib.ExitStack() as stack:
        try:
            stack.enter_context(owned(path, wait_s, on_wait))
        except Busy as busy:
            raise _in_use(path, command, busy.holder) from None
        yield


def check_free(path: str | Path, command: str, wait_s: float = 0.0,
               on_wait: Callable[[str | None], None] | None = None) -> None:
    """Return once the lock ``path`` is free (at once when nobody holds it; else after waiting up to
    ``wait_s`` seconds, ``on_wait(holder)`` called once when it must wait), or refuse as
    :func:`one_run` does; creates nothing."""
    import fcntl

    try:
        fd = os.open(path, os.O_RDWR)
    except OSError:
        return  # no lock file: nobody holds it
    try:
        end = time.monotonic() + wait_s
        told = False
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                fcntl.flock(fd, fcntl.LOCK_UN)
                return
            except BlockingIOError:
                who = holder(path)
                if time.monotonic() >= end:
                    raise _in_use(path, command, who) from None
                if not told and on_wait is not None:
                    on_wait(who)
                    told = True
                time.sleep(POLL_S)
    finally:
        os.close(fd)


def _in_use(path: str | Path, command: str, who: str | None) -> InputError:
    return InputError(f"--out: another {command} run is using {Path(path).parent} ({who or 'its process id unknown'}); "
                      "wait for it to end or choose another --out")


@contextlib.contextmanager
def signals_held(raise_after: bool = True):
    """The stop signals (:data:`cdpr_design.errors.STOP_SIGNALS`: Ctrl-C, a run stopping its workers, ``kill``, a
    closed terminal) held while a step that must not be cut runs: each one that came is delivered
    again after the step, to the handler that was there before (Python's KeyboardInterrupt, the
    command line's, or the default action) (``raise_after``; else dropped: the caller is stopping
    already).  Only the main thread receives signals; elsewhere nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got = []
    old = {s: signal.signal(s, lambda signum, _: got.append(signum)) for s in STOP_SIGNALS}
    try:
        yield
    finally:
        for s, h in old.items():  # None: a handler not set from Python, put back as Python's default
            signal.signal(s, h if h is not None else
                          signal.default_int_handler if s == signal.SIGINT else signal.SIG_DFL)
    if raise_after:
        for s in dict.fromkeys(got):
            signal.raise_signal(s)
