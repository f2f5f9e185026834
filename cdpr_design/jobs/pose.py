"""The ``pose`` job: one pose of a design as the ``pose --json`` object."""

from __future__ import annotations

import numpy as np


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
        "collisions": None if result.collisions is None else [list(p) for p in result.collisions],
    } | cable_model_data(design, result)


def cable_model_data(design, result) -> dict:
    """The keys a non-ideal cable model adds to ``pose --json`` (none for ideal cables)."""
    st = result.cable_state
    if st is None:
        return {}
    names = design.cable_names

    def per_cable(values):
        return {c: (float(v) if np.isfinite(v) else None) for c, v in zip(names, values)}

    return {"cable_model": result.cable_model, "outlet_tensions": per_cable(st.outlet_tensions),
            "unstretched_lengths": per_cable(st.unstretched_lengths), "sag": per_cable(st.sag),
            "cable_status": st.status}


def cable_fk_data(robot, unstretched, guess=None) -> dict:
    """The ``fk --json`` object with elastic or sagging cables (``unstretched`` lengths [m]) of the
    :class:`~cdpr_design.statics.robot.Robot` the command resolved for ``fk``."""
    from cdpr_design.statics.cable_fk import forward

    design = robot.design
    res = forward(robot, unstretched, guess)
    names = design.cable_names
    free = {} if res.tilt is None else {"orientation": res.orientation, "tilt": res.tilt,
                                        "effector_orientation": design.effector.orientation}
    return {"pose": [float(v) for v in res.pose], "residual": res.length_residual, "method": res.method,
            "cable_model": robot.cables.name, "force_residual": res.force_residual,
            "tensions": {c: float(v) for c, v in zip(names, res.tensions)},
            "outlet_tensions": {c: float(v) for c, v in zip(names, res.outlet_tensions)},
            "slack": res.slack,
            "within_bounds": bool(np.all((res.tensions >= design.tension_min - 1e-9)
                                         & (np.maximum(res.tensions, res.outlet_tensions) <= design.tension_max + 1e-9)))
            } | free


#: ``stiffness_reason`` where wrench closure holds but no tensions within the bounds hold the effector
CLOSURE_WITHOUT_TENSIONS = ("wrench closure holds here (it ignores the tension bounds), but no tensions within "
                            "the bounds balance the effector's load: no stiffness")


def stiffness_data(design, pose=None, tensions=None, reason: str | None = None, feasible: bool | None = None,
                   unstretched=None) -> dict:
    """The stiffness and vibration keys of ``pose --json`` (cli.md) at a pose held by ``tensions``
    [N] with the cables' ``unstretched`` lengths [m] (needed for sagging cables;
    :func:`cdpr_design.statics.stiffness.pose_stiffness`); with ``pose`` None, every value
    null and ``reason`` the stiffness_reason.  ``feasible``: the pose's feasibility for its kind;
    a feasible pose without tensions (wrench closure, which drops the bounds) is said to be so,
    not infeasible."""
    from cdpr_design.statics.stiffness import pose_stiffness

    names = design.cable_names
    if pose is not None and feasible and not np.all(np.isfinite(tensions)):
        pose, reason = None, CLOSURE_WITHOUT_TENSIONS
    if pose is None:
        return {"stiffness_matrix": None, "translational_stiffness": None, "min_stiffness": None,
                "natural_frequencies": None, "mode_shapes": None, "cable_frequencies": dict.fromkeys(names),
                "stiffness_reason": reason}
    s = pose_stiffness(design, pose, tensions, unstretched)

    def num(v):
        return float(v) if np.isfinite(v) else None

    def mat(a):
        return None if a is None else [[num(x) for x in row] for row in a]

    out = {"stiffness_matrix": mat(s.matrix), "translational_stiffness": mat(s.translational),
           "min_stiffness": num(s.min_stiffness),
           "natural_frequencies": None if s.frequencies is None else [num(v) for v in s.frequencies],
           "mode_shapes": mat(s.modes), "cable_frequencies": {c: num(v) for c, v in zip(names, s.cable_frequencies)},
           "stiffness_reason": s.reason}
    if s.frequency_floor is not None:
        out["cable_frequency_tensions"] = {c: float(v) for c, v in zip(names, s.frequency_floor)}
    return out


def acceleration_data(robot, pose=None) -> dict:
    """The acceleration keys of ``pose --json`` (cli.md) at ``pose`` (motion coordinates [m, rad]) of
    ``robot`` (:func:`cdpr_design.statics.acceleration.capability`): ``acceleration_radius`` [m/s^2],
    ``axis_accelerations`` ([min, max] per translational axis [m/s^2], null where unbounded or none
    reachable), ``acceleration_direction`` (the unit direction of least reach) and
    ``acceleration_reason`` (why they are null: the robot's
    :func:`~cdpr_design.statics.robot.acceleration_reason`, else null)."""
    from cdpr_design.statics.robot import acceleration_reason

    reason = acceleration_reason(robot.cables, robot.orientation)
    if reason is not None or pose is None:
        return {"acceleration_radius": None, "axis_accelerations": None, "acceleration_direction": None,
                "acceleration_reason": reason}
    from cdpr_design.statics.acceleration import capability

    c = capability(robot, pose)

    def num(v):
        return float(v) if np.isfinite(v) else None

    return {"acceleration_radius": num(c.radius),
            "axis_accelerations": [[num(lo), num(hi)] for lo, hi in c.axes],
            "acceleration_direction": [num(v) for v in c.direction] if np.all(np.isfinite(c.direction)) else None,
            "acceleration_reason": None}
