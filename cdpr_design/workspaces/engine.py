"""The straight-cable grid sweep: point outlets, no interference, one fixed orientation.

The robot's ``engine`` (:func:`cdpr_design.statics.robot.resolve`) says which of two
implementations sweeps it; each case has exactly one:

- ``numpy``: two cables and two wrench rows (static or wrench-feasible): the
  closed form t = W^-1 w, vectorised over each chunk (:func:`_planar2_numpy`),
  without loading numba;
- ``numba``: every other robot, by the kernels of :mod:`cdpr_design.kernels`
  (any m, n, kind).
"""

from __future__ import annotations

import numpy as np

from cdpr_design.model.design import Grid
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.wrenches import wrench_vertices
from cdpr_design.statics.robot import Robot, tension_lower
from cdpr_design.workspaces.grid import Rows, grid3, grid_positions
from cdpr_design.workspaces.parts import Base


def kernels():
    """The numba kernels, imported on first use: the sweep kernels now, the rest of the (lazy)
    package :mod:`cdpr_design.kernels` as its names are used."""
    import importlib

    from cdpr_design import kernels as K

    importlib.import_module("cdpr_design.kernels.sweep")
    return K


class StraightSweep(Base):
    """The base evaluator of straight cables from point outlets at one orientation ``ori`` (3,)
    [rad]: the robot's engine, numpy (the closed form of two cables) or the kernels; the arrays
    built once."""

    positions = False  # the engines work from the grid's indices

    def __init__(self, robot: Robot, ori: np.ndarray, g: Grid):
        design = robot.design
        R = kin.rotation_matrix(*ori)
        self.robot, self.kind, self.g, self.ori = robot, robot.kind, g, ori
        self.Rb = np.ascontiguousarray(robot.attachments @ R.T)
        self.wreq = wrench_vertices(design, robot.kind, ori)
        self.numpy = robot.engine == "numpy"
        self.K = None if self.numpy else kernels()
        self.wreq_used = self.wreq if robot.every_vertex else self.wreq[:1].copy()
        self.lower, self.step, self.shape = grid3(g)
        self.loads = False  # the frame-load envelope with the rows (keep_frame_loads)

    def keep_frame_loads(self) -> bool:
        """The kernels raise the envelope of the frame loads as they sweep (pose by pose, on their
        threads: :func:`~cdpr_design.kernels.sweep.sweep_grid`); numpy's closed form does not."""
        self.loads = not self.numpy
        return self.loads

    def rows(self, start: int, count: int, P: np.ndarray | None) -> Rows:
        r, cnt, m = self.robot, count, self.robot.m
        feas, marg = np.empty(cnt, dtype=np.uint8), np.empty(cnt)
        ten, lens = np.empty((cnt, m)), np.empty((cnt, m))
        if self.numpy:
            _planar2_numpy(grid_positions(self.g, start, cnt), self.Rb, r.outlet_points, self.wreq_used, r.tension_min,
                           r.tension_max, r.tension_floor, feas, marg, ten, lens)
            return Rows(feas, marg, ten, lens)
        loads = self.K.frame_loads.empty_envelope(m) if self.loads else (np.empty((0, 13)), np.empty((0, 3)))
        self._sweep(self.K.GridPoses(start, self.lower, self.step, self.shape, self.Rb, np.empty((0, 3)), *loads),
                    Rows(feas, marg, ten, lens))
        return Rows(feas, marg, ten, lens, loads=loads if self.loads else None)

    def _sweep(self, poses, rows: Rows) -> None:
        """The kernels' grid sweep of ``poses`` (:class:`~cdpr_design.kernels.sweep.GridPoses`) into ``rows``."""
        K, r = self.K, self.robot
        K.sweep_grid(poses, K.Statics(r.outlet_points, r.rows, r.tension_min, r.tension_max, r.tension_floor, r.combos,
                                      r.kcode),
                     self.wreq, K.Outputs(rows.feasible, rows.margin, rows.tensions, rows.lengths))

    def feasible_at(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Feasibility (k,) bool and capacity margin (k,) [N] at positions ``P`` (k, 3) [m], at the
        sweep's orientation: numpy's closed form, or the grid sweep's own compiled loop given the
        positions (:class:`~cdpr_design.kernels.sweep.GridPoses` ``P``)."""
        r, k, m = self.robot, P.shape[0], self.robot.m
        feas, marg = np.empty(k, dtype=np.uint8), np.empty(k)
        if self.numpy:
            _planar2_numpy(P[:, :2], self.Rb, r.outlet_points, self.wreq_used, r.tension_min, r.tension_max,
                           r.tension_floor, feas, marg, np.empty((k, m)), np.empty((k, m)))
            return feas.astype(bool), marg
        if k:
            self._sweep(self.K.GridPoses(0, self.lower, self.step, self.shape, self.Rb,
                                         np.ascontiguousarray(P, dtype=float)),
                        Rows(feas, marg, np.empty((k, m)), np.empty((k, m))))
        return feas.astype(bool), marg


def _planar2_numpy(pos, Rb, A, wreq, tmin, tmax, floor, feasible, margin, tensions, lengths):
    """The rows of a robot with two cables and two wrench rows at positions ``pos`` (count, 2) [m].

    ``Rb`` (2, 3) rotated attachments [m], ``A`` (2, 3) outlets [m], ``wreq`` (k, >=2) required
    wrenches [N] (row 0 the static one), ``tmin``, ``tmax``, ``floor`` (2,) tension bounds [N] and
    string floors [N/m^2].  t = W^-1 w in closed form, the capacity margin
    min_i min(t_i - t_min,i, t_max,i - t_i) / ||row_i(W^-1)||, the other rows of
    ``wreq`` (wrench-feasible) lowering the margin; t_min,i raised to ``floor``[i] L_i^2 where
    ``floor``[i] > 0 (:func:`~cdpr_design.statics.robot.tension_lower`).  Fills rows 0 .. count of
    the output buffers ``feasible`` (uint8), ``margin`` [N], ``tensions`` (NaN where a tension
    leaves its bounds or the pose is rank deficient) and ``lengths`` [m], as the kernels fill
    theirs for every other robot.
    """
    count = pos.shape[0]
    px, py = pos[:, 0], pos[:, 1]
    lx0 = (A[0, 0] - Rb[0, 0]) - px
    ly0 = (A[0, 1] - Rb[0, 1]) - py
    lx1 = (A[1, 0] - Rb[1, 0]) - px
    ly1 = (A[1, 1] - Rb[1, 1]) - py
    L0 = np.sqrt(lx0 * lx0 + ly0 * ly0)
    L1 = np.sqrt(lx1 * lx1 + ly1 * ly1)
    lengths[:count, 0] = L0
    lengths[:count, 1] = L1
    tn = tension_lower(tmin, floor, np.stack([L0, L1], axis=1))
    tn0, tn1 = tn[:, 0], tn[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        u0x, u0y, u1x, u1y = lx0 / L0, ly0 / L0, lx1 / L1, ly1 / L1
        det = u0x * u1y - u1x * u0y
        inv = 1.0 / det
        i00, i01, i10, i11 = u1y * inv, -u1x * inv, -u0y * inv, u0x * inv
        r0 = np.sqrt(i00 * i00 + i01 * i01)
        r1 = np.sqrt(i10 * i10 + i11 * i11)
        w0, w1 = wreq[0, 0], wreq[0, 1]
        t0 = i00 * w0 + i01 * w1
        t1 = i10 * w0 + i11 * w1
        s = np.minimum(np.minimum(t0 - tn0, tmax[0] - t0) / r0, np.minimum(t1 - tn1, tmax[1] - t1) / r1)
        inb = s >= 0.0
        for v in range(1, wreq.shape[0]):
            q0 = i00 * wreq[v, 0] + i01 * wreq[v, 1]
            q1 = i10 * wreq[v, 0] + i11 * wreq[v, 1]
            s = np.minimum(s, np.minimum(np.minimum(q0 - tn0, tmax[0] - q0) / r0,
                                         np.minimum(q1 - tn1, tmax[1] - q1) / r1))
    # a zero-length cable or parallel cables: rank deficient, no margin, infeasible
    bad = (L0 <= 1e-12) | (L1 <= 1e-12) | (np.abs(det) <= _RANK_TOL)
    s[bad] = np.nan
    s += 0.0  # -0.0 -> 0.0, as the kernels write it
    ok = s >= 0.0
    margin[:count] = s
    feasible[:count] = ok
    tensions[:count, 0] = np.where(inb & ~bad, t0, np.nan)
    tensions[:count, 1] = np.where(inb & ~bad, t1, np.nan)


#: |det W| at or below it is rank deficient (= ``kernels.RANK_TOL``, the kernels' tolerance; a test checks)
_RANK_TOL = 1e-10
