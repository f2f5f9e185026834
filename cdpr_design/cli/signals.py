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

Python runs a signal's handler between two bytecodes of the main thread,
wherever it is, and that may be inside a finaliser (a ``__del__`` or a weakref
callback: SQLAlchemy's, when optuna's storage is torn down).  An exception
there cannot propagate: Python prints "Exception ignored" and drops it, so the
interrupt would be lost and the command run on.  Within :func:`interruptible`
such a dropped :class:`KeyboardInterrupt` is raised again: the signal is
delivered once more, and its handler runs at the next bytecode outside the
finaliser.  It is sent again from a short-lived thread to the main thread, so
that the handler cannot run inside the hook that saw it dropped (an exception
there would be dropped too); a second finaliser that swallows it sends it again.
"""

from __future__ import annotations

import signal
import sys
import threading
from contextlib import contextmanager

from cdpr_design.errors import STOP_SIGNALS

#: The signals treated as an interrupt besides SIGINT (Python's own KeyboardInterrupt).
SIGNALS = tuple(s for s in STOP_SIGNALS if s != signal.SIGINT)


#: After a finaliser dropped an interrupt, when it is sent again [s] (the hook has long returned).
REDELIVERY_S = 0.02


class Interrupted(KeyboardInterrupt):
    """A SIGTERM or SIGHUP turned into a KeyboardInterrupt (``signum``: which)."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


@contextmanager
def interruptible():
    """Within the block, SIGTERM and SIGHUP raise :class:`Interrupted` in the main thread.

    A :class:`KeyboardInterrupt` (from any of the three) that a finaliser swallowed is
    raised again.  Outside the main thread (where Python cannot install handlers) the
    block runs unchanged.  The previous handlers and ``sys.unraisablehook`` are put
    back on the way out.
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

    unraisable = sys.unraisablehook

    def swallowed(info):
        exc = info.exc_value
        if not isinstance(exc, KeyboardInterrupt):
            unraisable(info)
            return
        raised.clear()  # this one never reached the command: the next is not a second signal
        again = threading.Timer(REDELIVERY_S, signal.pthread_kill,
                                (threading.main_thread().ident, getattr(exc, "signum", signal.SIGINT)))
        again.daemon = True
        again.start()

    previous = {}
    for s in SIGNALS:
        try:
            previous[s] = signal.signal(s, handler)
        except (OSError, ValueError):  # pragma: no cover - an embedded interpreter
            pass
    sys.unraisablehook = swallowed
    try:
        yield
    finally:
        sys.unraisablehook = unraisable
        for s, h in previous.items():
            signal.signal(s, h)
