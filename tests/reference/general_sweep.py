"""The rows of a straight-cable grid sweep by the general kernel, whatever the robot.

The product sweeps a robot of two cables and two wrench rows with the closed form of
:mod:`cdpr_design.workspaces.engine` (numpy, never the kernels);
:func:`cdpr_design.kernels.sweep_grid` computes the same rows for any m, n and kind
(the structure matrix, its factor and the hyperplane-shifting margin), so it is the
closed form's reference here.  Units: SI (m, N).
"""

from __future__ import annotations

import numpy as np

from cdpr_design import kernels as K
from cdpr_design.statics.robot import combinations
from cdpr_design.statics.wrenches import wrench_vertices
from cdpr_design.workspaces import grid as wsg

KIND_CODES = {"static": K.KIND_STATIC, "wrench-feasible": K.KIND_WRENCH_FEASIBLE,
              "wrench-closure": K.KIND_WRENCH_CLOSURE}


def general_kernel_rows(design, kind="static", grid=None):
    """(feasible (k,) uint8, margin (k,) [N], tensions (k, m) [N], lengths (k, m) [m]) of every pose
    of ``grid`` (default the design's), at the workspace's orientation, by the general kernel."""
    g = design.workspace.grid if grid is None else grid
    lower, step, shape = wsg.grid3(g)
    n, m = g.size, design.m
    out = np.empty(n, np.uint8), np.empty(n), np.empty((n, m)), np.empty((n, m))
    K.sweep_grid(K.GridPoses(0, lower, step, shape, design.attachments.copy()),
                 K.Statics(design.outlets, design.rows, design.tension_min, design.tension_max, design.string_floor,
                           combinations(m, design.n), KIND_CODES[kind]),
                 wrench_vertices(design, kind), K.Outputs(*out))
    return out
