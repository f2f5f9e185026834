"""Workspace sweeps with real hardware geometry: swivel pulleys and interference.

:class:`HardwareSweep` is the sweep plan's base evaluator when a design has
swivel pulleys or interference is checked, through
:func:`cdpr_design.kernels.sweep_points` (pulley-aware structure matrix,
interference mask per pose).  :class:`Evaluator` evaluates
explicit positions at one orientation; the orientation workspaces
(:mod:`cdpr_design.workspaces.orientation`) call it once per orientation.

Results are data: chunks go to ``on_chunk``, nothing touches files.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.hardware import hardware_arrays, in_cable_planes
from cdpr_design.statics.interference import HIT_NAMES
from cdpr_design.statics.wrenches import wrench_vertices
from cdpr_design.statics.robot import Robot
from cdpr_design.workspaces.cables import kind_counts
from cdpr_design.workspaces.grid import Rows
from cdpr_design.workspaces.parts import Base


class Evaluator:
    """Evaluates explicit positions of ``robot`` at one orientation (pulleys and, with the
    analysis's ``collisions``, interference included)."""

    def __init__(self, robot: Robot):
        design = self.design = robot.design
        self.kind = robot.kind
        self.kcode = robot.kcode
        self.interference = bool(robot.analysis.collisions)
        self.hw = hardware_arrays(design)
        self.A = robot.outlet_points
        self.Bp = robot.attachments
        self.Bp_planes = np.ascontiguousarray(in_cable_planes(robot.attachments, self.hw.zoff))  # interference
        self.rows = robot.rows
        self.tmin, self.tmax, self.floor = robot.tension_min, robot.tension_max, robot.tension_floor
        self.combos = robot.combos
        self._wreq = {}

    def wrench(self, ori) -> np.ndarray:
        key = tuple(float(x) for x in ori)
        if key not in self._wreq:
            self._wreq[key] = wrench_vertices(self.design, self.kind, np.asarray(ori, float))
        return self._wreq[key]

    def __call__(self, P: np.ndarray, ori, full: bool = True):
        """(feasible uint8, margin, tensions, lengths, mask uint8) at positions ``P`` (k, 3).

        ``feasible`` is the statics result only; ``mask`` the interference bits
        (zero when interference is not checked).
        """
        ori = np.asarray(ori, float)
        R = np.ascontiguousarray(kin.rotation_matrix(*ori))
        Rb = np.ascontiguousarray(self.Bp @ R.T)
        k, m = P.shape[0], self.design.m
        feas = np.empty(k, dtype=np.uint8)
        marg = np.empty(k)
        ten = np.empty((k, m))
        L = np.empty((k, m))
        mask = np.empty(k, dtype=np.uint8)
        from cdpr_design import kernels as K  # numba, on first use

        hw = self.hw
        K.sweep_points(np.ascontiguousarray(P, dtype=float), Rb, R,
                       K.Statics(self.A, self.rows, self.tmin, self.tmax, self.floor, self.combos, self.kcode),
                       self.wrench(ori), K.Pulleys(hw.axes, hw.eref, hw.radii),
                       K.Interference(self.interference, self.Bp_planes, hw.half, hw.rho, hw.frame_lower,
                                      hw.frame_upper, hw.dim, hw.tol, full, hw.zoff),
                       K.Outputs(feas, marg, ten, L), mask)
        return feas, marg, ten, L, mask


class HardwareSweep(Base):
    """The base evaluator with swivel pulleys and (the analysis's ``collisions``) interference, at
    one orientation ``ori`` (3,) [rad], through :func:`cdpr_design.kernels.sweep_points`.

    With interference the ``feasible`` flag is statics-feasible and collision free; tensions
    are blanked (NaN) where a pose collides; the margin stays the capacity margin; column
    ``collision_free``.  Summary keys: ``pulleys``, ``interference`` and, with interference,
    ``collision_free`` (collision-free poses), ``feasible_statics`` (feasible before the
    interference checks), ``collisions_by_kind`` (poses hit by each kind of interference).
    """

    def __init__(self, robot: Robot, ori: np.ndarray):
        self.robot, self.kind, self.ori = robot, robot.kind, ori
        self.ev = Evaluator(robot)
        self.interference = robot.analysis.collisions
        self.columns = ("collision_free",) if self.interference else ()
        self.n_free = self.n_stat = 0
        self.counts = {name: 0 for name in HIT_NAMES.values()}

    def rows(self, start: int, count: int, P: np.ndarray | None) -> Rows:
        feas, marg, ten, L, mask = self.ev(P, self.ori)
        extra = {}
        if self.interference:
            self.n_stat += int(np.count_nonzero(feas))
            cfree = (mask == 0).astype(np.uint8)
            self.n_free += int(np.count_nonzero(cfree))
            kind_counts(mask, self.counts)
            feas &= cfree
            ten[cfree == 0] = np.nan
            extra["collision_free"] = cfree
        return Rows(feas, marg, ten, L, extra)

    def summary(self, maps) -> dict:
        extra = {"pulleys": self.robot.outlets.pulleys, "interference": bool(self.interference)}
        if self.interference:
            extra.update(collision_free=self.n_free, feasible_statics=self.n_stat, collisions_by_kind=self.counts)
        return extra
