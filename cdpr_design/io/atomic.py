"""A file written under a temporary name and renamed into place only when it is complete.

:class:`AtomicFile` is the one way the tool writes a file: a final name never
holds a truncated file, and a failed write leaves the old file (or nothing).
The temporary name carries the writer's process id
(:func:`~cdpr_design.io.preflight.temp_prefix`), so a later run removes what a
killed one left.  An output folder (:class:`~cdpr_design.io.files.OutputDir`)
stages finished files to put a command's files in place together.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable

from cdpr_design.errors import WriteError
from cdpr_design.io.preflight import temp_prefix


class AtomicFile:
    """A file written under a temporary name and renamed into place on success.

    Use as a context manager; on an exception (or :meth:`abort`) the
    temporary file is removed and the final name is untouched.  ``stage``:
    instead of renaming it, :meth:`commit` hands the finished temporary file
    to ``stage`` (an :class:`~cdpr_design.io.files.OutputDir` puts it in place with its other files).
    Every OSError is a :class:`~cdpr_design.errors.WriteError` naming the file.
    """

    def __init__(self, path: str | Path, binary: bool = False, on_commit: Callable[[], None] | None = None,
                 stage: Callable[["AtomicFile"], None] | None = None):
        self.path = Path(path)
        self.on_commit = on_commit
        self._stage = stage
        # a marked name with the writer's pid: a later run removes what a killed one left (io.preflight)
        try:
            fd, tmp = tempfile.mkstemp(prefix=temp_prefix(self.path.name), suffix=".tmp", dir=self.path.parent)
        except OSError as exc:
            raise WriteError.of(self.path, exc) from None
        self.tmp = Path(tmp)
        self.fh = os.fdopen(fd, "wb" if binary else "w", **({} if binary else {"newline": "", "encoding": "utf-8"}))
        self.closed = False  # the temporary file is closed (finished or dropped)
        self.committed = False
        self.placed = False  # renamed to its final name
        try:
            os.chmod(self.tmp, 0o666 & ~_umask())
        except OSError as exc:
            self.abort()
            raise WriteError.of(self.path, exc) from None

    def write(self, data):
        try:
            return self.fh.write(data)
        except OSError as exc:
            raise WriteError.of(self.path, exc) from None

    def flush(self):
        try:
            self.fh.flush()
        except OSError as exc:
            raise WriteError.of(self.path, exc) from None

    def finish(self) -> None:
        """Flush, sync and close the temporary file: complete, not yet in place (once)."""
        if self.closed:
            return
        try:
            self.fh.flush()
            os.fsync(self.fh.fileno())
            self.fh.close()
        except OSError as exc:
            self.abort()
            raise WriteError.of(self.path, exc) from None
        self.closed = True

    def commit(self) -> Path:
        """Finish and rename into place, or hand to ``stage`` (once; later calls do nothing)."""
        if self.committed:
            return self.path
        self.finish()
        self.committed = True
        if self._stage is not None:
            self._stage(self)
            return self.path
        try:
            os.replace(self.tmp, self.path)
        except OSError as exc:
            self.discard()
            raise WriteError.of(self.path, exc, "replace") from None
        self.placed = True
        if self.on_commit:
            self.on_commit()
        return self.path

    def abort(self) -> None:
        """Drop the temporary file (the final name is untouched)."""
        if not self.closed:
            self.closed = True
            try:
                self.fh.close()
            except OSError:  # its last buffer could not be written: the file is dropped anyway
                pass
        self.discard()

    def discard(self) -> None:
        """Remove the temporary file, unless it was put in place."""
        if not self.placed:
            try:
                self.tmp.unlink(missing_ok=True)
            except OSError:
                pass

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.commit()
        else:
            self.abort()
        return False


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` through an :class:`AtomicFile`."""
    with AtomicFile(path) as fh:
        fh.write(text)
