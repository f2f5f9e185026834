"""One pose, evaluated exactly as a grid sweep would: the pose-level statics API.

Every analysis that asks "what happens at this pose" (the ``pose`` command,
a workspace sweep's required wrenches, the orientation workspaces) goes
through this module, so a cable or effector model changes the answers here,
once.

Kinds of workspace and their required wrenches: :mod:`cdpr_design.statics.wrenches`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cdpr_design.io.tables import Table
from cdpr_design.model.design import Design
from cdpr_design.statics import cables
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.robot import KINDS, Analysis, check_kind, combinations, has_pulleys, resolve, tension_lower
from cdpr_design.statics.wrenches import wrench_vertices


@dataclass
class PoseResult(Table):
    """One pose evaluated exactly as a grid sweep would (same kernel).

    Attributes: pose (motion coords), lengths (m,) [m], tensions (m,) [N] (NaN
    where infeasible), feasible, margin [N] (NaN where W is rank deficient),
    W (n, m) structure matrix, wrench (n,) the nominal required wrench,
    cables (m,) the cable names.  With elastic or sagging cables, ``tensions``
    are at the effector end and ``cable_state`` holds the outlet tensions,
    unstretched lengths and sag.  As a table: one row per cable.
    """

    pose: np.ndarray
    lengths: np.ndarray
    tensions: np.ndarray
    feasible: bool
    margin: float
    W: np.ndarray
    wrench: np.ndarray
    #: colliding pairs (cli.md names; :func:`cdpr_design.statics.interference.check_pose`)
    collisions: list = field(default_factory=list)
    cables: tuple = ()
    #: the design's cable model (:mod:`cdpr_design.statics.cables`)
    cable_model: str = "ideal"
    #: outlet tensions, unstretched lengths, sag and status (None for ideal cables)
    cable_state: object = None

    def columns(self) -> dict:
        """One row per cable: ``cable``, ``length`` [m], ``tension`` [N] (and the cable model's columns)."""
        out = {"cable": list(self.cables), "length": self.lengths, "tension": self.tensions}
        if self.cable_state is not None:
            out.update(outlet_tension=self.cable_state.outlet_tensions,
                       unstretched_length=self.cable_state.unstretched_lengths, sag=self.cable_state.sag)
        return out


def _structure(design: Design, full: np.ndarray, K):
    """(ok, W (n, m), lengths (m,) [m], free lengths (m,) [m]) at a full pose, pulleys honoured (the
    free length runs from the pulley's tangent point to the attachment)."""
    R = kin.rotation_matrix(*full[3:])
    Rb = np.ascontiguousarray(design.attachments @ R.T)
    A = np.ascontiguousarray(design.outlets)
    W = np.empty((design.n, design.m))
    L = np.empty(design.m)
    if has_pulleys(design):
        from cdpr_design.statics.interference import hardware_arrays

        hw = hardware_arrays(design)
        C = np.empty((design.m, 3))
        ok = K.structure_matrix_pulley(full[0], full[1], full[2], Rb, A, hw.axes, hw.eref, hw.radii,
                                       design.rows, W, L, C)
        return ok, W, L, np.linalg.norm(full[:3] + Rb - C, axis=1)
    ok = K.structure_matrix(full[0], full[1], full[2], Rb, A, design.rows, W, L)
    return ok, W, L, L


def evaluate_pose(design: Design, pose, kind: str = "static", objective: str = "min-norm",
                  weights=None) -> PoseResult:
    """Feasibility, capacity margin [N] and tensions [N] at one pose.

    The tensions are the minimum 2-norm feasible ones (exact kernel) unless
    ``objective`` ('min-max', 'min-sum') or per-cable ``weights`` ask for
    another distribution (:func:`cdpr_design.statics.tension.tensions_for_objective`);
    NaN where infeasible.  Swivel pulleys are honoured (true outlet points in
    W, arc + free lengths); ``collisions`` lists the interfering pairs
    (``feasible`` is the statics result, as in a sweep without interference).

    With elastic cables the tensions are the ideal ones and ``cable_state``
    adds the unstretched lengths; with sagging cables the tensions are at the
    effector end of each catenary, the bounds hold along the whole cable and
    ``cable_state`` says whether the shapes converged (``wrench-closure``
    ignores tensions, so it takes the chords: as tensions grow without bound
    every cable straightens onto its chord).
    """
    from cdpr_design import kernels as K  # numba, on first use
    from cdpr_design.statics.interference import collisions
    from cdpr_design.statics.tension import tensions_for_objective

    check_kind(kind)
    full = design.full_pose(pose)
    model = resolve(design, Analysis(command="statics", kind=kind)).cables  # at the commanded pose
    wreq = wrench_vertices(design, kind, full[3:])
    if model == "sagging" and kind != "wrench-closure":
        return _sagging_pose(design, pose, full, kind, wreq, objective, weights)
    ok, W, L, free = _structure(design, full, K)
    t = np.full(design.m, np.nan)
    tmin = tension_lower(design.tension_min, design.string_floor, free)  # the robot's floor, if any
    if ok:
        feasible, margin = K.eval_pose(W, wreq, tmin, design.tension_max,
                                       combinations(design.m, design.n), KINDS[kind], t)
    else:
        feasible, margin = False, np.nan
    if (objective != "min-norm" or weights is not None) and np.all(np.isfinite(t)):
        t2 = tensions_for_objective(W, wreq[0], tmin, design.tension_max, objective, weights)
        t = np.full(design.m, np.nan) if t2 is None else t2
    state = None if model == "ideal" else cables.straight_state(design, L, t)
    return PoseResult(np.asarray(pose, float), L, t, bool(feasible), float(margin), W, wreq[0],
                      collisions(design, pose), tuple(design.cable_names), model, state)


def _sagging_pose(design: Design, pose, full, kind: str, wreq, objective: str, weights) -> PoseResult:
    """:func:`evaluate_pose` with sagging cables (:mod:`cdpr_design.statics.cables`)."""
    from cdpr_design.statics.interference import collisions

    feasible, margin, t, L, W, state = cables.sagging_pose(design, full, wreq, combinations(design.m, design.n),
                                                           KINDS[kind])
    if (objective != "min-norm" or weights is not None) and feasible:
        t2, W, state = cables.sagging_for_objective(design, full, wreq[0], objective, weights, start=t)
        t = np.full(design.m, np.nan) if t2 is None else t2
    return PoseResult(np.asarray(pose, float), L, t, bool(feasible), float(margin), W, wreq[0],
                      collisions(design, pose), tuple(design.cable_names), "sagging", state)
