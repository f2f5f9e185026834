"""One pose of a resolved robot: the one-pose case of the sweep's batched evaluation.

:func:`evaluate_pose` runs the robot's sweep plan (:func:`~cdpr_design.workspaces.plan.plan`:
the same base evaluator and cable wrappers a workspace sweep of the robot runs) on a grid of
one position, at the pose's orientation: the feasibility, capacity margin, tensions, lengths
and cable state are that row's, so a bound, a cable model or an engine added to the sweep is
the ``pose`` command's too.  What only a single pose reports is computed after it, from the
statics of one pose: the structure matrix (:func:`cdpr_design.statics.pose.structure`,
:func:`cdpr_design.statics.cables.sagging_structure`), the tensions of another objective
(:func:`cdpr_design.statics.tension.tensions_for_objective`,
:func:`cdpr_design.statics.cables.sagging_for_objective`) and the colliding pairs
(:func:`cdpr_design.statics.interference.collisions`).
"""

from __future__ import annotations

import numpy as np

from cdpr_design.model.design import Grid
from cdpr_design.statics import cables
from cdpr_design.statics.pose import PoseResult, structure
from cdpr_design.statics.robot import Robot, tension_lower
from cdpr_design.statics.wrenches import wrench_vertices
from cdpr_design.workspaces.cables import cable_state
from cdpr_design.workspaces.plan import Plan, plan


def pose_plan(robot: Robot, full: np.ndarray) -> Plan:
    """The sweep plan of ``robot`` on the one-position grid of a full pose [x, y, z, rx, ry, rz]
    [m, rad], at its orientation: the plan of the robot resolved for one pose
    (:meth:`~cdpr_design.statics.robot.Robot.one_pose`), its statics only (the commanded pose fixes
    the orientation a hanging effector would find; interference is named, not masked:
    ``collisions``; no tilt, orientation set or stiffness columns)."""
    one = robot.one_pose()
    position = tuple(float(v) for v in full[: robot.design.motion.dim])
    return plan(one, Grid(position, position, (1.0,) * len(position)), full[3:], tilt=False)


def evaluate_pose(robot: Robot, pose, weights=None) -> PoseResult:
    """Feasibility, capacity margin [N] and tensions [N] of ``robot`` at one pose (the motion's
    coordinates [m, rad]), for the robot's kind (:func:`cdpr_design.statics.robot.resolve`).

    The feasibility, margin, minimum 2-norm tensions, lengths and (elastic, sagging cables) cable
    state are the sweep's at that pose (:func:`pose_plan`).  The robot's ``objective`` ('min-max',
    'min-sum') or per-cable ``weights`` (m,) ask for another distribution
    (:func:`cdpr_design.statics.tension.tensions_for_objective`); NaN where infeasible.  Swivel
    pulleys are honoured (true outlet points in W, arc + free lengths); ``collisions`` lists the
    interfering pairs (``feasible`` is the statics result, as in a sweep without interference).

    With elastic cables the tensions are the ideal ones and ``cable_state`` adds the unstretched
    lengths; with sagging cables the tensions are at the effector end of each catenary, the
    bounds hold along the whole cable and ``cable_state`` says whether the shapes converged
    (``wrench-closure`` ignores tensions, so it takes the chords: as tensions grow without bound
    every cable straightens onto its chord; the cables then have no shapes, and their outlet
    tensions, unstretched lengths and sag are NaN, as in the sweep's columns).
    """
    from cdpr_design.statics.tension import tensions_for_objective

    design = robot.design
    full = design.full_pose(pose)
    r = pose_plan(robot, full).rows(0, 1)
    t, L = r.tensions[0].copy(), r.lengths[0].copy()
    feasible, margin = bool(r.feasible[0]), float(r.margin[0])
    wreq0 = wrench_vertices(design, robot.kind, full[3:])[0]
    objective = robot.analysis.objective
    other = objective != "min-norm" or weights is not None
    if robot.cables.sags(robot.kind):
        W, state = cables.sagging_structure(robot, full), cable_state(robot, r, 0)
        if other and feasible:
            t2, W, state = cables.sagging_for_objective(design, full, wreq0, objective, weights, start=t)
            t = np.full(design.m, np.nan) if t2 is None else t2
    else:
        W, free = structure(robot, full)
        if other and np.all(np.isfinite(t)):
            lower = tension_lower(robot.tension_min, robot.tension_floor, free)  # the sweep's bounds there
            t2 = tensions_for_objective(W, wreq0, lower, robot.tension_max, objective, weights)
            t = np.full(design.m, np.nan) if t2 is None else t2
        # the sweep's columns: elastic cables' state; sagging cables under wrench closure have no
        # shapes (empty columns, status ok: nothing was solved); ideal cables: None
        state = cable_state(robot, r, 0)
        if other and robot.cables.stretches:
            state = cables.straight_state(robot, L, t)  # at the objective's tensions
    return PoseResult(np.asarray(pose, float), L, t, feasible, margin, W, wreq0, pose_collisions(robot, pose),
                      tuple(design.cable_names), robot.cables.name, state)


def pose_collisions(robot: Robot, pose) -> list | None:
    """The interfering pairs of ``robot`` at ``pose`` (the motion's coordinates [m, rad]): along the
    catenaries where its cables sag under its kind
    (:func:`cdpr_design.statics.interference.check_sagging_pose`; None where their shapes did not
    converge: not checked), else along the straight cables
    (:func:`cdpr_design.statics.interference.collisions`)."""
    from cdpr_design.statics.interference import check_sagging_pose, collisions

    if robot.cables.sags(robot.kind):
        c = check_sagging_pose(robot, robot.design.full_pose(pose))
        return c.pairs if c.known else None
    return collisions(robot.design, pose)
