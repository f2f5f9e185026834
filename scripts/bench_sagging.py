#!/usr/bin/env python3
"""Benchmark: sagging-cable workspaces of CoGiRo and IPAnema 3 against scipy and the ideal model.

For each design (designs/cogiro.yaml, designs/ipanema3.yaml) the static
workspace on the design's own grid (39,729 and 55,936 poses) is swept with
sagging cables through :func:`cdpr_design.workspaces.run`, the library call
behind ``cdpr-design workspace`` (the batched numba kernel
:func:`cdpr_design.kernels.sagging.sweep_grid_sagging`, parallel over poses):

* cold: the first sweep in a fresh process (numba's on-disk cache loaded, or
  compiled with ``--fresh-cache``), one child process per design and model;
* warm: the best of ``--repeat`` sweeps in this process;
* ideal: the same grid with ideal (straight, massless) cables, cold and warm:
  the cost of the sagging model relative to the ideal one;
* scipy: the robot-level problem solved pose by pose with ``scipy.optimize.fsolve``
  (``least_squares`` as a fallback) by the independent reference of
  tests/test_sagging.py (Irvine's closure as printed, force and moment balance,
  the minimum-norm conditions with the active bounds of the straight solution
  found by scipy's SLSQP, updated until the KKT conditions hold) on a random
  sample of the grid's poses (those with a straight solution within the
  bounds), timed per pose, in the same process: the ratio
  scipy / kernel per pose (conservative: the kernel's whole sweep time divided
  by its converged poses only, though the infeasible ones cost it time too),
  and how well the two agree.

poses/s are wall-clock with numba's threads (2 on the reference machine); as
the machine may be shared, the CPU time of the sweep is printed too, and
``2 / CPU s per pose`` is the rate two idle cores would reach.

Cable properties: a design with its own sagging properties keeps them;
otherwise every cable gets a 4 mm steel rope (issue 15: 0.6 N/m, EA = 1e6 N),
given through the raw spec (``cable.model: sagging``).

Usage:  python scripts/bench_sagging.py [--repeat 3] [--n-scipy 150] [--fresh-cache] [--seed 1]
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

DESIGNS = ("cogiro", "ipanema3")
#: 4 mm steel rope of issue 15: 0.6 N/m, EA = 1e6 N
STEEL_4MM = {"mass_per_length": 0.6 / 9.81, "axial_stiffness": 1e6}


def load(name: str, model: str):
    """designs/<name>.yaml with ``model`` cables (sagging: the design's properties, else STEEL_4MM)."""
    from cdpr_design.model import spec

    design = spec.load(ROOT / "designs" / f"{name}.yaml")
    if model == "ideal":
        return spec.with_cable_model(design, "ideal")
    cable = design.cables[0].props
    if cable.model == "sagging" and all(c.props == cable for c in design.cables):
        return design
    raw = copy.deepcopy(design.raw)
    raw["cable"] = dict(raw.get("cable") or {}, model="sagging", **STEEL_4MM)
    for c in raw["cables"]:
        for k in ("model", "mass_per_length", "axial_stiffness"):
            c.pop(k, None)
    return spec.from_dict(raw)


def sweep(design):
    """One static workspace sweep; (seconds wall, seconds CPU, result)."""
    from cdpr_design import workspaces

    t0, c0 = time.perf_counter(), time.process_time()
    res = workspaces.run(design, kind="static")
    return time.perf_counter() - t0, time.process_time() - c0, res


def child(name: str, model: str) -> None:
    """Cold: the first sweep of a fresh process, as JSON on stdout."""
    design = load(name, model)
    wall, cpu, res = sweep(design)
    print(json.dumps({"wall": wall, "cpu": cpu, "poses": res.summary()["poses"]}))


def cold(name: str, model: str, env: dict) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", name, model], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def scipy_sample(design, rng, n: int):
    """The scipy reference on up to n random grid poses where it applies: (poses, seconds, refs)."""
    from cdpr_design.workspaces import _setup
    from cdpr_design.workspaces.grid import grid_positions
    from tests.test_sagging import reference

    g, ori = _setup(design, "static", None, None, None, False)
    pos = grid_positions(g, 0, g.size)
    poses, refs, spent = [], [], 0.0
    for k in rng.permutation(g.size):
        pose = [*pos[k], *ori][: len(design.motion.coords)]
        t0 = time.perf_counter()
        ref = reference(design, pose, bounds=True)
        dt = time.perf_counter() - t0
        if ref is None:
            continue  # no straight solution within the bounds: the kernel stops at once there too
        spent += dt
        poses.append(pose)
        refs.append(ref)
        if len(poses) == n:
            break
    return poses, spent, refs


def agreement(design, poses, refs):
    """Kernel against scipy where both converged: (compared, with an active bound, agreeing to
    1e-9 of the largest tension, the largest such difference, other fixed points and how
    many of those have a kernel norm |t| no larger than the reference's).

    Near a flat direction of the minimum-norm problem (a cable at a bound, the others nearly
    free to trade tension) the sagging problem may have several self-consistent minimum-norm
    solutions (fixed points; tests/test_sagging.py checks the kernel's KKT conditions)."""
    from cdpr_design import api

    compared = active = agreed = other = smaller = 0
    worst = 0.0
    for pose, ref in zip(poses, refs):
        res = api.pose(design, pose)
        if not (ref.ok and res.feasible):
            continue
        compared += 1
        active += int(np.any(ref.active))
        d = float(np.max(np.abs(res.tensions - ref.t)) / np.max(ref.t))
        if d <= 1e-9:
            agreed += 1
            worst = max(worst, d)
        else:
            other += 1
            smaller += int(np.linalg.norm(res.tensions) <= np.linalg.norm(ref.t))
    return compared, active, agreed, worst, other, smaller


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3, help="warm sweeps per design and model (best is kept)")
    ap.add_argument("--n-scipy", type=int, default=150, help="poses per design for the scipy reference")
    ap.add_argument("--fresh-cache", action="store_true", help="cold = compilation (empty numba cache)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--child", nargs=2, metavar=("DESIGN", "MODEL"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(*args.child)
        return
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    if args.fresh_cache:
        env["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="numba-cache-")

    import numba
    from cdpr_design.kernels import parallel

    rng = np.random.default_rng(args.seed)
    threads = parallel.threads()
    print(f"numba {numba.__version__}, {threads} threads, load average {os.getloadavg()[0]:.1f}"
          + ("; fresh cache (cold = compilation)" if args.fresh_cache else ""))
    for name in DESIGNS:
        row = {}
        for model in ("sagging", "ideal"):
            design = load(name, model)
            c = cold(name, model, env)
            warm = min((sweep(design) for _ in range(args.repeat)), key=lambda r: r[0])
            row[model] = dict(cold=c, wall=warm[0], cpu=warm[1], res=warm[2], design=design)
        sag, ideal = row["sagging"], row["ideal"]
        n = sag["res"].summary()["poses"]
        status = sag["res"].extra.get("cable_status", {})
        props = sag["design"].cables[0].props
        print(f"\n{name}: {n:,} poses, sagging cables w = {props.mass_per_length * 9.81:.3g} N/m, "
              f"EA = {props.axial_stiffness:.3g} N; status {status}")
        for model, r in row.items():
            c = r["cold"]
            print(f"  {model:8s} warm {r['wall']:7.3f} s = {n / r['wall']:9,.0f} poses/s "
                  f"(CPU {r['cpu'] / n * 1e6:6.1f} us/pose -> {2 * n / r['cpu']:9,.0f} poses/s on 2 idle cores)"
                  f"   cold {c['wall']:7.3f} s = {n / c['wall']:9,.0f} poses/s")
        print(f"  sagging / ideal cost: warm {sag['wall'] / ideal['wall']:.1f}x (CPU {sag['cpu'] / ideal['cpu']:.1f}x), "
              f"cold {sag['cold']['wall'] / ideal['cold']['wall']:.1f}x")
        poses, spent, refs = scipy_sample(sag["design"], rng, args.n_scipy)
        per_scipy = spent / max(len(poses), 1)
        ok = sum(r.ok for r in refs)
        compared, active, agreed, worst, other, smaller = agreement(sag["design"], poses, refs)
        # conservative: all of the kernel's time charged to the poses that converged (status ok)
        n_ok = max(int(status.get("ok", n)), 1)
        per_wall, per_cpu = sag["wall"] / n_ok, sag["cpu"] / n_ok
        print(f"  scipy fsolve reference: {len(poses)} poses ({ok} converged), {per_scipy * 1e3:.2f} ms/pose; "
              f"of {compared} compared ({active} with a bound active) {agreed} agree with the kernel to "
              f"{worst:.1e} of the largest tension; {other} are another fixed point "
              f"({smaller} with the kernel's norm the smaller)")
        print(f"  ratio scipy / kernel per pose: {per_scipy / per_wall:,.0f}x wall ({threads} threads), "
              f"{per_scipy / per_cpu:,.0f}x per CPU second (one core); cold {per_scipy / (sag['cold']['wall'] / n_ok):,.0f}x "
              f"(kernel time per converged pose)")


if __name__ == "__main__":
    main()
