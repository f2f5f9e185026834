"""What only a single pose reports, beside the rows a sweep computes there.

A pose's feasibility, capacity margin, tensions, lengths and cable state are the
one-pose case of the sweep's batched evaluation
(:func:`cdpr_design.workspaces.pose.evaluate_pose`: the sweep plan run on a one-pose
grid).  This module holds its result (:class:`PoseResult`) and the structure matrix
at one pose (:func:`structure`; at many positions of one orientation, :func:`structure_many`); the tensions of another objective are
:func:`cdpr_design.statics.tension.tensions_for_objective`, the colliding pairs
:func:`cdpr_design.statics.interference.collisions`.

Kinds of workspace and their required wrenches: :mod:`cdpr_design.statics.wrenches`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cdpr_design.io.tables import Table
from cdpr_design.statics.robot import Robot


@dataclass
class PoseResult(Table):
    """One pose evaluated exactly as a grid sweep would (the sweep's rows at one position).

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
    #: colliding pairs (cli.md names; :func:`cdpr_design.statics.interference.check_pose`, sagging
    #: cables :func:`~cdpr_design.statics.interference.check_sagging_pose`); None where the sagging
    #: cables' shapes did not converge (not checked)
    collisions: list | None = field(default_factory=list)
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


def structure(robot: Robot, full: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The structure matrix W (n, m) of ``robot``'s straight cables at a full pose [x, y, z, rx,
    ry, rz] [m, rad] and their free lengths (m,) [m] (from the pulley's tangent point, else the
    outlet, to the attachment), swivel pulleys honoured (the sweep kernels' geometry: true
    outlet points); W's columns are unspecified where a cable has zero length."""
    return robot.outlets.structure(robot, full)


def structure_many(robot: Robot, positions: np.ndarray, Rb: np.ndarray):
    """Structure matrices (k, n, m), lengths, free lengths (k, m) [m] and curvatures (k, m) [1/m]
    at positions (k, 3), fixed orientation.

    With swivel pulleys (the robot's ``outlets``: ``pulleys``) the
    lengths are arc + free segment and u_i the free segment's unit vector
    from the tangent point (:mod:`cdpr_design.statics.pulley`), the free length from the
    tangent point to the attachment (the total length for a point outlet).  The curvatures
    bound the length's second derivative,
    |v^T H_i v| <= kappa_i |v|^2: 1 / L_i for a point outlet,
    max(1 / l_f, |kappa_t|) with a pulley (:meth:`CablePaths.max_curvature`).
    """
    design = robot.design
    L, free, u, kappa = robot.outlets.envelope_paths(design, positions, Rb[None, :, :])
    mom = np.cross(Rb[None, :, :], u)
    full = np.concatenate([u, mom], axis=2)  # (k, m, 6)
    W = np.transpose(full[:, :, list(design.motion.wrench_rows)], (0, 2, 1))
    return np.ascontiguousarray(W), L, free, kappa
