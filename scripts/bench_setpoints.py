"""Benchmark of real-cable set-points along a path and of the massive-cable simulation.

Sampling (``trajectory``): the paper's slow square on planar2 (8,121 samples
at 1 ms) with ideal, elastic and sagging cables, and, as the baseline measured
in the same process, the sagging statics of the same samples one pose at a
time through the per-pose kernel (``tests/reference_pose.py``'s ``sagging_pose``)
in a Python loop.  Reports samples/s, the sagging cost relative to the ideal
sampling and the batched kernel's speed-up over the per-pose loop; the first
(cold) call includes numba's compile or its on-disk cache load, the others
are warm (best of 3).

Simulation (``simulate``): the paper's fast square with ideal, elastic and
sagging cables (16 segments each), wall and CPU time and the CPU ratio to the
ideal run.

Run: python scripts/bench_setpoints.py [--no-sim]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cdpr_design.model import spec  # noqa: E402
from cdpr_design.motion import run, trajectory  # noqa: E402
from cdpr_design.statics.robot import combinations  # noqa: E402
from tests.reference_pose import sagging_pose  # noqa: E402


def timed(fn, repeat=3):
    """(cold time [s], best warm time [s], result)."""
    t0 = time.perf_counter()
    res = fn()
    cold = time.perf_counter() - t0
    warm = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        warm.append(time.perf_counter() - t0)
    return cold, min(warm), res


def per_pose_loop(design, samples):
    """The sagging statics of every sample through the per-pose function (the baseline)."""
    st = trajectory.states(design, samples.pose, samples.velocity, samples.acceleration, time=samples.time)
    combos = combinations(design.m, design.n)
    out = np.empty((len(samples), design.m))
    for j in range(len(samples)):
        _, _, _, _, _, state = sagging_pose(design, design.full_pose(samples.pose[j]),
                                            st["wrench"][j:j + 1].copy(), combos, 0)
        out[j] = state.unstretched_lengths
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-sim", action="store_true", help="skip the simulation runs")
    args = ap.parse_args()
    base = spec.load(ROOT / "designs" / "planar2.yaml")
    designs = {m: base if m == "ideal" else spec.with_cable_model(base, m) for m in ("ideal", "elastic", "sagging")}
    print("trajectory square_slow on planar2 (samples/s; cold includes compile or cache load)")
    warm_ideal = None
    for m, d in designs.items():
        cold, warm, s = timed(lambda d=d: trajectory.sample(d, "square_slow"))
        warm_ideal = warm_ideal or warm
        print(f"  {m:8s} {len(s):6d} samples  cold {cold:7.3f} s  warm {warm:7.4f} s  "
              f"{len(s) / warm:10,.0f} samples/s  x{warm / warm_ideal:5.1f} the ideal")
    d = designs["sagging"]
    s = trajectory.sample(d, "square_slow")
    t0 = time.perf_counter()
    ref = per_pose_loop(d, s)
    loop = time.perf_counter() - t0
    _, warm, _ = timed(lambda: trajectory.sample(d, "square_slow"))
    assert np.allclose(ref, s.cables.unstretched, rtol=1e-12, equal_nan=True)
    print(f"  per-pose loop (baseline) {loop:7.3f} s  {len(s) / loop:10,.0f} samples/s; "
          f"batched sampling is {loop / warm:5.1f}x faster (whole sampling against the loop alone)")
    if args.no_sim:
        return
    print("simulate square_fast on planar2")
    t_ideal = None
    for m, d in designs.items():
        samples = trajectory.sample(d, "square_fast", hold_end=0.5)
        t0, c0 = time.perf_counter(), time.process_time()
        res = run.simulate(d, samples)
        t, c = time.perf_counter() - t0, time.process_time() - c0
        t_ideal = t_ideal or c
        sub = f", {res.settings['cable_segments']} segments per cable" if "cable_segments" in res.settings else ""
        print(f"  {m:8s} wall {t:7.2f} s  cpu {c:7.2f} s  x{c / t_ideal:5.1f} the ideal's cpu{sub}")


if __name__ == "__main__":
    main()
