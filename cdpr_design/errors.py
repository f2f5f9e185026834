"""Typed errors of cdpr-design.

Only the command line turns these into exit codes: :class:`SpecError` and
:class:`InputError` mean bad input (exit 2; :class:`WriteError`, an output that cannot be
written, too), :class:`CheckFailed` means a design
failed a check it was asked to pass (exit 1).
"""

from __future__ import annotations

import reprlib
import signal

#: The signals every command stops on, cleanly, as on Ctrl-C: SIGINT, and SIGTERM (``kill``, a job
#: scheduler, ``timeout``) and SIGHUP (a closed terminal) where the platform has them.
STOP_SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))

#: Widest quotation of an offending value in a message (characters).
QUOTE_WIDTH = 80
#: Problems listed in one :class:`SpecError` message (the rest are counted).
MAX_PROBLEMS_SHOWN = 20

_repr = reprlib.Repr()
_repr.maxlevel, _repr.maxlist, _repr.maxtuple, _repr.maxdict = 2, 4, 4, 4
_repr.maxstring, _repr.maxother, _repr.maxlong = QUOTE_WIDTH, QUOTE_WIDTH, QUOTE_WIDTH


def quote(value) -> str:
    """``repr(value)`` shortened for a message: never the whole input.

    Nested containers are cut after a few entries and two levels, strings
    and other values to about :data:`QUOTE_WIDTH` characters, so a huge or
    self-referencing value (a YAML alias bomb) costs nothing to show.
    """
    text = _repr.repr(value)
    return text if len(text) <= QUOTE_WIDTH else text[: QUOTE_WIDTH - 3] + "..."


class CdprError(Exception):
    """Base class of every error this package raises on purpose."""


class SpecError(CdprError, ValueError):
    """A design spec (or catalogue, or option) breaks the format.

    Parameters
    ----------
    problems : list of (path, message)
        Each offending key by its path (``cables[1].outlet``) and what is wrong.
    source : str, optional
        The file the spec came from, for the message.
    """

    def __init__(self, problems, source: str | None = None):
        if isinstance(problems, str):
            problems = [("", problems)]
        self.problems = [(str(p), str(m)) for p, m in problems]
        self.source = source
        super().__init__(self._text())

    def _text(self) -> str:
        lines = [f"{p}: {m}" if p else m for p, m in self.problems]
        head = f"{self.source}: " if self.source else ""
        if len(lines) == 1:
            return head + lines[0]
        more = len(lines) - MAX_PROBLEMS_SHOWN
        shown = lines[:MAX_PROBLEMS_SHOWN] + ([f"... and {more} more"] if more > 0 else [])
        return head + f"{len(lines)} problems\n" + "\n".join("  " + s for s in shown)


class InputError(CdprError, ValueError):
    """A bad command-line value or input file other than a spec."""


class WriteError(InputError):
    """A file could not be written or put in place: a full disk or a file-size limit, a path too
    long, no permission, a read-only or immutable file.  Exit status 2 like bad input: the message
    names the file and the cause on one line."""

    @classmethod
    def of(cls, path, exc: BaseException, verb: str = "write") -> "WriteError":
        """``cannot write PATH: CAUSE`` of an OSError (``verb``: what could not be done)."""
        cause = getattr(exc, "strerror", None) or " ".join(str(exc).split()) or type(exc).__name__
        return cls(f"cannot {verb} {path}: {cause}")


class CheckFailed(CdprError):
    """A design failed a requirement it was asked to pass."""
