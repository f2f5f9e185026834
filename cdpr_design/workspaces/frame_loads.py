"""The loads the cables put on the frame, over the feasible grid poses of a sweep.

At each feasible pose with the sweep's tension distribution, the force on the frame at cable
i's outlet is

- straight cables (ideal, elastic) from a point outlet: t_i along the cable, from the outlet
  towards the effector, F_i = t_i (B_i - A_i) / |B_i - A_i|;
- over a swivel pulley: the resultant of both cable runs on its axle, F_i = t_i (d_i - k_i),
  d_i the unit vector from the tangent point towards the attachment and k_i the swivel axis
  (the run from the winch arrives along k_i, :mod:`cdpr_design.statics.pulley`);
- sagging cables: the outlet end's tension along the catenary's tangent there.  A cable of
  weight w_i per unstretched metre and unstretched length L0_i hangs in the vertical plane
  through its chord, so the frame carries what the effector does not: F_i = -f_i - w_i L0_i up,
  f_i the cable's force on the effector.  With the tensions T_b at the effector and T_a at the
  outlet (the sweep's ``tension_<c>`` and ``outlet_tension_<c>``) the vertical part of f_i is
  v = (T_a^2 - T_b^2 - (w L0)^2) / (2 w L0) and its horizontal part H = sqrt(T_b^2 - v^2), so
  F_i = H h_i - (v + w L0) up, h_i the horizontal unit vector from the outlet towards the
  attachment (Irvine, "Cable Structures", MIT Press 1981, ch. 2: the horizontal component is
  constant along the cable).

A pose's total force on the frame is sum_i F_i and its moment sum_i A_i x F_i about the frame's
origin (A_i the outlet, a pulley's swivel point).  The worst case the tension bounds allow
(``limit_`` columns) takes each cable at its upper bound t_max,i along every direction it takes
over the feasible poses: t_max,i F_i / s_i, s_i the tension at the outlet (t_i; T_a sagging).
The envelope is kept per chunk of rows (:class:`FrameLoadTable`): a few numbers a cable.
The total orientation workspace's rows stand for every orientation of its set: the loads are
the envelope over the positions feasible at every orientation and over every orientation, each
with its own tension distribution (its own statics, sagging cables' included:
:attr:`~cdpr_design.workspaces.grid.Rows.sets`).  The orientation range's rows are the nominal
orientation's, and so are its loads (sagging cables: the nominal's statics,
:attr:`~cdpr_design.workspaces.grid.Rows.nominal`: a catenary's end forces come from its own
tensions and length).
"""

from __future__ import annotations

import numpy as np

from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.robot import Robot
from cdpr_design.workspaces.grid import Maps, Rows, WorkspaceResult
from cdpr_design.workspaces.parts import Wrapper

#: Feasible rows whose loads are computed at once (the temporaries stay small).
BLOCK = 8192
#: The envelope statistics of each cable, in ``frame_loads.csv``'s order after ``cable``.
AXES = ("x", "y", "z")


def csv_columns(planar: bool) -> list[str]:
    """``frame_loads.csv``'s columns: ``cable``, ``max_force``, ``min_fx`` .. ``max_fy`` (``fz``
    spatial), then the same with ``limit_`` in front (all in N)."""
    axes = AXES[:2] if planar else AXES
    stats = ["max_force"] + [f"{mm}_f{a}" for a in axes for mm in ("min", "max")]
    return ["cable"] + stats + [f"limit_{s}" for s in stats]


class FrameLoadTable:
    """The streaming envelope of the frame loads of ``m`` cables in ``d`` = 2 or 3 axes."""

    def __init__(self, m: int, d: int):
        self.m, self.d = m, d
        self.poses = 0
        self.fmax = np.full(m, -np.inf)
        self.fmin_ax = np.full((m, d), np.inf)
        self.fmax_ax = np.full((m, d), -np.inf)
        self.lmax = np.full(m, -np.inf)
        self.lmin_ax = np.full((m, d), np.inf)
        self.lmax_ax = np.full((m, d), -np.inf)
        nm = 1 if d == 2 else 3
        self.tmin, self.tmax = np.full(d, np.inf), np.full(d, -np.inf)
        self.tnorm = -np.inf
        self.mmin, self.mmax = np.full(nm, np.inf), np.full(nm, -np.inf)
        self.mnorm = -np.inf

    def add(self, F: np.ndarray, U: np.ndarray, A: np.ndarray, tmax: np.ndarray, fmag=None, umag=None) -> None:
        """Forces ``F`` (m, 3, k) [N] on the outlets ``A`` (m, 3) [m] at k poses, and ``U``
        (m, 3, k) the same per newton of the cable's tension at its outlet (the ``limit_``
        envelope is ``tmax`` (m,) [N] times it); ``fmag`` (m, k) [N] and ``umag`` (m, k) their
        magnitudes where known (a straight cable's: its tension, and 1)."""
        if F.shape[2] == 0:
            return
        d = self.d
        self.poses += F.shape[2]
        if fmag is None:
            fmag = np.sqrt(np.einsum("mik,mik->mk", F, F))
        tm = tmax[:, None]
        np.fmax(self.fmax, fmag.max(axis=1), out=self.fmax)
        np.fmin(self.fmin_ax, F[:, :d].min(axis=2), out=self.fmin_ax)
        np.fmax(self.fmax_ax, F[:, :d].max(axis=2), out=self.fmax_ax)
        np.fmax(self.lmax, tmax * (np.sqrt(np.einsum("mik,mik->mk", U, U)).max(axis=1) if umag is None
                                   else umag.max(axis=1)), out=self.lmax)
        np.fmin(self.lmin_ax, tm * U[:, :d].min(axis=2), out=self.lmin_ax)
        np.fmax(self.lmax_ax, tm * U[:, :d].max(axis=2), out=self.lmax_ax)
        total = F.sum(axis=0)  # (3, k)
        moment = np.stack([A[:, 1] @ F[:, 2] - A[:, 2] @ F[:, 1], A[:, 2] @ F[:, 0] - A[:, 0] @ F[:, 2],
                           A[:, 0] @ F[:, 1] - A[:, 1] @ F[:, 0]])
        if d == 2:
            total, moment = total[:2], moment[2:]
        np.fmin(self.tmin, total.min(axis=1), out=self.tmin)
        np.fmax(self.tmax, total.max(axis=1), out=self.tmax)
        self.tnorm = max(self.tnorm, float(np.sqrt((total * total).sum(axis=0)).max()))
        np.fmin(self.mmin, moment.min(axis=1), out=self.mmin)
        np.fmax(self.mmax, moment.max(axis=1), out=self.mmax)
        self.mnorm = max(self.mnorm, float(np.sqrt((moment * moment).sum(axis=0)).max()))

    def add_envelope(self, cab: np.ndarray, tot: np.ndarray, tmax: np.ndarray) -> None:
        """The envelope of a chunk as :func:`cdpr_design.kernels.frame_loads.frame_load_stats`
        leaves it (``cab`` (m, 13), ``tot`` (5, 3)), for cables of tension bounds ``tmax`` (m,) [N]."""
        n = int(tot[4, 2])
        if n == 0:
            return
        d, tm = self.d, tmax[:, None]
        self.poses += n
        np.fmax(self.fmax, cab[:, 0], out=self.fmax)
        np.fmin(self.fmin_ax, cab[:, 1:1 + d], out=self.fmin_ax)
        np.fmax(self.fmax_ax, cab[:, 4:4 + d], out=self.fmax_ax)
        np.fmax(self.lmax, np.where(np.isfinite(cab[:, 7]), tmax, -np.inf), out=self.lmax)  # |u| = 1
        np.fmin(self.lmin_ax, tm * cab[:, 7:7 + d], out=self.lmin_ax)
        np.fmax(self.lmax_ax, tm * cab[:, 10:10 + d], out=self.lmax_ax)
        np.fmin(self.tmin, tot[0, :d], out=self.tmin)
        np.fmax(self.tmax, tot[1, :d], out=self.tmax)
        moments = slice(2, 3) if d == 2 else slice(0, 3)
        np.fmin(self.mmin, tot[2, moments], out=self.mmin)
        np.fmax(self.mmax, tot[3, moments], out=self.mmax)
        self.tnorm = max(self.tnorm, float(tot[4, 0]))
        self.mnorm = max(self.mnorm, float(tot[4, 1]))

    def rows(self, names) -> dict:
        """``frame_loads.csv``'s columns (name -> list), one row a cable; NaN without a pose."""
        cols = {"cable": list(names)}
        for prefix, top, lo, hi in (("", self.fmax, self.fmin_ax, self.fmax_ax),
                                    ("limit_", self.lmax, self.lmin_ax, self.lmax_ax)):
            cols[f"{prefix}max_force"] = _values(top)
            for j, a in enumerate(AXES[:self.d]):
                cols[f"{prefix}min_f{a}"] = _values(lo[:, j])
                cols[f"{prefix}max_f{a}"] = _values(hi[:, j])
        return cols

    def summary(self, names) -> dict:
        """``summary.json``'s ``frame_loads``: the total force [N] and moment [N m] about the frame's
        origin (componentwise envelope and largest magnitude), each cable's largest force [N]
        and ``max_force`` the largest of them; ``poses`` the feasible poses they cover."""
        none = self.poses == 0
        mom_axes = ["z"] if self.d == 2 else list(AXES)
        return {
            "poses": int(self.poses),
            "max_force": None if none else _num(self.fmax.max()),
            "max_force_per_cable": {c: (None if none else _num(v)) for c, v in zip(names, self.fmax)},
            "total_force": _envelope(self.tmin, self.tmax, self.tnorm, AXES[:self.d], none),
            "total_moment": _envelope(self.mmin, self.mmax, self.mnorm, mom_axes, none),
        }


def _num(v):
    v = float(v)
    return v if np.isfinite(v) else None


def _values(a: np.ndarray) -> list:
    return [float(v) if np.isfinite(v) else float("nan") for v in a]


def _envelope(lo, hi, norm, axes, none: bool) -> dict:
    if none:
        return {"min": {a: None for a in axes}, "max": {a: None for a in axes}, "max_magnitude": None}
    return {"min": {a: _num(v) for a, v in zip(axes, lo)}, "max": {a: _num(v) for a, v in zip(axes, hi)},
            "max_magnitude": _num(norm)}


class FrameLoads(Wrapper):
    """The sweep plan's part that accumulates the frame loads (see the module doc) of the
    feasible poses of each chunk, at the sweep's orientation ``ori`` (3,) [rad] or the rows'
    own (a hanging effector); adds no column.  Summary key ``frame_loads``; the result's
    ``frame_loads`` (a :class:`FrameLoadTable`); picture ``frame_loads.png``."""

    pictures = ("frame_loads.png",)

    def __init__(self, robot: Robot, ori: np.ndarray, inline: bool = False):
        super().__init__(robot)
        #: the base evaluator hands each chunk's envelope over with its rows (:attr:`Rows.loads`)
        self.inline = inline
        self.positions = not inline
        self.ori = np.asarray(ori, float)
        self.table = FrameLoadTable(robot.m, 2 if robot.planar else 3)
        self.R = kin.rotation_matrix(*self.ori)
        self.Rb = np.ascontiguousarray(robot.attachments @ self.R.T)
        #: one compiled pass a chunk: straight cables from point outlets at one orientation, numba's engine
        self.compiled = (robot.engine == "numba" and not robot.outlets.pulleys and not robot.orientation.free
                         and not robot.cables.sags(robot.kind))
        if robot.outlets.pulleys:
            from cdpr_design.statics.pulley import design_pulleys

            _, axes, radii = design_pulleys(robot.design)
            self.pulley_axes = axes * (radii > 0)[:, None]  # a point outlet among pulleys: no axle

    def add(self, r: Rows, start: int, P: np.ndarray | None) -> None:
        if self.inline:
            self.table.add_envelope(*r.loads, self.robot.tension_max)
        elif r.sets is not None:  # every orientation of a set, each with its own statics
            for ori, tensions, extra in r.sets:
                self._add(r, P, tensions, extra, kin.rotation_matrix(*ori))
        else:
            tensions, extra = (r.tensions, r.extra) if r.nominal is None else r.nominal  # sagging: the nominal's
            self._add(r, P, tensions, extra, None)

    def _add(self, r: Rows, P: np.ndarray, tensions: np.ndarray, extra: dict, R: np.ndarray | None) -> None:
        """The loads of the rows of ``r`` that are feasible with ``tensions`` (k, m) [N] (and the
        ``extra`` columns) at the rotation ``R`` (3, 3) (None: the sweep's or the rows' own)."""
        ok = r.feasible.astype(bool) & np.isfinite(tensions).all(axis=1)
        if not ok.any():
            return
        if self.compiled:
            from cdpr_design.kernels.frame_loads import empty_envelope, frame_load_stats

            Rb = self.Rb if R is None else np.ascontiguousarray(self.robot.attachments @ R.T)
            cab, tot = empty_envelope(self.robot.m)
            frame_load_stats(np.ascontiguousarray(P, dtype=float), ok.astype(np.uint8), np.ascontiguousarray(tensions),
                             self.robot.outlet_points, Rb, cab, tot)
            self.table.add_envelope(cab, tot, self.robot.tension_max)
            return
        feasible = np.flatnonzero(ok)
        for k in range(0, len(feasible), BLOCK):  # small temporaries: no page faults for each
            rows = feasible[k:k + BLOCK]
            F, U, fmag, umag = outlet_forces(self.robot, P[rows], self._rotations(r, rows) if R is None else R,
                                             tensions[rows], {n: v[rows] for n, v in extra.items()},
                                             getattr(self, "pulley_axes", None))
            self.table.add(F, U, self.robot.outlet_points, self.robot.tension_max, fmag, umag)

    def _rotations(self, r: Rows, rows: np.ndarray) -> np.ndarray:
        """Rotation matrices (k, 3, 3) of the rows where the effector hangs (its orientation in the
        rows' ``orientation_*`` columns, R = Rx Ry Rz), else the sweep's one (3, 3)."""
        if not self.robot.orientation.free:
            return self.R
        angles = np.zeros((len(rows), 3))
        for j, a in enumerate(("rx", "ry", "rz")):
            if f"orientation_{a}" in r.extra:
                angles[:, j] = r.extra[f"orientation_{a}"][rows]
        if "orientation_phi" in r.extra:
            angles[:, 2] = r.extra["orientation_phi"][rows]
        return rotations(angles)

    def summary(self, maps: Maps) -> dict:
        return {"frame_loads": self.table.summary(self.robot.design.cable_names)}

    def finish(self, result: WorkspaceResult, maps: Maps) -> None:
        result.frame_loads = self.table


def rotations(angles: np.ndarray) -> np.ndarray:
    """R = Rx(rx) Ry(ry) Rz(rz) (k, 3, 3) of xyz Euler angles ``angles`` (k, 3) [rad]
    (:func:`cdpr_design.statics.kinematics.rotation_matrix` for many at once)."""
    c, s = np.cos(angles), np.sin(angles)
    k = len(angles)
    one, zero = np.ones(k), np.zeros(k)
    Rx = np.stack([one, zero, zero, zero, c[:, 0], -s[:, 0], zero, s[:, 0], c[:, 0]], 1).reshape(k, 3, 3)
    Ry = np.stack([c[:, 1], zero, s[:, 1], zero, one, zero, -s[:, 1], zero, c[:, 1]], 1).reshape(k, 3, 3)
    Rz = np.stack([c[:, 2], -s[:, 2], zero, s[:, 2], c[:, 2], zero, zero, zero, one], 1).reshape(k, 3, 3)
    return Rx @ Ry @ Rz


def outlet_forces(robot: Robot, P: np.ndarray, R: np.ndarray, t: np.ndarray, extra: dict,
                  pulley_axes: np.ndarray | None = None):
    """(F, U, fmag, umag): the forces F (m, 3, k) [N] on the frame at each outlet for effector
    positions ``P`` (k, 3) [m], rotations ``R`` ((3, 3) or (k, 3, 3)) and effector-end tensions
    ``t`` (k, m) [N]; U the same per newton of tension at the outlet (see the module doc); fmag
    and umag (m, k) their magnitudes where known without computing them (straight cables from
    point outlets: t and 1), else None.  ``extra``: the rows' extra columns (sagging cables read
    ``outlet_tension_<c>`` and ``unstretched_length_<c>``); ``pulley_axes`` (m, 3) the swivel axes
    when the robot has pulleys (zero for a point outlet)."""
    A, b = robot.outlet_points, robot.attachments
    sagging = robot.cables.sags(robot.kind)
    if R.ndim == 2 and not sagging and not robot.outlets.pulleys:
        # straight cables from point outlets at one orientation: (m, 3, k) throughout
        U = P.T[None] + (b @ R.T - A)[:, :, None]
        U *= (1.0 / np.sqrt(np.einsum("mik,mik->mk", U, U)))[:, None, :]
        tt = np.ascontiguousarray(t.T)
        return U * tt[:, None, :], U, tt, np.ones_like(tt)
    if R.ndim == 2:
        B = P[:, None, :] + (b @ R.T)[None]
    else:
        B = P[:, None, :] + np.einsum("kij,mj->kmi", R, b)
    if sagging:
        names = robot.design.cable_names
        ta = np.stack([extra[f"outlet_tension_{c}"] for c in names], axis=1)
        L0 = np.stack([extra[f"unstretched_length_{c}"] for c in names], axis=1)
        F = np.ascontiguousarray(sagging_forces(A, B, t, ta, L0, robot.cable.w, robot.cable.up).transpose(1, 2, 0))
        with np.errstate(invalid="ignore", divide="ignore"):
            return F, F / ta.T[:, None, :], None, None
    if robot.outlets.pulleys:
        from cdpr_design.statics.pulley import design_cable_paths

        unit = -design_cable_paths(robot.design, B).directions - pulley_axes[None]
    else:
        D = B - A[None]
        unit = D / np.linalg.norm(D, axis=2, keepdims=True)
    U = np.ascontiguousarray(unit.transpose(1, 2, 0))
    return U * t.T[:, None, :], U, None, None


def sagging_forces(A, B, tb, ta, L0, w, up) -> np.ndarray:
    """Forces (k, m, 3) [N] on the frame at the outlets ``A`` (m, 3) of sagging cables to the
    attachments ``B`` (k, m, 3) [m], from the tensions at the effector ``tb`` and at the outlet
    ``ta`` (k, m) [N], the unstretched lengths ``L0`` (k, m) [m], the weights per length ``w``
    (m,) [N/m] and the unit vector ``up`` (3,) (see the module doc)."""
    W = w[None, :] * L0
    with np.errstate(invalid="ignore", divide="ignore"):
        v = (ta * ta - tb * tb - W * W) / (2.0 * W)
        v = np.where(W > 0, v, 0.0)
    H = np.sqrt(np.maximum(tb * tb - v * v, 0.0))
    D = B - A[None]
    straight = tb[..., None] * D / np.linalg.norm(D, axis=2, keepdims=True)  # a cable without weight
    Dh = D - np.einsum("kmi,i->km", D, up)[..., None] * up
    n = np.linalg.norm(Dh, axis=2, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        h = np.where(n > 1e-12, Dh / n, 0.0)
    return np.where((W > 0)[..., None], H[..., None] * h - (v + W)[..., None] * up, straight)
