"""Output folders and atomic files.

Every file is written to a temporary name in the destination folder and
renamed into place when complete, so an interrupted run never leaves a
truncated file under the final name.  An output folder remembers what
cdpr-design wrote into it (``.cdpr-design-outputs``): a file of the same name
that cdpr-design did not write is never overwritten unless the user asks
(``--overwrite``).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Iterable, Sequence

from cdpr_design.errors import InputError
from cdpr_design.io.preflight import check_folder, remove_stale, temp_prefix
from cdpr_design.io.tables import json_text

MANIFEST = ".cdpr-design-outputs"


class OutputDir:
    """An output folder; refuses to replace files cdpr-design did not write.

    Parameters
    ----------
    path : folder, created (with its parents) when the first file is written.
    overwrite : replace foreign files of the same name too.

    The constructor only checks that the folder is writable or can be created
    (:func:`~cdpr_design.io.preflight.check_folder`): a command that refuses
    its input afterwards leaves nothing behind, not even the folder.  The
    first write (:meth:`ensure`) creates it and removes the temporary files
    a killed run left there.
    """

    def __init__(self, path: str | Path, overwrite: bool = False):
        self.path = Path(path)
        self.overwrite = overwrite
        check_folder(self.path)
        self._ready = False
        self._manifest = self.path / MANIFEST
        try:
            self._ours = set(self._manifest.read_text().split("\n")) - {""}
        except (FileNotFoundError, NotADirectoryError):
            self._ours = set()
        except (OSError, UnicodeDecodeError) as exc:
            raise InputError(f"--out: cannot read {self._manifest}: {exc}") from None

    def ensure(self) -> Path:
        """Create the folder if missing and clear stale temporary files (once); the folder."""
        if not self._ready:
            try:
                self.path.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise InputError(f"--out: cannot create {self.path}: {exc.strerror or exc}") from None
            remove_stale(self.path)
            self._ready = True
        return self.path

    def target(self, name: str) -> Path:
        """The path for output ``name``, after checking it may be (over)written: a folder of
        that name is refused even with ``overwrite`` (that replaces files, never a folder)."""
        p = self.path / name
        if p.is_dir():
            raise InputError(f"--out: {p} is a folder, not a file cdpr-design can replace; move it away")
        # a symbolic link counts even when it points nowhere: the write would replace the link itself
        if (p.exists() or p.is_symlink()) and name not in self._ours and not self.overwrite:
            raise InputError(
                f"{p} exists and was not written by cdpr-design; move it away or pass --overwrite")
        return p

    def wrote(self, name: str) -> None:
        """Record ``name`` in the folder's manifest (cdpr-design wrote it)."""
        if name not in self._ours:
            self._ours.add(name)
            self.ensure()
            write_text_atomic(self._manifest, "\n".join(sorted(self._ours)) + "\n")

    def write_text(self, name: str, text: str) -> Path:
        p = self.target(name)
        self.ensure()
        write_text_atomic(p, text)
        self.wrote(name)
        return p

    def write_json(self, name: str, data) -> Path:
        """``data`` as indented JSON (numpy scalars and arrays as numbers and lists, NaN and
        infinities as null)."""
        return self.write_text(name, json_text(data, indent=2) + "\n")

    def write_csv(self, name: str, header: Sequence[str], rows: Iterable[Sequence]) -> Path:
        """A CSV of ``rows`` under ``header`` (cells as :func:`~cdpr_design.io.tables.fmt` writes them)."""
        rows = [list(r) for r in rows]
        cols = list(zip(*rows)) if rows else [()] * len(header)
        return self.write_columns(name, dict(zip(header, cols)), names=header)

    def write_columns(self, name: str, columns: dict, names: Sequence[str] | None = None,
                      metadata: dict | None = None) -> Path:
        """A table of named 1-D columns in one go, CSV or Parquet by the extension of ``name``
        (:class:`~cdpr_design.io.columns.ColumnWriter`)."""
        stem, _, ext = name.rpartition(".")
        with self.table(stem, ext, metadata=metadata, names=names if names is not None else list(columns)) as w:
            if columns and len(next(iter(columns.values()))):
                w.write(columns)
        return w.path

    def table(self, stem: str, format: str = "csv", metadata: dict | None = None,
              names: Sequence[str] | None = None, background: bool = False):
        """A :class:`~cdpr_design.io.columns.ColumnWriter` for ``stem.csv`` or ``stem.parquet``
        (refused if a foreign file has that name; recorded in the manifest when closed)."""
        from cdpr_design.io.columns import ColumnWriter, file_name

        name = file_name(stem, format)
        return ColumnWriter(self.target(name), format, metadata, names, on_commit=lambda: self.wrote(name),
                            background=background, before_open=self.ensure)

    def stream(self, name: str) -> "AtomicFile":
        """An :class:`AtomicFile` for writing ``name`` piece by piece."""
        p = self.target(name)
        self.ensure()
        return AtomicFile(p, on_commit=lambda: self.wrote(name))

    def write_bytes(self, name: str, data: bytes) -> Path:
        p = self.target(name)
        self.ensure()
        with AtomicFile(p, binary=True) as fh:
            fh.write(data)
        self.wrote(name)
        return p


class AtomicFile:
    """A file written under a temporary name and renamed into place on success.

    Use as a context manager; on an exception (or :meth:`abort`) the
    temporary file is removed and the final name is untouched.
    ``keep_partial=True`` renames what was written to ``<name>.partial``
    instead, so a long interrupted log is not lost.
    """

    def __init__(self, path: str | Path, binary: bool = False, on_commit=None, keep_partial: bool = False):
        self.path = Path(path)
        self.on_commit = on_commit
        self.keep_partial = keep_partial
        # a marked name with the writer's pid: a later run removes what a killed one left (io.preflight)
        fd, tmp = tempfile.mkstemp(prefix=temp_prefix(self.path.name), suffix=".tmp", dir=self.path.parent)
        self.tmp = Path(tmp)
        os.chmod(self.tmp, 0o666 & ~_umask())
        self.fh = os.fdopen(fd, "wb" if binary else "w", **({} if binary else {"newline": "", "encoding": "utf-8"}))
        self.closed = False

    def write(self, data):
        return self.fh.write(data)

    def flush(self):
        self.fh.flush()

    def commit(self) -> Path:
        """Flush, sync and rename into place (once; later calls do nothing)."""
        if self.closed:
            return self.path
        self.fh.flush()
        os.fsync(self.fh.fileno())
        self.fh.close()
        os.replace(self.tmp, self.path)
        self.closed = True
        if self.on_commit:
            self.on_commit()
        return self.path

    def abort(self) -> None:
        """Drop the temporary file (or keep it as ``<name>.partial``, see the class)."""
        if self.closed:
            return
        self.fh.close()
        self.closed = True
        if self.keep_partial and self.tmp.stat().st_size:
            os.replace(self.tmp, self.path.with_name(self.path.name + ".partial"))
        else:
            self.tmp.unlink(missing_ok=True)

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
