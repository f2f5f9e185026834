"""The two CSV formatters of numeric columns, each in a fresh process, in CPU time.

What a command pays to write a table's numbers as CSV cell by cell with Python's format
(Python's format a column at a time, :func:`cdpr_design.io.tables.cell_rows`) against the compiled one (:mod:`cdpr_design.io.csvfast`), in a new
Python process each time, as a command runs:

* ``cells``: format the table a column at a time with Python's format;
* ``numba, cold process``: import the compiled formatter -- numba's own start-up and the load of
  its cached machine code (the cache filled by a first run) -- then format the table: what a
  command pays that has not imported numba for anything else;
* ``numba, kernels loaded``: the same, numba imported and one cached kernel loaded before the
  clock starts: what a command pays whose sweep ran on the kernels;
* warm: a second formatting in the same process.

Each figure is user + system CPU of the process (from just before the import to just after the
formatting; the columns are made before), in interleaved rounds.  The tables are random columns
shaped as the tool writes them: planar2's ``workspace.csv`` (22,801 x 10), IPAnema 3's (154,440 x
24) and a million rows of 10 columns.
"""

from __future__ import annotations

from benchmarks import harness as h

OPTIONS = {"tables": (("planar2", 22_801, 10), ("IPAnema 3", 154_440, 24), ("1M rows", 1_000_000, 10))}
QUICK = {"tables": (("planar2", 22_801, 10), ("IPAnema 3", 154_440, 24))}

#: Runs in the child: make the columns, then time import + format (+ a warm second format).
CHILD = r"""
import json, resource, sys
import numpy as np

rows, ncol, path, preload = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4] == "1"
rng = np.random.default_rng(1)
cols = []
for j in range(ncol):
    kind = j % 5
    if kind == 0:  # positions [m]
        cols.append(rng.uniform(-3.0, 3.0, rows).round(6))
    elif kind == 1:  # a flag
        cols.append(rng.integers(0, 2, rows))
    elif kind == 2:  # margins, tensions [N]: a quarter empty
        c = rng.lognormal(3.0, 2.0, rows)
        c[rng.random(rows) < 0.25] = np.nan
        cols.append(c)
    elif kind == 3:  # lengths [m]
        cols.append(rng.uniform(0.1, 5.0, rows))
    else:  # angles [rad]
        cols.append(rng.normal(0.0, 0.5, rows))
if preload:  # a sweep on the kernels has run: numba imported, a cached kernel loaded
    from cdpr_design.kernels.geometry import rotation

    rotation(0.1, 0.2, 0.3, np.empty((3, 3)))


def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


t0 = cpu()
if path == "numba":
    from cdpr_design.io.csvfast import csv_rows
else:
    from cdpr_design.io.tables import cell_rows as csv_rows
t1 = cpu()
text = csv_rows(cols)
t2 = cpu()
again = csv_rows(cols)
t3 = cpu()
assert again == text
print(json.dumps({"import": t1 - t0, "format": t2 - t1, "warm": t3 - t2, "bytes": len(text)}))
"""




def child(rows: int, ncol: int, path: str, preload: bool) -> dict:
    return h.child_json(CHILD, str(rows), str(ncol), path, "1" if preload else "0")


def run(b: h.Bench) -> None:
    child(10, 3, "numba", False)  # numba's cache of the formatter filled
    for name, rows, ncol in b.opt["tables"]:
        out = {}

        def variant(path, preload):
            r = child(rows, ncol, path, preload)
            out.setdefault((path, preload), []).append(r)
            return h.Timing(r["import"] + r["format"], r["import"] + r["format"])

        t = h.rounds({"cells": lambda: variant("cells", False), "cold": lambda: variant("numba", False),
                      "loaded": lambda: variant("numba", True)}, b.rounds)
        cells = rows * ncol
        label = f"CSV of {name}'s table, {rows:,} x {ncol} ({cells / 1e6:.2g} M cells)"

        def warm(key):
            return min(r["warm"] for r in out[key]) / cells * 1e9

        b.row(f"{label}: numba, cold process", f"{h.spread(x.cpu for x in t['cold']).text()} CPU-s",
              h.ratios(t["cells"], t["cold"], "cpu"), "Python's format, fresh process (CPU)")
        b.row(f"{label}: numba, kernels loaded", f"{h.spread(x.cpu for x in t['loaded']).text()} CPU-s, warm "
              f"{warm(('numba', True)):.0f} ns a cell (Python's format {warm(('cells', False)):.0f})",
              h.ratios(t["cells"], t["loaded"], "cpu"), "Python's format, fresh process (CPU)")
