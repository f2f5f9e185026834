"""The hanging effector of a design: its arrays, its classification and the design-level answers.

What the other layers ask of a :class:`~cdpr_design.model.design.Design`
whose effector may hang (whether it does is the resolved robot's
``orientation``, :mod:`cdpr_design.statics.robot`): where it rests for given cable lengths under its
spec (:func:`equilibrium`, the ``fk`` command; :func:`fk` without the
spec's orientation rules); the orientation it hangs in at a commanded
position (:func:`hanging_pose`).  Each reads the design's arrays (:func:`design_arrays`) and asks the solvers on
plain arrays (:mod:`~cdpr_design.statics.hanging.forward`,
:mod:`~cdpr_design.statics.hanging.at_positions`), adding whether the
tensions are within the design's limits.

Units: SI (m, kg, N, rad).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from cdpr_design.statics.hanging.at_positions import hanging_pose_arrays
from cdpr_design.statics.hanging.forward import fk_arrays, fk_held_arrays
from cdpr_design.statics.hanging.results import HangingFK, HangingPose


def design_arrays(design):
    """(outlets, attachments, centre of mass, mass, gravity, planar) of a design [m, kg, m/s^2]."""
    planar = design.motion.name in ("2T", "1R2T")
    return (design.outlets, design.attachments, np.asarray(design.effector.center_of_mass, float),
            float(design.effector.mass), np.asarray(design.gravity, float), planar)


def _within(design, t) -> bool:
    return bool(np.all(t >= design.tension_min - 1e-9) and np.all(t <= design.tension_max + 1e-9))


def fk(design, lengths, **options) -> HangingFK:
    """:func:`~cdpr_design.statics.hanging.forward.fk_arrays` for a design: where it hangs for
    cable ``lengths`` [m], with ``within_limits`` set from the design's tension limits."""
    A, B, c, mass, g, planar = design_arrays(design)
    r = fk_arrays(A, B, c, mass, g, lengths, planar, **options)
    return dataclasses.replace(r, within_limits=None if r.indeterminate else _within(design, r.tensions))


def hanging_pose(design, position, **options) -> HangingPose:
    """:func:`~cdpr_design.statics.hanging.at_positions.hanging_pose_arrays` for a design: the
    orientation its effector hangs in at ``position`` [m], with ``within_limits`` set from the
    design's tension limits."""
    A, B, c, mass, g, planar = design_arrays(design)
    r = hanging_pose_arrays(A, B, c, mass, g, position, planar, **options)
    return dataclasses.replace(r, within_limits=_within(design, r.tensions) if r.feasible else None)


def nominal_rotation(design) -> np.ndarray:
    """The rotation of ``workspace.orientation`` (identity for 2T and 3T)."""
    from cdpr_design.statics.kinematics import rotation_matrix

    return rotation_matrix(*design.default_orientation_full())


def held_rotation(design) -> np.ndarray | None:
    """The rotation the spec holds the effector at for the forward problem, or None when
    the orientation is among its unknowns: ``effector.orientation: fixed`` on a translational
    motion (2T, 3T) holds it at the identity, the spec's model; rotational motions (1R2T, 3R3T)
    find it from the lengths, and ``free`` lets it hang."""
    if design.effector.orientation == "fixed" and not design.motion.rotational:
        return np.eye(3)
    return None


def equilibrium(design, lengths, **options) -> HangingFK:
    """Where the design's effector rests for cable ``lengths`` [m] under its spec (the ``fk``
    command): :func:`~cdpr_design.statics.hanging.forward.fk_held_arrays` at :func:`held_rotation` when
    the spec holds the orientation, else :func:`~cdpr_design.statics.hanging.forward.fk_arrays` started
    about :func:`nominal_rotation`.  Errors name
    the cables; ``within_limits`` from the design's tension limits."""
    A, B, c, mass, g, planar = design_arrays(design)
    held = held_rotation(design)
    names = design.cable_names
    if held is not None:
        r = fk_held_arrays(A, B, c, mass, g, lengths, planar, held, names=names)
    else:
        options.setdefault("nominal", nominal_rotation(design))
        r = fk_arrays(A, B, c, mass, g, lengths, planar, names=names, **options)
    return dataclasses.replace(r, within_limits=None if r.indeterminate else _within(design, r.tensions))
