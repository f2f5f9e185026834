"""CSV text of numeric columns, compiled: the cells :func:`~cdpr_design.io.tables.fmt` writes, in numba.

:func:`csv_rows` gives, byte for byte, every cell as :func:`~cdpr_design.io.tables.fmt`
writes it (floats ``'.10g'`` with ``-0`` written ``0``, integers and booleans as
integers, NaN and inf empty), one cell at a time in a compiled loop (``nogil``: a
sweep's kernels run on while the background writer formats; ``cache=True``).

How (the constants and tables are :mod:`~cdpr_design.io.csvcells`'): a float
``v != 0`` is rounded to 10 significant digits as an integer ``m`` in [1e9, 1e10)
and a decimal exponent ``X`` (``|v| ~ m 10^(X-9)``), X from the binary exponent,
m by at most two scalings by exact powers of ten (``10^k``, ``|k| <= 22``); the
scaled value is within 2 ulp of the exact product, so its nearest integer is the
correctly rounded one unless its fraction lies within ``TIE`` of one half.  The
ten digits come from a table of five-digit groups as bytes, the trailing zeros
from its table, the ``e-XX`` suffixes from theirs; ``printf``'s ``%g`` rule
then picks fixed or scientific notation.  The tables are module globals, which
numba freezes into the compiled code as constants.  The kernel writes a block of
rows into a preallocated byte buffer (at most :data:`CELL_MAX` bytes a cell) and
lists the cells it cannot format with certainty (a near tie, ``|v|`` outside
``FLOAT_RANGE``, integers of ten digits or more): Python formats those with
:func:`~cdpr_design.io.tables.fmt`, and their text is spliced in where the kernel
left room for nothing.

Importing this module imports numba: a writer uses it for large blocks and where
the kernels are loaded anyway (:class:`~cdpr_design.io.columns.ColumnWriter`).
"""

from __future__ import annotations

from typing import Sequence

import numba as nb
import numpy as np

from cdpr_design.io.csvcells import (BLOCK, DIGITS, FLOAT_RANGE, INT_LIMIT, P10, SUFFIX, TIE, TZ5,
                                     numeric_columns)
from cdpr_design.io.tables import fmt

#: Bytes of the longest cell and its separator, ``-1.234567891e-308,``: also the most a cell writes.
CELL_MAX = 18
_SUFFIX_X0 = 400  # _SUFFIX[X + 400] is the suffix of exponent X
_TENS_X0 = -400  # tens[k + 400] ~ 10^k (inf above 10^308): the first guess of the exponent
_TENS = np.array([float(f"1e{k}") for k in range(_TENS_X0, -_TENS_X0 + 1)])
# the tables as int64 (every entry < 2^40): no unsigned arithmetic in the kernel
_P10, _DIGITS, _TZ5, _SUFFIX = P10, DIGITS.astype(np.int64), TZ5, SUFFIX.astype(np.int64)
_JIT = dict(cache=True, nogil=True, error_model="numpy")
#: The cell helpers are inlined into the row loop (no call per cell); they read the tables as
#: globals, not arguments, so that no array is handed to them (and counted) cell by cell.
_INLINE = dict(_JIT, inline="always")


@nb.njit(**_INLINE)
def _scale(a, k):
    """a * 10^k [float64], |k| <= 44, with at most two roundings (as the numpy formatter's)."""
    k1 = min(max(k, -22), 22)
    out = a * _P10[k1] if k1 >= 0 else a / _P10[-k1]
    k2 = k - k1
    if k2 > 0:
        out = out * _P10[k2]
    elif k2 < 0:
        out = out / _P10[-k2]
    return out


@nb.njit(**_INLINE)
def _round10(a, bits, tie):
    """(m, X, ok) of one finite a > 0 as the numpy formatter's: a ~ m 10^(X - 9), m in [1e9, 1e10).

    bits : the IEEE 754 bits of a (or of -a) as int64.  X starts from the binary exponent
    e2 (floor(e2 log10 2), X or X - 1), raised by one where a >= tens[X + 1 - _TENS_X0]
    (10^(X+1), cheaper than log10), and corrected as there."""
    X = (((bits >> 52) & 2047) - 1023) * 78913 >> 18  # floor(e2 log10(2)), |e2| < 1650
    X += a >= _TENS[X + 1 - _TENS_X0]
    near = False
    for _ in range(3):  # X one off, then the rounding up to 10^10
        if abs(9 - X) > 44:
            return 0, X, False
        q = _scale(a, 9 - X)
        m = np.rint(q)
        if m >= 1e9 and m <= 1e10:  # a tie matters once the magnitude is right (and carries to 10^10)
            near = near or abs(q - m) >= 0.5 - tie
        if m >= 1e10:
            X += 1
        elif m < 1e9:
            X -= 1
        else:
            break
    ok = m >= 1e9 and m < 1e10 and not near
    return int(m) if ok else 0, X, ok


@nb.njit(**_INLINE)
def _put_cell(out, p, m, X, neg):
    """The text of a nonzero cell (``%.10g`` of m 10^(X - 9), a minus sign if neg) at out[p]; the end.

    Writes up to 17 bytes from p whatever the cell's length (the next cell overwrites the rest):
    the ten digits with a point after digit ``point`` (none when point = 9), in one pass."""
    hi5 = m // 100_000
    lo5 = m - hi5 * 100_000
    s = 10 - (5 + _TZ5[hi5] if lo5 == 0 else _TZ5[lo5])  # significant digits
    d_hi, d_lo = _DIGITS[hi5], _DIGITS[lo5]
    out[p] = 45
    p += neg
    sci = X >= 10 or X < -4
    if sci:  # d.ddde+XX
        point = 0
    elif X < 0:  # 0.000ddd
        for k in range(5):
            out[p + k] = 46 if k == 1 else 48
        p += 1 - X
        point = 9
    else:  # ddd.ddd
        point = X
    for k in range(5):
        out[p + k + (k > point)] = (d_hi >> (8 * k)) & 255
        out[p + 5 + k + (5 + k > point)] = (d_lo >> (8 * k)) & 255
    out[p + point + 1] = 46
    if not sci and X < 0:
        p += s
    else:
        p += s + 1 if s > point + 1 else point + 1
    if sci:
        w = _SUFFIX[X + _SUFFIX_X0]
        for k in range(5):
            out[p + k] = (w >> (8 * k)) & 255
        p += 4 if -100 < X < 100 else 5
    return p


@nb.njit(**_JIT)
def format_rows(values, bits, is_int, out, slow, lo, hi, int_limit, tie):
    """CSV rows of a block into out [uint8]; returns (bytes used, cells left to Python).

    values : (rows, columns) float64 -- integer columns converted (exact below int_limit).
    bits : values viewed as int64.
    is_int : (columns,) uint8, 1 for integer and boolean columns (formatted while |v| < int_limit).
    out : at least ``CELL_MAX * rows * columns`` bytes.
    slow : (rows * columns, 2) int64; row k < the count returned holds a cell left to
        Python: its index ``row * columns + column`` and the byte offset where its text goes.
    lo, hi : the range of |v| formatted for float columns; tie : the near-tie tolerance.
    """
    n, ncol = values.shape
    p = 0
    ns = 0
    for i in range(n):
        for j in range(ncol):
            v = values[i, j]
            a = abs(v)
            if v == 0:
                out[p] = 48  # also -0.0
                p += 1
            elif a < np.inf:  # NaN and inf: an empty cell
                m, X = 0, 0
                if is_int[j]:
                    ok = a < int_limit
                else:
                    ok = a >= lo and a < hi
                if ok:
                    m, X, ok = _round10(a, bits[i, j], tie)
                if ok:
                    p = _put_cell(out, p, m, X, v < 0)
                else:
                    slow[ns, 0] = i * ncol + j
                    slow[ns, 1] = p
                    ns += 1
            out[p] = 44 if j < ncol - 1 else 10
            p += 1
    return p, ns


def csv_rows(columns: Sequence) -> bytes:
    """CSV rows (``\\n`` ends, no header) of equal-length 1-D numeric columns (float, int, bool),
    every cell as :func:`~cdpr_design.io.tables.fmt` writes it."""
    return numba_rows(numeric_columns(columns)) if columns else b""


def numba_rows(arrays: Sequence[np.ndarray], block: int = BLOCK) -> bytes:
    """:func:`csv_rows` of checked columns by :func:`format_rows`, block by block.

    The blocks' text goes into one buffer of ``CELL_MAX`` bytes a cell (its pages
    touched only as far as it is filled), joined once with the cells Python formats."""
    n, ncol = len(arrays[0]) if arrays else 0, len(arrays)
    if not n or not ncol:
        return b""
    rows = min(n, block)
    values = np.empty((rows, ncol), dtype=np.float64)
    is_int = np.array([c.dtype.kind in "biu" for c in arrays], dtype=np.uint8)
    out = np.empty(CELL_MAX * n * ncol, dtype=np.uint8)
    slow = np.empty((rows * ncol, 2), dtype=np.int64)
    view = memoryview(out)
    pieces, end = [], 0
    for start in range(0, n, block):
        k = min(n, start + block) - start
        vals = values if k == rows else np.empty((k, ncol), dtype=np.float64)
        for j, c in enumerate(arrays):
            vals[:, j] = c[start:start + k]
        used, ns = format_rows(vals, vals.view(np.int64), is_int, out[end:], slow,
                               FLOAT_RANGE[0], FLOAT_RANGE[1], float(INT_LIMIT), TIE)
        prev = end
        for idx, pos in slow[:ns].tolist():  # the cells left to Python, in order
            i, j = divmod(idx, ncol)
            pieces += [view[prev:end + pos], fmt(arrays[j][start + i]).encode()]
            prev = end + pos
        end += used
        pieces.append(view[prev:end])
    return b"".join(pieces)
