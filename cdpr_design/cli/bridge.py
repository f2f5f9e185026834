"""``bridge``: the paper's loop A, PLC <-> simulated robot over ADS."""

from __future__ import annotations

import gc
from typing import Annotated, Optional

import typer

from cdpr_design.cli.common import (JsonOpt, OutOpt, OverwriteOpt, QuietOpt, SpecArg, command, emit_json, err,
                                    error, fmt, info, load_design, out_console, summary_table)

#: Exit status of ``bridge`` when the PLC stops answering (the run's log is kept).
EXIT_PLC_LOST = 3


def _table(design, summary: dict, cycle_time: float, files):
    lat = summary["latency"]
    return summary_table(
        f"{design.name} — bridge ({summary['stopped']})",
        [("cycles", summary["cycles"]), ("overruns", summary["overruns"]),
         ("cycle time [ms]", cycle_time * 1e3),
         ("round trip mean / p99 / max [ms]",
          " / ".join(fmt(None if v is None else v * 1e3) for v in (lat["mean"], lat["p99"], lat["max"]))),
         ("delay [ms]", ", ".join(f"{k}: {fmt(None if v is None else v * 1e3)}"
                                  for k, v in summary["delay"].items())),
         ("files", str(files))])


@command
def bridge(
    spec: SpecArg,
    test_plc: Annotated[Optional[str], typer.Option(
        "--test-plc", metavar="TRAJECTORY",
        help="Start a built-in test PLC on 127.0.0.1 that plays this spec trajectory as set-points.")] = None,
    duration: Annotated[Optional[float], typer.Option(
        "--duration", help="Stop after this many seconds (default: the test trajectory + 0.5 s; "
        "else until Ctrl-C).", min=1e-3, max=1e7)] = None,
    cycle_time: Annotated[Optional[float], typer.Option(
        "--cycle-time", help="Gateway cycle [s] (default plc.cycle_time).", min=1e-4, max=10.0)] = None,
    timeout: Annotated[Optional[float], typer.Option(
        "--timeout", help="Timeout of each ADS request [s] (default max(5 cycles, 50 ms)).", min=1e-4, max=600.0)] = None,
    reconnect: Annotated[int, typer.Option(
        "--reconnect", help="Reconnection attempts when the PLC stops answering, with back-off "
        "0.1 s doubling to 2 s (default 0: stop).", min=0, max=1000)] = 0,
    local_net_id: Annotated[Optional[str], typer.Option(
        "--local-net-id", help="AMS net id of this computer (the route the PLC knows it by).")] = None,
    out: OutOpt = None,
    json_: JsonOpt = False,
    quiet: QuietOpt = False,
    overwrite: OverwriteOpt = False,
):
    """Gateway PLC <-> simulated robot over ADS: bridge.csv (simulation.csv columns), bridge.json.

    Exit status: 0 done; 2 bad input (spec, option, a PLC symbol missing or
    mistyped: named); 3 the PLC cannot be reached or stopped answering (an
    addition to the common 0/1/2/130: the log written so far is kept);
    130 interrupted (Ctrl-C; the log is complete).
    """
    from cdpr_design.jobs import bridge as job
    from cdpr_design.plc.transport import PlcLinkError

    design = load_design(spec)
    # a real-time loop: Python's default collection thresholds (short pauses, often) rather than the
    # start-up's (cdpr_design.__main__: a pause of tens of ms every 200,000 allocations)
    gc.set_threshold(700, 10, 10)
    try:
        res, summary, dt, out_dir = job.bridge(
            design, test_plc, duration, cycle_time, timeout, reconnect, local_net_id, out, overwrite,
            log=lambda msg: info(quiet or json_, msg),  # link status (lost, reconnecting) only --quiet hides
            status=lambda msg: info(quiet, msg))
    except PlcLinkError as exc:
        error(str(exc))
        raise typer.Exit(EXIT_PLC_LOST) from None
    if json_:
        emit_json(summary)
    else:
        out_console.print(_table(design, summary, dt, out_dir.path))
    if res.stopped == "interrupted":
        err.print("interrupted")
        raise typer.Exit(130)
    if res.stopped == "plc_lost":
        error(f"PLC lost: {res.error}")
        raise typer.Exit(EXIT_PLC_LOST)


def register(app: typer.Typer) -> None:
    app.command()(bridge)
