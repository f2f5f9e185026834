"""The kinds of workspace and what the cables must exert at a pose.

Kinds (:data:`cdpr_design.statics.robot.KINDS`, the kernels' ``KIND_*`` codes):

- ``static``: gravity only;
- ``wrench-feasible``: gravity plus every vertex of ``workspace.external_wrench``;
- ``wrench-closure``: tension bounds ignored; the cables positively span the
  wrench space (rank n);
- ``dynamic``: as ``wrench-feasible``, with the inertial wrench M a of every vertex a
  of ``requirements.acceleration`` added to every one of its wrenches (the Minkowski
  sum of the two sets): every acceleration of the box reachable from rest.

:func:`wrench_vertices` gives the wrenches a kind requires at an orientation:
what the pose evaluation
(:mod:`cdpr_design.workspaces.pose`), the tension distribution
(:mod:`cdpr_design.statics.tension`), the cable models
(:mod:`cdpr_design.statics.cables`) and the sweeps share, below all of them.
"""

from __future__ import annotations

import itertools

import numpy as np

from cdpr_design.model.design import Design
from cdpr_design.statics import kinematics as kin

def wrench_vertices(design: Design, kind: str, orientation=None) -> np.ndarray:
    """Required-wrench vertices (nv, n) [N, N m] at a fixed orientation (3,) [rad].

    Row 0 is the nominal wrench -gravity (the one whose tensions are
    reported).  For ``wrench-feasible`` every vertex of the external wrench
    box is added to gravity (dimensions where lower = upper contribute one value);
    for ``dynamic`` also, and to each of those wrenches the inertial wrench M a
    (:func:`~cdpr_design.statics.kinematics.mass_matrix`) of every vertex a of
    ``requirements.acceleration`` is added.
    """
    ori = design.default_orientation_full() if orientation is None else np.asarray(orientation, float)
    g = kin.gravity_wrench(design, kin.pose_at(design, np.zeros(3), ori))
    rows = [-g]
    box = design.workspace.external_wrench
    if kind in ("wrench-feasible", "dynamic") and box is not None:
        for v in box_vertices(box.lower, box.upper):
            rows.append(-(g + v))
    if kind == "dynamic" and design.requirements.acceleration is not None:
        M = kin.mass_matrix(design, ori)
        inertial = [M @ a for a in box_vertices(*design.requirements.acceleration)]
        rows = rows[:1] + [r + f for r in rows for f in inertial]
    return np.ascontiguousarray(np.array(rows, dtype=float))


def box_vertices(lower, upper) -> list[np.ndarray]:
    """The vertices of the box ``lower`` .. ``upper`` (one value a dimension, any unit); a dimension
    whose two ends are equal gives one value, so a flat box has fewer than 2^d vertices."""
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    choices = [(lo[i],) if lo[i] == hi[i] else (lo[i], hi[i]) for i in range(lo.size)]
    return [np.asarray(v) for v in itertools.product(*choices)]


def external_loads(design: Design) -> np.ndarray:
    """The vertices of ``workspace.external_wrench`` as full wrenches (nv, 6) [N, N m] on the
    effector: force at the reference point (the platform origin) and moment, each vertex's values
    on the motion's wrench rows (``design.rows``), zeros on the others; (0, 6) without the box."""
    box = design.workspace.external_wrench
    vertices = [] if box is None else box_vertices(box.lower, box.upper)
    out = np.zeros((len(vertices), 6))
    if vertices:
        out[:, np.asarray(design.rows)] = vertices
    return out
