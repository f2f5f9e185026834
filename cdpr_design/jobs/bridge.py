"""The ``bridge`` job: gateway between a PLC and the simulated robot over ADS, logged to bridge.csv.

Set-up (settings, the PLC's address, an optional built-in test PLC playing a
spec trajectory), connection with retries, the run (:func:`cdpr_design.plc.bridge.run`)
under a Ctrl-C handler that asks the loop to stop, and ``bridge.json``.
A PLC that cannot be reached raises :class:`~cdpr_design.plc.ads.PlcLinkError`;
a PLC lost during the run ends it with ``stopped == "plc_lost"`` (the log is kept).
"""

from __future__ import annotations

import math
import signal
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, NamedTuple

from cdpr_design.errors import STOP_SIGNALS, InputError
from cdpr_design.io.files import OutputDir
from cdpr_design.io.tables import fmt
from cdpr_design.jobs.common import output_dir
from cdpr_design.jobs.motion import design_samples, require_trajectory
from cdpr_design.jobs.tables import Timings


class BridgeRun(NamedTuple):
    result: object  # plc.bridge.BridgeResult
    summary: dict  # the ``bridge --json`` object (also bridge.json)
    cycle_time: float  # [s]
    out: OutputDir


def _settings(design, cycle_time, duration, reconnect, timeout) -> tuple[float, float]:
    """(cycle time, ADS timeout) [s] after checking every setting."""
    dt = float(cycle_time if cycle_time is not None else design.plc.cycle_time)
    if not (math.isfinite(dt) and 1e-4 <= dt <= 10):
        raise InputError(f"--cycle-time: expected 0.0001 to 10 s, got {dt}")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise InputError(f"--duration: expected a positive number of seconds, got {duration}")
    if reconnect < 0:
        raise InputError(f"--reconnect: expected a count >= 0, got {reconnect}")
    tmo = float(timeout) if timeout is not None else max(5 * dt, 0.05)
    if not (math.isfinite(tmo) and tmo > 0):
        raise InputError(f"--timeout: expected a positive number of seconds, got {timeout}")
    return dt, tmo


class _Endpoint(NamedTuple):
    host: str
    net_id: str
    port: int
    local_net_id: str | None


def _check_net_ids(design, local_net_id: str | None) -> None:
    """``--local-net-id`` is an AMS net id, else exit 2 naming it (the spec's ``plc.ams_net_id``
    was checked when the spec was read)."""
    from cdpr_design.model.limits import net_id_problem

    if local_net_id is not None and (problem := net_id_problem(local_net_id)) is not None:
        raise InputError(f"--local-net-id: {problem}")


def _endpoint(design, test_plc: str | None, local_net_id: str | None) -> _Endpoint:
    """Where the PLC is: the built-in test PLC on the loopback (its port is known once it has
    started: see :func:`_session`), else the spec's plc section (the net ids checked first)."""
    from cdpr_design.plc.testplc import LOOPBACK, TEST_LOCAL_NET_ID, TEST_PLC_NET_ID

    _check_net_ids(design, local_net_id)
    if test_plc is not None:
        return _Endpoint(LOOPBACK, TEST_PLC_NET_ID, design.plc.port, local_net_id or TEST_LOCAL_NET_ID)
    host = design.plc.host or ".".join(design.plc.ams_net_id.split(".")[:4])
    return _Endpoint(host, design.plc.ams_net_id, design.plc.port, local_net_id)


@contextmanager
def _stop_on_signal():
    """A stop flag set by the first Ctrl-C, SIGTERM or SIGHUP (a second one interrupts); the
    handlers restored after."""
    stop = {"flag": False}

    def on_signal(signum, frame):
        if stop["flag"]:
            raise KeyboardInterrupt
        stop["flag"] = True

    old = {s: signal.signal(s, on_signal) for s in STOP_SIGNALS}
    try:
        yield stop
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def _connect(transport, reconnect: int, stop: dict, log: Callable[[str], None]) -> None:
    """Connect, retrying ``reconnect`` times with back-off 0.1 s doubling to 2 s."""
    from cdpr_design.plc.transport import PlcLinkError

    wait = 0.1
    for attempt in range(reconnect + 1):
        try:
            transport.connect()
            return
        except PlcLinkError as exc:
            if attempt == reconnect or stop["flag"]:
                raise
            log(f"{exc}; retrying in {wait:.2g} s")
            time.sleep(wait)
            wait = min(2 * wait, 2.0)


def _row_logger(log_file, rows, timings: Timings):
    """``on_row`` of the run: one bridge.csv line per cycle, flushed every 0.1 s of model time;
    the time it takes goes to ``timings.write_s``."""
    last_flush = [0.0]

    def on_row(sp, state):
        t = time.perf_counter()
        log_file.write(",".join(fmt(v) for v in rows.values(sp, state)) + "\n")
        now = state.time
        if now - last_flush[0] >= 0.1:
            log_file.flush()
            last_flush[0] = now
        timings.write_s += time.perf_counter() - t

    return on_row


def _summary(design, res, rows, plc_log, test_plc) -> dict:
    """``bridge.json``: the run's summary, its delays (PLC and model views) and the test PLC's."""
    from cdpr_design.plc.delay import axis_delays

    summary = res.summary()
    summary["delay"] = res.delay(design.cable_names)  # set-point read -> motion written (PLC view)
    summary["delay_model"] = rows.delay()  # bridge.csv: model time (what compare reports)
    if plc_log is not None and plc_log.shape[0] > 8:
        m = design.m
        summary["plc_delay"] = axis_delays(design.cable_names, plc_log[:, 0],
                                           plc_log[:, 1: 1 + m], plc_log[:, 1 + m: 1 + 2 * m])
    summary["name"] = design.name
    summary["test_plc"] = test_plc
    return summary


def bridge(design, test_plc: str | None = None, duration: float | None = None, cycle_time: float | None = None,
           timeout: float | None = None, reconnect: int = 0, local_net_id: str | None = None,
           out: str | Path | None = None, overwrite: bool = False,
           log: Callable[[str], None] | None = None, status: Callable[[str], None] | None = None) -> BridgeRun:
    """The ``bridge`` command: run the gateway loop, write bridge.csv and bridge.json into ``out``.

    ``test_plc``: name of a spec trajectory a built-in test PLC plays on
    127.0.0.1; ``duration`` [s] (default: that trajectory + 0.5 s, else until
    Ctrl-C); ``cycle_time`` [s] (default plc.cycle_time); ``timeout`` [s] of
    each ADS request; ``reconnect``: attempts when the PLC stops answering.
    ``log`` receives progress messages, ``status`` the link's (lost, reconnecting).
    """
    from cdpr_design.plc.symbols import PlcLayout

    if design.plc is None:
        raise InputError(f"{design.source}: plc: the spec has no plc: section (bridge needs its symbols)")
    timings = Timings()
    dt, tmo = _settings(design, cycle_time, duration, reconnect, timeout)
    where = _endpoint(design, test_plc, local_net_id)
    layout = PlcLayout.from_design(design)
    samples = plc_lengths = None
    if test_plc is not None:
        require_trajectory(design, test_plc, "--test-plc")
        samples = design_samples(design, test_plc)
        plc_lengths = _test_plc_setpoints(samples, test_plc)
        if duration is None:
            duration = samples.duration + 0.5
    out_dir = output_dir(design, out, overwrite)
    out_dir.target("bridge.csv")
    out_dir.target("bridge.json")
    log = log or (lambda msg: None)
    with _stop_on_signal() as stop:
        t0 = time.perf_counter()
        res, rows, plc_log = _session(design, layout, samples, plc_lengths, test_plc, where, dt, tmo,
                                      duration, reconnect, out_dir, stop, log, status or (lambda msg: None),
                                      timings)
        timings.sweep_s = time.perf_counter() - t0 - timings.write_s  # the loop, without its log's writing
    summary = _summary(design, res, rows, plc_log, test_plc)
    summary["timings"] = timings.as_dict()
    out_dir.write_json("bridge.json", summary)
    return BridgeRun(res, summary, dt, out_dir)


def _test_plc_setpoints(samples, name: str):
    """The set-points (k, m) [m] the test PLC plays for the sampled trajectory ``name``: those
    ``simulate`` commands (:func:`cdpr_design.motion.run.cable_setpoints`: the chords with ideal
    cables, the unstretched lengths with elastic or sagging ones, which the simulated robot's
    winches pay out).  A sample without a set-point is an :class:`InputError` naming the option."""
    from cdpr_design.motion.run import cable_setpoints

    try:
        return cable_setpoints(samples)[0]
    except ValueError as exc:
        raise InputError(f"--test-plc {name}: {exc}") from None


def _session(design, layout, samples, plc_lengths, test_plc, where, dt, timeout, duration, reconnect,
             out_dir, stop, log, status, timings):
    """Test PLC (if any, playing ``plc_lengths`` at the sample times, on a port the system
    chooses), connection (ADS requests time out after ``timeout`` [s]), the loop;
    (result, row maker, test PLC log or None).

    Whatever happens, the link is closed, the test PLC stopped and the rows
    logged so far kept in bridge.csv (every row is whole).
    """
    from cdpr_design.plc import bridge as br
    from cdpr_design.plc.ads import AdsTransport
    from cdpr_design.plc.rows import RowMaker, csv_header
    from cdpr_design.plc.testplc import TestPlc

    plc = transport = log_file = res = rows = plc_log = None
    try:
        if test_plc is not None:
            plc = TestPlc(layout, samples.time, plc_lengths, task_cycle=max(samples.cycle_time, 1e-3)).start()
            where = where._replace(host=plc.address, net_id=plc.net_id)
            log(f"test PLC on {plc.address} playing {test_plc!r} ({samples.duration:.3g} s)")
        transport = AdsTransport(layout, where.net_id, where.port, where.host, timeout=timeout,
                                 local_net_id=where.local_net_id)
        _connect(transport, reconnect, stop, log)
        sim = br.make_simulator(design, dt, transport.read_setpoints())
        rows = RowMaker(design)
        log_file = out_dir.stream("bridge.csv")
        log_file.write(",".join(csv_header(design)) + "\n")
        log(f"bridge running: {where.net_id}:{where.port} at {where.host}, cycle {dt * 1e3:.3g} ms"
            + (f", {duration:.3g} s" if duration else ", Ctrl-C to stop"))
        res = br.run(transport, sim, br.Loop(dt, duration, reconnect=reconnect),
                     on_row=_row_logger(log_file, rows, timings), should_stop=lambda: stop["flag"], on_status=status)
        if stop["flag"] and res.stopped == "stop":
            res.stopped = "interrupted"
    except KeyboardInterrupt:
        if res is None:
            raise
    finally:
        if transport is not None:
            transport.close()
        if log_file is not None:
            log_file.commit()  # every row is whole: what was logged is kept, also on failure
        if plc is not None:
            if res is not None:
                plc_log = plc.log()
            plc.stop()
    return res, rows, plc_log
