"""CSV text of numeric columns, vectorised: the cells :func:`~cdpr_design.io.tables.fmt` writes.

:func:`csv_rows` turns equal-length numeric columns into CSV rows, byte for
byte what formatting every cell with :func:`~cdpr_design.io.tables.fmt` gives:
floats as ``format(v, '.10g')`` (``-0`` written ``0``), integers and booleans
as integers, NaN and inf as empty cells.  It does so with whole-array numpy
operations instead of one Python call per cell.

How: a float ``v != 0`` is rounded to 10 significant digits as an integer
``m`` in [1e9, 1e10) and a decimal exponent ``X`` (``|v| ~ m 10^(X-9)``) by
scaling with exact powers of ten (``10^k``, ``|k| <= 22``, at most twice);
the scaled value is within 2 ulp of the exact product, so its nearest
integer is the correctly rounded one unless its fraction lies within 1e-5
of one half (then, and outside ``10^-34 .. 10^53``, the cell is formatted by
Python instead; both are rare).  The ten digits come from a table of
five-digit groups as bytes; ``printf``'s ``%g`` rule then picks fixed
notation (``-4 <= X < 10``: the decimal point inserted, or ``0.`` and zeros
put in front) or scientific notation (``d.ddde-XX``), trailing zeros dropped.
Each cell is laid out in four little-endian 64-bit words -- sign, 16 bytes of
digits, exponent suffix and separator -- with unused bytes zero; the row
block's bytes with the zeros removed are the CSV text.

When numba is already imported in the process (``"numba" in sys.modules``) with its
JIT on, :func:`csv_rows` hands the rows to the compiled formatter of
:mod:`cdpr_design.io.csvfast` instead (the same algorithm and tables, one cell
at a time, about four times faster, the GIL released).  Only then: importing
numba costs about a second, more than formatting a small table this way; a
sweep has imported it anyway, a trajectory or sizing table has not.
"""

from __future__ import annotations

import sys
from typing import Sequence

import numpy as np

_U = np.uint64
_WORDS = 3  # per cell: sign and digits (2 words), exponent suffix and separator
_P10 = 10.0 ** np.arange(23)
_IP10 = 10 ** np.arange(19, dtype=np.int64)
# |v| handled by the vectorised path: 10^(9 - X) in two scalings by _P10 (|9 - X| <= 44) for every
# exponent X that log10 and the corrections of _round10 can give (1e-35 itself gave X = -36)
_FLOAT_RANGE = (1e-34, 1e53)
#: A scaled value within this of a half (of its nearest integer) is a possible tie: Python decides.
_TIE = 1e-5
#: Integers with |v| below this are formatted here (ten digits at most), larger ones by Python.
_INT_LIMIT = 10 ** 10
#: Rows formatted per block (bounds the temporary arrays: ~ rows x columns x 40 bytes).
BLOCK = 16384


def _tables():
    # the five-digit numbers 00000..99999 as a (10,) * 5 grid, the j-th digit from the left
    # along axis j (in row-major order the flat index is the number): no division (2 ms, not 15)
    char = np.arange(48, 58, dtype=_U)  # "0".."9"
    first = np.arange(10) == 0
    digits = np.zeros((10,) * 5, dtype=_U)  # byte j (little-endian) holds the j-th digit's character
    tz = np.zeros((10,) * 5, dtype=np.int64)  # trailing zeros (5 for 00000)
    zeros = np.ones((10,) * 5, dtype=bool)  # digits j.. all "0"
    for j in range(5):
        digits |= char.reshape(_axis(j)) << _U(8 * j)
    for j in range(4, -1, -1):
        zeros = zeros & first.reshape(_axis(j))
        tz += zeros
    digits, tz = digits.ravel(), tz.ravel()
    # masks of bytes 0..b of a 128-bit value split in (lo, hi) words, at index b + 1 (b = -1 .. 15)
    keep_lo = np.array([2 ** (8 * min(b + 1, 8)) - 1 for b in range(-1, 16)], dtype=_U)
    keep_hi = np.array([2 ** (8 * max(b - 7, 0)) - 1 for b in range(-1, 16)], dtype=_U)
    # the decimal point at byte b (0..15) as (lo, hi)
    dot_lo = np.array([46 << 8 * b if b < 8 else 0 for b in range(16)], dtype=_U)
    dot_hi = np.array([46 << 8 * (b - 8) if b >= 8 else 0 for b in range(16)], dtype=_U)
    # "0." and z zeros (fixed notation below 1), z = 0..3
    pre = np.array([int.from_bytes(("0." + "0" * z).encode(), "little") for z in range(4)], dtype=_U)
    # exponent suffixes "e-05" .. "e+308" for X = -400 .. 400
    suffix = np.array([int.from_bytes(f"e{x:+03d}".encode(), "little") for x in range(-400, 401)], dtype=_U)
    return digits, tz, keep_lo, keep_hi, dot_lo, dot_hi, pre, suffix


def _axis(j: int) -> tuple:
    """The shape (1, .., 10, .., 1) of a ten-entry table laid along axis ``j`` of five."""
    return tuple(10 if i == j else 1 for i in range(5))


_DIGITS, _TZ5, _KEEP_LO, _KEEP_HI, _DOT_LO, _DOT_HI, _PRE, _SUFFIX = _tables()


def _scale(a, k):
    """a * 10^k [float64] for an integer array k, |k| <= 44, with at most two roundings."""
    lo, hi = int(k.min()), int(k.max())
    if lo >= 0 and hi <= 22:
        return a * _P10[k]
    k1 = np.clip(k, -22, 22)
    f = _P10[np.abs(k1)]
    out = np.where(k1 >= 0, a * f, a / f)
    if lo < -22 or hi > 22:
        k2 = k - k1
        f = _P10[np.abs(k2)]
        out = np.where(k2 >= 0, out * f, out / f)
    return out


def _round10(a):
    """(m, X, ok): a ~ m 10^(X - 9) with m the 10-digit correctly rounded mantissa
    (float, an integer in [1e9, 1e10)); ok False where that is not certain or a is
    0, NaN or inf (see the module)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        ok = (a >= _FLOAT_RANGE[0]) & (a < _FLOAT_RANGE[1])
        aa = a if ok.all() else np.where(ok, a, 1.0)
        X = np.floor(np.log10(aa)).astype(np.int64)
        q = _scale(aa, 9 - X)
        m = np.rint(q)
        # near a tie the scaled value may round either way: Python decides (also when that
        # rounding carried into an 11th digit and the exponent was raised below)
        tie = np.abs(q - m) >= 0.5 - _TIE
        for _ in range(2):  # log10 one off near powers of ten, or rounding up to 10^10
            up, down = m >= 1e10, m < 1e9
            fix = up | down
            if not fix.any():
                break
            X = X + up - down
            q = np.where(fix, _scale(aa, 9 - X), q)
            m = np.rint(q)
            tie |= np.abs(q - m) >= 0.5 - _TIE
        ok &= (m >= 1e9) & (m < 1e10) & ~tie
    return m, X, ok


def _int_digits(v):
    """(m, X, ok) of integers: m = |v| 10^(9 - X) exactly, ok where 0 < |v| < 10^10."""
    if v.dtype.kind == "u":  # from 2^63 on, a uint64 taken as int64 would be negative
        a = np.minimum(v.astype(np.uint64), np.uint64(_INT_LIMIT)).astype(np.int64)
    else:
        a = np.abs(v.astype(np.int64))
    ok = (a > 0) & (a < _INT_LIMIT)  # a < 0 only for the smallest int64
    a = np.where(ok, a, 0)
    X = np.maximum(np.searchsorted(_IP10[:11], a, side="right") - 1, 0)
    return a * _IP10[9 - X], X, ok


def _layout(cells, m, X, neg, fixed) -> None:
    """The sign, digit and suffix words of nonzero cells: m the 10-digit mantissa, X the exponent."""
    hi5, lo5 = np.divmod(m.astype(np.int64), 100_000)
    s = 10 - np.where(lo5 == 0, 5 + _TZ5[hi5], _TZ5[lo5])  # significant digits
    a_lo = _DIGITS[hi5] | (_DIGITS[lo5] << _U(40))
    a_hi = _DIGITS[lo5] >> _U(24)
    sci = ~fixed
    small = fixed & (X < 0)
    any_sci, any_small = bool(sci.any()), bool(small.any())
    # d.ddd form: the point after digit Xi (fixed notation with X >= 0; X = 0 for scientific)
    Xi = np.where(fixed & (X >= 0), X, 0) if any_sci or any_small else X
    k_lo, k_hi = _KEEP_LO[Xi + 1], _KEEP_HI[Xi + 1]
    t_lo = a_lo & ~k_lo
    r_lo = (a_lo & k_lo) | (t_lo << _U(8)) | _DOT_LO[Xi + 1]
    r_hi = (a_hi & k_hi) | ((a_hi & ~k_hi) << _U(8)) | (t_lo >> _U(56)) | _DOT_HI[Xi + 1]
    last = np.where(s > Xi + 1, s, Xi)  # the last byte kept
    if any_small:  # 0.000ddd form: fixed notation with X < 0
        rows = np.flatnonzero(small)
        z = np.clip(-X[rows] - 1, 0, 3)
        sh = (16 + 8 * z).astype(_U)
        r_lo[rows] = (a_lo[rows] << sh) | _PRE[z]
        r_hi[rows] = (a_hi[rows] << sh) | (a_lo[rows] >> (_U(64) - sh))
        last[rows] = 1 + z + s[rows]
    r_lo &= _KEEP_LO[last + 1]
    r_hi &= _KEEP_HI[last + 1]
    if neg.any():  # at most 15 bytes so far: room for the sign in front
        r_hi = np.where(neg, (r_hi << _U(8)) | (r_lo >> _U(56)), r_hi)
        r_lo = np.where(neg, (r_lo << _U(8)) | _U(45), r_lo)
    cells[:, 0] = r_lo
    cells[:, 1] = r_hi
    cells[:, 2] = np.where(fixed, _U(0), _SUFFIX[np.clip(X, -400, 400) + 400]) if any_sci else _U(0)


def _column(cells, v) -> np.ndarray:
    """Fill the (n, 3) words of one column's cells; returns the indices left to Python."""
    if v.dtype.kind in "biu":
        m, X, good = _int_digits(v)
        fixed = np.ones(v.shape, dtype=bool)
    else:
        v = v.astype(np.float64, copy=False)
        m, X, good = _round10(np.abs(v))
        fixed = (X >= -4) & (X < 10)
    _layout(cells, m, X, (v < 0) & good, fixed)
    if good.all():
        return np.flatnonzero(good[:0])
    bad = ~good
    cells[bad] = 0
    zero = v == 0
    cells[zero, 0] = _U(48)  # zero (also -0.0) is "0"
    if v.dtype.kind in "biu":
        return np.flatnonzero(bad & ~zero)
    return np.flatnonzero(bad & ~zero & np.isfinite(v))


def _python_cell(v) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return format(float(v) + 0.0, ".10g")  # + 0.0: -0.0 is written 0


def csv_rows(columns: Sequence[np.ndarray]) -> bytes:
    """CSV rows (``\\n`` ends, no header) of equal-length 1-D numeric columns (float, int, bool).

    Byte-identical to writing each cell with :func:`~cdpr_design.io.tables.fmt`:
    floats ``'.10g'``, integers and booleans as integers, NaN and inf empty.
    Compiled (:mod:`~cdpr_design.io.csvfast`) when numba is already imported,
    else vectorised numpy (see the module).
    """
    if not columns:
        return b""
    n = len(columns[0])
    arrays = [np.asarray(c) for c in columns]
    for c in arrays:
        if c.ndim != 1 or len(c) != n:
            raise ValueError("csv_rows: columns must be 1-D and of equal length")
        if c.dtype.kind not in "biuf":
            raise TypeError(f"csv_rows: numeric columns only, got dtype {c.dtype}")
    if "numba" in sys.modules and not sys.modules["numba"].config.DISABLE_JIT:
        from cdpr_design.io.csvfast import numba_rows

        return numba_rows(arrays)
    return numpy_rows(arrays)


def numpy_rows(arrays: Sequence[np.ndarray]) -> bytes:
    """:func:`csv_rows` of checked columns by whole-array numpy operations, block by block."""
    n = len(arrays[0]) if arrays else 0
    out = []
    for start in range(0, n, BLOCK):
        stop = min(n, start + BLOCK)
        out.append(_block([c[start:stop] for c in arrays]))
    return b"".join(out)


def _block(arrays) -> bytes:
    n, ncol = len(arrays[0]), len(arrays)
    words = np.empty((n, ncol, _WORDS), dtype="<u8")
    slow = []
    for j, c in enumerate(arrays):
        cells = words[:, j, :]
        left = _column(cells, c)
        if left.size:
            slow.append((j, left, c))
        cells[:, 2] |= _U(44 if j < ncol - 1 else 10) << _U(56)
    if slow:
        raw = words.view(np.uint8).reshape(n, ncol, _WORDS * 8)
        for j, rows, c in slow:
            for i in rows:
                text = _python_cell(c[i])
                raw[i, j, : 8 * _WORDS - 1] = 0
                raw[i, j, : len(text)] = np.frombuffer(text.encode(), dtype=np.uint8)
    return words.tobytes().translate(None, b"\0")
