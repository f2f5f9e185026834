"""SIGTERM and SIGHUP handled like Ctrl-C (SIGINT), for the command line only.

Python turns SIGINT into :class:`KeyboardInterrupt`; the default action of
SIGTERM (``kill``, a job scheduler, ``timeout``) and SIGHUP (a closed
terminal or SSH session) ends the process at once, so an interrupted
``workspace`` left its half-written temporary files behind.  Inside
:func:`interruptible` both raise :class:`Interrupted`, a
:class:`KeyboardInterrupt`: every ``with AtomicFile`` and ``try/finally`` on
the way out runs as for Ctrl-C (temporary files removed, a sweep's journal
flushed and kept for ``--resume``), and the command exits 130.

A second signal while that cleanup runs is ignored (a supervisor that sends
SIGTERM twice must not cut the cleanup short); SIGKILL cannot be caught, and
what it leaves is cleaned up by the next run in the same ``--out``
(:meth:`cdpr_design.io.files.OutputDir.ensure`).
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

from cdpr_design.errors import STOP_SIGNALS

#: The signals treated as an interrupt besides SIGINT (Python's own KeyboardInterrupt).
SIGNALS = tuple(s for s in STOP_SIGNALS if s != signal.SIGINT)


class Interrupted(KeyboardInterrupt):
    """A SIGTERM or SIGHUP turned into a KeyboardInterrupt (``signum``: which)."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


@contextmanager
def interruptible():
    """Within the block, SIGTERM and SIGHUP raise :class:`Interrupted` in the main thread.

    Outside the main thread (where Python cannot install handlers) the block
    runs unchanged.  The previous handlers are put back on the way out.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    raised = []

    def handler(signum, frame):
        if raised:  # cleaning up after the first one: let it finish
            return
        raised.append(signum)
        raise Interrupted(signum)

    previous = {}
    for s in SIGNALS:
        try:
            previous[s] = signal.signal(s, handler)
        except (OSError, ValueError):  # pragma: no cover - an embedded interpreter
            pass
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
