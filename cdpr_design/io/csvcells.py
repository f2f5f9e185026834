"""The constants and tables of the compiled CSV formatter (:mod:`~cdpr_design.io.csvfast`), the column check.

The formatter writes every cell as :func:`~cdpr_design.io.tables.fmt` does: a float
``v != 0`` is rounded to 10 significant digits as an integer ``m`` in [1e9, 1e10) and
a decimal exponent ``X`` (``|v| ~ m 10^(X-9)``) by scaling with exact powers of ten
(:data:`P10`, ``10^k`` for ``|k| <= 22``, at most twice); the ten digits come from a
table of five-digit groups as bytes (:data:`DIGITS`, with the trailing zeros of each
group in :data:`TZ5`); scientific notation ends with a suffix from :data:`SUFFIX`.
The cells this cannot format with certainty (a scaled value within :data:`TIE` of a
half, ``|v|`` outside :data:`FLOAT_RANGE`, integers from :data:`INT_LIMIT` on) are
formatted by :func:`~cdpr_design.io.tables.fmt`.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

_U = np.uint64
#: Exact powers of ten 10^0 .. 10^22 [float64].
P10 = 10.0 ** np.arange(23)
#: |v| formatted by the tables: 10^(9 - X) in two scalings by P10 (|9 - X| <= 44) for every
#: exponent X that log10 and the corrections can give (1e-35 itself gave X = -36).
FLOAT_RANGE = (1e-34, 1e53)
#: A scaled value within this of a half (of its nearest integer) is a possible tie: Python decides.
TIE = 1e-5
#: Integers with |v| below this are formatted by the tables (ten digits at most), larger ones by Python.
INT_LIMIT = 10 ** 10
#: Rows formatted per block (bounds the temporary arrays: ~ rows x columns x 40 bytes).
BLOCK = 16384


def axis(j: int) -> tuple:
    """The shape (1, .., 10, .., 1) of a ten-entry table laid along axis ``j`` of five."""
    return tuple(10 if i == j else 1 for i in range(5))


def _digit_tables():
    """(digits, tz5, suffix): the five-digit numbers 00000..99999 as 5 characters in a uint64
    (the j-th digit from the left in byte j, little-endian), their trailing zeros (5 for 00000),
    and the exponent suffixes ``e-400`` .. ``e+400`` as little-endian bytes (index X + 400)."""
    # the numbers as a (10,) * 5 grid, the j-th digit along axis j (in row-major order the flat
    # index is the number): no division
    char = np.arange(48, 58, dtype=_U)  # "0".."9"
    first = np.arange(10) == 0
    digits = np.zeros((10,) * 5, dtype=_U)
    tz = np.zeros((10,) * 5, dtype=np.int64)
    zeros = np.ones((10,) * 5, dtype=bool)  # digits j.. all "0"
    for j in range(5):
        digits |= char.reshape(axis(j)) << _U(8 * j)
    for j in range(4, -1, -1):
        zeros = zeros & first.reshape(axis(j))
        tz += zeros
    suffix = np.array([int.from_bytes(f"e{x:+03d}".encode(), "little") for x in range(-400, 401)], dtype=_U)
    return digits.ravel(), tz.ravel(), suffix


#: See :func:`_digit_tables`.
DIGITS, TZ5, SUFFIX = _digit_tables()


def numeric_columns(columns: Sequence) -> list[np.ndarray]:
    """The columns as arrays, checked: 1-D, of equal length, numeric (float, int, bool)."""
    arrays = [np.asarray(c) for c in columns]
    n = len(arrays[0]) if arrays else 0
    for c in arrays:
        if c.ndim != 1 or len(c) != n:
            raise ValueError("csv_rows: columns must be 1-D and of equal length")
        if c.dtype.kind not in "biuf":
            raise TypeError(f"csv_rows: numeric columns only, got dtype {c.dtype}")
    return arrays
