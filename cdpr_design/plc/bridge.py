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

Delays (the paper's Table 1 measures set-point to axis motion): the run's
:class:`DelayTrace` gives the end-to-end delay as the PLC sees it (set-point
read -> axis position written and held until the next write);
:meth:`RowMaker.delay` the model's own lag in model time (``bridge.csv``,
what ``compare`` reports); the test PLC's log the whole loop including the
PLC's own sampling.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from cdpr_design.plc.ads import PlcLinkError, SymbolError, Transport

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


class DelayTrace:
    """Wall-clock record of a bridged run: when each set-point was read, when each state was written.

    Bounded memory: the first ``keep`` cycles.
    """

    def __init__(self, keep: int = 1 << 20):
        self.keep = int(keep)
        self._r = None
        self._w = None
        self.nr = 0
        self.nw = 0

    @staticmethod
    def _put(buf, n, keep, row):
        if buf is None:
            buf = np.empty((64, len(row)))
        if n >= keep:
            return buf, n
        if n == buf.shape[0]:
            buf = np.concatenate([buf, np.empty_like(buf)])[:keep]
        buf[n] = row
        return buf, n + 1

    def read(self, t: float, setpoints) -> None:
        """Set-points [m] read at wall time ``t`` [s]."""
        self._r, self.nr = self._put(self._r, self.nr, self.keep, [t, *setpoints])

    def wrote(self, t: float, lengths, model_wall: float) -> None:
        """Axis lengths [m] written at wall time ``t`` [s], standing for wall time ``model_wall``."""
        self._w, self.nw = self._put(self._w, self.nw, self.keep, [t, model_wall, *lengths])

    def delay(self, names, cycle_time: float, max_delay: float = 1.0) -> dict:
        """End-to-end delay [s] of each axis as the PLC sees it, keyed ``length_<cable>``.

        The set-points are taken as read (linear between reads: the value
        the PLC held at the read's time); the axis positions as the PLC sees
        them: each written value held until the next write (zero-order hold).
        The delay is the sub-sample cross-correlation lag between the two
        (:func:`cdpr_design.motion.compare.estimate_delay`) on a uniform grid of
        cycle_time / 4 (at most 1 ms).  Positive: the axes lag the
        set-points.  It includes the model's own lag, the computation and the
        write, and the hold; it leaves out the time a set-point waited in the
        PLC before the read and an actual waited before the PLC's task read
        it (the test PLC's log, ``plc_delay``, sees those too).
        """
        from cdpr_design.motion.compare import estimate_delay

        out = {f"length_{c}": None for c in names}
        if self.nr < 8 or self.nw < 8:
            return out
        r, w = self._r[: self.nr], self._w[: self.nw]
        t0, t1 = max(r[0, 0], w[0, 0]), min(r[-1, 0], w[-1, 0])
        if not t1 > t0:
            return out
        g = min(cycle_time / 4, 1e-3)
        g = max(g, (t1 - t0) / (1 << 20))
        grid = t0 + g * np.arange(int((t1 - t0) / g) + 1)
        idx = np.clip(np.searchsorted(w[:, 0], grid, side="right") - 1, 0, w.shape[0] - 1)
        md = min(max_delay, 0.45 * (t1 - t0))
        for j, c in enumerate(names):
            x = np.interp(grid, r[:, 0], r[:, 1 + j])
            y = w[idx, 2 + j]
            d = estimate_delay(g, x, y, max_delay=md)
            out[f"length_{c}"] = float(d) if np.isfinite(d) else None
        return out


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


def run(transport: Transport, simulator, *, cycle_time: float, duration: float | None = None,
        on_row: Callable | None = None, should_stop: Callable[[], bool] | None = None,
        max_missed: int = 3, reconnect: int = 0, backoff: tuple[float, float] = (0.1, 2.0),
        spin: float = 2e-4, on_status: Callable[[str], None] | None = None,
        max_catchup: float = 0.1, max_lag: float = 0.5, velocity_window: float | None = None,
        keep: int = 1 << 20, clock=time.perf_counter, sleep=time.sleep) -> BridgeResult:
    """Run the gateway loop until ``duration``, a stop request, Ctrl-C or a lost PLC.

    Parameters
    ----------
    transport : Transport
        Already connected (:meth:`Transport.connect` checked its symbols).
    simulator : object
        ``advance(setpoint_lengths, duration, velocity=...)`` and ``state()``
        returning an object with ``time`` [s], ``pose``, ``lengths`` [m] and
        ``tensions`` [N]; ``timestep`` [s] when it steps in whole physics
        steps (:class:`cdpr_design.motion.simulation.Simulator`).
    cycle_time : float
        Period [s].
    duration : float, optional
        Stop after this much simulated (= wall-clock) time [s].
    on_row : callable, optional
        ``on_row(setpoints, state)`` once per cycle (logging), one cycle
        late: ``setpoints`` are the PLC's set-points at ``state.time``,
        interpolated between the reads around it (the rows still pending at
        the end get the reference the model followed).
    should_stop : callable, optional
        Polled each cycle; True ends the run (``stopped="stop"``).
    max_missed : int
        Consecutive failed cycles after which the PLC counts as lost.
    reconnect : int
        Reconnection attempts per outage (0: none), with back-off doubling
        from ``backoff[0]`` up to ``backoff[1]`` seconds.  While the link is
        down the model holds the last reference.
    spin : float
        Busy-wait the last ``spin`` seconds before each cycle start (the OS
        sleep overshoots by ~0.1 ms) [s].
    max_catchup : float
        Most model time one cycle may simulate [s] (a late cycle catches up
        at most this much, so the PLC keeps being served).
    max_lag : float
        When the model falls further than this behind real time [s] (a
        machine too slow for real time), it *slips*: the lag is dropped and
        counted in ``slips`` (the only case where the reference may jump).
    velocity_window : float, optional
        Span of set-point samples the velocity is estimated over [s];
        default max(2 cycles, 4 ms) (the PLC's own task quantises its
        set-points in time).
    keep : int
        Cycles kept for the delay estimate (bounded memory).

    Returns
    -------
    BridgeResult
        Never raises for a lost PLC or Ctrl-C (see ``stopped``);
        :class:`SymbolError` on reconnection propagates.

    Notes
    -----
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
    """
    dt = float(cycle_time)
    if not dt > 0:
        raise ValueError("cycle_time must be positive")
    from collections import deque

    res = BridgeResult(cycle_time=dt, round_trips=getattr(transport, "round_trips", 2))
    res.trace = DelayTrace(keep)
    h = float(getattr(simulator, "timestep", 0.0) or 0.0)
    layout = transport.layout
    state = simulator.state()
    sim_time0 = float(state.time)
    sp = np.asarray(getattr(state, "setpoints", state.lengths), dtype=float).copy()
    if not np.all(np.isfinite(sp)):
        sp = np.asarray(state.lengths, dtype=float).copy()
    ref = _Reference(sp, sim_time0)
    window = float(velocity_window) if velocity_window is not None else max(2 * dt, 4e-3)
    hist: deque = deque(maxlen=max(4, int(math.ceil(window / dt)) + 3))
    pending: deque = deque()          # states logged one cycle late
    heartbeat = 0
    missed = 0
    last_err = ""
    t_wall0 = clock()
    t0 = t_wall0                      # schedule origin
    k = 0                             # periods since the (re)started schedule
    offset = None                     # wall time - model time
    end_time = None if duration is None else sim_time0 + float(duration)
    tol = 0.5 * h if h > 0 else 1e-9
    status = on_status or (lambda msg: None)

    def emit(upto: float | None) -> None:
        while pending and (upto is None or float(pending[0].time) <= upto + 1e-12):
            st = pending.popleft()
            target = _interp_setpoint(hist, float(st.time)) if upto is not None \
                else ref.value(float(st.time))
            if on_row is not None:
                on_row(target, st)

    try:
        while True:
            if should_stop is not None and should_stop():
                res.stopped = "stop"
                break
            if end_time is not None and float(state.time) >= end_time - tol:
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
                link_ok = True
                ts = 0.5 * (start + t1)
                if offset is None:   # the first read defines model time = now
                    offset = ts - float(state.time)
                if new_sp.shape == sp.shape and np.all(np.isfinite(new_sp)):
                    sp = new_sp
                if hist and ts - offset <= hist[-1][0]:
                    hist.pop()
                hist.append((ts - offset, sp.copy()))
                res.trace.read(ts, sp)
                vel = _window_velocity(hist, window)
                goal, t_goal = sp + vel * dt, ts - offset + dt
            except PlcLinkError as err:
                t1 = clock()
                link_ok = False
                last_err = str(err)
                if offset is None:
                    offset = t1 - float(state.time)
                # no new set-point: the axes hold where the reference is
                goal, t_goal = ref.value(float(state.time)), t1 - offset + dt
            emit(hist[-1][0] if hist else None)
            # 2. the model: from the reference's current value to the goal
            now = float(state.time)
            if t_goal - now > max_lag + dt:
                slip = t_goal - now - dt
                offset += slip
                t_goal -= slip
                hist.clear()
                if link_ok:
                    hist.append((ts - offset, sp.copy()))
                res.slips += 1
                res.slipped += slip
                status(f"the model fell {slip:.3g} s behind real time: skipped")
            ref.aim(now, goal, t_goal)
            t_end = min(t_goal, now + max_catchup)
            if end_time is not None:
                t_end = min(t_end, end_time)
            if t_end > now + tol:
                state = ref.drive(simulator, t_end, h)
            res.lag.add(max(t_goal - float(state.time), 0.0))
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
                    res.trace.wrote(0.5 * (t2 + t3), state.lengths, float(state.time) + offset)
                except PlcLinkError as err:
                    link_ok = False
                    last_err = str(err)
            if link_ok:
                missed = 0
            else:
                missed += 1
                res.missed += 1
            res.cycles += 1
            pending.append(state)
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
                t0, k = clock(), 0
                emit(None)
                offset = None   # model time goes on from where it is
                hist.clear()
    except KeyboardInterrupt:
        res.stopped = "interrupted"
    finally:
        try:
            emit(None)
        except KeyboardInterrupt:
            pass
        res.sim_time = float(state.time) - sim_time0
        res.elapsed = clock() - t_wall0
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
        from cdpr_design.statics.kinematics import forward_kinematics

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
        (:func:`cdpr_design.motion.compare.estimate_delay`); None where an axis did
        not move.
        """
        return axis_delays(self.design.cable_names, self._buf[: self.n, 0],
                           self._buf[: self.n, 1: 1 + self.design.m],
                           self._buf[: self.n, 1 + self.design.m:])


def axis_delays(names, t, target, actual, max_delay: float = 1.0) -> dict:
    """Per-axis delay [s] of ``actual`` behind ``target`` (NaN-free dict, None where unknown)."""
    from cdpr_design.motion.compare import estimate_delay, resample, uniform_grid

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
    """The physics model the gateway drives (:class:`cdpr_design.motion.simulation.Simulator`).

    Started at rest at the forward kinematics of ``initial_lengths`` (the
    PLC's first set-points), so the first cycle does not jerk the robot.
    """
    from cdpr_design.motion.simulation import Simulator

    sim = Simulator(design)
    pose = None
    if initial_lengths is not None:
        from cdpr_design.statics.kinematics import forward_kinematics

        try:
            pose = forward_kinematics(design, initial_lengths).pose
        except ValueError:
            pose = None
    sim.reset(pose)
    return sim
