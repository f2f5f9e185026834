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
2. re-aim the axes' reference from its current value to the set-point
   extrapolated one cycle ahead and advance the physics model there
   (continuous, piecewise-linear reference: no steps, no stale ramps),
3. write back actual lengths, tensions, pose, heartbeat (+1 per cycle) and
   the fault flag,
4. hand the row to ``on_row`` one cycle late, with the PLC's set-point at the
   row's time interpolated between the reads around it (the command line
   streams it to ``bridge.csv``).

A cycle that ends after the next cycle's start is an *overrun*: the missed
periods are skipped and the next cycle catches the model up to real time
(at most ``max_catchup`` of model time per cycle), driving the reference
straight from where it was to the new goal.  A loaded machine therefore
degrades timing (overruns, delay) but the simulated robot stays on the
commanded path: it never extrapolates a stale ramp through a stall, and a
set-point that arrives late is never a step.  A PLC that stops answering
(every request has a timeout) is given up after ``max_missed`` consecutive
failed cycles: the fault flag is raised where the link still allows it, and
the run stops (or reconnects with exponential back-off when asked).  The
command line exits with status 3 then (``cdpr-design bridge``: an addition
to cli.md's 0/1/2/130, documented in ``bridge --help``; the log written so
far is kept).  The core touches no file: logging is the caller's ``on_row``.

Timing model.  Sample k of the set-points is read at wall time t_k
(the middle of the read request), i.e. model time t_k - offset.  The
reference is re-aimed from its current value to the set-point
extrapolated with its velocity one cycle ahead, reached at model time
t_k - offset + cycle_time, and the model is advanced there: the state
written back in cycle k stands for the start of cycle k + 1, so the
PLC, which keeps a written value until the next write, sees on average
the gateway's computation time minus half a cycle of added delay
instead of the computation time plus half a cycle.  A late cycle is an
overrun (counted): the reference runs straight from where it was to
the new goal, so a stall only cuts the path between two consecutive
reads; it never extrapolates a stale ramp.

Delays (the paper's Table 1 measures set-point to axis motion): the run's
:class:`~cdpr_design.plc.delay.DelayTrace` gives the end-to-end delay as the
PLC sees it (set-point read -> axis position written and held until the next
write); :meth:`cdpr_design.plc.rows.RowMaker.delay` the model's own lag in
model time (``bridge.csv``, what ``compare`` reports); the test PLC's log the
whole loop including the PLC's own sampling.
"""

from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from cdpr_design.plc.delay import DelayTrace
from cdpr_design.plc.stats import StreamStats
from cdpr_design.plc.symbols import SymbolError
from cdpr_design.plc.transport import PlcLinkError, Transport

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
    lag : StreamStats
        How far the model is behind real time after each cycle [s] (0 when
        it kept up; grows while a late cycle is being caught up).
    slips, slipped : int, float
        Times the model fell more than ``max_lag`` behind and skipped, and
        the model time skipped [s].
    trace : DelayTrace
        Wall-clock times of the set-points read and of the states written
        (the end-to-end delay, :meth:`delay`).
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
    lag: StreamStats = field(default_factory=StreamStats)
    slips: int = 0
    slipped: float = 0.0
    trace: "DelayTrace | None" = None

    def delay(self, names) -> dict:
        """End-to-end delay [s] per axis (``length_<cable>``): set-point read -> motion written.

        See :meth:`DelayTrace.delay`.  None where an axis did not move.
        """
        if self.trace is None:
            return {f"length_{c}": None for c in names}
        return self.trace.delay(names, self.cycle_time)

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
            "lag": _strip(self.lag.summary()),
            "slips": self.slips,
            "slipped_s": self.slipped,
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


class _Reference:
    """The set-point the simulated axes follow: continuous and piecewise linear in model time.

    Each cycle it is re-aimed from its *current value* to a goal (the PLC's
    set-point extrapolated by one cycle) at a goal time, and it holds the goal
    once reached.  So the reference never steps (a step of 0.5 mm in a cable
    of axial stiffness 2e4 N/m is a 10 N tension kick) and never runs on past
    the goal (a late cycle does not drive the robot beyond the path).
    """

    def __init__(self, value, t: float):
        self.r0 = np.array(value, dtype=float)
        self.t0 = float(t)
        self.vel = np.zeros_like(self.r0)
        self.goal = self.r0.copy()
        self.t_goal = self.t0

    def value(self, t: float) -> np.ndarray:
        if t >= self.t_goal:
            return self.goal.copy()
        return self.r0 + self.vel * (t - self.t0)

    def aim(self, t: float, goal, t_goal: float) -> None:
        r = self.value(t)
        self.r0, self.t0 = r, float(t)
        self.goal = np.array(goal, dtype=float)
        if t_goal > t + 1e-12:
            self.t_goal = float(t_goal)
            self.vel = (self.goal - r) / (self.t_goal - t)
        else:  # no time to get there: hold where the reference is
            self.goal, self.t_goal, self.vel = r, float(t), np.zeros_like(r)

    def drive(self, simulator, t_end: float, h: float):
        """Advance ``simulator`` to model time ``t_end`` along the reference (whole steps of h)."""
        state = simulator.state()
        for seg_end in (min(self.t_goal, t_end), t_end):
            t = float(state.time)
            span = seg_end - t
            if h > 0:
                span = round(span / h) * h
            if span <= 1e-12:
                continue
            moving = t < self.t_goal - 1e-12
            state = simulator.advance(self.value(t), span,
                                      velocity=self.vel if moving else np.zeros_like(self.vel))
        return state


def _window_velocity(hist, window: float) -> np.ndarray:
    """Set-point velocity [m/s] over the last ``window`` s of (model time, set-point) samples."""
    t1, s1 = hist[-1]
    for t0, s0 in reversed(hist):
        if t1 - t0 >= window - 1e-12:
            break
    if t1 - t0 <= 1e-12:
        return np.zeros_like(s1)
    return (s1 - s0) / (t1 - t0)


def _interp_setpoint(hist, t: float) -> np.ndarray:
    """The PLC's set-point at model time ``t``: linear between the samples read around it."""
    if t <= hist[0][0]:
        return hist[0][1].copy()
    for (ta, sa), (tb, sb) in zip(hist, list(hist)[1:]):
        if ta <= t <= tb:
            w = 0.0 if tb <= ta else (t - ta) / (tb - ta)
            return sa + (sb - sa) * w
    return hist[-1][1].copy()


class _Gateway:
    """The state of one bridged run between its cycles (see :func:`run`).

    Each cycle: wait for its start, read the set-points, advance the model,
    write the outputs, count it; when the PLC is lost, recover or stop.
    """

    def __init__(self, transport: Transport, simulator, dt: float, *, on_row, status, window: float,
                 keep: int, spin: float, max_catchup: float, max_lag: float, clock, sleep):
        self.transport, self.simulator, self.layout = transport, simulator, transport.layout
        self.dt, self.window, self.spin = dt, window, spin
        self.max_catchup, self.max_lag = max_catchup, max_lag
        self.on_row, self.status, self.clock, self.sleep = on_row, status, clock, sleep
        self.res = BridgeResult(cycle_time=dt, round_trips=transport.round_trips)
        self.res.trace = DelayTrace(keep)
        self.h = float(getattr(simulator, "timestep", 0.0) or 0.0)  # 0: advances by any span
        self.state = simulator.state()
        self.sim_time0 = float(self.state.time)
        sp = np.asarray(getattr(self.state, "setpoints", self.state.lengths), dtype=float).copy()
        if not np.all(np.isfinite(sp)):
            sp = np.asarray(self.state.lengths, dtype=float).copy()
        self.sp = sp                      # the last valid set-points [m]
        self.ref = _Reference(sp, self.sim_time0)
        self.hist: deque = deque(maxlen=max(4, int(math.ceil(window / dt)) + 3))
        self.pending: deque = deque()     # states logged one cycle late
        self.heartbeat = 0
        self.missed = 0
        self.last_err = ""
        self.end_time = None
        self.tol = 0.5 * self.h if self.h > 0 else 1e-9
        self.t_wall0 = clock()
        self.t0 = self.t_wall0            # schedule origin
        self.k = 0                        # periods since the (re)started schedule
        self.offset = None                # wall time - model time

    def finished(self, should_stop) -> str | None:
        """``stop`` when asked to, ``duration`` when the model reached the end time, else None."""
        if should_stop is not None and should_stop():
            return "stop"
        if self.end_time is not None and float(self.state.time) >= self.end_time - self.tol:
            return "duration"
        return None

    def cycle(self) -> None:
        """One period: read, advance, write, count (the rows due are handed to ``on_row``)."""
        deadline = self.t0 + self.k * self.dt
        _wait_until(deadline, self.clock, self.sleep, self.spin)
        start = self.clock()
        self.res.jitter.add(abs(start - deadline))
        goal, t_goal, t1, ts = self._read(start)
        self.emit(self.hist[-1][0] if self.hist else None)
        self._advance(goal, t_goal, ts)
        link_ok = ts is not None and self._write(start, t1)
        self._count(link_ok, start)

    def _read(self, start: float):
        """1. The set-points: (goal [m], goal time [s] in model time, end of the read, read time).

        The goal is the set-point extrapolated one cycle ahead; the read time
        (wall clock, the middle of the request) is None when the read failed:
        the axes then hold where the reference is.
        """
        try:
            new_sp = self.transport.read_setpoints()
        except PlcLinkError as err:
            t1 = self.clock()
            self.last_err = str(err)
            if self.offset is None:
                self.offset = t1 - float(self.state.time)
            return self.ref.value(float(self.state.time)), t1 - self.offset + self.dt, t1, None
        t1 = self.clock()
        self.res.latency.add(t1 - start)
        ts = 0.5 * (start + t1)
        if self.offset is None:   # the first read defines model time = now
            self.offset = ts - float(self.state.time)
        if new_sp.shape == self.sp.shape and np.all(np.isfinite(new_sp)):
            self.sp = new_sp
        if self.hist and ts - self.offset <= self.hist[-1][0]:
            self.hist.pop()
        self.hist.append((ts - self.offset, self.sp.copy()))
        self.res.trace.read(ts, self.sp)
        vel = _window_velocity(self.hist, self.window)
        return self.sp + vel * self.dt, ts - self.offset + self.dt, t1, ts

    def _advance(self, goal, t_goal: float, ts) -> None:
        """2. The model: from the reference's current value to the goal (at most ``max_catchup``)."""
        now = float(self.state.time)
        if t_goal - now > self.max_lag + self.dt:
            t_goal = self._slip(t_goal, now, ts)
        self.ref.aim(now, goal, t_goal)
        t_end = min(t_goal, now + self.max_catchup)
        if self.end_time is not None:
            t_end = min(t_end, self.end_time)
        if t_end > now + self.tol:
            self.state = self.ref.drive(self.simulator, t_end, self.h)
        self.res.lag.add(max(t_goal - float(self.state.time), 0.0))

    def _slip(self, t_goal: float, now: float, ts) -> float:
        """Drop the model's lag behind real time (counted); the goal time moved back [s]."""
        slip = t_goal - now - self.dt
        self.offset += slip
        t_goal -= slip
        self.hist.clear()
        if ts is not None:
            self.hist.append((ts - self.offset, self.sp.copy()))
        self.res.slips += 1
        self.res.slipped += slip
        self.status(f"the model fell {slip:.3g} s behind real time: skipped")
        return t_goal

    def _write(self, start: float, t1: float) -> bool:
        """3. The outputs (lengths, tensions, pose, heartbeat); False when the write failed."""
        self.heartbeat = (self.heartbeat + 1) & 0xFFFFFFFF
        st = self.state
        try:
            t2 = self.clock()
            self.transport.write_outputs(self.layout.pack_outputs(
                st.lengths, st.tensions, st.pose, self.heartbeat, False))
            t3 = self.clock()
        except PlcLinkError as err:
            self.last_err = str(err)
            return False
        self.res.latency.add(t3 - t2)
        self.res.exchange.add((t1 - start) + (t3 - t2))
        self.res.trace.wrote(0.5 * (t2 + t3), st.lengths, float(st.time) + self.offset)
        return True

    def _count(self, link_ok: bool, start: float) -> None:
        """Count the cycle, queue its row and skip the periods it ran into (an overrun)."""
        if link_ok:
            self.missed = 0
        else:
            self.missed += 1
            self.res.missed += 1
        self.res.cycles += 1
        self.pending.append(self.state)
        end = self.clock()
        self.res.work.add(end - start)
        self.k += 1
        if end > self.t0 + self.k * self.dt:
            self.res.overruns += 1
            self.k = int(math.floor((end - self.t0) / self.dt)) + 1

    def emit(self, upto: float | None) -> None:
        """4. Hand the queued states up to model time ``upto`` [s] (all: None) to ``on_row``.

        With ``upto``, the set-point of a row is the PLC's, interpolated
        between the reads around it; without, the reference the model followed.
        """
        while self.pending and (upto is None or float(self.pending[0].time) <= upto + 1e-12):
            st = self.pending.popleft()
            target = _interp_setpoint(self.hist, float(st.time)) if upto is not None \
                else self.ref.value(float(st.time))
            if self.on_row is not None:
                self.on_row(target, st)

    def recover(self, attempts: int, backoff, should_stop) -> bool:
        """The PLC is lost: raise the fault flag, reconnect (True) or stop the run (False)."""
        res = self.res
        res.fault_raised = self.transport.raise_fault() or res.fault_raised
        self.status(f"PLC lost after {self.missed} failed cycles: {self.last_err}")
        if not _reconnect(self.transport, attempts, backoff, res, self.status, self.sleep, should_stop):
            res.stopped = "plc_lost"
            res.error = self.last_err
            return False
        self.missed = 0
        self.t0, self.k = self.clock(), 0
        self.emit(None)
        self.offset = None   # model time goes on from where it is
        self.hist.clear()
        return True


@dataclass(frozen=True)
class Loop:
    """The timing of the gateway loop (:func:`run`).

    ``cycle_time`` [s] the period; ``duration`` [s] stop after this much simulated (= wall-clock)
    time (None: until stopped); ``max_missed`` consecutive failed cycles after which the PLC
    counts as lost; ``reconnect`` reconnection attempts per outage (0: none), with back-off
    doubling from ``backoff[0]`` up to ``backoff[1]`` seconds (while the link is down the model
    holds the last reference); ``spin`` [s] busy-wait the last ``spin`` seconds before each
    cycle start (the OS sleep overshoots by ~0.1 ms); ``max_catchup`` [s] the most model time one
    cycle may simulate (a late cycle catches up at most this much, so the PLC keeps being
    served); ``max_lag`` [s] when the model falls further than this behind real time (a machine
    too slow for real time) it *slips*: the lag is dropped and counted in ``slips`` (the only
    case where the reference may jump); ``velocity_window`` [s] the span of set-point samples the
    velocity is estimated over (default max(2 cycles, 4 ms): the PLC's own task quantises its
    set-points in time); ``keep`` cycles kept for the delay estimate (bounded memory).
    """

    cycle_time: float
    duration: float | None = None
    max_missed: int = 3
    reconnect: int = 0
    backoff: tuple[float, float] = (0.1, 2.0)
    spin: float = 2e-4
    max_catchup: float = 0.1
    max_lag: float = 0.5
    velocity_window: float | None = None
    keep: int = 1 << 20


def run(transport: Transport, simulator, loop: Loop, *, on_row: Callable | None = None,
        should_stop: Callable[[], bool] | None = None, on_status: Callable[[str], None] | None = None,
        clock=time.perf_counter, sleep=time.sleep) -> BridgeResult:
    """Run the gateway loop until ``duration``, a stop request, Ctrl-C or a lost PLC.

    Parameters
    ----------
    transport : Transport
        Already connected (:meth:`Transport.connect` checked its symbols).
    simulator : object
        ``advance(setpoint_lengths, duration, velocity=...)`` and ``state()``
        returning an object with ``time`` [s], ``pose``, ``lengths`` [m] and
        ``tensions`` [N] (and ``setpoints`` [m], the reference the axes
        follow, when it has them); ``timestep`` [s] when it steps in whole
        physics steps (:class:`cdpr_design.motion.simulation.Simulator`).
    loop : Loop
        The period, the duration and the loop's limits.
    on_row : callable, optional
        ``on_row(setpoints, state)`` once per cycle (logging), one cycle
        late: ``setpoints`` are the PLC's set-points at ``state.time``,
        interpolated between the reads around it (the rows still pending at
        the end get the reference the model followed).
    should_stop : callable, optional
        Polled each cycle; True ends the run (``stopped="stop"``).
    on_status : callable, optional
        ``on_status(message)`` on a lost link, a reconnection and a slip.
    clock, sleep : callable
        The wall clock [s] and the sleep the loop times itself by.

    Returns
    -------
    BridgeResult
        Never raises for a lost PLC or Ctrl-C (see ``stopped``);
        :class:`SymbolError` on reconnection propagates.

    Notes
    -----
    The timing model is in the module notes.
    """
    cycle_time, duration, max_missed, reconnect = loop.cycle_time, loop.duration, loop.max_missed, loop.reconnect
    backoff, spin, max_catchup, max_lag = loop.backoff, loop.spin, loop.max_catchup, loop.max_lag
    velocity_window, keep = loop.velocity_window, loop.keep
    dt = float(cycle_time)
    if not dt > 0:
        raise ValueError("cycle_time must be positive")
    window = float(velocity_window) if velocity_window is not None else max(2 * dt, 4e-3)
    gw = _Gateway(transport, simulator, dt, on_row=on_row, status=on_status or (lambda msg: None),
                  window=window, keep=keep, spin=spin, max_catchup=max_catchup, max_lag=max_lag,
                  clock=clock, sleep=sleep)
    if duration is not None:
        gw.end_time = gw.sim_time0 + float(duration)
    res = gw.res
    try:
        while True:
            stopped = gw.finished(should_stop)
            if stopped is not None:
                res.stopped = stopped
                break
            gw.cycle()
            if gw.missed >= max_missed and not gw.recover(reconnect, backoff, should_stop):
                break
    except KeyboardInterrupt:
        res.stopped = "interrupted"
    finally:
        try:
            gw.emit(None)
        except KeyboardInterrupt:
            pass
        res.sim_time = float(gw.state.time) - gw.sim_time0
        res.elapsed = clock() - gw.t_wall0
    return res


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


def make_simulator(design, cycle_time: float, initial_lengths=None):
    """The physics model the gateway drives (:class:`cdpr_design.motion.simulation.Simulator`).

    Started at rest at the forward kinematics of ``initial_lengths`` (the
    PLC's first set-points), so the first cycle does not jerk the robot.
    """
    from cdpr_design.motion.simulation import Simulator
    from cdpr_design.statics.robot import Analysis, resolve

    sim = Simulator(resolve(design, Analysis(command="motion")))
    pose = None
    if initial_lengths is not None:
        from cdpr_design.statics.kinematics import forward_kinematics

        try:
            pose = forward_kinematics(design, initial_lengths).pose
        except ValueError:
            pose = None
    sim.reset(pose)
    return sim


__all__ = ["BridgeResult", "make_simulator", "run"]
