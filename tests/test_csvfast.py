"""The compiled CSV formatter (io.csvfast) against the cell-by-cell reference and the numpy path.

Everything here also passes with NUMBA_DISABLE_JIT=1 (``.ci/run`` runs it so, with
small arrays: the kernel is then plain Python)."""

from __future__ import annotations

import sys

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cdpr_design.io import csvfast, csvtext
from cdpr_design.io.csvfast import numba_rows
from cdpr_design.io.csvtext import numpy_rows

from .test_outputs import random_columns, reference_text

JIT = not numba.config.DISABLE_JIT
N = 20_000 if JIT else 400  # rows of the random tables (the pure-Python kernel is slow)


def check(cols, **kw):
    """numba_rows equals the reference text and the numpy path on these columns."""
    text = numba_rows(cols, **kw)
    assert text.decode() == reference_text(cols)
    assert text == numpy_rows(cols)


@pytest.mark.slow
def test_random_numbers_of_every_kind_match_the_reference():
    check(random_columns(np.random.default_rng(18), N))


def test_each_kind_of_cell_in_a_column_of_its_own():
    """One kind per column beside a row number (no neighbour to hide a misplaced byte)."""
    for col in random_columns(np.random.default_rng(5), N // 10):
        check([np.arange(col.size), col])
        check([col, np.arange(col.size)])


@pytest.mark.slow
def test_every_magnitude_of_the_double_range():
    """|v| from the subnormals (5e-324) to 1.8e308, both signs, uniform in the exponent: every %g
    switch, every suffix, the ranges handed to Python (below 1e-34, from 1e53)."""
    rng = np.random.default_rng(3)
    bits = rng.integers(0, 0x7FF0_0000_0000_0000, 4 * N, dtype=np.int64)  # every finite positive double
    x = bits.view(np.float64) * rng.choice([-1.0, 1.0], bits.size)
    check([x[: 2 * N], x[2 * N:]])
    e = rng.uniform(-324, 308.25, N)
    with np.errstate(over="ignore"):  # 10^308 times up to 10: inf, an empty cell
        y = rng.choice([-1.0, 1.0], N) * rng.uniform(1, 10, N) * 10.0 ** np.floor(e)
    check([y, np.where(np.isfinite(y), y, 0.0)])


def test_ties_and_short_decimals():
    """Exact ties at the 11th digit ((m + 1/2) exactly, and 0.5e-9 multiples of short decimals),
    numbers with fewer than ten digits, powers of ten and their neighbours."""
    rng = np.random.default_rng(11)
    m = rng.integers(10 ** 9, 10 ** 10, N).astype(float)
    ties = (m + 0.5) * 10.0 ** rng.integers(-12, 3, N)  # exact at 10^0, near elsewhere
    halves = np.round(rng.normal(size=N), 4) + 5e-10 * rng.integers(-9, 10, N)
    short = np.array([round(v, int(d)) for v, d in zip(rng.normal(size=N) * 10.0 ** rng.integers(-6, 11, N),
                                                       rng.integers(0, 9, N))])
    p10 = 10.0 ** rng.integers(-40, 60, N)
    check([m + 0.5, ties, halves, short, -short, p10, np.nextafter(p10, 0), np.nextafter(p10, np.inf)])


def test_integers_booleans_and_their_extremes():
    rng = np.random.default_rng(4)
    i64 = np.iinfo(np.int64)
    ext = np.array([i64.min, i64.max, i64.min + 1, 0, -1, 1, 10 ** 10 - 1, 10 ** 10, -(10 ** 10) + 1, -(10 ** 10)])
    u64 = np.array([0, 1, 2 ** 63, 2 ** 64 - 1, 10 ** 10 - 1, 10 ** 10], dtype=np.uint64)
    cols = [rng.choice(ext, N), rng.integers(i64.min, i64.max, N), rng.integers(0, 2, N).astype(bool),
            rng.integers(0, 256, N).astype(np.uint8), rng.choice(u64, N), rng.integers(-99, 99, N).astype(np.int8),
            rng.integers(-(10 ** 11), 10 ** 11, N)]
    check(cols)


def test_special_values():
    x = np.array([0.0, -0.0, np.nan, np.inf, -np.inf, 5e-324, -5e-324, 2.2250738585072014e-308,
                  1.7976931348623157e308, 9.9999999995e-5, 9999999999.5, 0.5, 1e-4, 1e10])
    edges = np.array([1e-36, 1e-35, 1e-34, 1e53, 1e54, 1e55])  # the exact range's ends and beyond
    x = np.concatenate([x, edges, np.nextafter(edges, 0), np.nextafter(edges, np.inf), -edges])
    assert numba_rows([x, np.arange(x.size)]).split(b"\n")[:5] == [b"0,0", b"0,1", b",2", b",3", b",4"]
    check([x, np.arange(x.size)])
    with np.errstate(over="ignore"):  # beyond float32: inf
        x32 = x.astype(np.float32)
    check([x32, x])


@pytest.mark.parametrize("block", [1, 2, 7, 63, 64, 65, 1000])
def test_block_boundaries(block):
    """Blocks of any size, the last one short, Python's cells falling in every block."""
    rng = np.random.default_rng(block)
    cols = random_columns(rng, 64)
    check(cols, block=block)
    check(cols[:1], block=block)


def test_empty_and_one_cell():
    assert numba_rows([np.array([])]) == b"" and numba_rows([]) == b""
    assert numba_rows([np.array([-0.0])]) == b"0\n"
    assert numba_rows([np.array([np.nan]), np.array([np.nan])]) == b",\n"


finite = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)


@pytest.mark.slow
@settings(max_examples=300 if JIT else 60, deadline=None)
@given(st.lists(st.tuples(finite, finite, st.integers(-(2 ** 63), 2 ** 63 - 1), st.booleans()),
                min_size=1, max_size=40))
def test_hypothesis_rows(rows):
    a, b, i, t = (np.array(c) for c in zip(*rows))
    check([a, b, i.astype(np.int64), t.astype(bool)])


def test_the_kernel_formats_ordinary_numbers_itself():
    """Python gets only the rare cells (near ties; |v| outside 1e-34..1e53): the compiled path is taken."""
    rng = np.random.default_rng(7)
    n = N
    x = (rng.normal(size=n) * 10.0 ** rng.uniform(-30, 50, n)).reshape(n, 1)
    out = np.empty(csvfast.CELL_MAX * n, dtype=np.uint8)
    slow = np.empty((n, 2), dtype=np.int64)

    def left(v, is_int):
        return csvfast.format_rows(v, v.view(np.int64), np.array([is_int], np.uint8), out, slow, *csvfast._TABLES,
                                   *csvtext._FLOAT_RANGE, 1e10, csvtext._TIE)[1]

    assert left(x, 0) < max(10, n // 5000)  # ~ 2e-5 of the cells fall within 1e-5 of a tie
    ints = rng.integers(-(10 ** 9), 10 ** 9, n).astype(np.float64).reshape(n, 1)
    assert left(ints, 1) == 0
    assert left(np.full((n, 1), 1e60), 0) == n  # beyond the exact range: every cell to Python


def test_csv_rows_uses_the_kernel_only_where_numba_is_imported_and_compiles(monkeypatch):
    """Where numba is imported with its JIT on, csv_rows takes the compiled path; elsewhere
    (numba not imported, or NUMBA_DISABLE_JIT: the kernel would run interpreted, ~50x slower
    than numpy) the numpy one."""
    import numba

    calls = []
    monkeypatch.setattr(csvfast, "numba_rows", lambda a: calls.append("numba") or numba_rows(a))
    monkeypatch.setattr(csvtext, "numpy_rows", lambda a: calls.append("numpy") or numpy_rows(a))
    cols = [np.array([1.5, -0.0]), np.array([3, 4])]
    monkeypatch.setattr(numba.config, "DISABLE_JIT", False)
    assert csvtext.csv_rows(cols) == b"1.5,3\n0,4\n"
    monkeypatch.setattr(numba.config, "DISABLE_JIT", True)
    assert csvtext.csv_rows(cols) == b"1.5,3\n0,4\n"
    monkeypatch.delitem(sys.modules, "numba")
    assert csvtext.csv_rows(cols) == b"1.5,3\n0,4\n"
    assert calls == ["numba", "numpy", "numpy"]
