"""Benchmark: what ``workspace --accelerations`` costs against a plain sweep, in one process.

For each design: the whole workspace sweep as a command runs it (``workspaces.run``: the sweep
plan, its wrappers, the maps; no files), without and with ``accelerations=True``, back to back
in each of ``--repeat`` rounds (the kernels compiled or loaded before timing).  Prints the CPU
seconds (``time.process_time``, every thread of this process) and the wall seconds of the best
round of each, their ratio, and the median and range of the rounds' own ratios (a round's two
runs share the machine's moment); the load average before and after.

    python scripts/bench_accelerations.py                    # planar2, ipanema3
    python scripts/bench_accelerations.py --repeat 5 planar4

Measured figures: docs/performance.md.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _run(design, accelerations: bool) -> tuple[float, float]:
    from cdpr_design import workspaces as ws

    c0, t0 = time.process_time(), time.perf_counter()
    ws.run(design, keep_maps=True, tilt=False, accelerations=accelerations)
    return time.process_time() - c0, time.perf_counter() - t0


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="bench_accelerations.py")
    ap.add_argument("designs", nargs="*", default=["planar2", "ipanema3"])
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args(argv)
    import cdpr_design as cd

    print(f"load average before: {os.getloadavg()[0]:.2f}")
    print(f"{'design':12s} {'poses':>7s} {'plain cpu':>9s} {'accel cpu':>9s} {'ratio':>6s} {'plain wall':>10s} "
          f"{'accel wall':>10s} {'ratio':>6s} {'median':>6s}  range")
    for name in a.designs:
        design = cd.load(ROOT / "designs" / f"{name}.yaml")
        _run(design, True)  # compile or load every kernel first
        _run(design, False)
        plain, accel, ratios = [], [], []
        for _ in range(a.repeat):
            p = _run(design, False)
            q = _run(design, True)
            plain.append(p)
            accel.append(q)
            ratios.append(q[0] / p[0])
        bp, bq = min(plain), min(accel)
        wp, wq = min(w for _, w in plain), min(w for _, w in accel)
        print(f"{name:12s} {design.workspace.grid.size:7d} {bp[0]:9.3f} {bq[0]:9.3f} {bq[0] / bp[0]:6.2f} {wp:10.3f} "
              f"{wq:10.3f} {wq / wp:6.2f} {statistics.median(ratios):6.2f}  {min(ratios):.2f}-{max(ratios):.2f}")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
