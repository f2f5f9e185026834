"""The PLC gateway: drive the simulated robot from a controller in real time.

This is the seed paper's *loop A* (Rivera, Garrido, Riveiro, Silva,
"Environment for the Design and Automation of New CDPR Architectures",
Sec. 3, Fig. 4): the controller computes the axis set-points, a gateway
carries them to the simulated robot and carries the simulated axis positions
back.  The paper's gateway (Python between TwinCAT/ADS and CoppeliaSim over
websockets) delayed the simulated axes by 110-150 ms behind the target
(its Table 1).  Here the simulation runs in the gateway's own process and
each cycle costs two ADS round trips (a sum read and a sum write).

Each cycle of :func:`run` (period ``cycle_time``, wall-clock paced against an
absolute schedule so that errors do not accumulate):

1. read the set-points (cable lengths) from the PLC,
2. advance the physics model by the elapsed periods with the set-points held,
3. write back actual lengths, tensions, pose, heartbeat (+1 per cycle) and
   the fault flag,
4. hand the row to ``on_row`` (the command line streams it to ``bridge.csv``).

A cycle that ends after the next cycle's start is an *overrun*: the missed
periods are skipped (the model still advances by the real elapsed time, so
it stays in real time).  A PLC that stops answering (every request has a
timeout) is given up after ``max_missed`` consecutive failed cycles: the
fault flag is raised where the link still allows it, and the run stops
(or reconnects with exponential back-off when asked).  The core touches no
file: logging is the caller's ``on_row``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .plc import PlcLinkError, SymbolError, Transport

# ----------------------------------------------------------------------------
# Streaming statistics (bounded memory on runs of any length)
# ----------------------------------------------------------------------------

_EDGES = np.logspace(-7, 2, 901)  # 1e-7 .. 1e2 s, 1 % bins


class StreamStats:
    """Mean, max and p99 of a stream of durations [s] in bounded memory.

    The percentile comes from a histogram with logarithmic bins 1 % wide
    (1e-7 s to 100 s), so it is exact to within 1 %.
    """

    def __init__(self):
        self.count = 0
        self.total = 0.0
        self.max = 0.0
        self.hist = np.zeros(_EDGES.size + 1, dtype=np.int64)

    def add(self, v: float) -> None:
        self.count += 1
        self.total += v
        if v > self.max:
            self.max = v
        self.hist[int(np.searchsorted(_EDGES, v))] += 1

    def percentile(self, q: float) -> float:
        if not self.count:
            return math.nan
        k = int(np.searchsorted(np.cumsum(self.hist), math.ceil(q / 100 * self.count)))
        if k == 0:
            return float(_EDGES[0])
        if k >= _EDGES.size:
            return self.max
        return float(min(_EDGES[k], self.max))  # upper edge of the bin

    def summary(self) -> dict:
        if not self.count:
            return {"mean": None, "p99": None, "max": None, "count": 0}
        return {"mean": self.total / self.count, "p99": self.percentile(99.0),
                "max": self.max, "count": self.count}


# ----------------------------------------------------------------------------
# Result
# ----------------------------------------------------------------------------


@dataclass
class BridgeResult:
    """What a bridged run did.

    Attributes
    ----------
    cycles : int
        Cycles completed (set-points read, model advanced, outputs written).
    overruns : int
        Cycles that ended after the next cycle's start.
    cycle_time : float
        Nominal period [s].
    latency : StreamStats
        Duration of each PLC round trip [s] (a read or a write request).
    exchange : StreamStats
        Read + write per cycle [s]: what the gateway spends on the PLC.
    jitter : StreamStats
        |actual - scheduled| start of each cycle [s].
    work : StreamStats
        Whole cycle work (exchange + model step + logging) [s].
    stopped : str
        ``duration``, ``stop`` (asked to), ``interrupted`` (Ctrl-C),
        ``plc_lost`` or ``error``.
    error : str or None
        Why the run stopped, when it was not asked to.
    reconnects : int
        Successful reconnections.
    fault_raised : bool
        The fault flag was set in the PLC.
    sim_time : float
        Simulated time at the end [s].
    """

    cycle_time: float
    cycles: int = 0
    overruns: int = 0
    missed: int = 0
    latency: StreamStats = field(default_factory=StreamStats)
    exchange: StreamStats = field(default_factory=StreamStats)
    jitter: StreamStats = field(default_factory=StreamStats)
    work: StreamStats = field(default_factory=StreamStats)
    stopped: str = "duration"
    error: str | None = None
    reconnects: int = 0
    fault_raised: bool = False
    sim_time: float = 0.0
    elapsed: float = 0.0
    round_trips: int = 2

    @property
    def ok(self) -> bool:
        return self.stopped in ("duration", "stop")

    def summary(self) -> dict:
        """JSON-ready figures (cli.md ``bridge`` keys plus extras)."""
        lat = self.latency.summary()
        return {
            "cycles": self.cycles,
            "overruns": self.overruns,
            "cycle_time": self.cycle_time,
            "latency": {k: lat[k] for k in ("mean", "p99", "max")},
            "exchange": _strip(self.exchange.summary()),
            "jitter": _strip(self.jitter.summary()),
            "work": _strip(self.work.summary()),
            "round_trips_per_cycle": self.round_trips,
            "missed": self.missed,
            "stopped": self.stopped,
            "error": self.error,
            "reconnects": self.reconnects,
            "fault_raised": self.fault_raised,
            "sim_time": self.sim_time,
            "elapsed_s": self.elapsed,
        }


def _strip(d: dict) -> dict:
    return {k: d[k] for k in ("mean", "p99", "max")}


# ----------------------------------------------------------------------------
# The loop
# ----------------------------------------------------------------------------


def _wait_until(deadline: float, clock, sleep, spin: float) -> None:
    """Sleep until ``deadline`` (clock seconds); spin the last ``spin`` seconds."""
    while True:
        rest = deadline - clock()
        if rest <= 0:
            return
        if rest > spin:
            sleep(rest - spin)
        elif spin > 0:
            while clock() < deadline:
                pass
            return
        else:
            sleep(rest)


def run(transport: Transport, simulator, *, cycle_time: float, duration: float | None = None,
        on_row: Callable | None = None, should_stop: Callable[[], bool] | None = None,
        max_missed: int = 3, reconnect: int = 0, backoff: tuple[float, float] = (0.1, 2.0),
        spin: float = 2e-4, on_status: Callable[[str], None] | None = None,
        clock=time.perf_counter, sleep=time.sleep) -> BridgeResult:
    """Run the gateway loop until ``duration``, a stop request, Ctrl-C or a lost PLC.

    Parameters
    ----------
    transport : Transport
        Already connected (:meth:`Transport.connect` checked its symbols).
    simulator : object
        ``advance(setpoint_lengths, duration)`` and ``state()`` returning an
        object with ``time`` [s], ``pose``, ``lengths`` [m] and ``tensions`` [N]
        (:class:`cdpr_design.simulation.Simulator`).
    cycle_time : float
        Period [s].
    duration : float, optional
        Stop after this much simulated (= wall-clock) time [s].
    on_row : callable, optional
        ``on_row(setpoints, state)`` after each cycle (logging).
    should_stop : callable, optional
        Polled each cycle; True ends the run (``stopped="stop"``).
    max_missed : int
        Consecutive failed cycles after which the PLC counts as lost.
    reconnect : int
        Reconnection attempts per outage (0: none), with back-off doubling
        from ``backoff[0]`` up to ``backoff[1]`` seconds.  The model does
        not advance while the link is down.
    spin : float
        Busy-wait the last ``spin`` seconds before each cycle start (the OS
        sleep overshoots by ~0.1 ms) [s].

    Returns
    -------
    BridgeResult
        Never raises for a lost PLC or Ctrl-C (see ``stopped``);
        :class:`SymbolError` on reconnection propagates.
    """
    dt = float(cycle_time)
    if not dt > 0:
        raise ValueError("cycle_time must be positive")
    res = BridgeResult(cycle_time=dt, round_trips=getattr(transport, "round_trips", 2))
    layout = transport.layout
    state = simulator.state()
    sp = np.asarray(state.lengths, dtype=float).copy()
    heartbeat = 0
    missed = 0
    t_wall0 = clock()
    k = 0                      # periods since the (re)started schedule
    k_prev = -1                # the previous cycle's k
    seg_time0 = float(state.time)   # model time at the schedule origin
    issue_rel, issue_sp, issue_vel, issue_sp0 = 0.0, sp.copy(), np.zeros_like(sp), sp.copy()
    t0 = t_wall0               # schedule origin
    sim_time0 = float(state.time)
    end_time = None if duration is None else sim_time0 + float(duration)
    status = on_status or (lambda msg: None)
    try:
        while True:
            if should_stop is not None and should_stop():
                res.stopped = "stop"
                break
            if end_time is not None and float(state.time) >= end_time - 1e-9:
                res.stopped = "duration"
                break
            deadline = t0 + k * dt
            _wait_until(deadline, clock, sleep, spin)
            start = clock()
            res.jitter.add(abs(start - deadline))
            # 1. set-points
            try:
                new_sp = transport.read_setpoints()
                t1 = clock()
                res.latency.add(t1 - start)
                if new_sp.shape == sp.shape and np.all(np.isfinite(new_sp)):
                    sp = new_sp
                link_ok = True
            except PlcLinkError as err:
                t1 = clock()
                link_ok = False
                last_err = str(err)
            # 2. the model: catch up over skipped periods with the last set-point
            #    ramp still running (as a servo does without new set-points), then
            #    issue the new set-point with its velocity over the schedule time
            #    since the last read (the PLC's clock is the wall clock).
            now_rel = float(state.time) - seg_time0
            gap = k * dt - now_rel
            if k_prev >= 0 and gap > 1e-9 and not _past(state, end_time):
                tau = now_rel - issue_rel
                gap = gap if end_time is None else min(gap, end_time - float(state.time))
                simulator.advance(issue_sp + issue_vel * tau, gap, velocity=issue_vel)
            if k_prev >= 0 and link_ok:
                vel = (sp - issue_sp0) / ((k - k_prev) * dt)
            else:
                vel = np.zeros_like(sp)
            k_prev = k
            state = simulator.state()
            step = dt
            if end_time is not None:
                step = min(step, end_time - float(state.time))
            issue_rel = float(state.time) - seg_time0
            issue_sp, issue_vel, issue_sp0 = sp.copy(), vel, sp.copy()
            if step > 1e-12:
                simulator.advance(sp, step, velocity=vel)
            state = simulator.state()
            # 3. outputs
            if link_ok:
                heartbeat = (heartbeat + 1) & 0xFFFFFFFF
                try:
                    t2 = clock()
                    transport.write_outputs(layout.pack_outputs(
                        state.lengths, state.tensions, state.pose, heartbeat, False))
                    t3 = clock()
                    res.latency.add(t3 - t2)
                    res.exchange.add((t1 - start) + (t3 - t2))
                except PlcLinkError as err:
                    link_ok = False
                    last_err = str(err)
            if link_ok:
                missed = 0
            else:
                missed += 1
                res.missed += 1
            res.cycles += 1
            if on_row is not None:
                on_row(sp, state)
            end = clock()
            res.work.add(end - start)
            # pacing: skip the periods this cycle ran into
            k += 1
            if end > t0 + k * dt:
                res.overruns += 1
                k = int(math.floor((end - t0) / dt)) + 1
            if missed >= max_missed:
                res.fault_raised = transport.raise_fault() or res.fault_raised
                status(f"PLC lost after {missed} failed cycles: {last_err}")
                if not _reconnect(transport, reconnect, backoff, res, status, sleep, should_stop):
                    res.stopped = "plc_lost"
                    res.error = last_err
                    break
                missed = 0
                t0, k, k_prev = clock(), 0, -1
                seg_time0 = float(state.time)
    except KeyboardInterrupt:
        res.stopped = "interrupted"
    finally:
        res.sim_time = float(state.time) - sim_time0
        res.elapsed = clock() - t_wall0
    return res


def _past(state, end_time) -> bool:
    return end_time is not None and float(state.time) >= end_time - 1e-9


def _reconnect(transport, attempts, backoff, res, status, sleep, should_stop) -> bool:
    """Close and reopen the link up to ``attempts`` times with back-off."""
    wait = backoff[0]
    for i in range(attempts):
        if should_stop is not None and should_stop():
            return False
        transport.close()
        status(f"reconnecting in {wait:.2g} s (attempt {i + 1} of {attempts})")
        sleep(wait)
        try:
            transport.connect()
        except SymbolError:
            raise
        except PlcLinkError as err:
            status(f"reconnection failed: {err}")
            wait = min(2 * wait, backoff[1])
            continue
        res.reconnects += 1
        status("reconnected")
        return True
    transport.close()
    return False


# ----------------------------------------------------------------------------
# Rows of bridge.csv (the simulation.csv layout) and the delay of a run
# ----------------------------------------------------------------------------


def csv_header(design) -> list[str]:
    """``bridge.csv`` columns: the ``simulation.csv`` layout (cli.md ``simulate``)."""
    coords = list(design.motion.coords)
    names = design.cable_names
    return (["time"] + [f"{c}_target" for c in coords] + coords
            + [f"length_{c}_target" for c in names] + [f"length_{c}" for c in names]
            + [f"tension_{c}" for c in names])


def motion_pose(design, pose) -> np.ndarray:
    """A simulator pose (motion coordinates or the full 6-vector) in motion coordinates."""
    p = np.asarray(pose, dtype=float).reshape(-1)
    k = len(design.motion.coords)
    if p.size == k:
        return p
    if p.size == 6:
        return p[list(design.motion.pose_index)]
    raise ValueError(f"simulator pose has {p.size} numbers, expected {k} or 6")


class RowMaker:
    """Turns (set-points, simulator state) into ``bridge.csv`` rows.

    The target pose is the forward kinematics of the set-point lengths
    (closed form for the paper's planar 2-cable robot, eq. 4-5), warm-started
    from the previous target.  Keeps the last ``keep`` (time, target lengths,
    actual lengths) in memory for :meth:`delay`.
    """

    def __init__(self, design, keep: int = 1 << 20):
        from .kinematics import forward_kinematics

        self.design = design
        self._fk = forward_kinematics
        self._guess = None
        self._last_sp = None
        self._last_target = None
        m = design.m
        self.keep = int(keep)
        self._buf = np.empty((min(self.keep, 4096), 1 + 2 * m))
        self.n = 0

    def target_pose(self, sp) -> np.ndarray:
        if self._last_sp is not None and np.array_equal(sp, self._last_sp):
            return self._last_target
        try:
            r = self._fk(self.design, sp, guess=self._guess)
            p = np.asarray(r.pose, dtype=float)
        except (ValueError, ArithmeticError):
            p = np.full(len(self.design.motion.coords), np.nan)
        if np.all(np.isfinite(p)):
            self._guess = p
        self._last_sp, self._last_target = np.array(sp, copy=True), p
        return p

    def values(self, sp, state) -> list[float]:
        t = float(state.time)
        sp = np.asarray(sp, dtype=float)
        lengths = np.asarray(state.lengths, dtype=float)
        row = [t, *self.target_pose(sp), *motion_pose(self.design, state.pose), *sp, *lengths,
               *np.asarray(state.tensions, dtype=float)]
        if self.n < self.keep:
            if self.n == self._buf.shape[0]:
                self._buf = np.concatenate([self._buf, np.empty_like(self._buf)])[: self.keep]
            self._buf[self.n, 0] = t
            self._buf[self.n, 1:] = np.concatenate([sp, lengths])
            self.n += 1
        return row

    def delay(self) -> dict:
        """Delay [s] of each simulated axis behind its set-point, keyed ``length_<cable>``.

        Cross-correlation of the logged set-point and actual length
        (:func:`cdpr_design.compare.estimate_delay`); None where an axis did
        not move.
        """
        return axis_delays(self.design.cable_names, self._buf[: self.n, 0],
                           self._buf[: self.n, 1: 1 + self.design.m],
                           self._buf[: self.n, 1 + self.design.m:])


def axis_delays(names, t, target, actual, max_delay: float = 1.0) -> dict:
    """Per-axis delay [s] of ``actual`` behind ``target`` (NaN-free dict, None where unknown)."""
    from .compare import estimate_delay, resample, uniform_grid

    out = {f"length_{c}": None for c in names}
    t = np.asarray(t, float)
    if t.size < 8:
        return out
    grid = uniform_grid(t)
    dt = float(grid[1] - grid[0]) if grid.size > 1 else 0.0
    if not dt > 0:
        return out
    md = min(max_delay, 0.45 * (grid[-1] - grid[0]))
    for j, c in enumerate(names):
        x = resample(t, target[:, j], grid)
        y = resample(t, actual[:, j], grid)
        d = estimate_delay(dt, x, y, max_delay=md)
        out[f"length_{c}"] = float(d) if np.isfinite(d) else None
    return out


def make_simulator(design, cycle_time: float, initial_lengths=None):
    """The physics model the gateway drives (:class:`cdpr_design.simulation.Simulator`).

    Started at rest at the forward kinematics of ``initial_lengths`` (the
    PLC's first set-points), so the first cycle does not jerk the robot.
    """
    from .simulation import Simulator

    sim = Simulator(design)
    pose = None
    if initial_lengths is not None:
        from .kinematics import forward_kinematics

        try:
            pose = forward_kinematics(design, initial_lengths).pose
        except ValueError:
            pose = None
    sim.reset(pose)
    return sim
