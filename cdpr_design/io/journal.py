"""The append-only journal of a parameter sweep (``sweep.journal.jsonl``)."""

from __future__ import annotations

import json
import os
from typing import Sequence

from cdpr_design.errors import InputError
from cdpr_design.io.files import OutputDir, write_text_atomic


class SweepJournal:
    """The append-only journal of a sweep (``sweep.journal.jsonl`` in the output folder).

    Line 1 is a JSON object naming the sweep (``fingerprint``); every further
    line is one finished variant (:func:`cdpr_design.batch.local.record`), appended
    and flushed as it finishes, so an interrupted sweep loses at most the
    variants in flight.  A torn last line (the process was killed while
    writing it) is dropped when the journal is read back.
    """

    NAME = "sweep.journal.jsonl"

    def __init__(self, out: OutputDir, name: str | None = None):
        self.out = out
        self.name = name or self.NAME
        self.path = out.path / self.name
        self.fh = None

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
                if not isinstance(obj, dict) or obj.get("journal") != "cdpr-design sweep":
                    raise InputError(f"--resume: {self.path} is not a sweep journal")
                meta = obj
            elif isinstance(obj, dict) and "variant" in obj:
                records.append((k + 1, obj))
        return meta, records

    def start(self, meta: dict, records: Sequence[dict] = ()) -> None:
        """Write the journal afresh (meta and the records kept), then keep it open for appending."""
        self.out.target(self.name)
        self.out.ensure()
        body = json.dumps(meta, sort_keys=True) + "\n" + "".join(
            json.dumps(r) + "\n" for r in records)
        write_text_atomic(self.path, body)
        self.out.wrote(self.name)
        self.fh = open(self.path, "a", encoding="utf-8", newline="")

    def append(self, rec: dict) -> None:
        """Add one finished variant and flush it to the file."""
        self.fh.write(json.dumps(rec) + "\n")
        self.fh.flush()

    def close(self) -> None:
        if self.fh is not None:
            self.fh.flush()
            try:
                os.fsync(self.fh.fileno())
            except OSError:
                pass
            self.fh.close()
            self.fh = None
