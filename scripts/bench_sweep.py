"""Benchmark of ``cdpr-design sweep`` backends on 1,000 planar2 variants.

Runs the same sweep (effector mass x upper tension limit x outlet position of
cable c2, 10 x 10 x 10 variants, the spec's own 0.01 m grid) on

- this process (``workers=1``), the baseline;
- a process pool of 1 and of 2 spawned workers;
- a Dask LocalCluster of 2 worker processes (1 thread each), started for the sweep;

checks that every backend gives the same table, and prints wall times (the
best of ``--repeat`` interleaved rounds, with the range) and ratios measured in
this run (the issue's targets: pool 2 vs 1 >= 1.7x; Dask
within 20 % of the pool).  Pools pay a fixed start-up (spawned processes
import numpy / numba / scipy and load the kernels from numba's on-disk cache);
a second, smaller sweep separates that fixed cost from the per-variant
throughput.  Also reports the worker start-up with a warm and with a cold
(empty) numba cache.

    python scripts/bench_sweep.py            # full (about 2 minutes on 2 cores)
    python scripts/bench_sweep.py --quick    # 200 variants
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cdpr_design.model import spec  # noqa: E402
from cdpr_design import batch as sw  # noqa: E402

STARTUP = """
import time; t0 = time.perf_counter()
import importlib
from cdpr_design.model import spec
from cdpr_design import workspaces as ws
ev = importlib.import_module("cdpr_design.design.evaluate")
d = spec.load({spec!r}); cat = spec.load_catalogue()
ws.load_kernels()  # what a worker of a big sweep does first (sweep._prepare_process)
from cdpr_design.kernels import parallel; parallel.set_threads(1)
t1 = time.perf_counter()
ev.evaluate(d, catalogue=cat)
t2 = time.perf_counter()
ev.evaluate(d, catalogue=cat)
t3 = time.perf_counter()
print(f"{{t1 - t0:.3f}} {{t2 - t1:.3f}} {{t3 - t2:.4f}}")
"""


def worker_startup(cache_dir: str | None) -> tuple[float, float, float]:
    env = dict(os.environ)
    if cache_dir:
        env["NUMBA_CACHE_DIR"] = cache_dir
    code = STARTUP.format(spec=str(ROOT / "designs" / "planar2.yaml"))
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout.split()
    return tuple(float(x) for x in out)


def plan_of(n_side: int):
    design = spec.load(ROOT / "designs" / "planar2.yaml")
    return sw.make_plan(design, [
        ("effector.mass", sw.parse_values(f"0.5:2:{n_side}")),
        ("tension.1", sw.parse_values(f"10:30:{n_side}")),
        ("cables.c2.outlet.0", sw.parse_values(f"1.3:1.5:{n_side}")),
    ])


def timed(plan, **kw):
    """Wall time until every row is in the caller's hands (what a sweep's caller waits for);
    the workers' exit, which overlaps the caller's next steps, is waited for afterwards so
    that it does not disturb the next run."""
    recs = []
    t = time.perf_counter()
    stats = sw.run(plan, sw.Options(), on_record=recs.append, **kw)
    wall = time.perf_counter() - t
    sw.wait_closed()
    return wall, stats, sw.table(plan, recs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="200 variants, no cold-cache start-up")
    ap.add_argument("--repeat", type=int, default=3,
                    help="rounds over the backends, interleaved; the best (least disturbed) time counts")
    args = ap.parse_args()
    sizes = [(6, "216")] if args.quick else [(10, "1,000"), (6, "216")]
    print(f"cores: {sw.default_workers()}, load average before: {os.getloadavg()[0]:.2f}")
    print("worker start-up (import + first evaluate, s; steady evaluate in brackets):")
    imp, first, steady = worker_startup(None)
    print(f"  warm numba cache: import {imp:.2f} + first evaluate {first:.2f}  [{steady * 1e3:.1f} ms]")
    if not args.quick:
        with tempfile.TemporaryDirectory() as d:
            imp, first, steady = worker_startup(d)
        print(f"  cold numba cache: import {imp:.2f} + first evaluate {first:.2f} (compiles)  "
              f"[{steady * 1e3:.1f} ms]")
    results = {}
    for n_side, label in sizes:
        plan = plan_of(n_side)
        n = len(plan)
        print(f"\n{label} variants:")
        runs = [("this process (1)", dict(workers=1)),
                ("process pool, 1 worker", dict(workers=1, pool=True)),
                ("process pool, 2 workers", dict(workers=2)),
                ("Dask LocalCluster, 2 workers", dict(workers=2, scheduler="local"))]
        ref = None
        walls: dict[str, list[float]] = {name: [] for name, _ in runs}
        for _ in range(max(1, args.repeat)):
            for name, kw in runs:
                wall, stats, tab = timed(plan, **kw)
                if ref is None:
                    ref = tab
                if tab != ref:
                    raise SystemExit(f"{name}: ROWS DIFFER from the first backend")
                walls[name].append(wall)
        for name, _ in runs:
            wall = min(walls[name])
            results[(n, name)] = wall
            spread = f"{min(walls[name]):.2f}-{max(walls[name]):.2f} s" if len(walls[name]) > 1 else ""
            print(f"  {name:30s} {wall:7.2f} s  {wall / n * 1e3:6.2f} ms/variant  ({spread}; same rows)")
        p1, p2 = results[(n, "process pool, 1 worker")], results[(n, "process pool, 2 workers")]
        s1, dk = results[(n, "this process (1)")], results[(n, "Dask LocalCluster, 2 workers")]
        print(f"  speed-up pool 2 vs pool 1: {p1 / p2:.2f}x (target >= 1.7)")
        print(f"  speed-up pool 2 vs this process: {s1 / p2:.2f}x")
        print(f"  Dask LocalCluster / pool 2: {dk / p2:.2f} (overhead {100 * (dk / p2 - 1):+.0f} %, target <= +20 %)")
        paired = sorted(d / p for d, p in zip(walls["Dask LocalCluster, 2 workers"],
                                              walls["process pool, 2 workers"]))
        if len(paired) > 1:
            print("  Dask / pool 2 round by round: " + ", ".join(f"{100 * (r - 1):+.0f} %" for r in paired))
    if len(sizes) == 2:
        big, small = len(plan_of(sizes[0][0])), len(plan_of(sizes[1][0]))
        print(f"\nfixed cost and throughput from the {big} and {small} variant sweeps "
              "(wall = fixed + n x per-variant):")
        per = {}
        for name in ("this process (1)", "process pool, 1 worker", "process pool, 2 workers",
                     "Dask LocalCluster, 2 workers"):
            a, b = results[(big, name)], results[(small, name)]
            slope = (a - b) / (big - small)
            per[name] = slope
            print(f"  {name:30s} fixed {a - slope * big:5.2f} s, {slope * 1e3:6.2f} ms/variant")
        print(f"  throughput pool 2 vs pool 1: {per['process pool, 1 worker'] / per['process pool, 2 workers']:.2f}x; "
              f"Dask vs pool 2 per variant: {per['Dask LocalCluster, 2 workers'] / per['process pool, 2 workers']:.2f}")
    print(f"\nload average after: {os.getloadavg()[0]:.2f} (other work on the machine skews the ratios)")


if __name__ == "__main__":
    main()
