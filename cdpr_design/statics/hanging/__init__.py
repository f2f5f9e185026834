"""Where an effector hangs: the geometrico-static problem of cable robots.

A cable can pull but never push, and a cable of length rho_i only keeps its
attachment within rho_i of its outlet; the effector rests where its potential
energy is smallest among the configurations those lengths allow (Carricato &
Merlet 2013; Abbasnejad & Carricato 2015: the references are in
:mod:`~cdpr_design.statics.hanging.forward`).  A robot is *under-constrained*
when its taut cables cannot fix every free degree of freedom: fewer than 3
cables for a planar rigid body, fewer than 6 for a spatial one, fewer than its
dimension for a point mass (an effector whose attachments coincide); then its
orientation is not commanded but follows from the lengths.

One module a concept (SI units throughout; ``tilt_deg`` in degrees):

* :mod:`~cdpr_design.statics.hanging.geometry` - rotations, the lowest point
  of an intersection of balls, the effector on its cables at one
  configuration (balance, Jacobian, reduced Hessian);
* :mod:`~cdpr_design.statics.hanging.refine` - an equilibrium near a
  configuration (Newton's method with an active set; scipy fall-backs);
* :mod:`~cdpr_design.statics.hanging.forward` - the forward problem: where the
  effector rests for given lengths (:func:`fk_arrays`, :func:`fk_held_arrays`);
* :mod:`~cdpr_design.statics.hanging.balance` - batched Newton's method on
  force and moment balance at commanded positions;
* :mod:`~cdpr_design.statics.hanging.family` - the marches along a spatial
  body's family of balanced orientations on four or five cables;
* :mod:`~cdpr_design.statics.hanging.planar2` - the closed form of a planar
  body on two cables, vectorised with numpy;
* :mod:`~cdpr_design.statics.hanging.at_positions` - the orientation it hangs
  in at many commanded positions (the workspaces' search) and at one
  (:func:`hanging_pose_arrays`);
* :mod:`~cdpr_design.statics.hanging.results` - the answers, status codes and
  errors;
* :mod:`~cdpr_design.statics.hanging.design` - the same questions for a
  :class:`~cdpr_design.model.design.Design` (:func:`equilibrium`,
  :func:`hanging_pose`, ...).

The names below are what the other layers use.
"""

from cdpr_design.model.design import has_weight, is_point_mass, is_underconstrained
from cdpr_design.statics.hanging.at_positions import hanging_pose_arrays
from cdpr_design.statics.hanging.design import (
    design_arrays, equilibrium, fk, hanging_pose, held_rotation, nominal_rotation,
)
from cdpr_design.statics.hanging.forward import fk_arrays, fk_held_arrays
from cdpr_design.statics.hanging.geometry import check_weight
from cdpr_design.statics.hanging.results import (
    Equilibrium, HangingFK, HangingPose, NotUnderconstrained, UnreachableLengths, orientation_of, tilt_of,
)

__all__ = [
    "Equilibrium", "HangingFK", "HangingPose", "NotUnderconstrained", "UnreachableLengths",
    "check_weight", "design_arrays", "equilibrium", "fk", "fk_arrays", "fk_held_arrays", "hanging_pose",
    "hanging_pose_arrays", "has_weight", "held_rotation", "is_point_mass", "is_underconstrained",
    "nominal_rotation", "orientation_of", "tilt_of",
]
