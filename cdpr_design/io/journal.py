"""The append-only journal of a parameter sweep (``sweep.journal.jsonl``)."""

from __future__ import annotations

import contextlib
import json
import logging
import os
from typing import Sequence

from cdpr_design.errors import InputError, WriteError
from cdpr_design.io.atomic import write_text_atomic
from cdpr_design.io.files import LOCK_WAIT_S, OutputDir
from cdpr_design.io.locks import check_free, one_run


class SweepJournal:
    """The append-only journal of a sweep (``sweep.journal.jsonl`` in the output folder).

    Line 1 is a JSON object naming the sweep (``fingerprint``); every further
    line is one finished variant (:func:`cdpr_design.batch.local.record`), appended
    and flushed as it finishes, so an interrupted sweep loses at most the
    variants in flight.  A torn last line (the process was killed while
    writing it) is dropped when the journal is read back.

    From :meth:`start` to :meth:`close` the sweep holds the folder's
    ``.sweep.lock`` (:func:`~cdpr_design.io.locks.one_run`): a second sweep
    into the same folder waits for the first to end (up to
    :data:`~cdpr_design.io.files.LOCK_WAIT_S`, saying whom for; then it is
    refused, naming the first) instead of writing the same journal.
    """

    NAME = "sweep.journal.jsonl"
    LOCK = ".sweep.lock"
    #: the command that writes it (its line 1's ``journal`` is ``cdpr-design <COMMAND>``)
    COMMAND = "sweep"
    #: the key every record line has
    RECORD = "variant"

    def __init__(self, out: OutputDir, name: str | None = None):
        self.out = out
        self.name = name or self.NAME
        self.path = out.path / self.name
        self.fh = None
        self._lock = contextlib.ExitStack()

    def check_free(self) -> None:
        """Wait for another run writing this folder's journal to end (up to
        :data:`~cdpr_design.io.files.LOCK_WAIT_S`; then refused, exit 2 naming it)."""
        check_free(self.out.path / self.LOCK, self.COMMAND, LOCK_WAIT_S, self._waiting)

    def _waiting(self, holder: str | None) -> None:
        logging.getLogger("cdpr_design").warning(
            f"waiting for {holder or 'another process'} to finish writing {self.out.path}")

    def read(self) -> tuple[dict | None, list[dict]]:
        """(meta, records) of the journal on disk; (None, []) when there is none."""
        meta, numbered = self.read_numbered()
        return meta, [rec for _, rec in numbered]

    def read_numbered(self) -> tuple[dict | None, list[tuple[int, dict]]]:
        """:meth:`read` with each record's line number in the file (from 1): (meta, [(line, record)])."""
        try:
            text = self.path.read_text(encoding="utf-8")
        except FileNotFoundError:
            return None, []
        except (OSError, UnicodeDecodeError) as exc:
            raise InputError(f"--resume: cannot read {self.path}: {exc}") from None
        lines = text.split("\n")
        meta, records = None, []
        for k, line in enumerate(lines):
            if not line.strip():
                continue
            try:
                obj = json.loads(line)
            except json.JSONDecodeError:
                if k >= len(lines) - 2:  # the last line, torn by a kill
                    break
                raise InputError(f"--resume: {self.path} line {k + 1} is not a journal line") from None
            if meta is None:
                if not isinstance(obj, dict) or obj.get("journal") != f"cdpr-design {self.COMMAND}":
                    raise InputError(f"--resume: {self.path} is not a {self.COMMAND} journal")
                meta = obj
            elif isinstance(obj, dict) and self.RECORD in obj:
                records.append((k + 1, obj))
        return meta, records

    def resumed(self, meta: dict, resume: bool, log, what: str) -> list[tuple[int, dict]] | None:
        """The journal's (line, record) pairs to resume from (None: not ``resume``, or no journal), after
        checking its first line has ``meta``'s fingerprint (another run's journal: an
        :class:`InputError`, ``what`` naming what it records, e.g. "sweep (other spec, keys,
        values or options)"); ``log`` says when there is no journal to resume."""
        if not resume:
            return None
        old_meta, numbered = self.read_numbered()
        if old_meta is None:
            log(f"--resume: no journal in {self.out.path}; starting the {self.COMMAND}")
            return None
        if old_meta.get("fingerprint") != meta["fingerprint"]:
            raise InputError(f"--resume: the journal in {self.out.path} is from another {what}; "
                             "run without --resume to start over")
        return numbered

    def start(self, meta: dict, records: Sequence[dict] = ()) -> None:
        """Write the journal afresh (meta and the records kept), then keep it open for appending."""
        self.out.target(self.name)
        self.out.ensure()
        self._lock.enter_context(one_run(self.out.path / self.LOCK, self.COMMAND, LOCK_WAIT_S, self._waiting))
        body = json.dumps(meta, sort_keys=True) + "\n" + "".join(
            json.dumps(r) + "\n" for r in records)
        self.out.wrote(self.name)  # recorded first: another run checking the folder sees it is ours
        write_text_atomic(self.path, body)
        try:
            self.fh = open(self.path, "a", encoding="utf-8", newline="")
        except OSError as exc:
            raise WriteError.of(self.path, exc) from None

    def append(self, rec: dict) -> None:
        """Add one finished variant and flush it to the file (a :class:`WriteError` when it cannot be:
        the lines before it stay whole, a torn one is dropped when read)."""
        try:
            self.fh.write(json.dumps(rec) + "\n")
            self.fh.flush()
        except OSError as exc:
            raise WriteError.of(self.path, exc) from None

    def close(self) -> None:
        """Flush, sync and close (what cannot be written any more is dropped: the journal is read back
        up to its last whole line)."""
        if self.fh is not None:
            fh, self.fh = self.fh, None
            try:
                fh.flush()
                os.fsync(fh.fileno())
            except OSError:
                pass
            try:
                fh.close()
            except OSError:
                pass
        self._lock.close()


class CertifyJournal(SweepJournal):
    """The journal of ``certify`` (``certify.journal.jsonl``): line 1 names the paving
    (``fingerprint``), every further line one level of the branch-and-prune classified
    (``{"level": k, "boxes": n, "status": ...}``), appended as it finishes; a resumed run
    replays those levels instead of classifying them again."""

    NAME = "certify.journal.jsonl"
    LOCK = ".certify.lock"
    COMMAND = "certify"
    RECORD = "level"


class LazyJournal:
    """The journal written afresh (its meta and the records kept) only at the first finished
    record, or when the run ends: a run refused while its backend starts (an unreachable
    ``--scheduler``) leaves the folder, and a journal already in it, as they were."""

    def __init__(self, journal: "SweepJournal", meta: dict, kept: list[dict]):
        self.journal, self.meta, self.kept = journal, meta, kept
        self.started = False

    def start(self) -> None:
        if not self.started:
            self.journal.start(self.meta, self.kept)
            self.started = True

    def append(self, rec: dict) -> None:
        self.start()
        self.journal.append(rec)
