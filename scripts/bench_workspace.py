#!/usr/bin/env python3
"""Benchmark: the planar2 static workspace sweep, numba kernel vs vectorised numpy.

Both compute, for every grid pose, the cable lengths, the structure matrix,
the tensions t = W^-1 w, feasibility under the bounds and the closed-form
capacity margin.  They run in the same process on the same grid (default
0.001 m: 2,253,001 poses) and must agree; the script prints poses/s and the
ratio.  It also times the whole `cdpr-design workspace designs/planar2.yaml`
command with a cold numba cache (a fresh NUMBA_CACHE_DIR: compile time
included) and a warm one.

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

from cdpr_design import spec  # noqa: E402
from cdpr_design import workspace as ws  # noqa: E402


def numpy_sweep(design, grid, chunk=1 << 18):
    """The same computation as the kernel, vectorised over poses with numpy."""
    A = design.outlets[:, :2]
    B = design.attachments[:, :2]
    w = ws.wrench_vertices(design, "static")[0]
    tmin, tmax = design.tension_min, design.tension_max
    total = grid.size
    feas = np.empty(total, dtype=np.uint8)
    margin = np.empty(total)
    T = np.empty((total, 2))
    L = np.empty((total, 2))
    for start in range(0, total, chunk):
        n = min(chunk, total - start)
        p = ws.grid_positions(grid, start, n)
        vec = A[None] - p[:, None, :] - B[None]          # (n, 2 cables, 2)
        Ln = np.linalg.norm(vec, axis=2)
        u = vec / Ln[:, :, None]
        det = u[:, 0, 0] * u[:, 1, 1] - u[:, 1, 0] * u[:, 0, 1]
        inv = np.empty((n, 2, 2))
        inv[:, 0, 0] = u[:, 1, 1] / det
        inv[:, 0, 1] = -u[:, 1, 0] / det
        inv[:, 1, 0] = -u[:, 0, 1] / det
        inv[:, 1, 1] = u[:, 0, 0] / det
        t = inv @ w
        rn = np.linalg.norm(inv, axis=2)
        s = (np.minimum(t - tmin, tmax - t) / rn).min(axis=1)
        # rank deficient (a zero-length cable or parallel cables): no margin, infeasible
        singular = (Ln.min(axis=1) <= 1e-12) | ~(np.abs(det) > 1e-10)
        s[singular] = np.nan
        ok = s >= 0
        feas[start:start + n] = ok
        margin[start:start + n] = s
        T[start:start + n] = np.where(ok[:, None], t, np.nan)
        L[start:start + n] = Ln
    return feas, margin, T, L


def kernel_sweep(design, grid):
    out = {}

    def keep(c):
        out.setdefault("f", []).append(c.feasible)
        out.setdefault("m", []).append(c.margin)
        out.setdefault("t", []).append(c.tensions)

    r = ws.run(design, grid=grid, on_chunk=keep, keep_maps=False)
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
    env = dict(os.environ, **env_extra)
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
    ws.run(design, step=0.1)  # load the kernels (cache) before timing

    import numba

    print(f"planar2 static workspace, step {args.step} m: {grid.size:,} poses, "
          f"numba threads {numba.get_num_threads()}")
    tk, (r, fk, mk, Tk) = best(lambda: kernel_sweep(design, grid), args.repeat)
    tstats, _ = best(lambda: ws.run(design, grid=grid, keep_maps=False), args.repeat)
    tn, (fn, mn, Tn, _) = best(lambda: numpy_sweep(design, grid), args.repeat)
    assert np.array_equal(fk, fn), "feasibility differs"
    assert np.allclose(mk, mn, rtol=1e-9, atol=1e-12, equal_nan=True), "margins differ"
    assert np.allclose(Tk, Tn, rtol=1e-9, atol=1e-12, equal_nan=True), "tensions differ"
    rows = [
        ("numba sweep (stats only)", tstats),
        ("numba sweep + rows to the caller", tk),
        ("vectorised numpy, same computation", tn),
    ]
    print(f"{'':38s} {'time [s]':>9s} {'Mposes/s':>9s} {'x numpy':>8s}")
    for name, t in rows:
        print(f"{name:38s} {t:9.3f} {grid.size / t / 1e6:9.2f} {tn / t:8.1f}")
    print(f"feasible: {r.feasible:,} ({100 * r.fraction:.2f} %), identical in both versions")
    if not args.no_cli:
        with tempfile.TemporaryDirectory() as tmp:
            cold = cli_time({"NUMBA_CACHE_DIR": os.path.join(tmp, "numba-cache")}, os.path.join(tmp, "a"))
            warm = [cli_time({}, os.path.join(tmp, "b")) for _ in range(3)]
        print(f"`cdpr-design workspace designs/planar2.yaml`: cold numba cache {cold:.2f} s, "
              f"warm {min(warm):.2f} s (best of 3)")


if __name__ == "__main__":
    main()
