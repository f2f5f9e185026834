#!/usr/bin/env python3
"""Benchmark: the planar2 static workspace sweep, numba kernel vs vectorised numpy.

Both compute, for every grid pose, the cable lengths, the structure matrix,
the tensions t = W^-1 w, feasibility under the bounds and the closed-form
capacity margin: the numba kernel (``_kernels.sweep_grid_planar2``) and the
package's numpy engine (``workspace._planar2_numpy``, the same formulas
vectorised over each chunk).  They run in the same process on the same grid
(default 0.001 m: 2,253,001 poses) and must agree bit for bit; the script
prints poses/s and the ratio.

It also times the whole `cdpr-design workspace designs/planar2.yaml` command
(a new process each time): as shipped (``auto``: the numpy engine for this
small grid, pictures drawn by the picture worker), with the numba engine and a
cold (empty) and warm numba cache, and without the picture worker.

    python3 scripts/bench_workspace.py [--step 0.001] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cdpr_design.model import spec  # noqa: E402
from cdpr_design import workspaces as ws  # noqa: E402


def rows_sweep(design, grid, engine):
    """A sweep handing every row back to the caller (as the CLI does for workspace.csv)."""
    out = {}

    def keep(c):
        out.setdefault("f", []).append(c.feasible)
        out.setdefault("m", []).append(c.margin)
        out.setdefault("t", []).append(c.tensions)

    r = ws.run(design, grid=grid, on_chunk=keep, keep_maps=False, engine=engine)
    return r, np.concatenate(out["f"]), np.concatenate(out["m"]), np.concatenate(out["t"])


def best(fn, repeat):
    times = []
    res = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = fn()
        times.append(time.perf_counter() - t0)
    return min(times), res


def cli_time(env_extra, out_dir):
    env = dict(os.environ, CDPR_DESIGN_ENGINE="auto", CDPR_DESIGN_PICTURE_WORKER="1")
    env.update(env_extra)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "cdpr_design", "workspace", str(ROOT / "designs/planar2.yaml"),
                    "--out", out_dir, "--quiet", "--json"], check=True, env=env, capture_output=True)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=0.001)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-cli", action="store_true", help="skip the cold/warm command timings")
    args = ap.parse_args()
    design = spec.load(ROOT / "designs/planar2.yaml")
    grid = ws.make_grid(design, args.step, force=True)
    ws.run(design, step=0.1, engine="numba")  # load the kernels (cache) before timing

    from cdpr_design.kernels import parallel

    print(f"planar2 static workspace, step {args.step} m: {grid.size:,} poses, "
          f"kernel threads {parallel.threads()}")
    tk, (r, fk, mk, Tk) = best(lambda: rows_sweep(design, grid, "numba"), args.repeat)
    tn, (_, fn, mn, Tn) = best(lambda: rows_sweep(design, grid, "numpy"), args.repeat)
    tks, _ = best(lambda: ws.run(design, grid=grid, keep_maps=False, engine="numba"), args.repeat)
    tns, _ = best(lambda: ws.run(design, grid=grid, keep_maps=False, engine="numpy"), args.repeat)
    for a, b, what in ((fk, fn, "feasibility"), (mk, mn, "margins"), (Tk, Tn, "tensions")):
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8)), f"{what} differ"
    rows = [
        ("numba kernel (stats only)", tks, tns),
        ("numba kernel + rows to the caller", tk, tn),
        ("numpy engine (stats only)", tns, tns),
        ("numpy engine + rows to the caller", tn, tn),
    ]
    print(f"{'':38s} {'time [s]':>9s} {'Mposes/s':>9s} {'x numpy':>8s}")
    for name, t, base in rows:
        print(f"{name:38s} {t:9.3f} {grid.size / t / 1e6:9.2f} {base / t:8.1f}")
    print(f"feasible: {r.feasible:,} ({100 * r.fraction:.2f} %), bit-identical in both engines")
    if not args.no_cli:
        print("\n`cdpr-design workspace designs/planar2.yaml` (new process, wall clock; best of 3 when warm):")
        with tempfile.TemporaryDirectory() as tmp:
            def warm(env, tag):
                return min(cli_time(env, os.path.join(tmp, f"{tag}{k}")) for k in range(3))

            cache = {"NUMBA_CACHE_DIR": os.path.join(tmp, "numba-cache")}
            shipped = warm({}, "a")
            no_worker = warm({"CDPR_DESIGN_PICTURE_WORKER": "0"}, "b")
            cold = cli_time({**cache, "CDPR_DESIGN_ENGINE": "numba"}, os.path.join(tmp, "c"))
            numba_warm = warm({**cache, "CDPR_DESIGN_ENGINE": "numba"}, "d")
        print(f"  as shipped (numpy engine, picture worker)  {shipped:5.2f} s")
        print(f"  without the picture worker                  {no_worker:5.2f} s")
        print(f"  numba engine, cold numba cache (compiles)   {cold:5.2f} s")
        print(f"  numba engine, warm numba cache              {numba_warm:5.2f} s")


if __name__ == "__main__":
    main()
