#!/usr/bin/env python3
"""Benchmark: the two CSV formatters of numeric columns, each in a fresh process, in CPU time.

What a command pays to write a table's numbers as CSV with the vectorised
numpy formatter (:mod:`cdpr_design.io.csvtext`) against the compiled one
(:mod:`cdpr_design.io.csvfast`), in a new Python process each time, as a
command runs:

* ``numpy``: import the numpy formatter, format the table;
* ``numba, cold process``: import the compiled formatter -- numba's own
  start-up and the load of its cached machine code (the cache is filled by a
  first run, as after any earlier command) -- then format the table: what a
  command pays that has not imported numba for anything else (planar2's sweep
  on the numpy engine, a trajectory, a motor sizing);
* ``numba, kernels loaded``: the same, numba imported and one cached kernel
  loaded before the clock starts: what a command pays whose sweep ran on the
  kernels (IPAnema 3);
* ``numba warm``: a second formatting in the same process.

Each figure is the least user + system CPU time of ``--repeat`` processes
(getrusage of the process, from just before the import to just after the
formatting; the table's columns are made before), so that other work on a
shared machine changes it little.  The tables are random columns shaped as
the tool writes them: planar2's ``workspace.csv`` (22,801 rows x 10 columns)
and a million rows of the same columns (and IPAnema 3's 154,440 x 24 with
``--ipanema``): positions, an integer flag, margins, tensions with a
quarter of the cells empty (NaN), lengths, angles.

    python3 scripts/bench_csv.py [--repeat 3] [--ipanema]

The figures are written into :mod:`cdpr_design.io.csvtext`'s docstring.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

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
    from cdpr_design.io.csvtext import csv_rows
t1 = cpu()
text = csv_rows(cols)
t2 = cpu()
again = csv_rows(cols)
t3 = cpu()
assert again == text
print(json.dumps({"import": t1 - t0, "format": t2 - t1, "warm": t3 - t2, "bytes": len(text)}))
"""


def child(rows: int, ncol: int, path: str, preload: bool) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", CHILD, str(rows), str(ncol), path, "1" if preload else "0"],
                         env=env, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def best(rows: int, ncol: int, path: str, preload: bool, repeat: int) -> dict:
    runs = [child(rows, ncol, path, preload) for _ in range(repeat)]
    out = {k: min(r[k] for r in runs) for k in ("import", "format", "warm")}
    out["total"] = min(r["import"] + r["format"] for r in runs)
    out["bytes"] = runs[0]["bytes"]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--ipanema", action="store_true", help="also IPAnema 3's 154,440 x 24 table")
    args = ap.parse_args()
    child(10, 3, "numba", False)  # numba's cache of the formatter filled
    tables = [("planar2", 22_801, 10), ("1M rows", 1_000_000, 10)]
    if args.ipanema:
        tables.insert(1, ("IPAnema 3", 154_440, 24))
    print(f"CPU seconds (user + system), least of {args.repeat} fresh processes; "
          "import + first format [warm format]")
    for name, rows, ncol in tables:
        np_ = best(rows, ncol, "numpy", False, args.repeat)
        cold = best(rows, ncol, "numba", False, args.repeat)
        loaded = best(rows, ncol, "numba", True, args.repeat)
        cells = rows * ncol
        print(f"\n{name}: {rows:,} rows x {ncol} columns ({cells:,} cells, {np_['bytes'] / 1e6:.1f} MB)")
        for label, t in (("numpy", np_), ("numba, cold process", cold), ("numba, kernels loaded", loaded)):
            print(f"  {label:22s} {t['total']:.3f} s = import {t['import']:.3f} + format {t['format']:.3f} "
                  f"[warm {t['warm']:.3f} s, {t['warm'] / cells * 1e9:.0f} ns/cell]")
        print(f"  numba cold / numpy {cold['total'] / np_['total']:.2f}x; "
              f"numba, kernels loaded / numpy {loaded['total'] / np_['total']:.2f}x")


if __name__ == "__main__":
    main()
