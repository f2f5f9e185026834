"""Winch and motor formulas: drum and motor torque, reflected inertia, motor speed, margins.

For a drum radius r [m], gear ratio i (motor turns per drum turn) and
efficiency eta:

- drum torque T r [N m];
- motor torque tau = T r / (i eta) + J_refl alpha, with the reflected
  inertia J_refl = J_rotor + J_gearbox + J_drum / i^2 and the motor's angular
  acceleration alpha = i a_cable / r (the peaks are added: a conservative
  sum-of-peaks sizing);
- motor speed n = i v_cable / r  (x 60 / 2 pi for rpm);
- RMS torque over a duty cycle (:mod:`cdpr_design.design.duty`).

The inverse, the tension limit a motor implies, is t_max = tau_peak i eta / r
(rated: tau_rated i eta / r).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cdpr_design.design.duty import DutyCycle
from cdpr_design.design.envelope import Envelope
from cdpr_design.model.catalogue import Motor

RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)


@dataclass(frozen=True)
class WinchLoad:
    """What one cable asks of its winch for one drum radius / gear ratio / motor."""

    drum_radius: float
    gear_ratio: float
    efficiency: float
    gearbox: str
    reflected_inertia: float
    drum_torque: float
    peak_motor_torque: float
    rms_motor_torque: float
    peak_motor_speed: float


def motor_torque(tension, cable_accel, r, i, eta, J_refl):
    """Motor shaft torque [N m]: tau = T r / (i eta) - J_refl (i / r) L''.

    T [N] cable tension, L'' [m/s^2] cable length acceleration (negative while
    reeling in faster), r drum radius [m], i motor turns per drum turn, eta
    gearbox efficiency, J_refl = J_rotor + J_gearbox + J_drum / i^2 [kg m^2].
    """
    return np.asarray(tension) * r / (i * eta) - J_refl * (i / r) * np.asarray(cable_accel)


def reflected_inertia(rotor: float, gearbox: float, drum: float, i: float) -> float:
    """J_refl = J_rotor + J_gearbox + J_drum / i^2 [kg m^2] at the motor shaft."""
    return rotor + gearbox + drum / (i * i)


def winch_load(cable: int, env: Envelope, cycle: DutyCycle, r: float, i: float, eta: float,
               J_gear: float, J_drum: float, J_rotor: float, gearbox: str = "") -> WinchLoad:
    """Peak and RMS motor torque [N m] and peak speed [rpm] of one cable for one winch choice.

    r drum radius [m], i gear ratio, eta efficiency, inertias [kg m^2] (the
    gearbox's at the motor shaft, the drum's about its axis, the rotor's).
    """
    J = reflected_inertia(J_rotor, J_gear, J_drum, i)
    T = env.peak_tension[cable]
    a = env.peak_cable_accel[cable]
    v = env.peak_cable_speed[cable]
    peak = T * r / (i * eta) + J * (i * a / r)
    tau = motor_torque(cycle.tension[:, cable], cycle.cable_accel[:, cable], r, i, eta, J)
    peak = max(peak, float(np.max(np.abs(tau))))
    rms = float(np.sqrt(np.sum(cycle.weight * tau * tau)))
    v = max(v, float(np.max(np.abs(cycle.cable_speed[:, cable]))))
    speed = i * v / r * RPM_PER_RAD_S
    return WinchLoad(r, i, eta, gearbox, J, T * r, float(peak), rms, float(speed))


def margins(load: WinchLoad, motor: Motor, sf: float) -> tuple[float, float, float]:
    """(peak torque, RMS torque, speed) margins: available / (safety factor x required)."""
    def ratio(avail, need):
        need = sf * need
        return math.inf if need <= 0 else avail / need
    return (ratio(motor.usable_peak_torque, load.peak_motor_torque),
            ratio(motor.usable_rated_torque, load.rms_motor_torque),
            ratio(motor.max_speed, load.peak_motor_speed))


def implied_tension(torque: float, drum_radius: float, gear_ratio: float = 1.0,
                    efficiency: float = 1.0) -> float:
    """Cable tension [N] a motor torque [N m] holds: t = tau i eta / r.

    The seed paper's limit 0 <= T <= 20 N came "from the maximum torque of
    the motors" (Rivera et al., section 3): this is that relation, inertia left out.
    """
    return torque * gear_ratio * efficiency / drum_radius
