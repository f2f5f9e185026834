"""Acceleration capability: how hard the effector can accelerate from rest at a pose.

At rest (zero velocity) the effector's dynamics are linear in the tensions and the
acceleration:

    W t + w_g + w_e = M a,

W the structure matrix, w_g the gravity wrench, w_e the external wrench, M the mass
matrix at rest (:func:`~cdpr_design.statics.kinematics.mass_matrix`).  With the tensions
within their bounds (the lower bound raised by ``requirements.min_cable_frequency``,
:func:`~cdpr_design.statics.robot.tension_lower`) the reachable accelerations form a
polytope; with zero angular acceleration its translational part is what this module
reports (:func:`capability`):

- the **acceleration radius** [m/s^2]: the radius of the largest ball of translational
  accelerations about rest that every external wrench of ``workspace.external_wrench``
  (when given) leaves reachable; 0 where the pose cannot be held at rest;
- the **axis accelerations** [m/s^2]: along each translational axis, the least and the
  greatest acceleration reachable;
- the **direction** in which the radius is reached (a unit vector).

With a velocity the Coriolis and gyroscopic terms (w x I w, and the centripetal
acceleration w x (w x R c) of a centre of mass off the reference point) add a wrench
that does not depend on the acceleration: it shifts the required wrench, as the
external wrench does, and these figures are those of rest.

The polytope's half-spaces are the facets of the available wrench set found by
hyperplane shifting, mapped through M (:mod:`cdpr_design.kernels.acceleration`;
docs/algorithms.md has the method and its sources).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.pose import structure, structure_many
from cdpr_design.statics.robot import Robot, tension_lower
from cdpr_design.statics.wrenches import wrench_vertices


@dataclass(frozen=True)
class Capability:
    """The acceleration capability at one pose: ``radius`` [m/s^2] (0 where the pose is not held at
    rest; NaN where the structure matrix has no facet), ``axes`` (d, 2) the least and greatest
    acceleration along each translational axis [m/s^2] (±inf unbounded, NaN none reachable),
    ``direction`` (d,) the unit direction in which the radius is reached."""

    radius: float
    axes: np.ndarray
    direction: np.ndarray


@dataclass(frozen=True)
class Loads:
    """What the capability takes at one orientation, built once: ``wnom`` (n,) the wrench the
    cables supply at rest without external load [N, N m], ``elo``, ``ehi`` (n,) the external wrench
    box (zeros without one), ``Mt`` (n, d) the mass matrix's translational columns [kg, kg m],
    ``Rb`` (m, 3) the rotated attachments [m]."""

    wnom: np.ndarray
    elo: np.ndarray
    ehi: np.ndarray
    Mt: np.ndarray
    Rb: np.ndarray


def loads(robot: Robot, orientation) -> Loads:
    """The :class:`Loads` of ``robot`` at a full orientation (3,) [rad]."""
    design = robot.design
    ori = np.asarray(orientation, float)
    box = design.workspace.external_wrench
    n = robot.n
    elo = np.zeros(n) if box is None else np.asarray(box.lower, float)
    ehi = np.zeros(n) if box is None else np.asarray(box.upper, float)
    Mt = kin.mass_matrix(design, ori)[:, : design.motion.dim]
    Rb = robot.attachments @ kin.rotation_matrix(*ori).T
    c = np.ascontiguousarray
    return Loads(c(wrench_vertices(design, "static", ori)[0]), c(elo), c(ehi), c(Mt), c(Rb))


def at_positions(robot: Robot, ld: Loads, positions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The capability at positions (k, 3) [m] at the orientation of ``ld``: radius (k,) [m/s^2],
    axes (k, d, 2) [m/s^2] and directions (k, d) (as :class:`Capability`)."""
    from cdpr_design.kernels import acceleration as KA  # numba, on first use

    P = np.ascontiguousarray(np.asarray(positions, float).reshape(-1, 3))
    W, _, free, _ = structure_many(robot, P, ld.Rb)
    return _many(robot, ld, W, tension_lower(robot.tension_min, robot.tension_floor, free), KA)


def _many(robot: Robot, ld: Loads, W, lower, KA):
    k, d = W.shape[0], ld.Mt.shape[1]
    radius, axes, worst = np.empty(k), np.empty((k, d, 2)), np.empty((k, d))
    KA.capability_many(np.ascontiguousarray(W), np.ascontiguousarray(lower), robot.tension_max, ld.wnom, ld.elo,
                       ld.ehi, ld.Mt, robot.combos, radius, axes, worst)
    return radius, axes, worst


def capability(robot: Robot, pose) -> Capability:
    """The acceleration capability of ``robot`` at ``pose`` (motion coordinates [m, rad]); the
    structure matrix is the pose's own (:func:`~cdpr_design.statics.pose.structure`: swivel
    pulleys honoured).  Straight cables, the orientation commanded or held
    (:func:`~cdpr_design.statics.robot.acceleration_reason`)."""
    from cdpr_design.kernels import acceleration as KA  # numba, on first use

    full = robot.design.full_pose(pose)
    W, free = structure(robot, full)
    lower = tension_lower(robot.tension_min, robot.tension_floor, free)
    radius, axes, worst = _many(robot, loads(robot, full[3:]), W[None], lower[None], KA)
    return Capability(float(radius[0]), axes[0], worst[0])
