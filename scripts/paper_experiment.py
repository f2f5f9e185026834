"""Reproduce the seed paper's experiment in simulation and print its Tables 1 and 2.

Rivera, Garrido, Riveiro, Silva, "Environment for the Design and Automation of
New CDPR Architectures", section 4: the planar 2-cable robot runs a square
path at 100 and 1000 mm/s; Table 1 gives the time delay of each axis behind
its target, Table 2 the mean target and mean actual height of the upper and
lower horizontal segments with the position error in %.

Here the robot is the MuJoCo model of ``designs/planar2.yaml`` (rigid 1 kg
effector free to swing and tilt, elastic cables that never push, winch axes
with a position loop), run twice per speed:

- **direct**: set-points reach the axes at once (the role of the paper's
  industrial prototype, loop B, which showed 20-30 ms);
- **delayed**: a 130 ms transport delay on the set-points (the role of the
  paper's simulated model behind its ADS / Python / WebSocket path, loop A,
  which showed 110-150 ms).

Usage::

    python scripts/paper_experiment.py [--delay 0.13] [--json]

Prints the tables in the paper's layout with the paper's figures beside
ours, and the wall time of each run (simulated seconds per wall second).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cdpr_design.motion.run import simulate
from cdpr_design.model import spec
from cdpr_design.statics.robot import Analysis, resolve  # noqa: E402
from cdpr_design.motion import trajectory  # noqa: E402

#: The paper's Table 1 [ms]: velocity -> (simulated axis 1, axis 2, prototype axis 1, axis 2).
PAPER_T1 = {100: (150, 120, 20, 30), 1000: (130, 110, 20, 20)}
#: The paper's Table 2 [mm, %]: velocity -> rows (target, simulated, error %, target, prototype, error %, diff %).
PAPER_T2 = {
    100: [(947.613, 946.016, 0.168, 947.613, 948.670, 0.112, 0.057),
          (749.578, 750.183, 0.081, 749.582, 748.844, 0.098, -0.017)],
    1000: [(948.046, 945.437, 0.275, 948.035, 945.879, 0.227, 0.048),
           (749.594, 750.510, 0.122, 749.600, 746.090, 0.468, -0.346)],
}


def run(design, name: str, delay: float) -> dict:
    samples = trajectory.sample(resolve(design, Analysis(command="motion")), name, hold_end=0.5 + delay)
    t0 = time.perf_counter()
    res = simulate(resolve(design, Analysis(command="motion")), samples, delay=delay)
    wall = time.perf_counter() - t0
    s = res.summary()
    s["wall_s"] = wall
    s["simulated_s"] = float(samples.time[-1])
    return s


def horizontal(summary: dict) -> list[dict]:
    """The y (horizontal) segments, upper first as in the paper."""
    rows = [r for r in summary["segments"] if r["axis"] == "y"]
    return sorted(rows, key=lambda r: -r["mean_target"])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spec", default=str(ROOT / "designs" / "planar2.yaml"))
    ap.add_argument("--delay", type=float, default=0.13, help="transport delay of the delayed runs [s]")
    ap.add_argument("--json", action="store_true", help="print the raw summaries as JSON")
    args = ap.parse_args(argv)
    design = spec.load(args.spec)
    runs = {}
    for vel, name in ((100, "square_slow"), (1000, "square_fast")):
        for label, d in (("direct", 0.0), ("delayed", args.delay)):
            runs[vel, label] = run(design, name, d)
    if args.json:
        print(json.dumps({f"{v}_{lab}": s for (v, lab), s in runs.items()}, indent=2))
        return 0

    ms = lambda v: "  —  " if v is None else f"{abs(1e3 * v) if abs(v) < 5e-5 else 1e3 * v:6.1f}"  # noqa: E731
    dl = int(round(args.delay * 1e3))
    print("Table 1. Time delay of the axis trajectories behind their targets [ms]")
    print(f"(ours: MuJoCo model direct and behind a {dl} ms transport delay; paper: simulated model and prototype)")
    print(f"{'Velocity':>9} | {'delayed ' + str(dl) + ' ms':^17} | {'direct':^17} | {'paper simulated':^17} | {'paper prototype':^17}")
    print(f"{'[mm/s]':>9} | {'Axis 1':>8} {'Axis 2':>8} | {'Axis 1':>8} {'Axis 2':>8} | {'Axis 1':>8} {'Axis 2':>8} | {'Axis 1':>8} {'Axis 2':>8}")
    for vel in (100, 1000):
        a, b = runs[vel, "delayed"]["delay"], runs[vel, "direct"]["delay"]
        p = PAPER_T1[vel]
        print(f"{vel:>9} | {ms(a['length_c1']):>8} {ms(a['length_c2']):>8} | {ms(b['length_c1']):>8} "
              f"{ms(b['length_c2']):>8} | {p[0]:>8} {p[1]:>8} | {p[2]:>8} {p[3]:>8}")
    print()
    print("Table 2. Position error of the horizontal segments of the square")
    print(f"{'Velocity':>9} | {'delayed ' + str(dl) + ' ms':^30} | {'direct':^30} | {'Error':>7} || "
          f"{'paper: simulated':^24} | {'paper: prototype':^24} | {'Error':>6}")
    print(f"{'[mm/s]':>9} | {'target':>9} {'actual':>9} {'err %':>8} | {'target':>9} {'actual':>9} {'err %':>8} | "
          f"{'diff %':>7} || {'target':>8} {'sim':>8} {'err %':>6} | {'target':>8} {'proto':>8} {'err %':>6} | {'diff %':>6}")
    for vel in (100, 1000):
        rows_d = horizontal(runs[vel, "delayed"])
        rows_0 = horizontal(runs[vel, "direct"])
        for k, (rd, r0) in enumerate(zip(rows_d, rows_0)):
            p = PAPER_T2[vel][k]
            print(f"{vel if k == 0 else '':>9} | {1e3 * rd['mean_target']:9.3f} {1e3 * rd['mean_actual']:9.3f} "
                  f"{rd['error_pct']:8.3f} | {1e3 * r0['mean_target']:9.3f} {1e3 * r0['mean_actual']:9.3f} "
                  f"{r0['error_pct']:8.3f} | {rd['error_pct'] - r0['error_pct']:7.3f} || "
                  f"{p[0]:8.3f} {p[1]:8.3f} {p[2]:6.3f} | {p[3]:8.3f} {p[4]:8.3f} {p[5]:6.3f} | {p[6]:6.3f}")
    print()
    print("Tracking and cost of each run")
    print(f"{'run':>17} | {'RMS err [mm]':>12} | {'max err [mm]':>12} | {'min T [N]':>9} | {'max tilt [deg]':>14} | "
          f"{'simulated [s]':>13} | {'wall [s]':>8} | {'x real time':>11}")
    import math

    for (vel, lab), s in runs.items():
        tmin = min(s["min_tension"].values())
        print(f"{str(vel) + ' mm/s ' + lab:>17} | {1e3 * s['rms_error']:12.3f} | {1e3 * s['max_error']:12.3f} | "
              f"{tmin:9.3f} | {math.degrees(s['max_tilt']):14.2f} | {s['simulated_s']:13.3f} | {s['wall_s']:8.2f} | "
              f"{s['simulated_s'] / s['wall_s']:11.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
