"""The ``pose`` job: one pose of a design, its tensions for a chosen objective, as plain data."""

from __future__ import annotations

import numpy as np


def evaluate_pose(design, pose, kind: str = "static", objective: str = "min-norm", weights=None):
    """Lengths [m], tensions [N], feasibility and capacity margin [N] at ``pose``.

    The tensions are re-solved for ``objective`` ('min-norm', 'min-max',
    'min-sum') and the per-cable ``weights`` when either differs from the
    unweighted minimum norm (:func:`cdpr_design.statics.tension.tensions_for_objective`);
    infeasible: NaN.
    """
    from cdpr_design.statics import tension as T
    from cdpr_design.statics import pose as sp

    result = sp.evaluate_pose(design, pose, kind)
    if (objective != "min-norm" or weights is not None) and np.all(np.isfinite(result.tensions)):
        t = T.tensions_for_objective(result.W, result.wrench, design.tension_min, design.tension_max,
                                     objective, weights)
        result.tensions = np.full(design.m, np.nan) if t is None else t
    return result


def pose_data(design, result) -> dict:
    """The ``pose --json`` object (cli.md keys)."""
    names = design.cable_names
    return {
        "pose": [float(v) for v in result.pose],
        "lengths": {c: float(v) for c, v in zip(names, result.lengths)},
        "tensions": {c: (float(v) if np.isfinite(v) else None) for c, v in zip(names, result.tensions)},
        "feasible": bool(result.feasible),
        "margin": float(result.margin) if np.isfinite(result.margin) else None,
        "structure_matrix": [[float(x) for x in row] for row in result.W],
        "collisions": [list(p) for p in result.collisions],
    }
