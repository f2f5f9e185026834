"""Worst-case tensions, cable speeds and cable accelerations over the task poses.

The first step of the sizing (:mod:`cdpr_design.design.sizing`), per cable,
over the grid of ``requirements.task_box`` at the workspace's fixed
orientation, or the statically feasible workspace grid when no task box is
given:

- static tension t0 (W t = w_req, w_req = -w_gravity);
- dynamic tension when the platform accelerates with |a| <= A
  (``requirements.max_acceleration``): the inertial wrench is linear in a,
  w_req(a) = w0 + M a with M = [m I ; m [R c]x] (rows of the motion), so
  for m = n (t = W^-1 w unique) the worst case over the ball of
  accelerations is exact: t_i,max = t0_i + A ||row_i(W^-1 M)||;
  for m > n the minimum 2-norm tensions (the exact Goldfarb-Idnani kernel)
  are evaluated at the vertices of a polytope inscribed in the ball
  (16 directions in the plane, 26 in space);
- cable speed L'_i = -J_i v: the worst case over |v| <= V
  (``requirements.max_speed``) is V ||J_i,v|| = V (no angular velocity is
  required, so every attachment point moves with v);
- cable acceleration L''_i = -u_i . a - |v_perp|^2 / L_i, bounded by
  A + V^2 / L_i over the task poses.

With sagging cables (:mod:`cdpr_design.statics.cables`) W is built from
each catenary's end-force directions at the static solution, and the static
and peak tensions are those the winch holds: the effector-end tension plus the
static difference between the outlet and the effector end (the cable's share
of its own weight).  The dynamic part keeps the static cable shapes (a
linearisation: the shapes change little over the acceleration set).

With swivel pulleys (``cables[i].pulley``) lengths are arc + free
segment and u_i leaves from the pulley's tangent point
(:mod:`cdpr_design.statics.pulley`); L'_i = -u_i . v still holds (|u_i| = 1) and
the curvature term is bounded by V^2 max(1 / l_f, |kappa_t|), the largest
eigenvalue of the pulley-aware Hessian of L_i.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Callable, Iterable

import numpy as np

from cdpr_design.model.design import Design, Grid
from cdpr_design.statics import cables as cable_models
from cdpr_design.statics.robot import Robot, tension_lower
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.degenerate import degenerate_structure
from cdpr_design.statics.pose import structure_many
from cdpr_design import workspaces as workspace
from cdpr_design.workspaces import grid as wsg


def acceleration_directions(dim: int) -> np.ndarray:
    """Unit directions whose multiples by A are the vertices of the acceleration polytope.

    Planar: 16 evenly spaced directions; spatial: the 26 normalised vectors of
    {-1, 0, 1}^3 without 0 (cube vertices, edge and face centres).  The
    polytope is inscribed in the ball |a| <= A.
    """
    if dim == 2:
        ang = np.arange(16) * (2 * math.pi / 16)
        return np.stack([np.cos(ang), np.sin(ang)], axis=1)
    v = np.array([p for p in itertools.product((-1.0, 0.0, 1.0), repeat=3) if any(p)])
    return v / np.linalg.norm(v, axis=1, keepdims=True)


@dataclass
class Envelope:
    """Worst cases per cable over the task poses (arrays of length m).

    Attributes
    ----------
    poses : int
        Task poses evaluated.
    source : str
        ``task_box`` or ``feasible workspace``.
    static_tension : (m,) peak static tension [N].
    peak_tension : (m,) peak tension with the acceleration set [N].
    min_tension : (m,) least tension with the acceleration set [N] (below
        t_min means the cable would go slack at some acceleration).
    peak_cable_speed, peak_cable_accel : (m,) [m/s], [m/s^2].
    worst_pose : (m, ncoords) pose of each cable's peak tension.
    worst_static : (m,) static tension at that pose [N].
    worst_gain : (m,) (peak - static) / A at that pose [N per m/s^2]: the
        tension gained per unit of acceleration in the worst direction.
    singular : int
        Task poses where W is rank deficient (left out).
    """

    poses: int
    source: str
    static_tension: np.ndarray
    peak_tension: np.ndarray
    min_tension: np.ndarray
    peak_cable_speed: np.ndarray
    peak_cable_accel: np.ndarray
    worst_pose: np.ndarray
    worst_static: np.ndarray
    worst_gain: np.ndarray
    singular: int = 0
    max_speed: float = 0.0
    max_acceleration: float = 0.0


def task_grid(design: Design, step: float | None = None) -> Grid | None:
    """The grid over ``requirements.task_box`` (workspace step unless ``step`` [m]), or None."""
    box = design.requirements.task_box
    if box is None:
        return None
    if step is not None:
        wsg.check_step(step, "--step")
    st = (float(step),) * len(box[0]) if step is not None else design.workspace.grid.step
    return Grid(tuple(float(x) for x in box[0]), tuple(float(x) for x in box[1]), tuple(st))


def wrench_model(design: Design, orientation) -> tuple[np.ndarray, np.ndarray]:
    """w_req(a) = w0 + M a for a platform acceleration a (dim) at a fixed orientation.

    w0 = -w_gravity; M = rows of [m I ; m [R c]x] (d'Alembert: the cables must
    supply m a at the centre of mass besides balancing gravity).  Returns
    (w0 (n,), M (n, dim)).
    """
    d = design.motion.dim
    pose = np.zeros(len(design.motion.coords))
    pose[d:] = rotation_coords(design, orientation)
    w0 = kin.required_wrench(design, pose)
    return w0, kin.mass_matrix(design, orientation)[:, :d]


def rotation_coords(design: Design, ori3) -> np.ndarray:
    """The motion's rotation coordinates [rad] of an orientation (rx, ry, rz): (), (rz,) or all three."""
    ori3 = np.asarray(ori3, float)
    name = design.motion.name
    if name == "1R2T":
        return ori3[2:3]
    if name == "3R3T":
        return ori3
    return np.zeros(0)


def _min_norm_general(W, wreq, tmin, tmax):
    """Minimum 2-norm tensions [N] for m > n at one pose, one row of ``wreq`` each.

    Bounded by [t_min, t_max] where that is feasible, otherwise by t_min only
    (the tension the winch must supply to hold the pose).  NaN where none.
    Exact: the Goldfarb-Idnani kernel through
    :func:`cdpr_design.statics.tension.min_norm_many` and
    :func:`~cdpr_design.statics.tension.min_norm_above` (imported here:
    they load numba, which the m = n designs never need).
    """
    from cdpr_design.statics import tension

    out = tension.min_norm_many(W, wreq, tmin, tmax)
    for k in np.flatnonzero(~np.all(np.isfinite(out), axis=1)):
        t = tension.min_norm_above(W, wreq[k], tmin)
        if t is not None:
            out[k] = t
    return out


def envelope_chunk(robot: Robot, positions: np.ndarray, orientation, A: float, V: float) -> dict:
    """Per-pose worst cases of ``robot`` (resolved for ``size-motors``) for a chunk of positions
    (k, dim) [m] at a fixed orientation (rx, ry, rz) [rad].

    A [m/s^2] and V [m/s] bound the platform's acceleration and speed.
    Returns a dict of (k, m) arrays: ``static``, ``peak``, ``low`` (least
    tension over the acceleration set) [N], ``accel`` (cable acceleration
    bound) [m/s^2], and a (k,) bool ``ok`` (W of full rank).
    """
    design = robot.design
    k = positions.shape[0]
    d = design.motion.dim
    pos3 = np.zeros((k, 3))
    pos3[:, :d] = positions
    R = kin.rotation_matrix(*orientation)
    Rb = design.attachments @ R.T
    W, L, free, kappa = structure_many(robot, pos3, Rb)
    sag_ok, offset = None, 0.0
    if not robot.cables.straight:
        sag_ok, Ws, t_eff, t_out = cable_models.sagging_structures(robot, pos3, orientation)
        W[sag_ok] = Ws[sag_ok]
        offset = np.where(sag_ok[:, None], np.nan_to_num(t_out - t_eff), 0.0)
    w0, M = wrench_model(design, orientation)
    if design.m == design.n:
        static, peak, low, ok = _square_chunk(W, w0, M, A)
    else:
        lower = tension_lower(robot.tension_min, robot.tension_floor, free)  # (k, m): the frequency floor
        static, peak, low, ok = _redundant_chunk(design, W, w0, M, A, lower)
    if sag_ok is not None:
        # the winch holds the outlet tension: the effector's plus the cable's share of its weight
        ok &= sag_ok
        static, peak = static + offset, peak + offset
    bad = degenerate_structure(W)  # a cable of zero length: left out, as `pose` calls it infeasible
    if bad.any():
        ok = ok & ~bad
        for a in (static, peak, low):
            a[bad] = np.nan
    with np.errstate(divide="ignore", invalid="ignore"):
        accel = A + V * V * kappa  # kappa = 1 / L for a point outlet
    accel[:, :] = np.where(L > 1e-12, accel, np.nan)
    return {"static": static, "peak": peak, "low": low, "accel": accel, "ok": ok}


def _square_chunk(W, w0, M, A):
    """m = n: t = W^-1 w is unique; the worst case over |a| <= A is t0 +- A ||row_i(W^-1 M)|| [N]."""
    k, n, m = W.shape
    static, peak, low = (np.full((k, m), np.nan) for _ in range(3))
    scale = np.abs(W).max(axis=(1, 2))
    ok = np.abs(np.linalg.det(W)) > 1e-10 * np.maximum(scale, 1e-300) ** n
    if ok.any():
        Wi = np.linalg.inv(W[ok])
        t0 = Wi @ w0
        G = np.linalg.norm(Wi @ M, axis=2)
        static[ok] = t0
        peak[ok] = t0 + A * G
        low[ok] = t0 - A * G
    return static, peak, low, ok


def _redundant_chunk(design: Design, W, w0, M, A, lower):
    """m > n: minimum 2-norm tensions [N] at w0 and at the vertices of the acceleration polytope,
    within each pose's lower bounds ``lower`` (k, m) [N] (:func:`~cdpr_design.statics.robot.tension_lower`)
    and the cables' upper bounds."""
    k, n, m = W.shape
    static, peak, low = (np.full((k, m), np.nan) for _ in range(3))
    ok = np.zeros(k, dtype=bool)
    dirs = acceleration_directions(design.motion.dim) * A
    wreq = np.vstack([w0[None, :], w0[None, :] + dirs @ M.T]) if A > 0 else w0[None, :]
    for j in range(k):
        if np.linalg.matrix_rank(W[j]) < n:
            continue
        T = _min_norm_general(W[j], wreq, lower[j], design.tension_max)
        if not np.all(np.isfinite(T[0])):
            continue
        ok[j] = True
        static[j] = T[0]
        peak[j] = np.nanmax(T, axis=0)
        low[j] = np.nanmin(T, axis=0)
    return static, peak, low, ok


def task_envelope(robot: Robot, *, step: float | None = None, positions: np.ndarray | None = None,
                  chunk: int = 4096, progress: Callable[[int, int], None] | None = None,
                  engine: str = "auto") -> Envelope:
    """Worst-case tensions, cable speeds and accelerations over the task poses.

    Parameters
    ----------
    robot : Robot
        The design resolved for ``size-motors`` (:func:`~cdpr_design.statics.robot.resolve`).
    step : float, optional
        Grid step [m] over the task box (default: ``workspace.grid.step``).
    positions : (k, dim) array, optional
        Evaluate these platform positions [m] instead (at the workspace's fixed
        orientation).  Without a task box and without positions the statically
        feasible poses of the workspace grid are used.
    chunk : int
        Task-box grid poses evaluated at once.
    progress : callable(done, total), optional
    engine : {'auto', 'numba', 'numpy'}
        Engine of the workspace sweep used without a task box.
    """
    design = robot.design
    req = design.requirements
    A = float(req.max_acceleration or 0.0)
    V = float(req.max_speed or 0.0)
    ori = design.default_orientation_full()
    source, blocks = _task_positions(design, step, positions, chunk, engine)
    worst = _Worst(design, rotation_coords(design, ori), A)
    for pos in blocks:
        if pos.shape[0] == 0:
            continue
        if worst.add(pos, envelope_chunk(robot, pos, ori, A, V)) and progress is not None:
            progress(worst.total, worst.total)
    return worst.envelope(source, V)


def _task_positions(design: Design, step: float | None, positions, chunk: int,
                    engine: str) -> tuple[str, Iterable[np.ndarray]]:
    """(source, blocks of (k, dim) positions [m]): the given ones, the task box grid or the feasible workspace."""
    d = design.motion.dim
    if positions is not None:
        return "given poses", [np.atleast_2d(np.asarray(positions, float))[:, :d]]
    if design.requirements.task_box is not None:
        g = task_grid(design, step)
        wsg.check_grid_size(g, False, "requirements.task_box")
        return "task_box", (wsg.grid_positions(g, s, min(chunk, g.size - s)) for s in range(0, g.size, chunk))
    feas: list[np.ndarray] = []
    workspace.run(design, workspace.Analysis(engine=engine), step=step, keep_maps=False, tilt=False,
                  on_chunk=lambda c: feas.append(c.poses[c.feasible.astype(bool), :d]))
    return "feasible workspace", feas


class _Worst:
    """The running worst cases of :func:`task_envelope`, chunk by chunk."""

    def __init__(self, design: Design, rot: np.ndarray, A: float):
        m = design.m
        self.d, self.rot, self.A = design.motion.dim, rot, A
        self.static = np.full(m, -np.inf)
        self.peak = np.full(m, -np.inf)
        self.low = np.full(m, np.inf)
        self.acc = np.full(m, -np.inf)
        self.worst_pose = np.full((m, len(design.motion.coords)), np.nan)
        self.worst_static = np.full(m, np.nan)
        self.worst_gain = np.full(m, np.nan)
        self.total = 0
        self.singular = 0

    def add(self, pos: np.ndarray, e: dict) -> bool:
        """Take in one :func:`envelope_chunk`; False when none of its poses has a full-rank W."""
        okp = e["ok"]
        self.total += pos.shape[0]
        self.singular += int((~okp).sum())
        if not okp.any():
            return False
        self.static = np.fmax(self.static, np.nanmax(e["static"][okp], axis=0))
        self.low = np.fmin(self.low, np.nanmin(e["low"][okp], axis=0))
        self.acc = np.fmax(self.acc, np.nanmax(e["accel"][okp], axis=0))
        pk = np.where(okp[:, None], e["peak"], -np.inf)
        j = np.argmax(pk, axis=0)
        for i in range(self.peak.size):
            if pk[j[i], i] > self.peak[i]:
                self.peak[i] = pk[j[i], i]
                self.worst_pose[i, :self.d] = pos[j[i]]
                self.worst_pose[i, self.d:] = self.rot
                self.worst_static[i] = e["static"][j[i], i]
                self.worst_gain[i] = (self.peak[i] - self.worst_static[i]) / self.A if self.A > 0 else 0.0
        return True

    def envelope(self, source: str, V: float) -> Envelope:
        """The :class:`Envelope` (NaN where no pose gave a figure)."""
        for arr in (self.static, self.peak, self.acc, self.low):
            arr[~np.isfinite(arr)] = np.nan
        speed = np.full(self.peak.size, V)  # |J_i v| <= V |u_i| = V for a translating platform
        return Envelope(self.total, source, self.static, self.peak, self.low, speed, self.acc,
                        self.worst_pose, self.worst_static, self.worst_gain, self.singular, V, self.A)
