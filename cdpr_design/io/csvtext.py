"""CSV text of numeric columns, vectorised: the cells :func:`~cdpr_design.io.tables.fmt` writes.

:func:`csv_rows` turns equal-length numeric columns into CSV rows, byte for
byte what formatting every cell with :func:`~cdpr_design.io.tables.fmt` gives:
floats as ``format(v, '.10g')`` (``-0`` written ``0``), integers and booleans
as integers, NaN and inf as empty cells.  It does so with whole-array numpy
operations instead of one Python call per cell.

How (the constants and tables shared with the compiled formatter are in
:mod:`~cdpr_design.io.csvcells`): a float ``v != 0`` is rounded to 10 significant digits as an integer
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

Why two formatters: :mod:`~cdpr_design.io.csvfast` formats the same bytes
by the same algorithm in numba, faster a cell, but in a process that has not
loaded numba yet its first table costs numba's start-up (importing numba and
loading the cached machine code).  So the numpy formatter serves a command
that does not otherwise load numba (planar2's sweep on the numpy engine, a
trajectory, a motor sizing, a study's table), and the compiled one a command
that ran the kernels (figures: docs/performance.md).  The writer's caller says which
(:class:`~cdpr_design.io.columns.ColumnWriter`'s ``compiled``).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from cdpr_design.io.csvcells import (BLOCK, DIGITS, FLOAT_RANGE, INT_LIMIT, P10, SUFFIX, TIE, TZ5,
                                     numeric_columns)
from cdpr_design.io.tables import fmt

_U = np.uint64
_WORDS = 3  # per cell: sign and digits (2 words), exponent suffix and separator
_IP10 = 10 ** np.arange(19, dtype=np.int64)


def _masks():
    """The byte masks of the layout: bytes 0..b of a 128-bit value split in (lo, hi) words at
    index b + 1 (b = -1 .. 15); the decimal point at byte b (0..15) as (lo, hi); ``0.`` and z
    zeros (fixed notation below 1, z = 0..3)."""
    keep_lo = np.array([2 ** (8 * min(b + 1, 8)) - 1 for b in range(-1, 16)], dtype=_U)
    keep_hi = np.array([2 ** (8 * max(b - 7, 0)) - 1 for b in range(-1, 16)], dtype=_U)
    dot_lo = np.array([46 << 8 * b if b < 8 else 0 for b in range(16)], dtype=_U)
    dot_hi = np.array([46 << 8 * (b - 8) if b >= 8 else 0 for b in range(16)], dtype=_U)
    pre = np.array([int.from_bytes(("0." + "0" * z).encode(), "little") for z in range(4)], dtype=_U)
    return keep_lo, keep_hi, dot_lo, dot_hi, pre


_KEEP_LO, _KEEP_HI, _DOT_LO, _DOT_HI, _PRE = _masks()


def _scale(a, k):
    """a * 10^k [float64] for an integer array k, |k| <= 44, with at most two roundings."""
    lo, hi = int(k.min()), int(k.max())
    if lo >= 0 and hi <= 22:
        return a * P10[k]
    k1 = np.clip(k, -22, 22)
    f = P10[np.abs(k1)]
    out = np.where(k1 >= 0, a * f, a / f)
    if lo < -22 or hi > 22:
        k2 = k - k1
        f = P10[np.abs(k2)]
        out = np.where(k2 >= 0, out * f, out / f)
    return out


def _round10(a):
    """(m, X, ok): a ~ m 10^(X - 9) with m the 10-digit correctly rounded mantissa
    (float, an integer in [1e9, 1e10)); ok False where that is not certain or a is
    0, NaN or inf (see the module)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        ok = (a >= FLOAT_RANGE[0]) & (a < FLOAT_RANGE[1])
        aa = a if ok.all() else np.where(ok, a, 1.0)
        X = np.floor(np.log10(aa)).astype(np.int64)
        q = _scale(aa, 9 - X)
        m = np.rint(q)
        # near a tie the scaled value may round either way: Python decides (also when that
        # rounding carried into an 11th digit and the exponent was raised below)
        tie = np.abs(q - m) >= 0.5 - TIE
        for _ in range(2):  # log10 one off near powers of ten, or rounding up to 10^10
            up, down = m >= 1e10, m < 1e9
            fix = up | down
            if not fix.any():
                break
            X = X + up - down
            q = np.where(fix, _scale(aa, 9 - X), q)
            m = np.rint(q)
            tie |= np.abs(q - m) >= 0.5 - TIE
        ok &= (m >= 1e9) & (m < 1e10) & ~tie
    return m, X, ok


def _int_digits(v):
    """(m, X, ok) of integers: m = |v| 10^(9 - X) exactly, ok where 0 < |v| < 10^10."""
    if v.dtype.kind == "u":  # from 2^63 on, a uint64 taken as int64 would be negative
        a = np.minimum(v.astype(np.uint64), np.uint64(INT_LIMIT)).astype(np.int64)
    else:
        a = np.abs(v.astype(np.int64))
    ok = (a > 0) & (a < INT_LIMIT)  # a < 0 only for the smallest int64
    a = np.where(ok, a, 0)
    X = np.maximum(np.searchsorted(_IP10[:11], a, side="right") - 1, 0)
    return a * _IP10[9 - X], X, ok


def _layout(cells, m, X, neg, fixed) -> None:
    """The sign, digit and suffix words of nonzero cells: m the 10-digit mantissa, X the exponent."""
    hi5, lo5 = np.divmod(m.astype(np.int64), 100_000)
    s = 10 - np.where(lo5 == 0, 5 + TZ5[hi5], TZ5[lo5])  # significant digits
    a_lo = DIGITS[hi5] | (DIGITS[lo5] << _U(40))
    a_hi = DIGITS[lo5] >> _U(24)
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
    cells[:, 2] = np.where(fixed, _U(0), SUFFIX[np.clip(X, -400, 400) + 400]) if any_sci else _U(0)


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


def csv_rows(columns: Sequence) -> bytes:
    """CSV rows (``\\n`` ends, no header) of equal-length 1-D numeric columns (float, int, bool).

    Byte-identical to writing each cell with :func:`~cdpr_design.io.tables.fmt`:
    floats ``'.10g'``, integers and booleans as integers, NaN and inf empty.
    """
    return numpy_rows(numeric_columns(columns)) if columns else b""


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
                text = fmt(c[i])
                raw[i, j, : 8 * _WORDS - 1] = 0
                raw[i, j, : len(text)] = np.frombuffer(text.encode(), dtype=np.uint8)
    return words.tobytes().translate(None, b"\0")
