"""The PLC gateway (bridge) against the loopback test PLC.

For 10 ms and 1 ms gateway cycles on the fast square (planar2, 1000 mm/s): the per-round-trip ADS
latency (mean / p99 / max) and the PLC exchange per cycle (a sum read and a sum write), overruns
and start jitter; the end-to-end delay as the PLC sees it (target set-point in the PLC -> simulated
axis position back in the PLC, cross-correlation of the test PLC's own 1 ms log), the delay of the
same simulation run offline (no gateway), and their difference: what the gateway adds (the seed
paper's gateway added 110-150 ms, its Table 1).  As a baseline in the same process, one cycle's
exchange with one request per symbol through handles against the two sum requests.

The test PLC listens on a free port of 127.0.0.1 the system chooses.
"""

from __future__ import annotations

import time

import yaml

from benchmarks import harness as h

OPTIONS = {"seconds": None, "cycles": (0.01, 0.001), "exchanges": 2000}
QUICK = {"cycles": (0.01,), "exchanges": 500}


def design_on_loopback():
    from cdpr_design.model import spec
    from cdpr_design.plc.testplc import LOOPBACK, TEST_PLC_NET_ID

    data = yaml.safe_load((h.ROOT / "designs" / "planar2.yaml").read_text())
    data["plc"] = {
        "ams_net_id": TEST_PLC_NET_ID, "host": LOOPBACK, "port": 851, "cycle_time": 0.01,
        "setpoints": ["MAIN.fCableLen1", "MAIN.fCableLen2"],
        "actuals": ["MAIN.fSimLen1", "MAIN.fSimLen2"], "tensions": ["MAIN.fSimT1", "MAIN.fSimT2"],
        "pose": "MAIN.aSimPose", "heartbeat": "MAIN.nSimHeartbeat", "fault": "MAIN.bSimFault"}
    return spec.from_dict(data)


def ms(v):
    return "—" if v is None else f"{v * 1e3:.3f} ms"


def transport(layout, plc, mode: str = "sum"):
    """A connected ADS transport to the test PLC ``plc``."""
    from cdpr_design.plc.ads import AdsTransport
    from cdpr_design.plc.testplc import TEST_LOCAL_NET_ID

    tr = AdsTransport(layout, plc.net_id, 851, plc.address, timeout=0.2, local_net_id=TEST_LOCAL_NET_ID, mode=mode)
    tr.connect()
    return tr


def exchange_only(layout, plc, mode: str, n: int) -> float:
    """Mean time [s] of one read + write exchange, no simulation."""
    tr = transport(layout, plc, mode)
    vals = layout.pack_outputs([1.0, 1.0], [5.0, 5.0], [0.7, 0.8], 1, False)
    for _ in range(50):
        tr.read_setpoints()
        tr.write_outputs(vals)
    t = time.perf_counter()
    for _ in range(n):
        tr.read_setpoints()
        tr.write_outputs(vals)
    out = (time.perf_counter() - t) / n
    tr.close()
    return out


def run(b: h.Bench) -> None:
    from cdpr_design.motion import run as motion_run
    from cdpr_design.motion import trajectory
    from cdpr_design.plc import bridge as br
    from cdpr_design.plc.delay import axis_delays
    from cdpr_design.plc.rows import RowMaker
    from cdpr_design.plc.symbols import PlcLayout
    from cdpr_design.plc.testplc import TestPlc
    from cdpr_design.statics.robot import Analysis, resolve

    d = design_on_loopback()
    layout = PlcLayout.from_design(d)
    samples = trajectory.sample(resolve(d, Analysis(command="motion")), "square_fast")
    seconds = b.opt["seconds"] or samples.duration + 0.5
    off = motion_run.simulate(resolve(d, Analysis(command="motion")), samples).summary()["delay"]
    with TestPlc(layout, samples.time, samples.lengths) as plc:
        t = h.rounds({"sum": lambda: exchange_only(layout, plc, "sum", b.opt["exchanges"]),
                      "handles": lambda: exchange_only(layout, plc, "handles", b.opt["exchanges"] // 2)}, b.rounds)
    b.row("ADS exchange a cycle, sum read + sum write (2 round trips)", ms(h.best(t["sum"])),
          h.ratios(t["handles"], t["sum"]), f"one request per symbol through handles ({len(layout.symbols)} round trips)")
    for dt in b.opt["cycles"]:
        with TestPlc(layout, samples.time, samples.lengths) as plc:
            tr = transport(layout, plc)
            sim = br.make_simulator(d, dt, tr.read_setpoints())
            rows = RowMaker(d)
            res = br.run(tr, sim, br.Loop(dt, seconds), on_row=lambda sp, st: rows.values(sp, st))
            log = plc.log()
            tr.close()
        s = res.summary()
        plc_delay = axis_delays(d.cable_names, log[:, 0], log[:, 1:3], log[:, 3:5])
        gw_delay = res.delay(d.cable_names)
        stats = ", ".join(f"{label} {ms(s[key]['mean'])} (p99 {ms(s[key]['p99'])}, max {ms(s[key]['max'])})"
                          for key, label in (("latency", "round trip"), ("exchange", "exchange a cycle"),
                                             ("work", "whole cycle"), ("jitter", "start jitter")))
        b.say(f"cycle {dt * 1e3:g} ms: {s['cycles']} cycles, {s['overruns']} overruns, {s['elapsed_s']:.2f} s, model "
              f"lag max {s['lag']['max'] * 1e3:.3f} ms, {s['slips']} slips; {stats}")
        for c in ("length_c1", "length_c2"):
            tot, base = plc_delay[c], off.get(c)
            add = None if tot is None or base is None else tot - base
            b.row(f"bridge at a {dt * 1e3:g} ms cycle, {c}: delay the gateway adds",
                  f"{ms(add)} (seen by the PLC {ms(tot)}, offline {ms(base)}, gateway's estimate {ms(gw_delay[c])})",
                  h.spread([0.110 / add]) if add else None, "the seed paper's gateway (110 ms, the low end)")
