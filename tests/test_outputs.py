"""The table writer: CSV cells against the cell-by-cell reference, the files of the previous writer,
Parquet round trips and metadata, streaming, atomicity and bounded memory."""

from __future__ import annotations

import csv
import gzip
import io
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cdpr_design.io.columns import ColumnWriter, read_table, table_metadata
from cdpr_design.io.csvfast import csv_rows, numba_rows
from cdpr_design.io.tables import cell_rows
from cdpr_design.io.files import OutputDir
from cdpr_design.io.tables import fmt

from .helpers import DESIGNS, PLANAR2, ROOT, invoke, subprocess_env

#: The previous writer's files (generated with 7c8ae5c).  ipanema1-ws and ipanema2-ws were generated
#: again when the closed-form tension QP (project_two) replaced the active-set method for two redundant
#: cables: 170 tension cells moved by at most 1.3e-13 N (a few ulps of tensions up to 700 N), every
#: other cell -- coordinates, feasibility, margins -- was unchanged.  A kernel change regenerates a file
#: only after such a cell-by-cell numeric comparison; the writer itself is held to the cell-by-cell
#: reference (reference_text) below.
DATA = ROOT / "tests" / "data" / "outputs"


def reference_text(columns) -> str:
    """The slow obvious writer: every cell through fmt, rows through the csv module."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    n = len(columns[0]) if columns else 0
    for i in range(n):
        w.writerow([fmt(c[i]) for c in columns])
    return buf.getvalue()


def random_columns(rng, n: int) -> list[np.ndarray]:
    """Numbers of every kind a table holds, across the whole double range."""
    mags = [rng.uniform(-320, 308, n), rng.uniform(-40, 60, n), rng.uniform(-6, 12, n), rng.uniform(-1, 4, n)]
    cols = [rng.normal(size=n) * 10.0 ** m for m in mags]
    # short decimals (grid coordinates, rounded inputs) and their float noise
    dec = np.array([round(v, int(d)) for v, d in zip(rng.normal(size=n) * 10.0 ** rng.integers(-5, 11, n),
                                                     rng.integers(0, 12, n))])
    cols += [dec, dec + dec * 2.0 ** -52, dec * (1 - 2.0 ** -53)]
    # exact ties at the 11th digit (n + 1/2) 2^k, and their neighbours one ulp away
    ties = (rng.integers(10 ** 9, 10 ** 10, n).astype(float) + 0.5) * 2.0 ** rng.integers(-40, 4, n)
    cols += [ties, np.nextafter(ties, np.inf), np.nextafter(ties, -np.inf)]
    # near powers of ten and the %g switch points
    p10 = 10.0 ** rng.integers(-12, 14, n)
    cols += [p10 * (1 - 10.0 ** rng.uniform(-17, -9, n)), p10 * (1 + 10.0 ** rng.uniform(-17, -9, n))]
    special = np.array([0.0, -0.0, np.nan, np.inf, -np.inf, 1e-4, 9.9999999995e-5, 9.99999999949999e-5,
                        9999999999.5, 9999999999.4, 1e10, 0.5, -2.220446049250313e-16, 5e-324, 1.7976931348623157e308,
                        1e-5, 123456789.0, 1.5, -1e-300, 2.5e-308, 99.999999995, 9.9999999995, 0.00099999999995])
    cols.append(rng.choice(special, n))
    cols.append(rng.normal(size=n).astype(np.float32) * np.float32(1e3))
    cols += [rng.integers(-2 ** 63, 2 ** 63 - 1, n, dtype=np.int64), rng.integers(-10 ** 10, 10 ** 10, n),
             rng.integers(0, 2, n).astype(bool), rng.integers(0, 255, n).astype(np.uint8),
             rng.integers(-100, 100, n).astype(np.int32)]
    return cols


@pytest.mark.slow
def test_csv_cells_match_the_reference_on_random_numbers():
    rng = np.random.default_rng(18)
    cols = random_columns(rng, 20_000)
    assert csv_rows(cols).decode() == reference_text(cols)
    assert cell_rows(cols).decode() == reference_text(cols)


def test_csv_cells_of_every_float_kind_one_by_one():
    """Each kind of cell in a column of its own beside a row number (no neighbour of another
    kind to hide a misplaced byte; two columns, as the csv module writes a lone empty cell '""')."""
    rng = np.random.default_rng(5)
    for col in random_columns(rng, 3000):
        cols = [np.arange(col.size), col]
        assert csv_rows(cols).decode() == reference_text(cols)
        assert cell_rows(cols).decode() == reference_text(cols)


def test_negative_zero_is_written_zero_and_nonfinite_is_empty():
    for rows in (csv_rows, cell_rows):
        assert rows([np.array([-0.0, 0.0, np.nan, -np.inf]), np.array([1, 0, -3, 7])]) == b"0,1\n0,0\n,-3\n,7\n"
    assert fmt(-0.0) == "0" and fmt(np.float64(-0.0)) == "0"


# ----------------------------------------------------------------------------
# The previous writer's files (generated before the change; tests/data/outputs)
# ----------------------------------------------------------------------------

#: case -> command line that wrote the reference files of tests/data/outputs/<case>__<file>.csv.gz
GOLDEN = {
    "planar2-ws": ["workspace", "planar2.yaml", "--step", "0.05"],
    "planar4-ws": ["workspace", "planar4.yaml", "--step", "0.1"],
    "planar4-range": ["workspace", "planar4.yaml", "--orientations", "range", "--step", "0.25"],
    "ipanema1-ws": ["workspace", "ipanema1.yaml", "--step", "0.5"],
    "ipanema2-ws": ["workspace", "ipanema2.yaml", "--step", "1.0", "--kind", "wrench-closure"],
    "ipanema3-col": ["workspace", "ipanema3.yaml", "--step", "1.2", "--collisions"],
    "cogiro-ws": ["workspace", "cogiro.yaml", "--step", "1.5", "--kind", "wrench-feasible"],
    "planar2-size": ["size-motors", "planar2.yaml"],
    "ipanema3-size": ["size-motors", "ipanema3.yaml", "--step", "1.0"],
    "planar2-traj": ["trajectory", "planar2.yaml", "square_fast", "--cycle-time", "0.02"],
    "planar2-sweep": ["sweep", "planar2.yaml", "--vary", "effector.mass=0.5,1", "--step", "0.1", "--workers", "1",
                      "--no-picture"],
}
_NEG0 = re.compile(r"(?<![^,\n])-0(?![^,\n])")


class _NoPictures:
    def wait(self):
        return []


@pytest.fixture
def no_pictures(monkeypatch):
    """The tables only: the commands' pictures are not drawn (they have their own tests)."""
    from cdpr_design.jobs import motion, workspace

    monkeypatch.setattr(workspace, "workspace_pictures", lambda result, names=None: [])
    monkeypatch.setattr(motion, "submit_pictures", lambda *a, **k: _NoPictures())


@pytest.mark.parametrize("case", sorted(GOLDEN))
def test_csv_identical_to_the_previous_writer(case, tmp_path, no_pictures):
    files = sorted(DATA.glob(f"{case}__*.csv.gz"))
    assert files, f"no reference file for {case}"
    args = list(GOLDEN[case])
    args[1] = DESIGNS / args[1]
    r = invoke(*args, "--out", tmp_path, "--quiet")
    assert r.exit_code == 0, r.output
    for f in files:
        old = gzip.decompress(f.read_bytes()).decode()
        new = (tmp_path / f.name.split("__")[1][:-3]).read_text()
        assert _old_columns(new, old) == _NEG0.sub("0", old), f.name


def _old_columns(new: str, old: str) -> str:
    """``new`` restricted to the columns ``old`` has, in its order: the contract lets later
    issues add columns (planar2's workspace gained its hanging tilt), never change one."""
    import csv
    import io

    old_head = next(csv.reader(io.StringIO(old)))
    rows = list(csv.reader(io.StringIO(new)))
    if rows[0] == old_head:
        return new
    idx = [rows[0].index(c) for c in old_head]
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows([[r[i] for i in idx] for r in rows])
    return out.getvalue()


def test_the_references_hold_negative_zeros_and_scientific_cells():
    """The reference files exercise the contract's one change and the %g switch."""
    texts = [gzip.decompress(f.read_bytes()).decode() for f in DATA.glob("*.csv.gz")]
    assert sum(bool(_NEG0.search(t)) for t in texts) >= 1
    assert sum("e-" in t for t in texts) >= 3
    assert any('"' in t for t in texts)  # a quoted cell (sweep's duty_cycle text)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(p.stem for p in DESIGNS.glob("*.yaml")))
def test_workspace_table_of_every_design_matches_the_reference(name):
    """In-process: the writer's CSV of each shipped design's workspace equals the cell-by-cell text."""
    from cdpr_design.model import spec
    from cdpr_design.statics.robot import Analysis
    from cdpr_design.workspaces.table import collect

    d = spec.load(DESIGNS / f"{name}.yaml")
    step = 0.1 if d.motion.planar else 0.8
    checks = not d.motion.planar and d.effector.orientation == "fixed"  # a free body: no interference sweep
    table = collect(d, Analysis(collisions=checks), step=step)
    cols = table.columns()
    assert "collision_free" in cols or not checks
    arrays = [np.asarray(v) for v in cols.values()]
    text = numba_rows(arrays).decode()
    ref = reference_text(arrays)
    assert text == ref
    assert cell_rows(arrays).decode() == ref  # and the cell-by-cell path
    assert len(text.splitlines()) == table.poses.shape[0] > 0


# ----------------------------------------------------------------------------
# ColumnWriter: streaming, types, metadata, atomicity
# ----------------------------------------------------------------------------


def _chunks(rng, sizes):
    for n in sizes:
        yield {"x": rng.normal(size=n), "feasible": rng.integers(0, 2, n).astype(bool),
               "count": rng.integers(0, 9, n), "margin": np.where(rng.random(n) < 0.2, np.nan, rng.normal(size=n))}


def test_parquet_streams_row_groups_with_types_and_metadata(tmp_path):
    import pyarrow.parquet as pq

    rng = np.random.default_rng(1)
    meta = {"name": "demo", "grid": {"step": [0.1]}, "units": {"x": "m", "margin": "N"}}
    with ColumnWriter(tmp_path / "t.parquet", "parquet", metadata=meta) as w:
        for ch in _chunks(rng, [1000, 10, 2500]):
            w.write(ch)
    f = pq.ParquetFile(tmp_path / "t.parquet")
    assert f.metadata.num_row_groups == 3 and f.metadata.num_rows == 3510
    schema = f.schema_arrow
    assert [str(schema.field(k).type) for k in ("x", "feasible", "count", "margin")] == \
        ["double", "bool", "int64", "double"]
    assert schema.field("margin").metadata == {b"unit": b"N"}
    m = table_metadata(tmp_path / "t.parquet")
    import cdpr_design

    assert m["name"] == "demo" and m["grid"] == {"step": [0.1]} and m["version"] == cdpr_design.__version__
    # dictionary pages only where they pay: integers (and text), not the floating-point figures
    # (booleans are bit-packed, never dictionary-encoded)
    group = f.metadata.row_group(0)
    dictionary = {group.column(i).path_in_schema: group.column(i).has_dictionary_page
                  for i in range(group.num_columns)}
    assert dictionary == {"x": False, "feasible": False, "count": True, "margin": False}


def test_csv_and_parquet_of_the_same_chunks_agree(tmp_path):
    rng = np.random.default_rng(2)
    chunks = list(_chunks(rng, [700, 1, 300]))
    for fmt_ in ("csv", "parquet"):
        with ColumnWriter(tmp_path / f"t.{fmt_}", fmt_, background=True) as w:
            for ch in chunks:
                w.write(ch)
    a, b = read_table(tmp_path / "t.csv"), read_table(tmp_path / "t.parquet")
    assert list(a) == list(b) == ["x", "feasible", "count", "margin"]
    for k in a:
        want = np.concatenate([c[k] for c in chunks]).astype(float)
        np.testing.assert_allclose(a[k], want, rtol=1e-9, atol=0)  # CSV: 10 significant digits
        np.testing.assert_array_equal(b[k].astype(float), want)  # Parquet: exact
    assert b["feasible"].dtype == bool


def test_text_columns_quoted_like_the_csv_module(tmp_path):
    cols = {"name": ["a,b", 'say "hi"', "plain", None], "v": [1, 2.5, None, True], "n": [1, 2, 3, 4]}
    with ColumnWriter(tmp_path / "t.csv") as w:
        w.write(cols)
    assert (tmp_path / "t.csv").read_text() == "name,v,n\n" + reference_text(list(cols.values()))
    with ColumnWriter(tmp_path / "t.parquet", "parquet") as w:
        w.write(cols)
    back = read_table(tmp_path / "t.parquet")
    assert list(back["name"]) == ["a,b", 'say "hi"', "plain", None]
    assert back["n"].dtype == np.int64


def test_a_failed_write_leaves_no_file(tmp_path):
    out = OutputDir(tmp_path)
    with pytest.raises(ValueError, match="differ"):
        with out.table("t", "csv", names=["a", "b"], background=True) as w:
            w.write({"a": np.ones(3), "b": np.ones(3)})
            w.write({"a": np.ones(3), "c": np.ones(3)})  # raised by the thread, re-raised here
            w.write({"a": np.ones(3), "b": np.ones(3)})
    assert not (tmp_path / "t.csv").exists()
    assert not list(tmp_path.glob(".t.csv.*"))  # no temporary file left either
    with out.table("t", "parquet", names=["a"]) as w:
        pass  # no rows: a valid empty table with the columns
    assert read_table(tmp_path / "t.parquet")["a"].size == 0


def test_header_of_a_table_without_rows(tmp_path):
    OutputDir(tmp_path).write_columns("e.csv", {"a": (), "b,c": ()})
    assert (tmp_path / "e.csv").read_text() == 'a,"b,c"\n'


_RSS = r"""
import resource, sys, numpy as np
from cdpr_design.io.columns import ColumnWriter
fmt_, n, chunk = sys.argv[1], int(sys.argv[2]), 1 << 18
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
with ColumnWriter(sys.argv[3], fmt_, background=True) as w:
    for s in range(0, n, chunk):
        k = min(chunk, n - s)
        i = np.arange(s, s + k, dtype=float)
        w.write({"x": i * 1e-3, "y": i * 2e-3, "z": i * 3e-3, "feasible": (i % 3) > 0, "margin": np.sin(i),
                 "t1": np.cos(i), "t2": np.sqrt(i), "l1": i * 7e-4, "l2": i * 9e-4, "l3": i * 1e-5})
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - base)
"""


@pytest.mark.slow
def test_memory_stays_bounded_streaming_10_million_rows(tmp_path):
    """10,000,000 rows of 10 columns (800 MB as float64) stream in chunks: the peak grows by < 200 MB."""
    out = subprocess.run([sys.executable, "-c", _RSS, "parquet", "10000000", str(tmp_path / "big.parquet")],
                         env=subprocess_env(), capture_output=True, text=True, check=True)
    grown_mb = int(out.stdout.split()[-1]) / 1024  # ru_maxrss is in KiB on Linux
    assert grown_mb < 200, grown_mb
    import pyarrow.parquet as pq

    f = pq.ParquetFile(tmp_path / "big.parquet")
    assert f.metadata.num_rows == 10_000_000 and f.metadata.num_row_groups == 39


def test_summaries_carry_timings(tmp_path, no_pictures):
    r = invoke("workspace", DESIGNS / "planar2.yaml", "--step", "0.05", "--out", tmp_path, "--json")
    assert r.exit_code == 0, r.output
    for s in (json.loads(r.stdout), json.loads((tmp_path / "summary.json").read_text())):
        t = s["timings"]
        assert set(t) == {"load_s", "sweep_s", "write_s", "pictures_s", "total_s", "boundary_s"}
        assert all(v >= 0 for v in t.values()) and t["total_s"] >= t["sweep_s"] >= t["boundary_s"]


#: Commands whose JSON summary is written last: their arguments and that file's name.
LAST_JSON = {"workspace": (["--step", "0.25"], "summary.json"), "report": (["--step", "0.25"], "report.json"),
             "trajectory": (["square_fast"], "trajectory.json"), "simulate": (["square_fast"], "simulation.json")}


@pytest.mark.parametrize("command", sorted(LAST_JSON))
def test_a_foreign_json_summary_is_refused_before_anything_is_written(tmp_path, command):
    args, name = LAST_JSON[command]
    (tmp_path / name).write_text("mine\n")
    r = invoke(command, PLANAR2, *args, "--out", tmp_path, "--quiet")
    assert r.exit_code == 2 and f"{tmp_path / name} exists and was not written" in r.output, r.output
    assert [p.name for p in tmp_path.iterdir()] == [name]  # was: the table, the PNGs and the manifest
    assert (tmp_path / name).read_text() == "mine\n"


@pytest.mark.parametrize("name", ["summary.json", "workspace.csv", "workspace.png"])
def test_a_folder_where_an_output_goes_is_refused_even_with_overwrite(tmp_path, name):
    out = tmp_path / "out"
    (out / name).mkdir(parents=True)
    (out / name / "notes.txt").write_text("mine\n")
    r = invoke("workspace", PLANAR2, "--step", "0.25", "--out", out, "--overwrite", "--quiet")
    assert r.exit_code == 2 and f"{out / name} is a folder" in r.output, r.output  # was: IsADirectoryError
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == [Path(name), Path(name) / "notes.txt"]
    assert (out / name / "notes.txt").read_text() == "mine\n"


def test_a_dangling_symbolic_link_where_an_output_goes_is_a_foreign_file(tmp_path):
    """A link of the user's that points nowhere (yet) is theirs: not replaced without --overwrite."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").symlink_to(tmp_path / "elsewhere" / "summary.json")
    r = invoke("workspace", PLANAR2, "--step", "0.25", "--out", out, "--quiet")
    assert r.exit_code == 2 and "exists and was not written by cdpr-design" in r.output, r.output
    assert (out / "summary.json").is_symlink() and sorted(p.name for p in out.iterdir()) == ["summary.json"]


#: Designs whose workspace run draws an extra picture, and that picture.
EXTRA_PICTURE = {"crane4": "tilt_map.png", "planar2": "tilt_map.png", "sagging40": "cable_models.png"}


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(p.stem for p in DESIGNS.glob("*.yaml")))
def test_every_file_a_workspace_run_writes_is_known_before_the_sweep(tmp_path, name):
    """The names checked for foreign files up front are exactly the files the run writes."""
    from cdpr_design import workspaces as ws
    from cdpr_design.jobs.workspace import output_names
    from cdpr_design.model.spec import load
    from cdpr_design.statics.robot import resolve

    design = load(DESIGNS / f"{name}.yaml")
    grid = ws.make_grid(design, 0.5)
    plan = ws.plan(resolve(design), grid, solid=True)
    r = invoke("workspace", DESIGNS / f"{name}.yaml", "--step", "0.5", "--out", tmp_path, "--quiet")
    assert r.exit_code == 0, r.output
    written = sorted(p.name for p in tmp_path.iterdir())
    # besides them: the record of what cdpr-design wrote, and the folder's lock file (issue 40)
    assert written == sorted(output_names(plan) + ["workspace.csv", ".cdpr-design-outputs",
                                                     ".cdpr-design.lock"]), written
    assert (EXTRA_PICTURE.get(name) in written) if name in EXTRA_PICTURE else \
        not {"tilt_map.png", "cable_models.png"} & set(written)


@pytest.mark.parametrize("name, picture", sorted(EXTRA_PICTURE.items()))
def test_a_foreign_extra_picture_is_refused_before_the_sweep(tmp_path, name, picture):
    """The refusal comes before the sweep: on a grid of 200 times the design's resolution per
    axis (10^9 poses and more, hours of sweeping, accepted with --force) the command answers at
    once.  The time limit is a hang guard, not a timing: a command that swept first would not
    finish within it."""
    import subprocess

    from cdpr_design.model import spec

    d = spec.load(DESIGNS / f"{name}.yaml")
    step = min(d.workspace.grid.step) / 200
    (tmp_path / picture).write_text("mine\n")
    r = subprocess.run([sys.executable, "-m", "cdpr_design", "workspace", str(DESIGNS / f"{name}.yaml"),
                        "--step", f"{step:g}", "--force", "--out", str(tmp_path), "--quiet"],
                       capture_output=True, text=True, env=subprocess_env(), timeout=600)
    assert r.returncode == 2 and f"{tmp_path / picture} exists and was not written" in r.stderr, r.stderr
    assert [p.name for p in tmp_path.iterdir()] == [picture]  # was: refused after the sweep
    assert (tmp_path / picture).read_text() == "mine\n"
