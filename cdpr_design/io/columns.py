"""Tables written column chunk by column chunk, as CSV or Parquet, atomically.

Every table the tool writes (``workspace``, ``sweep``, motor sizing,
``trajectory``, ``simulate``, ...) goes through one :class:`ColumnWriter`:

    with ColumnWriter(path, "parquet", metadata={"name": "planar2", "units": {"x": "m"}}) as w:
        for chunk in chunks:
            w.write({"x": ..., "feasible": ..., ...})

CSV follows the command line's contract (docs/cli.md): one header row, ``\\n``
line ends, numbers with 10 significant digits, integers and booleans as
integers, NaN/None as empty cells: every cell as :func:`~cdpr_design.io.tables.fmt`
writes it.  Numeric columns are formatted by the compiled
:func:`cdpr_design.io.csvfast.csv_rows` where the caller says the kernels are
loaded (``compiled``) or a chunk has at least :data:`COMPILED_CELLS` cells,
else cell by cell (:func:`~cdpr_design.io.tables.cell_rows`) -- the same bytes;
other columns cell by cell with the ``csv`` module's quoting.  Parquet keeps the types -- booleans as ``bool``, integers as
``int64``, every other number as ``float64`` (NaN where CSV has an empty
cell), text as strings -- writes each :meth:`ColumnWriter.write` as a row
group (memory stays bounded whatever the table's length), and carries the
``metadata`` given (JSON under the schema key ``cdpr-design``, with the tool's
version) and each column's unit (field metadata ``unit``).

The file appears under its name only when :meth:`ColumnWriter.close` succeeds
(:class:`~cdpr_design.io.atomic.AtomicFile`; in an output folder's ``with``
block, when the block ends); an exception inside the ``with`` block leaves
nothing.  A write that fails (a full disk, a file-size limit) is a
:class:`~cdpr_design.errors.WriteError` naming the file.
"""

from __future__ import annotations

import csv
import io
import json
import queue
import threading
import time
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from cdpr_design.errors import InputError, WriteError, quote
from cdpr_design.io.atomic import AtomicFile
from cdpr_design.io.tables import cell_rows, fmt, json_default

#: Table formats: name -> file extension.
FORMATS = {"csv": ".csv", "parquet": ".parquet"}
#: Schema metadata key of the table's description in Parquet files.
META_KEY = b"cdpr-design"
#: Numeric cells of a chunk from which the compiled formatter writes its CSV even where the
#: kernels are not loaded: numba's start-up (its import and the formatter's load from its cache)
#: is then repaid by the per-cell cost it saves (docs/performance.md).
COMPILED_CELLS = 2_000_000


def file_name(stem: str, format: str = "csv") -> str:
    """``workspace`` -> ``workspace.csv`` / ``workspace.parquet``."""
    check_format(format)
    return stem + FORMATS[format]


def check_format(format: str) -> None:
    """A table format the writers know (bad input, as ``--format``: an :class:`InputError`)."""
    if format not in FORMATS:
        raise InputError(f"--format: expected one of {', '.join(FORMATS)}, got {quote(format)}")


def as_columns(data) -> dict:
    """name -> 1-D numpy array (numeric or object) of a mapping, pyarrow Table or RecordBatch."""
    if hasattr(data, "schema") and hasattr(data, "column_names"):  # pyarrow Table / RecordBatch
        return {name: data.column(i).to_numpy(zero_copy_only=False)
                for i, name in enumerate(data.column_names)}
    out = {}
    for name, values in data.items():
        arr = values if isinstance(values, np.ndarray) else _list_array(values)
        if arr.ndim != 1:
            raise ValueError(f"column {name!r}: expected a 1-D array, got shape {arr.shape}")
        out[str(name)] = arr
    lengths = {len(v) for v in out.values()}
    if len(lengths) > 1:
        raise ValueError(f"columns of unequal length: {sorted(lengths)}")
    return out


def _list_array(values) -> np.ndarray:
    """A list of cells as an array: numeric dtype when every cell is a number (not None)."""
    values = list(values)
    kinds = {type(v) for v in values}
    if kinds and all(issubclass(k, (bool, np.bool_)) for k in kinds):
        return np.asarray(values, dtype=bool)
    if kinds and all(issubclass(k, (int, np.integer)) and not issubclass(k, (bool, np.bool_)) for k in kinds):
        arr = np.asarray(values)
        return arr if arr.dtype.kind in "iu" else _objects(values)
    if kinds and all(issubclass(k, (float, np.floating)) for k in kinds):
        return np.asarray(values, dtype=np.float64)
    return _objects(values)


def _objects(values) -> np.ndarray:
    arr = np.empty(len(values), dtype=object)
    arr[:] = values
    return arr


class ColumnWriter:
    """One table, streamed to ``path`` as CSV or Parquet (see the module).

    Parameters
    ----------
    path : the file's final name.
    format : ``csv`` or ``parquet``.
    metadata : JSON-able description of the table (Parquet only): e.g. the
        design's name, the grid, ``units`` (column -> unit string).
    names : the columns in order, when known before the first chunk (the
        header of a table with no rows); chunks must then carry exactly these.
    stage : given the finished temporary file instead of renaming it into place (an
        output folder puts it in place with the command's other files).
    before_open : called just before the temporary file is made, at the first
        write or at :meth:`close` (the output folder's creation): a sweep that
        refuses its input before its first chunk leaves nothing behind.
    background : format and write in a thread of this process, so that the
        caller's next work (a sweep's next chunk: the kernels release the GIL;
        pictures drawn by another process) overlaps the writing.  At most two
        chunks wait (memory stays bounded); an error in the thread is raised by
        the next :meth:`write` or by :meth:`close`.
    compiled : format every chunk's CSV numbers with the compiled formatter
        (:mod:`~cdpr_design.io.csvfast`, numba): where the caller loads the kernels anyway
        (a sweep on them); else only chunks of at least :data:`COMPILED_CELLS` cells, the
        others cell by cell in Python.  The same bytes either way.

    ``busy_s`` is the time spent formatting and writing so far [s].
    """

    def __init__(self, path: str | Path, format: str = "csv", metadata: Mapping | None = None,
                 names: Sequence[str] | None = None, stage: Callable[[AtomicFile], None] | None = None,
                 background: bool = False, before_open: Callable[[], object] | None = None,
                 compiled: bool = False):
        check_format(format)
        self.path = Path(path)
        self.format = format
        self.metadata = dict(metadata or {})
        self.names = list(names) if names is not None else None
        self.rows = 0
        self._atomic: AtomicFile | None = None
        self._stage = stage
        self._before_open = before_open
        self._schema = None
        self._parquet = None
        self._header_done = False
        self.busy_s = 0.0
        self.compiled = compiled
        self._queue: queue.Queue | None = None
        self._thread: threading.Thread | None = None
        self._error: BaseException | None = None
        self._dropping = False
        if background:
            self._queue = queue.Queue(maxsize=2)
            self._thread = threading.Thread(target=self._run, name=f"write {self.path.name}", daemon=True)
            self._thread.start()

    def warm_up(self) -> None:
        """Compile (or load from numba's cache) the compiled CSV formatter now, on a table of one
        row, if this writer will use it (a caller times numba's start-up apart from the writing)."""
        if self.format == "csv" and self.compiled:
            numeric_csv([np.zeros(1), np.zeros(1, dtype=np.int64)], True)

    @property
    def _file(self) -> AtomicFile:
        """The temporary file, made on first use."""
        if self._atomic is None:
            if self._before_open is not None:
                self._before_open()
            self._atomic = AtomicFile(self.path, binary=True, stage=self._stage)
        return self._atomic

    # -- writing -----------------------------------------------------------

    def write(self, data) -> None:
        """Append rows: a mapping name -> 1-D array or list, or a pyarrow Table / RecordBatch.

        With ``background`` the arrays must not change afterwards (they are written later)."""
        if self._queue is not None:
            self._raise_error()
            self._queue.put(data)
            return
        self._write_now(data)

    def _write_now(self, data) -> None:
        t = time.perf_counter()
        try:
            self._write_columns(data)
        except OSError as exc:  # pyarrow's writes into the file
            raise WriteError.of(self.path, exc) from None
        finally:
            self.busy_s += time.perf_counter() - t

    def _run(self) -> None:
        """The background thread: write what arrives until the stop mark (None)."""
        while True:
            data = self._queue.get()
            if data is None:
                return
            if self._error is None and not self._dropping:
                try:
                    self._write_now(data)
                except BaseException as exc:  # noqa: BLE001 - raised in the caller's thread
                    self._error = exc

    def _stop_thread(self) -> None:
        if self._thread is not None:
            self._queue.put(None)
            self._thread.join()
            self._thread = self._queue = None

    def _raise_error(self) -> None:
        if self._error is not None:
            exc, self._error = self._error, None
            raise exc

    def _write_columns(self, data) -> None:
        cols = as_columns(data)
        if self.names is None:
            self.names = list(cols)
        elif list(cols) != self.names:
            if set(cols) != set(self.names):
                raise ValueError(f"{self.path.name}: chunk columns {list(cols)} differ from {self.names}")
            cols = {k: cols[k] for k in self.names}
        n = len(next(iter(cols.values()))) if cols else 0
        if self.format == "csv":
            self._write_csv(cols)
        else:
            self._write_parquet(cols)
        self.rows += n

    def _write_csv(self, cols: dict) -> None:
        if not self._header_done:
            self._csv_header()
        arrays = list(cols.values())
        if not arrays or not len(arrays[0]):
            return
        if all(a.dtype.kind in "biuf" for a in arrays):
            self._file.write(numeric_csv(arrays, self.compiled))
            return
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        for row in zip(*arrays):
            w.writerow([fmt(v) for v in row])
        self._file.write(buf.getvalue().encode("utf-8"))

    def _csv_header(self) -> None:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(self.names or [])
        self._file.write(buf.getvalue().encode("utf-8"))
        self._header_done = True

    def _write_parquet(self, cols: dict) -> None:
        import pyarrow as pa

        arrays = [_arrow_array(a) for a in cols.values()]
        if self._schema is None:
            self._schema = self._make_schema([(k, a.type) for k, a in zip(cols, arrays)])
            self._parquet = _parquet_writer(self._file.fh, self._schema)
        arrays = [a.cast(f.type) if a.type != f.type else a for a, f in zip(arrays, self._schema)]
        self._parquet.write_batch(pa.RecordBatch.from_arrays(arrays, schema=self._schema))

    def _make_schema(self, fields):
        import pyarrow as pa

        from cdpr_design import __version__

        units = self.metadata.get("units") or {}
        meta = {"tool": "cdpr-design", "version": __version__, **self.metadata}
        out = []
        for name, typ in fields:
            if pa.types.is_null(typ):  # a column of empty cells only
                typ = pa.float64()
            unit = units.get(name)
            out.append(pa.field(name, typ, metadata={"unit": unit} if unit else None))
        return pa.schema(out, metadata={META_KEY: json.dumps(meta, default=json_default)})

    # -- ending ------------------------------------------------------------

    def close(self) -> Path:
        """Finish the file and move it into place; returns its path."""
        self._stop_thread()
        t = time.perf_counter()
        try:
            self._raise_error()
            return self._finish()
        except OSError as exc:  # pyarrow's last writes
            self.abort()
            raise WriteError.of(self.path, exc) from None
        except BaseException:
            self.abort()
            raise
        finally:
            self.busy_s += time.perf_counter() - t

    def _finish(self) -> Path:
        if self.format == "csv":
            if not self._header_done:
                self._csv_header()
        else:
            if self._parquet is None:  # no rows: the schema from the names, float64 columns
                import pyarrow as pa

                self._schema = self._make_schema([(k, pa.float64()) for k in self.names or []])
                self._parquet = _parquet_writer(self._file.fh, self._schema)
            self._parquet.close()
        return self._file.commit()

    def abort(self) -> None:
        """Drop the file (the final name is untouched)."""
        self._dropping = True
        self._stop_thread()
        if self._parquet is not None:
            try:
                self._parquet.close()
            except Exception:  # noqa: BLE001 - the file is dropped anyway
                pass
        if self._atomic is not None:
            self._atomic.abort()

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.close()
        else:
            self.abort()
        return False


def numeric_csv(arrays: Sequence[np.ndarray], compiled: bool) -> bytes:
    """CSV rows of equal-length 1-D numeric columns: by the compiled formatter when ``compiled``
    or the chunk has at least :data:`COMPILED_CELLS` cells, else cell by cell (the same bytes)."""
    if compiled or len(arrays) * len(arrays[0]) >= COMPILED_CELLS:
        from cdpr_design.io import csvfast  # imports numba: only then

        return csvfast.numba_rows(arrays)
    return cell_rows(arrays)


def _parquet_writer(fh, schema):
    """A ParquetWriter of ``schema`` on ``fh``: dictionary encoding for every column but the
    floating-point ones, where it costs time and makes the file larger (docs/performance.md)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    dictionary = [f.name for f in schema if not pa.types.is_floating(f.type)]
    return pq.ParquetWriter(fh, schema, use_dictionary=dictionary or False)


def _arrow_array(a: np.ndarray):
    """A pyarrow array of a column: bool, int64, float64, or strings (cells of mixed kinds)."""
    import pyarrow as pa

    kind = a.dtype.kind
    if kind == "b":
        return pa.array(a, type=pa.bool_())
    if kind in "iu":
        return pa.array(a.astype(np.int64, copy=False), type=pa.int64())
    if kind == "f":
        return pa.array(a.astype(np.float64, copy=False), type=pa.float64())
    values = list(a)
    try:
        arr = pa.array(values, from_pandas=True)
    except (pa.ArrowInvalid, pa.ArrowTypeError):
        arr = None
    if arr is None or not (pa.types.is_floating(arr.type) or pa.types.is_integer(arr.type)
                           or pa.types.is_boolean(arr.type) or pa.types.is_string(arr.type)
                           or pa.types.is_null(arr.type)):
        arr = pa.array([None if v is None else fmt(v) for v in values], type=pa.string())
    if pa.types.is_integer(arr.type) and any(isinstance(v, float) for v in values):
        arr = arr.cast(pa.float64())
    return arr


def read_table(path: str | Path) -> dict[str, np.ndarray]:
    """The columns of a table this module wrote (CSV or Parquet, by extension): name -> array.

    CSV cells come back as float64 (empty -> NaN) where every cell is a number
    or empty, else as text; Parquet columns with their stored types.
    """
    p = Path(path)
    if p.suffix == ".parquet":
        import pyarrow.parquet as pq

        return as_columns(pq.read_table(p))
    with open(p, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    out = {}
    for j, name in enumerate(header):
        cells = [r[j] for r in body]
        try:
            out[name] = np.array([float(c) if c != "" else np.nan for c in cells], dtype=np.float64)
        except ValueError:
            out[name] = _objects(cells)
    return out


def table_metadata(path: str | Path) -> dict:
    """The ``metadata`` a Parquet table was written with (plus ``tool`` and ``version``)."""
    import pyarrow.parquet as pq

    meta = pq.read_schema(path).metadata or {}
    return json.loads(meta[META_KEY]) if META_KEY in meta else {}
