"""Benchmark of the PLC gateway (bridge) against the loopback test PLC.

Prints, for 10 ms and 1 ms gateway cycles on the paper's fast square
(planar2, 1000 mm/s):

- per-round-trip ADS latency (mean / p99 / max) and the PLC exchange per cycle
  (sum read + sum write), overruns and start jitter;
- the end-to-end delay as the PLC sees it (target set-point in the PLC ->
  simulated axis position back in the PLC, cross-correlation of the test
  PLC's own 1 ms log, as TwinCAT's scope in the seed paper), the delay of the
  same simulation run offline (no gateway), and their difference: what the
  gateway adds.  The seed paper's gateway added 110-150 ms (its Table 1).

And, as a baseline measured in the same process, the exchange of one cycle
with one request per symbol through handles against the two sum requests.

Run: python scripts/bench_bridge.py [--seconds S]
(binds 127.0.0.1:48898: do not run it alongside the bridge tests).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import yaml

from cdpr_design.plc import bridge as br
from cdpr_design.motion import run
from cdpr_design.model import spec
from cdpr_design.motion import trajectory
from cdpr_design.plc.ads import AdsTransport
from cdpr_design.plc.delay import axis_delays
from cdpr_design.plc.rows import RowMaker
from cdpr_design.plc.symbols import PlcLayout
from cdpr_design.plc.testplc import LOOPBACK, TEST_LOCAL_NET_ID, TEST_PLC_NET_ID, TestPlc

ROOT = Path(__file__).resolve().parents[1]


def design_on_loopback():
    data = yaml.safe_load((ROOT / "designs" / "planar2.yaml").read_text())
    data["plc"] = {
        "ams_net_id": TEST_PLC_NET_ID, "host": LOOPBACK, "port": 851, "cycle_time": 0.01,
        "setpoints": ["MAIN.fCableLen1", "MAIN.fCableLen2"],
        "actuals": ["MAIN.fSimLen1", "MAIN.fSimLen2"], "tensions": ["MAIN.fSimT1", "MAIN.fSimT2"],
        "pose": "MAIN.aSimPose", "heartbeat": "MAIN.nSimHeartbeat", "fault": "MAIN.bSimFault"}
    return spec.from_dict(data)


def ms(v):
    return "   —  " if v is None else f"{v * 1e3:7.3f}"


def exchange_only(layout, mode: str, n: int) -> float:
    """Mean time [s] of one read + write exchange, no simulation."""
    tr = AdsTransport(layout, TEST_PLC_NET_ID, 851, LOOPBACK, timeout=0.2,
                      local_net_id=TEST_LOCAL_NET_ID, mode=mode)
    tr.connect()
    vals = layout.pack_outputs([1.0, 1.0], [5.0, 5.0], [0.7, 0.8], 1, False)
    for _ in range(50):
        tr.read_setpoints()
        tr.write_outputs(vals)
    t = time.perf_counter()
    for i in range(n):
        tr.read_setpoints()
        tr.write_outputs(vals)
    out = (time.perf_counter() - t) / n
    tr.close()
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=None, help="run length (default: the square + 0.5 s)")
    args = ap.parse_args()
    d = design_on_loopback()
    layout = PlcLayout.from_design(d)
    samples = trajectory.sample(d, "square_fast")
    seconds = args.seconds or samples.duration + 0.5

    t = time.perf_counter()
    off = run.simulate(d, samples).summary()["delay"]
    print(f"offline simulation (no gateway) of square_fast: {time.perf_counter() - t:.2f} s wall")
    off_delay = {k: off.get(k) for k in ("length_c1", "length_c2")}

    print("\nADS exchange per cycle, no simulation (same process):")
    with TestPlc(layout, samples.time, samples.lengths):
        t_sum = exchange_only(layout, "sum", 2000)
        t_hnd = exchange_only(layout, "handles", 1000)
    print(f"  sum read + sum write (2 round trips): {t_sum * 1e3:.3f} ms")
    print(f"  handles, one request per symbol ({len(layout.symbols)} round trips): "
          f"{t_hnd * 1e3:.3f} ms  (ratio handles/sum {t_hnd / t_sum:.2f})")

    for dt in (0.01, 0.001):
        with TestPlc(layout, samples.time, samples.lengths) as plc:
            tr = AdsTransport(layout, TEST_PLC_NET_ID, 851, LOOPBACK, timeout=0.2,
                              local_net_id=TEST_LOCAL_NET_ID)
            tr.connect()
            sim = br.make_simulator(d, dt, tr.read_setpoints())
            rows = RowMaker(d)
            res = br.run(tr, sim, cycle_time=dt, duration=seconds,
                         on_row=lambda sp, st: rows.values(sp, st))
            log = plc.log()
            tr.close()
        s = res.summary()
        plc_delay = axis_delays(d.cable_names, log[:, 0], log[:, 1:3], log[:, 3:5])
        gw_delay = res.delay(d.cable_names)
        print(f"\ncycle {dt * 1e3:g} ms: {s['cycles']} cycles, {s['overruns']} overruns, "
              f"{s['elapsed_s']:.2f} s, model lag max {s['lag']['max'] * 1e3:.3f} ms, "
              f"{s['slips']} slips; load average {open('/proc/loadavg').read().split()[0]}")
        print("                      mean     p99      max   [ms]")
        for key, label in (("latency", "round trip"), ("exchange", "exchange/cycle"),
                           ("work", "whole cycle"), ("jitter", "start jitter")):
            v = s[key]
            print(f"  {label:16s} {ms(v['mean'])} {ms(v['p99'])} {ms(v['max'])}")
        for c in ("length_c1", "length_c2"):
            tot, base = plc_delay[c], off_delay[c]
            add = None if tot is None or base is None else tot - base
            print(f"  {c}: gateway's estimate (read -> written, held) {ms(gw_delay[c])} ms")
            print(f"  {c}: delay seen by the PLC {ms(tot)} ms, offline {ms(base)} ms, "
                  f"gateway adds {ms(add)} ms  (paper: 110-150 ms; ratio "
                  f"{'—' if add is None else f'{add / 0.110:.3f}'} of 110 ms)")


if __name__ == "__main__":
    main()
