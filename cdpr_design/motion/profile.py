"""Rest-to-rest speed profiles s(t) and their sampling at a cycle time.

A straight segment (or a circle's whole arc) is run with a minimum-time
rest-to-rest motion law: trapezoidal speed (acceleration-limited), or
jerk-limited "double S" when a jerk limit is given.  Each law is stretched
to a whole number of cycles by uniform time scaling (speed / lambda,
acceleration / lambda^2, jerk / lambda^3, lambda >= 1), so the limits still
hold and the last sample falls exactly on the end.

References
----------
Biagiotti & Melchiorri, "Trajectory Planning for Automatic Machines and
Robots", Springer 2008, sections 3.2 (trapezoidal) and 3.4 (double-S) profiles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.model.design import Trajectory


@dataclass(frozen=True)
class Profile:
    """A rest-to-rest motion law s(t) over distance ``distance``.

    Piecewise-constant jerk: phase p lasts ``durations[p]``, starts with
    acceleration ``a0[p]`` and has jerk ``jerk[p]`` (a trapezoid has zero
    jerk and acceleration steps).  ``scale`` >= 1 is the uniform time scaling
    applied afterwards (t' = scale * t).
    """

    distance: float
    durations: np.ndarray
    a0: np.ndarray
    jerk: np.ndarray
    scale: float = 1.0

    @property
    def raw_duration(self) -> float:
        return float(self.durations.sum())

    @property
    def duration(self) -> float:
        """Duration after time scaling [s]."""
        return self.raw_duration * self.scale

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position s [m], speed [m/s] and acceleration [m/s^2] at times t [s] (scaled time)."""
        t = np.asarray(t, dtype=float) / self.scale
        d, a0, j = self.durations, self.a0, self.jerk
        # state at the start of each phase
        n = d.size
        s0 = np.zeros(n + 1)
        v0 = np.zeros(n + 1)
        for p in range(n):
            T = d[p]
            s0[p + 1] = s0[p] + v0[p] * T + a0[p] * T * T / 2 + j[p] * T ** 3 / 6
            v0[p + 1] = v0[p] + a0[p] * T + j[p] * T * T / 2
        ends = np.cumsum(d)
        starts = ends - d
        p = np.clip(np.searchsorted(ends, t, side="right"), 0, n - 1)
        tau = np.clip(t - starts[p], 0.0, None)
        s = s0[p] + v0[p] * tau + a0[p] * tau ** 2 / 2 + j[p] * tau ** 3 / 6
        v = v0[p] + a0[p] * tau + j[p] * tau ** 2 / 2
        a = a0[p] + j[p] * tau
        # exact end: the raw law reaches `distance` up to rounding; remove it
        total = s0[n]
        if total > 0:
            s = s * (self.distance / total)
        after = t >= self.raw_duration * (1 - 1e-12)  # the last cycle lands on the end despite rounding
        s = np.where(after, self.distance, s)
        v = np.where(after, 0.0, v)
        a = np.where(after, 0.0, a)
        return s, v / self.scale, a / self.scale ** 2


def trapezoid(distance: float, speed: float, acceleration: float) -> Profile:
    """Minimum-time rest-to-rest trapezoidal profile (triangular when short).

    Parameters
    ----------
    distance : float
        Path length [m] (or [rad]), >= 0.
    speed, acceleration : float
        Limits [m/s], [m/s^2], > 0.
    """
    D, v, a = float(distance), float(speed), float(acceleration)
    if D <= 0:
        return Profile(0.0, np.zeros(1), np.zeros(1), np.zeros(1))
    if D <= v * v / a:  # triangular: the cruise speed is never reached
        Ta = np.sqrt(D / a)
        Tv = 0.0
    else:
        Ta = v / a
        Tv = (D - v * v / a) / v
    return Profile(D, np.array([Ta, Tv, Ta]), np.array([a, 0.0, -a]), np.zeros(3))


def double_s(distance: float, speed: float, acceleration: float, jerk: float) -> Profile:
    """Minimum-time rest-to-rest jerk-limited ("double S") profile.

    Symmetric acceleration and deceleration (Biagiotti & Melchiorri 2008,
    section 3.4); when the distance is too short for the cruise speed, the
    peak speed is lowered (bisection) until the two ramps meet.
    """
    D, vmax, amax, jmax = float(distance), float(speed), float(acceleration), float(jerk)
    if D <= 0:
        return Profile(0.0, np.zeros(1), np.zeros(1), np.zeros(1))

    def ramp(vp):
        if vp * jmax <= amax * amax:  # the acceleration limit is not reached
            Tj = np.sqrt(vp / jmax)
            return Tj, 2 * Tj, jmax * Tj
        Tj = amax / jmax
        return Tj, vp / amax + Tj, amax

    Tj, Ta, ap = ramp(vmax)
    if vmax * Ta <= D:  # two ramps cover vmax * Ta / 2 each
        vp = vmax
    else:
        lo, hi = 0.0, vmax
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            Tj, Ta, ap = ramp(mid)
            if mid * Ta > D:
                hi = mid
            else:
                lo = mid
        vp = lo
        Tj, Ta, ap = ramp(vp)
    Tv = max(D - vp * Ta, 0.0) / vp
    Tc = max(Ta - 2 * Tj, 0.0)
    j = jmax if Tj > 0 else 0.0
    ap = j * Tj
    durations = np.array([Tj, Tc, Tj, Tv, Tj, Tc, Tj])
    a0 = np.array([0.0, ap, ap, 0.0, 0.0, -ap, -ap])
    jk = np.array([j, 0.0, -j, 0.0, -j, 0.0, j])
    return Profile(D, durations, a0, jk)


def fit_to_cycle(profile: Profile, cycle_time: float) -> Profile:
    """Stretch a profile in time so its duration is a whole number of cycles.

    Uniform time scaling by lambda = N dt / T >= 1 divides speed by lambda,
    acceleration by lambda^2 and jerk by lambda^3: every limit still holds.
    """
    T = profile.raw_duration
    if T <= 0:
        return profile
    n = T / cycle_time
    if not n <= MAX_SAMPLES:  # before int(): T / cycle_time may be huge or inf
        raise ValueError(too_many_samples(n))
    N = max(int(np.ceil(n - 1e-9)), 1)
    return Profile(profile.distance, profile.durations, profile.a0, profile.jerk,
                   scale=N * cycle_time / T)


def for_trajectory(traj: Trajectory, distance: float, speed: float, accel: float,
                   cycle_time: float) -> Profile:
    """The trajectory's law over ``distance`` [m] with limits ``speed`` [m/s] and ``accel``
    [m/s^2], fitted to whole cycles of ``cycle_time`` [s]: double S when the trajectory
    has a ``jerk`` limit, else trapezoidal."""
    if traj.jerk is not None:
        law = double_s(distance, speed, accel, traj.jerk)
    else:
        law = trapezoid(distance, speed, accel)
    return fit_to_cycle(law, cycle_time)


#: Most samples of one sampled path (whole trajectory): 1,000 s at the default 1 ms cycle.  The
#: samples and their statics are held in memory (about 1-2 kB a sample for a spatial robot).
MAX_SAMPLES = 1_000_000


def too_many_samples(n: float) -> str:
    """The message for a path of ``n`` samples (more than :data:`MAX_SAMPLES`)."""
    return (f"the path would have {n:.4g} samples, more than the {MAX_SAMPLES:,} sampled; raise the speed, "
            "the acceleration or the cycle time, or shorten the path")


def sampled(profile: Profile, cycle_time: float, *, include_start: bool = False):
    """s [m], speed [m/s] and acceleration [m/s^2] of a cycle-fitted profile at every cycle.

    The samples are at t = j * cycle_time for j = 1 .. N (j = 0 .. N with
    ``include_start``), N = duration / cycle_time.
    """
    n = profile.duration / cycle_time
    if not n <= MAX_SAMPLES:  # checked as a float, before anything is allocated
        raise ValueError(too_many_samples(n))
    N = int(round(n))
    t = cycle_time * np.arange(0 if include_start else 1, N + 1)
    return profile.evaluate(t)


__all__ = ["MAX_SAMPLES", "Profile", "double_s", "fit_to_cycle", "for_trajectory", "sampled", "trapezoid"]
