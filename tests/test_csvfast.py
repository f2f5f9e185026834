"""The compiled CSV formatter (io.csvfast) against the cell-by-cell reference.

Everything here also passes with NUMBA_DISABLE_JIT=1 (``.ci/run`` runs it so, with
small arrays: the kernel is then plain Python)."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cdpr_design.io.columns import ColumnWriter
from cdpr_design.io.csvfast import numba_rows
from cdpr_design.io import columns
from cdpr_design.io.tables import cell_rows

from .test_outputs import random_columns, reference_text

JIT = not numba.config.DISABLE_JIT
N = 20_000 if JIT else 400  # rows of the random tables (the pure-Python kernel is slow)


def check(cols, **kw):
    """numba_rows equals the reference text and the writer's cell-by-cell path on these columns."""
    text = numba_rows(cols, **kw)
    assert text.decode() == reference_text(cols)
    assert text == cell_rows(cols)


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


@pytest.mark.parametrize("fmt_", ["csv", "parquet"])
def test_the_writer_gives_the_same_file_compiled_or_not(tmp_path, fmt_, monkeypatch):
    """ColumnWriter's ``compiled`` and the chunks' size change the speed, never the file: compiled,
    cell by cell, and compiled from a chunk size on write the same bytes, chunk after chunk."""
    rng = np.random.default_rng(9)
    chunks = [random_columns(rng, 300) for _ in range(3)]
    files = {}
    for case, compiled, cells in (("compiled", True, None), ("cells", False, None), ("big", False, 1000)):
        if cells is not None:  # every chunk here holds 300 x 19 = 5,700 cells
            monkeypatch.setattr(columns, "COMPILED_CELLS", cells)
        path = tmp_path / f"{case}.{fmt_}"
        with ColumnWriter(path, fmt_, compiled=compiled) as w:
            for cols in chunks:
                w.write({f"c{j}": c for j, c in enumerate(cols)})
        files[case] = path.read_bytes()
    assert files["compiled"] == files["cells"] == files["big"]
    if fmt_ == "csv":
        body = files["compiled"].split(b"\n", 1)[1]
        assert body.decode() == "".join(reference_text(cols) for cols in chunks)
