"""CSV cells and blocks, CSV and log reading, and the JSON encoding of numpy values.

Numbers are written with 10 significant digits (never ``-0``), integers as
integers, booleans as 1/0 and NaN/None as empty cells; JSON never holds NaN or
infinities (``null`` instead); whole tables: :mod:`cdpr_design.io.columns`.  Readers raise
:class:`~cdpr_design.errors.InputError` naming the file (and the option or
argument it came from).
"""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Sequence

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.io.inputs import MAX_LOG_BYTES, read_text


def json_default(o):
    """``json.dumps(default=...)``: numpy scalars as Python numbers, arrays as lists."""
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def json_finite(o):
    """A copy of plain data for JSON: NaN and infinities (never valid JSON) become None, ``-0.0``
    becomes 0.0, numpy values Python ones; a non-finite number is not a result to report."""
    if isinstance(o, (float, np.floating)):
        v = float(o)
        return v + 0.0 if math.isfinite(v) else None
    if isinstance(o, dict):
        return {k: json_finite(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [json_finite(v) for v in o]
    if isinstance(o, np.ndarray):
        return json_finite(o.tolist())
    if isinstance(o, np.generic):
        return json_finite(o.item())
    return o


def json_text(data, indent: int | None = None) -> str:
    """``data`` as JSON text through :func:`json_finite` (strict JSON: no ``NaN``, no ``Infinity``)."""
    return json.dumps(json_finite(data), indent=indent, default=json_default, allow_nan=False)


#: A summary's ``timings`` phases, in the order they are shown (``load_s`` only where measured).
TIMING_PHASES = ("load_s", "sweep_s", "write_s", "pictures_s", "total_s")


def timing_phases(timings: dict) -> list[tuple[str, float]]:
    """(phase without ``_s``, seconds) of a summary's ``timings``, in :data:`TIMING_PHASES` order."""
    return [(k[:-2], timings[k]) for k in TIMING_PHASES if k in timings]


def fmt(v) -> str:
    """A CSV cell: numbers with 10 significant digits (``-0`` as ``0``), NaN/None as empty.

    The definition the compiled :func:`cdpr_design.io.csvfast.csv_rows` follows byte for byte."""
    if v is None:
        return ""
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return "" if not math.isfinite(v) else format(float(v) + 0.0, ".10g")  # + 0.0: -0 is written 0
    return str(v)


def cell_rows(arrays) -> bytes:
    """CSV rows (``\\n`` ends, no header) of equal-length 1-D numeric columns (float, int,
    bool), every cell as :func:`fmt` writes it, in Python a column at a time."""
    return ("\n".join(map(",".join, zip(*map(column_cells, arrays)))) + "\n").encode()


def column_cells(a: np.ndarray) -> list[str]:
    """:func:`fmt` of every value of a 1-D numeric array, by its dtype."""
    if a.dtype.kind == "b":
        return ["1" if v else "0" for v in a.tolist()]
    if a.dtype.kind in "iu":
        return [str(v) for v in a.tolist()]
    vals = (a.astype(np.float64) + 0.0).tolist()  # + 0.0: -0 is written 0
    finite = np.isfinite(a)
    if finite.all():
        return [format(v, ".10g") for v in vals]
    return [format(v, ".10g") if f else "" for v, f in zip(vals, finite.tolist())]


def text_rows(rows) -> list[list[str]]:
    """The CSV cells (:func:`fmt`) of rows of values."""
    return [[fmt(v) for v in r] for r in rows]


def read_csv_columns(path: str | Path, what: str = "CSV", dropped: list | None = None) -> dict[str, np.ndarray]:
    """Numeric columns of a CSV log with a header row: name -> float array.

    Empty or non-numeric cells become NaN; columns with no number at all are
    dropped (their names appended to ``dropped`` when given).  Bad files
    raise :class:`InputError` naming the file; only regular files of at most
    :data:`~cdpr_design.io.inputs.MAX_LOG_BYTES` are read.
    """
    p = Path(path)
    try:
        text = read_text(p, MAX_LOG_BYTES, encoding="utf-8-sig")
    except InputError as exc:
        raise InputError(f"{what} {p}: {exc}") from None
    rows = list(csv.reader(io.StringIO(text)))
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if len(rows) < 2:
        raise InputError(f"{what} {p}: expected a header row and at least one data row")
    header = [h.strip() for h in rows[0]]
    if len(set(header)) != len(header):
        raise InputError(f"{what} {p}: duplicate column names in the header")
    data = np.full((len(rows) - 1, len(header)), np.nan)
    for i, r in enumerate(rows[1:]):
        for j, cell in enumerate(r[: len(header)]):
            try:
                data[i, j] = float(cell)
            except ValueError:
                pass
    out = {}
    for j, h in enumerate(header):
        if np.any(np.isfinite(data[:, j])):
            out[h] = data[:, j]
        elif dropped is not None:
            dropped.append(h)
    return out


def read_log(path: str | Path, what: str = "log", dropped: list | None = None) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A logged run: its time column [s] (``time`` or ``t``, increasing) and the other columns
    (``dropped``: as for :func:`read_csv_columns`)."""
    cols = read_csv_columns(path, what, dropped)
    tname = "time" if "time" in cols else ("t" if "t" in cols else None)
    if tname is None:
        raise InputError(f"{what} {path}: no time column (expected 'time' or 't'; found {', '.join(cols) or 'none'})")
    t = cols.pop(tname)
    ok = np.isfinite(t)
    t = t[ok]
    cols = {k: v[ok] for k, v in cols.items()}
    if t.size < 4:
        raise InputError(f"{what} {path}: expected at least 4 timed rows, got {t.size}")
    if np.any(np.diff(t) <= 0):
        raise InputError(f"{what} {path}: the time column must strictly increase")
    return t, cols


def read_csv_table(path: str | Path, what: str = "--check-against") -> tuple[list[str], list[list[str]]]:
    """(header, rows) of a CSV file, cells as text; bad files raise :class:`InputError`."""
    p = Path(path)
    try:
        text = read_text(p, MAX_LOG_BYTES, encoding="utf-8-sig")
    except InputError as exc:
        raise InputError(f"{what}: {exc}") from None
    rows = [r for r in csv.reader(io.StringIO(text)) if r]
    if not rows:
        raise InputError(f"{what}: {p} is empty (expected a header row)")
    return rows[0], rows[1:]


class Table:
    """Mixin for results that are tables: ``columns()`` gives the named columns in order.

    ``to_dict()`` returns them (name -> 1-D numpy array or list; hand it to
    ``pandas.DataFrame`` or ``polars.DataFrame``), ``to_arrow()`` builds a
    pyarrow Table (pyarrow imported on first use).
    """

    def columns(self) -> dict:  # pragma: no cover - every subclass defines it
        raise NotImplementedError

    def to_dict(self) -> dict:
        """The columns, name -> array, in the order of the command's CSV."""
        return dict(self.columns())

    def to_arrow(self):
        """A pyarrow ``Table`` of the columns."""
        import pyarrow as pa

        return pa.table({k: np.asarray(v) for k, v in self.columns().items()})


def rows_to_columns(rows: Sequence[dict]) -> dict:
    """Records (one dict per row, same keys) as columns: name -> list of the rows' values."""
    names = list(rows[0]) if rows else []
    return {k: [r.get(k) for r in rows] for k in names}
