"""Output folders and atomic files: a command's files are put in place together, or not at all.

Every file is written under a temporary name in its destination folder
(:class:`~cdpr_design.io.atomic.AtomicFile`), so a final name never holds a truncated file.  An
output folder (:class:`OutputDir`) used as a context manager -- ``with out:``,
what every command does around its writing -- keeps each finished file under
its temporary name (*staged*) and puts them all in place when the block ends
(:meth:`OutputDir.commit`); an exception in the block (a full disk, a file
too large, Ctrl-C) removes every staged file and replaces nothing, so the
folder keeps the previous run's files whole.  Outside a ``with`` block each
file is put in place as soon as it is written.

The commit, under the folder's lock (``.cdpr-design.lock``; another command
writing into the folder waits for it, up to :data:`LOCK_WAIT_S`):

1. the record ``.cdpr-design-outputs`` is read again (another command may
   have committed meanwhile), the names are checked against it (a file that
   cdpr-design did not write is not replaced without ``overwrite``), and the
   new record -- the old one and this command's names -- is written as one
   more staged file: every byte is written and synced before anything is
   replaced, so a write error leaves the folder as it was;
2. the list of renames is written (``.cdpr-design-commit``), a hard link to
   each file about to be replaced is made beside it (a backup; where links
   are not supported, the old file is moved aside), then the renames run,
   the record first, with the stop signals held (:func:`~cdpr_design.io.locks.signals_held`);
3. a rename that fails (an immutable file, a permission) undoes those
   already done from the backups: the old files are back, the new ones gone;
4. the list and the backups are removed.

A process killed during step 2 (SIGKILL or a power cut: the renames take
microseconds) leaves the list; the next command that opens the folder
finishes the renames from it before it reads or writes anything
(:func:`recover`), so the folder then holds the new set whole -- or, if it
was undoing a failed commit, the old set.  Between the kill and that next
command the folder may hold some new files beside old ones: that is the one
window where a mix can be seen.

An output folder remembers what cdpr-design wrote into it
(``.cdpr-design-outputs``): a file of the same name that cdpr-design did not
write is never overwritten unless the user asks (``--overwrite``).  Every
failure to write or put a file in place is a :class:`~cdpr_design.errors.WriteError`
naming the file and the cause.
"""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path
from typing import Callable, Sequence

from cdpr_design.errors import InputError, WriteError
from cdpr_design.io.atomic import AtomicFile, write_text_atomic
from cdpr_design.io.columns import ColumnWriter, file_name
from cdpr_design.io.locks import Busy, owned, signals_held
from cdpr_design.io.preflight import check_folder, check_name, remove_stale
from cdpr_design.io.tables import json_text

MANIFEST = ".cdpr-design-outputs"
#: The lock held while a command changes the folder (its first write, its commit, a record).
LOCK = ".cdpr-design.lock"
#: The renames of a commit under way; the same list once it is being undone.
INTENT = ".cdpr-design-commit"
ROLLBACK = ".cdpr-design-rollback"
#: Seconds a command waits for another one changing the same folder before it refuses (exit 2).
LOCK_WAIT_S = 120.0
#: The suffix of a backup's name: the temporary name it replaces, ``…<random>_old.tmp``.
BACKUP = "_old.tmp"

_log = logging.getLogger("cdpr_design")


def read_manifest(path: Path) -> set[str]:
    """The names in the record ``path`` (empty when there is none)."""
    try:
        return set(path.read_text(encoding="utf-8").split("\n")) - {""}
    except (FileNotFoundError, NotADirectoryError):
        return set()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"--out: cannot read {path}: {exc}") from None


class OutputDir:
    """An output folder; refuses to replace files cdpr-design did not write.

    Parameters
    ----------
    path : folder, created (with its parents) when the first file is written.
    overwrite : replace foreign files of the same name too.

    The constructor only checks that the folder is writable or can be created
    (:func:`~cdpr_design.io.preflight.check_folder`): a command that refuses
    its input afterwards leaves nothing behind, not even the folder (it does
    finish a commit a killed command left, see the module).  The first write
    (:meth:`ensure`) creates it and removes the temporary files a killed run
    left there.  ``with out:`` makes the files written in the block one set,
    put in place when it ends (see the module).
    """

    def __init__(self, path: str | Path, overwrite: bool = False):
        self.path = Path(path)
        self.overwrite = overwrite
        check_folder(self.path)
        self._ready = False
        self._manifest = self.path / MANIFEST
        self._staged: dict[str, AtomicFile] = {}
        self._depth = 0
        if _unfinished(self.path):
            with self._locked():
                recover(self.path)
        self._ours = read_manifest(self._manifest)

    # -- the folder ----------------------------------------------------------

    def ensure(self) -> Path:
        """Create the folder if missing, finish a killed command's commit and clear stale temporary
        files (once); the folder."""
        if not self._ready:
            try:
                self.path.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise InputError(f"--out: cannot create {self.path}: {exc.strerror or exc}") from None
            with self._locked():
                recover(self.path)
                remove_stale(self.path)
            self._ready = True
        return self.path

    def _locked(self):
        """The folder's lock (waited for; a :class:`WriteError` when its file cannot be made)."""
        return _FolderLock(self.path)

    def target(self, name: str) -> Path:
        """The path for output ``name``, after checking it may be (over)written: a folder of
        that name is refused even with ``overwrite`` (that replaces files, never a folder), and so
        is a path too long for its temporary name."""
        p = self.path / name
        check_name(p, MANIFEST)
        self._check(name, self._ours if name in self._ours else self._recorded())
        return p

    def _recorded(self) -> set[str]:
        """The folder's record as it is now: another command sharing the folder may have put its
        files in place since this one last read it (a commit renames the record before the files,
        so a file of cdpr-design's is never seen without its name in the record)."""
        self._ours = read_manifest(self._manifest)
        return self._ours

    def _check(self, name: str, ours: set[str]) -> None:
        p = self.path / name
        if p.is_dir():
            raise InputError(f"--out: {p} is a folder, not a file cdpr-design can replace; move it away")
        # a symbolic link counts even when it points nowhere: the write would replace the link itself
        if os.path.lexists(p) and name not in ours and not self.overwrite:
            raise InputError(
                f"{p} exists and was not written by cdpr-design; move it away or pass --overwrite")

    def wrote(self, name: str) -> None:
        """Record ``name`` in the folder's record now (a file written in place as the command runs:
        a sweep's journal, a study): call it before the file is made, so that another command
        sharing the folder never sees the file without its name in the record."""
        self._record(add=name)

    def forget(self, name: str) -> None:
        """Take ``name`` off the record (a file the command made and removed again)."""
        self._record(drop=name)

    def _record(self, add: str | None = None, drop: str | None = None) -> None:
        self.ensure()
        with self._locked():
            ours = read_manifest(self._manifest)
            new = (ours | {add} if add else ours) - {drop}
            if new != ours:
                write_text_atomic(self._manifest, "\n".join(sorted(new)) + "\n")
            self._ours = new

    # -- one set of files ----------------------------------------------------

    def __enter__(self) -> "OutputDir":
        self._depth += 1
        return self

    def __exit__(self, exc_type, exc, tb):
        self._depth -= 1
        if self._depth == 0:
            if exc_type is None:
                self.commit()
            else:
                self.discard()
        return False

    def _stage(self, name: str, f: "AtomicFile") -> None:
        """A finished file, put in place at the end of the ``with`` block (at once outside one)."""
        old = self._staged.pop(name, None)
        if old is not None:
            old.discard()
        self._staged[name] = f
        if self._depth == 0:
            self.commit()

    def commit(self) -> list[Path]:
        """Put every staged file in place together, with the folder's record (see the module);
        their paths.  On any failure nothing is replaced and the staged files are removed."""
        staged, self._staged = self._staged, {}
        if not staged:
            return []
        record = None
        try:
            with self._locked():
                ours = read_manifest(self._manifest)
                for name in staged:
                    self._check(name, ours)  # another command may have written one meanwhile
                names = ours | set(staged)
                record = AtomicFile(self._manifest)
                record.write("\n".join(sorted(names)) + "\n")
                record.finish()
                with signals_held():
                    replace_together(self.path, [record] + list(staged.values()))
                self._ours = names
        except BaseException:
            for f in [record, *staged.values()]:
                if f is not None:
                    f.discard()
            raise
        return [f.path for f in staged.values()]

    def discard(self) -> None:
        """Remove every staged file (nothing is replaced)."""
        staged, self._staged = self._staged, {}
        for f in staged.values():
            f.discard()

    # -- writing -------------------------------------------------------------

    def write_text(self, name: str, text: str) -> Path:
        with self.stream(name) as fh:
            fh.write(text)
        return fh.path

    def write_json(self, name: str, data) -> Path:
        """``data`` as indented JSON (numpy scalars and arrays as numbers and lists, NaN and
        infinities as null)."""
        return self.write_text(name, json_text(data, indent=2) + "\n")

    def write_columns(self, name: str, columns: dict, names: Sequence[str] | None = None,
                      metadata: dict | None = None, compiled: bool = False) -> Path:
        """A table of named 1-D columns in one go, CSV or Parquet by the extension of ``name``
        (:class:`~cdpr_design.io.columns.ColumnWriter`, ``compiled`` as there)."""
        stem, _, ext = name.rpartition(".")
        with self.table(stem, ext, metadata=metadata, names=names if names is not None else list(columns),
                        compiled=compiled) as w:
            if columns and len(next(iter(columns.values()))):
                w.write(columns)
        return w.path

    def table(self, stem: str, format: str = "csv", metadata: dict | None = None,
              names: Sequence[str] | None = None, background: bool = False, compiled: bool = False):
        """A :class:`~cdpr_design.io.columns.ColumnWriter` for ``stem.csv`` or ``stem.parquet``
        (refused if a foreign file has that name; staged when closed; ``compiled`` as there)."""
        name = file_name(stem, format)
        return ColumnWriter(self.target(name), format, metadata, names, stage=self._stager(name),
                            background=background, before_open=self.ensure, compiled=compiled)

    def stream(self, name: str) -> "AtomicFile":
        """An :class:`AtomicFile` for writing ``name`` piece by piece (staged when committed)."""
        p = self.target(name)
        self.ensure()
        return AtomicFile(p, stage=self._stager(name))

    def write_bytes(self, name: str, data: bytes) -> Path:
        p = self.target(name)
        self.ensure()
        with AtomicFile(p, binary=True, stage=self._stager(name)) as fh:
            fh.write(data)
        return p

    def _stager(self, name: str) -> Callable[["AtomicFile"], None]:
        return lambda f: self._stage(name, f)


class _FolderLock:
    """The lock of an output folder (:data:`LOCK`), waited for up to :data:`LOCK_WAIT_S` (a note
    on the ``cdpr_design`` logger says whom for); refused with exit 2 naming the holder after that."""

    def __init__(self, folder: Path):
        self.folder = folder
        self._cm = None

    def __enter__(self):
        path = self.folder / LOCK
        self._cm = owned(path, LOCK_WAIT_S, on_wait=self._waiting)
        try:
            return self._cm.__enter__()
        except Busy as busy:
            raise InputError(f"--out: {self.folder} is being written by {busy.holder or 'another process'} "
                             f"(waited {LOCK_WAIT_S:g} s); wait for it to end or choose another --out") from None
        except OSError as exc:
            raise WriteError.of(path, exc) from None

    def __exit__(self, *exc):
        return self._cm.__exit__(*exc)

    def _waiting(self, holder: str | None) -> None:
        _log.warning(f"waiting for {holder or 'another process'} to finish writing {self.folder}")


# -- putting a set of files in place ---------------------------------------------


def replace_together(folder: Path, files: Sequence[AtomicFile]) -> None:
    """Rename the finished temporary ``files`` of ``folder`` to their final names, all of them or
    none (steps 2 to 4 of the module's commit); a :class:`WriteError` naming the file that could
    not be replaced, the old files back in place."""
    entries = [{"tmp": f.tmp.name, "final": f.path.name, "backup": f.tmp.name[:-len(".tmp")] + BACKUP,
                "old": os.path.lexists(f.path)} for f in files]
    write_text_atomic(folder / INTENT, json.dumps(entries))
    _sync(folder)
    try:
        for e in entries:
            if e["old"]:
                _back_up(folder, e)
        for e in entries:
            try:
                os.replace(folder / e["tmp"], folder / e["final"])
            except OSError as exc:
                raise WriteError.of(folder / e["final"], exc, "replace") from None
    except BaseException:
        _undo(folder, entries)
        raise
    for f in files:
        f.placed = True
    _close(folder, entries, folder / INTENT)


def _back_up(folder: Path, e: dict) -> None:
    """A hard link to the file about to be replaced (or, without links, the file moved aside)."""
    final, backup = folder / e["final"], folder / e["backup"]
    try:
        os.link(final, backup, follow_symlinks=False)
    except OSError:
        try:
            os.rename(final, backup)
        except OSError as exc:  # an immutable or append-only file, a mount point, ...
            raise WriteError.of(final, exc, "replace") from None


def _undo(folder: Path, entries: list[dict]) -> None:
    """Put the old files back (a failed commit): the list is renamed :data:`ROLLBACK` first, so a
    kill while undoing is undone by :func:`recover` too.  Every file is tried; when one fails the
    list stays (the next command tries again)."""
    failed = False
    try:
        if os.path.lexists(folder / INTENT):
            os.replace(folder / INTENT, folder / ROLLBACK)
    except OSError:
        failed = True
    for e in reversed(entries):
        final, tmp, backup = folder / e["final"], folder / e["tmp"], folder / e["backup"]
        try:
            if e["old"]:
                if os.path.lexists(backup):
                    os.replace(backup, final)  # two links to one file: nothing happens, hence _close's unlink
            elif not os.path.lexists(tmp):  # the new file was put in place: removed again
                final.unlink(missing_ok=True)
        except OSError:
            failed = True
    if not failed:
        _close(folder, entries, folder / ROLLBACK)


def _close(folder: Path, entries: list[dict], marker: Path) -> None:
    """The renames are on disk: drop the list, then the backups and temporary files left."""
    _sync(folder)
    for path in [marker] + [folder / e[k] for e in entries for k in ("backup", "tmp")]:
        try:
            path.unlink(missing_ok=True)
        except OSError:  # a leftover: the list is finished again (nothing to do), a file with
            pass  # this process's id removed by a later run (io.preflight)


def _unfinished(folder: Path) -> bool:
    try:
        return os.path.lexists(folder / INTENT) or os.path.lexists(folder / ROLLBACK)
    except OSError:
        return False


def recover(folder: str | Path) -> None:
    """Finish the commit a killed command left in ``folder`` (call under the folder's lock): the
    renames still to do are done (or, when it was being undone, the old files put back)."""
    folder = Path(folder)
    for marker in (folder / ROLLBACK, folder / INTENT):
        try:
            entries = json.loads(marker.read_text(encoding="utf-8"))
        except FileNotFoundError:
            continue
        except (OSError, ValueError):
            raise InputError(f"--out: {marker} (an unfinished commit of cdpr-design) cannot be read; "
                             "check the files in the folder, then delete it") from None
        if marker.name == ROLLBACK:
            _undo(folder, entries)
            continue
        try:
            for e in entries:
                if os.path.lexists(folder / e["tmp"]):
                    os.replace(folder / e["tmp"], folder / e["final"])
        except OSError:
            _undo(folder, entries)
            continue
        _close(folder, entries, marker)


def _sync(folder: Path) -> None:
    """Make the renames in ``folder`` durable (where the file system can sync a folder)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
