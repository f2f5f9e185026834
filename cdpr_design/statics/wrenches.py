"""The kinds of workspace and what the cables must exert at a pose.

Kinds (:data:`cdpr_design.statics.robot.KINDS`, the kernels' ``KIND_*`` codes):

- ``static``: gravity only;
- ``wrench-feasible``: gravity plus every vertex of ``workspace.external_wrench``;
- ``wrench-closure``: tension bounds ignored; the cables positively span the
  wrench space (rank n).

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
    box is added to gravity (dimensions where lower = upper contribute one value).
    """
    ori = design.default_orientation_full() if orientation is None else np.asarray(orientation, float)
    g = kin.gravity_wrench(design, kin.pose_at(design, np.zeros(3), ori))
    rows = [-g]
    box = design.workspace.external_wrench
    if kind == "wrench-feasible" and box is not None:
        lo, hi = np.asarray(box.lower), np.asarray(box.upper)
        choices = [(lo[i],) if lo[i] == hi[i] else (lo[i], hi[i]) for i in range(lo.size)]
        for v in itertools.product(*choices):
            rows.append(-(g + np.asarray(v)))
    return np.ascontiguousarray(np.array(rows, dtype=float))
