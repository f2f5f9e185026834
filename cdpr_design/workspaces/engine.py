"""The straight-cable grid sweep: point outlets, no interference, one fixed orientation.

Two engines compute the same rows:

- ``numba``: the kernels of :mod:`cdpr_design.kernels` (any m, n, kind);
- ``numpy``: the closed form of two cables and two wrench rows, vectorised
  over each chunk with the same formulas in the same order (bit-identical
  results, tested).

The robot's ``engine`` (:func:`cdpr_design.statics.robot.resolve`) says which:
``auto`` takes numpy for closed-form grids up to
:data:`~cdpr_design.statics.robot.NUMPY_MAX_POSES` poses while the kernels are
not loaded in the process: numba's start-up (its import and the cached
kernels' load) would cost more than the sweep itself.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.model.design import Grid
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.wrenches import wrench_vertices
from cdpr_design.statics.robot import Robot, tension_lower
from cdpr_design.workspaces.grid import Rows, grid3, grid_positions
from cdpr_design.workspaces.parts import Base

#: The kernel module whose import loads the sweep kernels (numba): the package
#: :mod:`cdpr_design.kernels` itself is lazy (``kernels.parallel`` is imported without numba by
#: the batch and optimize layers).
LOADED = "cdpr_design.kernels.sweep"


def kernels():
    """The numba kernels, imported on first use (importing numba is slow): :data:`LOADED`
    now, the rest of the (lazy) package as its names are used."""
    import importlib

    from cdpr_design import kernels as K

    importlib.import_module(LOADED)
    return K


def load_kernels() -> None:
    """Load the numba kernels now: for a process that will sweep many grids (a sweep worker),
    where numba's start-up is repaid (it then resolves its robots with ``kernels_loaded``)."""
    kernels()


class StraightSweep(Base):
    """The base evaluator of straight cables from point outlets at one orientation ``ori`` (3,)
    [rad]: the robot's engine, numpy (closed form) or the kernels; the arrays built once."""

    positions = False  # the engines work from the grid's indices

    def __init__(self, robot: Robot, ori: np.ndarray, g: Grid):
        design = robot.design
        R = kin.rotation_matrix(*ori)
        self.robot, self.kind, self.g, self.ori = robot, robot.kind, g, ori
        self.Rb = np.ascontiguousarray(robot.attachments @ R.T)
        self.wreq = wrench_vertices(design, robot.kind, ori)
        self.numpy = robot.engine == "numpy"
        # the paper's case (two cables, two wrench rows) has a closed form
        self.planar2 = robot.m == 2 and robot.n == 2 and robot.kind != "wrench-closure"
        self.K = None if self.numpy else kernels()
        self.wreq_used = self.wreq if robot.kind == "wrench-feasible" else self.wreq[:1].copy()
        self.lower, self.step, self.shape = grid3(g)

    def rows(self, start: int, count: int, P: np.ndarray | None) -> Rows:
        r, cnt, m = self.robot, count, self.robot.m
        feas, marg = np.empty(cnt, dtype=np.uint8), np.empty(cnt)
        ten, lens = np.empty((cnt, m)), np.empty((cnt, m))
        if self.numpy:
            _planar2_numpy(grid_positions(self.g, start, cnt), self.Rb, r.outlet_points, self.wreq_used, r.tension_min,
                           r.tension_max, r.tension_floor, feas, marg, ten, lens)
        elif self.planar2:
            self.K.sweep_grid_planar2(start, cnt, self.lower, self.step, self.shape, self.Rb, r.outlet_points,
                                      self.wreq_used, r.tension_min, r.tension_max, r.tension_floor, feas, marg,
                                      ten, lens)
        else:
            K = self.K
            K.sweep_grid(K.GridPoses(start, self.lower, self.step, self.shape, self.Rb),
                         K.Statics(r.outlet_points, r.rows, r.tension_min, r.tension_max, r.tension_floor, r.combos,
                                   r.kcode),
                         self.wreq, K.Outputs(feas, marg, ten, lens))
        return Rows(feas, marg, ten, lens)

    def feasible_at(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Feasibility (k,) bool and capacity margin (k,) [N] at positions ``P`` (k, 3) [m]: numpy's
        closed form, or the kernels' statics at explicit positions
        (:func:`cdpr_design.kernels.hanging.eval_rotated`, every pose at the sweep's orientation)."""
        r, k, m = self.robot, P.shape[0], self.robot.m
        feas, marg = np.empty(k, dtype=np.uint8), np.empty(k)
        if self.numpy:
            _planar2_numpy(P[:, :2], self.Rb, r.outlet_points, self.wreq_used, r.tension_min, r.tension_max,
                           r.tension_floor, feas, marg, np.empty((k, m)), np.empty((k, m)))
            return feas.astype(bool), marg
        from cdpr_design.kernels import hanging as KH
        from cdpr_design.kernels.pose import Outputs, Statics

        R = np.ascontiguousarray(np.broadcast_to(kin.rotation_matrix(*self.ori), (k, 3, 3)))
        wreq = np.ascontiguousarray(np.broadcast_to(self.wreq, (k,) + self.wreq.shape))
        KH.eval_rotated(np.ascontiguousarray(P, dtype=float), R, r.attachments,
                        Statics(r.outlet_points, r.rows, r.tension_min, r.tension_max, r.tension_floor, r.combos,
                                r.kcode),
                        wreq, Outputs(feas, marg, np.empty((k, m)), np.empty((k, m))))
        return feas.astype(bool), marg

    def stats(self, rows: Rows, tpeak: np.ndarray) -> tuple:
        if self.numpy:  # numba's start-up is what the numpy engine saves
            return _chunk_stats_numpy(rows.feasible, rows.margin, rows.tensions, rows.feasible.shape[0], tpeak)
        return self.K.chunk_stats(rows.feasible, rows.margin, rows.tensions, rows.feasible.shape[0], tpeak)


def _planar2_numpy(pos, Rb, A, wreq, tmin, tmax, floor, feasible, margin, tensions, lengths):
    """``kernels.sweep_grid_planar2`` vectorised with numpy: same formulas, same order.

    Two cables, two wrench rows: t = W^-1 w in closed form, the capacity margin
    min_i min(t_i - t_min,i, t_max,i - t_i) / ||row_i(W^-1)||, the other rows of
    ``wreq`` (wrench-feasible) lowering the margin; t_min,i raised to ``floor``[i] L_i^2 where
    ``floor``[i] > 0 (:func:`~cdpr_design.statics.robot.tension_lower`).  ``pos`` (count, 2) [m]
    the positions; fills rows 0 .. count of the output buffers exactly as the kernel does.
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
    s += 0.0  # -0.0 -> 0.0, as the kernel (np.minimum and min() differ on the sign of equal zeros)
    ok = s >= 0.0
    margin[:count] = s
    feasible[:count] = ok
    tensions[:count, 0] = np.where(inb & ~bad, t0, np.nan)
    tensions[:count, 1] = np.where(inb & ~bad, t1, np.nan)


#: = ``kernels.RANK_TOL`` (a test checks): |det W| at or below it is rank deficient
_RANK_TOL = 1e-10


def _chunk_stats_numpy(feasible, margin, tensions, count, tpeak):
    """``kernels.chunk_stats`` with numpy: (feasible count, min margin, max margin); raises ``tpeak``."""
    f = feasible[:count].astype(bool)
    nf = int(np.count_nonzero(f))
    if not nf:
        return 0, np.inf, -np.inf
    mm = margin[:count][f]
    np.maximum(tpeak, tensions[:count][f].max(axis=0), out=tpeak)
    return nf, float(mm.min()) + 0.0, float(mm.max()) + 0.0
