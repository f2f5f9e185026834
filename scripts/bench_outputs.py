#!/usr/bin/env python3
"""Benchmark: the whole ``workspace`` command and its kernels against per-pose scipy LP.

For IPAnema 3 on a fine grid and for planar2, all in one run on this machine:

1. the baseline: per-pose scipy ``linprog`` (HiGHS) feasibility of a random
   sample of the grid's poses, in this process, scaled to the whole grid (the
   LP answers feasibility only: no tensions, no margin, no file);
2. the kernels in this process: ``workspaces.run`` without maps or rows,
   cold (the first call: numba's on-disk cache loaded, or compiled) and warm
   (best of ``--repeat``), and the ``sweep_s`` the command reports;
3. the whole command, ``python -m cdpr_design workspace SPEC --step S --json``
   in a new process each time (start-up, spec, sweep, ``workspace.csv``,
   ``workspace.png``, ``tension_map.png``, ``summary.json``): cold (an empty
   numba cache: every kernel compiled) and warm (best of ``--repeat``), with
   ``--format csv`` and ``--format parquet``;
4. the CSV writer alone on the IPAnema 3 rows: the previous one (printf per
   row, as ``io.tables.format_block`` was) against both paths of
   :func:`cdpr_design.io.csvtext.csv_rows`, the vectorised numpy one and the
   compiled one of :mod:`cdpr_design.io.csvfast` (warm, and its first call in the
   process with numba's cache warm).

Ratios are LP time for the grid / measured time, in wall-clock time and in CPU
time (user + system, all threads and the picture process: less sensitive to
other work on a shared machine; the LP runs on one core, the kernels and the
command on two).  ``--root`` runs the command
from another checkout (e.g. the previous version, for before/after; its
summary has no ``timings``, so its ``elapsed_s`` -- which then included the CSV
formatting -- stands in for ``sweep_s``).

    python3 scripts/bench_outputs.py [--step 0.14] [--sample 300] [--repeat 3] [--root DIR] [--no-cold]

Figures (2-core development machine, shared: the load average is given with
each run; on a loaded machine the wall-clock ratios of anything using both
cores drop, the CPU ratios much less).  IPAnema 3, 154,440 poses, static:

===========================================  ==========================  ==========================
                                             before (e612e10), load 0-4  after, load 3.7
===========================================  ==========================  ==========================
per-pose linprog (wall / CPU)                2.64 / 2.64 ms              1.64 / 1.64 ms
kernels in-process, warm, wall               0.70 s = 581x LP            0.42 s = 602x LP
kernels in-process, warm, CPU                1.36 s = 301x LP CPU        0.60 s = 421x LP CPU
kernel CPU per pose, interleaved runs        5.8-6.1 us                  3.7-3.9 us
  two threads, same minute (load 4)          0.46 s (333,000 poses/s)    0.29 s (528,000 poses/s)
whole command, warm, csv: wall / CPU         5.42 s = 75x / 81x          3.21 s = 79x / 94x
  its sweep_s                                1.88 s = 217x               0.99 s = 257x
whole command, warm, parquet: wall / CPU     8.48 s = 48x / 98x          5.06 s = 50x / 89x
cold: first sweep with an empty numba cache  36 s (load 215)             57-65 s (load 290-430)
===========================================  ==========================  ==========================

The LP itself ran at 1.6-3.1 ms per pose over the day (other work on the
machine), so the ratios move with it; the per-pose CPU of the kernels is the
steadier comparison (interleaved runs of both versions, same minutes).

The cold figure (numba compiling every kernel into its cache, once per
machine) grew: the closed forms add code that every kernel calling
``hsm_factored`` compiles; measured only on a heavily loaded machine, to be
looked at again.

planar2 (22,801 poses): kernels warm 0.47 s (189x) before, 0.22 s (196x,
LP 1.85 ms) after; the whole command 3.8 s before, 2.9 s after (its start-up
and pictures, not the sweep, set it).

The CSV writer alone on the IPAnema 3 rows (3,706,560 cells, one core, load
1.2-1.4): previous writer 554 ns/cell, numpy ``csv_rows`` 94 ns/cell (5.9x),
numba ``csv_rows`` 45 ns/cell warm (12.4x the previous writer, 2.1x numpy;
2.5x in interleaved runs of the two) and 69 ns/cell on its first call (the
compiled code loaded from numba's cache).  Of the 45 ns about 37 are the
kernel, the rest the copy of the columns into a block and the final join.

Where the time goes, per IPAnema 3 pose in the kernels (one thread, CPU):
before, structure matrix 0.2-0.5 us, basis factorisation 0.6-1.4 us, margin
by hyperplane shifting 3.4-7 us (56 facets through the general enumeration),
tensions (null space + Goldfarb-Idnani) 1.1-1.5 us; after, the same except
the margin, 1.3-1.4 us (the closed forms of ``kernels.hsm_small``, the
closure test left out of static sweeps) and 0.5 us less loop overhead
(``kernels.sweep.grid_block``).  With two idle cores the 3.6-4.0 us of CPU
per pose give 516,000-541,000 poses/s (0.29 s for the grid): 1,400x an LP
of 2.64 ms per pose, 880x the 1.64 ms the LP took in the run of the table
(where the kernels themselves got 0.42 s, 600x): the 1000x target is met
only when the LP is slow and both cores are free.

The whole command: Python start-up and imports 1.2-2 s (typer and pydantic
0.5 s, numpy 0.2 s, numba 0.3 s, scipy.linalg that numba imports to look for
BLAS 0.3 s, the spec schema 0.1 s), numba's first-call set-up and cache load
0.5-1 s (counted in ``sweep_s``), the sweep 0.3-0.6 s, the CSV 0.75 s of CPU
on one core after the sweep (the grid is one chunk), the two pictures 0.6 and
0.8 s of CPU in the helper process (matplotlib's text and axis layout, not
the 154,440 cells, which are one ``imshow``).  These fixed costs put the
whole command at 3.2 s (79x an LP of 1.64 ms, 120x one of 2.64 ms): the
200x target for the whole process is not met.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cdpr_design import workspaces as ws  # noqa: E402
from cdpr_design.model import spec  # noqa: E402
from cdpr_design.statics import kinematics as kin  # noqa: E402
from cdpr_design.workspaces.grid import grid_positions  # noqa: E402


def lp_poses(design, grid, count, rng) -> list[list[float]]:
    """A random sample of ``count`` poses of the grid (the LP baseline's poses)."""
    idx = np.sort(rng.choice(grid.size, size=min(count, grid.size), replace=False))
    ori = list(design.workspace.orientation or [])
    return [list(grid_positions(grid, int(i), 1)[0]) + ori for i in idx]


def lp_seconds_per_pose(design, poses) -> tuple[float, float]:
    """Mean (wall, CPU) time [s] of one per-pose linprog feasibility check over ``poses``."""
    from scipy.optimize import linprog

    bounds = list(zip(design.tension_min, design.tension_max))
    t0, c0 = time.perf_counter(), time.process_time()
    for pose in poses:
        W = kin.structure_matrix(design, pose)
        w = kin.required_wrench(design, pose)
        linprog(np.zeros(design.m), A_eq=W, b_eq=w, bounds=bounds, method="highs")
    return (time.perf_counter() - t0) / len(poses), (time.process_time() - c0) / len(poses)


def _timed(fn, cpu: bool = False):
    t0, c0 = time.perf_counter(), time.process_time()
    fn()
    wall = time.perf_counter() - t0
    return (wall, time.process_time() - c0) if cpu else wall


def command(root: Path, spec_path: Path, step: float | None, fmt: str, out: str, cache: str | None):
    """Wall time [s] of one ``workspace`` process and its summary."""
    env = _env(root)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = cache
    args = [sys.executable, "-m", "cdpr_design", "workspace", str(spec_path), "--out", out, "--json", "--overwrite"]
    if step is not None:
        args += ["--step", str(step)]
    if fmt != "csv":
        args += ["--format", fmt]
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = subprocess.run(args, env=env, cwd=root, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode:
        raise SystemExit(f"{' '.join(args)} failed ({r.returncode}): {r.stderr[-500:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return (wall, cpu), json.loads(r.stdout)


def _env(root: Path) -> dict:
    """The commands' environment: ``root`` first on the path, and Python's bytecode cache
    allowed (an installed package has its ``.pyc`` files; a machine set to
    ``PYTHONDONTWRITEBYTECODE`` would otherwise compile every module of the package from
    source in every run, 0.3-0.5 s)."""
    env = dict(os.environ, PYTHONPATH=str(root))
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


FLOOR = {
    "python start-up": "pass",
    "python, numpy": "import numpy",
    "python, numpy, numba, a small cached kernel's first call": ("import numpy as np; from cdpr_design.kernels.linalg import det_small; "
                                                "det_small(np.eye(2), 2)"),
    "python, the command's modules (no numba)": "import cdpr_design.cli.app, cdpr_design.jobs.workspace",
    "python, matplotlib.pyplot (the picture process)": "import matplotlib; matplotlib.use('Agg'); import matplotlib.pyplot",
}


def floor_times(root: Path, repeat: int) -> list[tuple[str, float]]:
    """Best wall time [s] of a fresh process doing only each of :data:`FLOOR`: the fixed
    costs under every command, whatever its grid."""
    out = []
    for what, code in FLOOR.items():
        args = [sys.executable, "-c", code]
        subprocess.run(args, env=_env(root), cwd=root, check=True)  # bytecode and numba cache written
        best = min(_timed(lambda: subprocess.run(args, env=_env(root), cwd=root, check=True))
                   for _ in range(repeat))
        out.append((what, best))
    return out


def sweep_s(summary: dict) -> float:
    return summary["timings"]["sweep_s"] if "timings" in summary else summary["elapsed_s"]


def previous_format_block(columns, int_cols) -> str:
    """The previous CSV writer of workspace rows: one printf per row, NaN cells removed by a regex."""
    ints = set(int_cols)
    fmt = ",".join("%d" if j in ints else "%.10g" for j in range(len(columns)))
    block = np.column_stack([np.asarray(c, dtype=float) for c in columns])
    text = "\n".join([fmt % row for row in map(tuple, block.tolist())]) + "\n"
    return re.sub(r"(?<![^,\n])-?(?:nan|inf)(?![^,\n])", "", text)


def _prime_csv_kernel() -> None:
    """numba's on-disk cache of the compiled CSV formatter filled, by another process."""
    code = "import numba, numpy; from cdpr_design.io.csvfast import numba_rows; numba_rows([numpy.ones(3)])"
    subprocess.run([sys.executable, "-c", code], env=dict(os.environ, PYTHONPATH=str(ROOT)), check=True)


def writer_times(design, grid, repeat: int) -> dict:
    """Seconds to format every row of the grid as CSV text, and the cell count (``cells``).

    ``previous``: printf per row; ``numpy``: :func:`cdpr_design.io.csvtext.numpy_rows`;
    ``numba_cold``: the first call of :func:`cdpr_design.io.csvfast.numba_rows` in this
    process (numba's cache warm: loaded, not compiled); ``numba``: warm (best of ``repeat``)."""
    from cdpr_design.io import csvfast
    from cdpr_design.io.csvtext import numpy_rows

    _prime_csv_kernel()
    chunks = []
    ws.run(design, grid=grid, keep_maps=False, on_chunk=chunks.append)

    def cols(c):
        return ([c.poses[:, j] for j in range(c.poses.shape[1])] + [c.feasible, c.margin]
                + [c.tensions[:, i] for i in range(c.tensions.shape[1])] + [c.lengths[:, i] for i in range(c.lengths.shape[1])])

    k = chunks[0].poses.shape[1]
    out = {"numba_cold": _timed(lambda: [csvfast.numba_rows(cols(c)) for c in chunks])}
    out["previous"] = min(_timed(lambda: [previous_format_block(cols(c), [k]) for c in chunks]) for _ in range(repeat))
    out["numpy"] = min(_timed(lambda: [numpy_rows(cols(c)) for c in chunks]) for _ in range(repeat))
    out["numba"] = min(_timed(lambda: [csvfast.numba_rows(cols(c)) for c in chunks]) for _ in range(repeat))
    out["cells"] = sum(len(cols(c)) * len(c.feasible) for c in chunks)
    return out


def print_writer_times(t: dict) -> None:
    cells = t["cells"]

    def ns(what):
        return f"{t[what]:.3f} s ({t[what] / cells * 1e9:.0f} ns/cell)"

    print(f"\nCSV of the IPAnema 3 rows ({cells:,} cells): previous writer {ns('previous')}, numpy csv_rows "
          f"{ns('numpy')}, numba csv_rows warm {ns('numba')}, cold (first call, cache warm) {ns('numba_cold')}: "
          f"numba {t['previous'] / t['numba']:.1f}x the previous writer, {t['numpy'] / t['numba']:.1f}x numpy; "
          f"numpy {t['previous'] / t['numpy']:.1f}x the previous writer")


def bench_design(name: str, step: float | None, args, rng) -> dict:
    """Rounds of (LP, kernels warm, whole commands, LP again) for one design; prints the table.

    The machine's speed drifts (the LP took 1.6-3.1 ms a pose between runs of one day on
    the shared machine), so every round times the LP around what it is compared with, and
    each ratio is taken within its round; the table gives the median round and the range.
    """
    path = ROOT / "designs" / f"{name}.yaml"
    d = spec.load(path)
    g = ws.make_grid(d, step)
    poses = lp_poses(d, g, args.sample, rng)
    root = Path(args.root).resolve() if args.root else ROOT
    fmts = ("csv", "parquet") if not args.root else ("csv",)
    label = f"{name} ({g.size:,} poses, step {step or d.workspace.grid.step[0]} m)"
    print(f"\n{label}: per-pose linprog over {len(poses)} poses, {args.repeat} rounds", flush=True)
    first_call = _timed(lambda: ws.run(d, grid=g, keep_maps=False), cpu=True)
    measures: dict[str, list] = {}  # what -> [(wall, cpu or None, LP wall, LP cpu)], one per round

    def add(what, wall, cpu, lp):
        measures.setdefault(what, []).append((wall, cpu, lp[0], lp[1]))

    best = {}
    with tempfile.TemporaryDirectory() as tmp:
        if args.cold:
            lp = lp_seconds_per_pose(d, poses)
            (wall, cpu), s = command(root, path, step, "csv", f"{tmp}/cold", tempfile.mkdtemp(dir=tmp))
            add("whole command, cold numba cache (csv)", wall, cpu, lp)
            add("  its load_s (numba compiling)", s.get("timings", {}).get("load_s", 0.0), None, lp)
        for fmt in fmts:
            command(root, path, step, fmt, f"{tmp}/prime", None)  # numba's cache and the bytecode warm
        add("kernels in-process, first call", *first_call, lp_seconds_per_pose(d, poses))
        for _ in range(args.repeat):
            before = lp_seconds_per_pose(d, poses)
            kw = _timed(lambda: ws.run(d, grid=g, keep_maps=False), cpu=True)
            runs = {fmt: command(root, path, step, fmt, f"{tmp}/{fmt}", None) for fmt in fmts}
            after = lp_seconds_per_pose(d, poses)
            lp = ((before[0] + after[0]) / 2, (before[1] + after[1]) / 2)
            add("kernels in-process, warm", *kw, lp)
            for fmt, ((wall, cpu), s) in runs.items():
                add(f"whole command, warm ({fmt})", wall, cpu, lp)
                add(f"  its sweep_s ({fmt})", sweep_s(s), None, lp)
                if fmt not in best or wall < best[fmt][0]:
                    best[fmt] = (wall, s)
    lps = [r[2] for r in measures["kernels in-process, warm"]]
    print(f"  per-pose linprog {min(lps) * 1e3:.2f}-{max(lps) * 1e3:.2f} ms over the rounds "
          f"({np.median(lps) * g.size:.1f} s for the grid at the median)")
    for fmt, (wall, s) in best.items():
        if "timings" in s:
            t = s["timings"]
            load = f"load {t['load_s']:.3f} s, " if "load_s" in t else ""
            print(f"  {fmt}: timings of the fastest run: {load}sweep {t['sweep_s']:.3f} s, write {t['write_s']:.3f} s, "
                  f"pictures {t['pictures_s']:.3f} s, job total {t['total_s']:.3f} s; process {wall:.3f} s")
    print(f"  {'what (median round)':40s} {'wall [s]':>9s} {'poses/s':>10s} {'x LP (range)':>20s} {'CPU [s]':>8s} "
          f"{'x LP CPU':>9s}")
    for what, rounds in measures.items():
        ratios = sorted(lpw * g.size / w for w, _, lpw, _ in rounds)
        wall, cpu, _, lpc = sorted(rounds)[len(rounds) // 2]
        ratio_text = f"{np.median(ratios):7.1f} ({ratios[0]:.0f}-{ratios[-1]:.0f})"
        cpu_text = f"{cpu:8.3f} {lpc * g.size / cpu:9.1f}" if cpu else ""
        print(f"  {what:40s} {wall:9.3f} {g.size / wall:10,.0f} {ratio_text:>20s} {cpu_text}")
    return measures


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=0.14, help="IPAnema 3 grid step [m] (0.14: 154,440 poses)")
    ap.add_argument("--planar2-step", type=float, default=0.002, help="planar2's fine grid step [m]")
    ap.add_argument("--sample", type=int, default=300, help="poses of the per-pose LP baseline")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--root", help="checkout whose command is timed (default: this one)")
    ap.add_argument("--no-cold", dest="cold", action="store_false", help="skip the cold-cache command")
    args = ap.parse_args(argv)
    import numba

    rng = np.random.default_rng(0)
    print(f"numba threads {numba.get_num_threads()}, load average {os.getloadavg()[0]:.2f}; command from "
          f"{args.root or ROOT}")
    root = Path(args.root).resolve() if args.root else ROOT
    print("\nfixed costs of a process (best of --repeat, wall):")
    for what, t in floor_times(root, args.repeat):
        print(f"  {what:58s} {t:7.3f} s")
    bench_design("ipanema3", args.step, args, rng)
    bench_design("planar2", None, args, rng)
    bench_design("planar2", args.planar2_step, args, rng)
    d = spec.load(ROOT / "designs" / "ipanema3.yaml")
    print_writer_times(writer_times(d, ws.make_grid(d, args.step), args.repeat))


if __name__ == "__main__":
    main()
