"""Duty cycles: the load profile a cable's RMS motor torque is computed over.

Either a sampled trajectory's (:func:`trajectory_cycle`) or, without one,
:data:`DEFAULT_CYCLE` at each cable's worst task pose (:func:`default_cycle`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.design.envelope import Envelope

#: The default duty cycle used for the RMS torque when no trajectory is given:
#: at the cable's worst task pose, a trapezoidal move along the worst
#: acceleration direction -- accelerate at A up to V, cruise, decelerate at A,
#: dwell -- every phase lasting V / A seconds (four equal phases).  Tension
#: during the phases: t0 + A g (accelerate), t0 (cruise), t0 - A g (decelerate),
#: t0 (dwell, holding); cable acceleration +-A while accelerating/decelerating.
DEFAULT_CYCLE = ("accelerate", "cruise", "decelerate", "dwell")
DEFAULT_CYCLE_TEXT = ("default cycle at the worst task pose: accelerate at max_acceleration to "
                      "max_speed, cruise, decelerate, dwell; four phases of max_speed/max_acceleration each")


@dataclass(frozen=True)
class DutyCycle:
    """Per-cable load profile for the RMS torque: tension [N], cable acceleration [m/s^2], weights.

    ``tension`` and ``cable_accel`` are (k, m); ``weight`` (k,) sums to 1
    (time fraction of each sample).  ``cable_speed`` (k, m) [m/s] is used for
    the peak speed.  ``text`` says what the cycle is.
    """

    tension: np.ndarray
    cable_accel: np.ndarray
    cable_speed: np.ndarray
    weight: np.ndarray
    text: str


def default_cycle(env: Envelope) -> DutyCycle:
    """The :data:`DEFAULT_CYCLE` at each cable's worst task pose.

    Phases (equal durations V/A): accelerate (tension t0 + A g, cable
    reeled in at A), cruise (t0, speed V), decelerate (t0 - A g, -A), dwell
    (t0, holding).  Without an acceleration or speed requirement the cycle is
    pure holding at t0.
    """
    t0 = env.worst_static
    A = env.max_acceleration
    g = np.nan_to_num(env.worst_gain)
    V = env.max_speed
    if A > 0 and V > 0:
        ten = np.vstack([t0 + A * g, t0, t0 - A * g, t0])
        # reeling in is L'' < 0: the motor torque adds J alpha while it speeds the drum up
        acc = np.vstack([-np.full_like(t0, A), 0 * t0, np.full_like(t0, A), 0 * t0])
        spd = np.vstack([0 * t0, -np.full_like(t0, V), 0 * t0, 0 * t0])
        w = np.full(4, 0.25)
        return DutyCycle(ten, acc, spd, w, DEFAULT_CYCLE_TEXT)
    return DutyCycle(t0[None, :], 0 * t0[None, :], 0 * t0[None, :], np.ones(1),
                     "holding at the worst task pose (no max_speed/max_acceleration given)")


def trajectory_cycle(samples) -> DutyCycle:
    """Duty cycle of a sampled trajectory (``time``, ``tensions``, ``cable_speed``, ``cable_accel``).

    With elastic or sagging cables the tensions are the outlet (winch-side) ones.
    """
    t = np.asarray(samples.time, float)
    if t.size > 1:
        dt = np.gradient(t)
        w = dt / dt.sum()
    else:
        w = np.ones(t.size)
    tensions = np.asarray(samples.tensions, float)
    cables = getattr(samples, "cables", None)
    if cables is not None:  # elastic or sagging cables: the winch holds the outlet tension
        tensions = np.asarray(cables.outlet_tensions, float)
    return DutyCycle(tensions, np.asarray(samples.cable_accel, float),
                     np.asarray(samples.cable_speed, float), w,
                     f"trajectory {getattr(samples, 'name', '')}".strip())
