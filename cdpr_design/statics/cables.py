"""Cable models: the one seam through which every analysis sees its cables.

Three models (``cable.model`` in the spec, ``--cable-model`` on the command
line; docs/cable-models.md):

- ``ideal``: massless, inextensible, straight; the tension is the same at
  both ends and the unstretched length is the chord.  Every analysis's
  historical answer.
- ``elastic``: straight and massless, stretched by T/EA: the tensions are the
  ideal ones, the winch pays out L0 = L / (1 + T/EA).
- ``sagging``: Irvine's elastic catenary (weight and stretch): the end force
  at the effector is along the cable's tangent there, the outlet sees a larger
  tension than the effector, and the unstretched length is the catenary's
  (:mod:`cdpr_design.kernels.sagging`).

A design's model is the heaviest of its cables' (``sagging`` if any cable
sags: :func:`cdpr_design.statics.robot.cable_model`).  Swivel pulleys take
straight cables: with ``sagging`` they are refused by the resolved robot's one
table (:data:`cdpr_design.statics.robot.REFUSALS`); interference is checked along
the catenaries (:func:`cdpr_design.statics.interference.check_sagging_pose`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.model.design import Design
from cdpr_design.statics.robot import Robot, cable_arrays

#: Status names of a sagging pose, by the kernel's code (``cable_status`` column).
STATUS = ("ok", "no-tensions", "no-catenary", "not-converged", "singular")
#: Fixed-point iterations allowed per pose (it converges in 3-10 on the shipped designs).
MAX_ITERATIONS = 60


def elastic_unstretched(lengths: np.ndarray, tensions: np.ndarray, EA: np.ndarray) -> np.ndarray:
    """Unstretched lengths [m] of straight elastic cables: L0 = L / (1 + T/EA) (NaN where T is)."""
    return np.asarray(lengths, float) / (1.0 + np.asarray(tensions, float) / EA)


@dataclass
class CableState:
    """Per-cable results of a non-ideal model at one pose (NaN where infeasible).

    ``outlet_tensions`` [N], ``unstretched_lengths`` [m], ``sag`` [m] (largest
    distance of the cable from its chord), ``status`` (one of :data:`STATUS`).
    """

    outlet_tensions: np.ndarray
    unstretched_lengths: np.ndarray
    sag: np.ndarray
    status: str = "ok"


def straight_state(robot: Robot, lengths: np.ndarray, tensions: np.ndarray) -> CableState:
    """The :class:`CableState` of straight cables (ideal or elastic) of ``robot`` at one pose or
    many (``lengths`` [m], ``tensions`` [N], (m,) or (k, m)): outlet = effector tension, no sag,
    unstretched lengths L / (1 + T/EA) (NaN where T is)."""
    t = np.asarray(tensions, float)
    sag = np.where(np.isfinite(t), 0.0, np.nan)
    return CableState(t.copy(), elastic_unstretched(lengths, t, robot.cable.EA), sag)


def sag_cables(arr, rows, tension_min, tension_max):
    """The kernels' :data:`~cdpr_design.kernels.sag_shapes.SagCables` of the cable arrays ``arr``
    (:class:`~cdpr_design.statics.robot.CableArrays`), wrench ``rows`` and tension bounds [N]."""
    from cdpr_design.kernels.sag_shapes import SagCables

    c = np.ascontiguousarray
    return SagCables(c(rows, dtype=np.int64), c(arr.up, dtype=float), c(arr.w, dtype=float), c(arr.EA, dtype=float),
                     c(tension_min, dtype=float), c(tension_max, dtype=float))


def sag_robot(robot: Robot, wreq: np.ndarray, kind: int):
    """The sagging kernels' :data:`~cdpr_design.kernels.sagging.SagRobot` of ``robot`` for the
    required wrenches ``wreq`` (nv, n) [N, N m] (one row a sample on a path) and the kernels'
    ``kind`` code, with :data:`MAX_ITERATIONS`."""
    from cdpr_design.kernels import sagging as KS

    cab = sag_cables(robot.cable, robot.rows, robot.tension_min, robot.tension_max)
    return KS.sag_robot(robot.outlet_points, cab, wreq, robot.combos, kind, MAX_ITERATIONS)


def sagging_structure(robot: Robot, full: np.ndarray) -> np.ndarray:
    """The structure matrix W (n, m) of ``robot``'s sagging cables at one pose (full [x, y, z,
    rx, ry, rz] [m, rad]): the end-force directions of the converged catenaries of the sweep's
    solve (:func:`cdpr_design.kernels.sagging.sag_pose`, with the robot's kind and the same
    inputs as the sweep's); NaN where the shapes are not known."""
    from cdpr_design.kernels import sagging as KS
    from cdpr_design.statics import kinematics as kin
    from cdpr_design.statics.wrenches import wrench_vertices

    Rb = np.ascontiguousarray(robot.attachments @ kin.rotation_matrix(*full[3:]).T)
    wreq = wrench_vertices(robot.design, robot.kind, full[3:])
    return KS.sag_points(full[None, :3], Rb, sag_robot(robot, wreq, robot.kcode)).Ws[0]


def sagging_structures(robot: Robot, positions3: np.ndarray, orientation) -> tuple:
    """Sagging statics of ``robot`` (resolved for ``size-motors``) at many positions (k, 3) [m]
    at one orientation (3,) [rad], static load.

    Returns (ok (k,) bool: converged and feasible, W (k, n, m) from the
    end-force directions, tensions (k, m) at the effector end [N], outlet
    tensions (k, m) [N]).  For the sizing: the winch sees the outlet tension.
    """
    from cdpr_design.kernels import sagging as KS
    from cdpr_design.statics import kinematics as kin
    from cdpr_design.statics.robot import KINDS
    from cdpr_design.statics.wrenches import wrench_vertices

    design = robot.design
    Rb = np.ascontiguousarray(design.attachments @ kin.rotation_matrix(*orientation).T)
    wreq = wrench_vertices(design, "static", orientation)
    out = KS.sag_points(positions3, Rb, sag_robot(robot, wreq, KINDS["static"]))
    return out.feasible.astype(bool), out.Ws, out.tensions, out.outlet


def sagging_for_objective(design: Design, full: np.ndarray, wreq0: np.ndarray, objective: str, weights,
                          start: np.ndarray | None = None):
    """Tensions [N] of another objective (min-max, min-sum, weighted) with sagging cables.

    The same fixed point as the kernel's, with the objective's distribution
    (:func:`cdpr_design.statics.tension.tensions_for_objective`) in place of
    the minimum-norm one, started from the shapes of the effector-end tensions
    ``start`` (m,) [N] (the converged minimum-norm ones: the straight tensions can
    be too far, see :func:`cdpr_design.kernels.sag_fixed.solve`), else from the
    straight cables.  Returns (tensions or None, W, CableState); W is NaN unless
    the tensions converged.
    """
    from cdpr_design.kernels import sag_shapes as S
    from cdpr_design.kernels.catenary import catenary_sag
    from cdpr_design.statics import kinematics as kin
    from cdpr_design.statics.tension import tensions_for_objective

    arr = cable_arrays(design)
    m, n = design.m, design.n
    R = kin.rotation_matrix(*full[3:])
    Rb = np.ascontiguousarray(design.attachments @ R.T)
    A = np.ascontiguousarray(design.outlets)
    W, cw = np.full((n, m), np.nan), np.empty((m, S.NCW))  # cw: every column span() reads is written there
    L = np.empty(m)
    nan = np.full(m, np.nan)
    if not S.span(full[0], full[1], full[2], Rb, A, arr.up, cw, L):
        return None, W, CableState(nan, nan.copy(), nan.copy(), "singular")
    cab = sag_cables(arr, design.rows, design.tension_min, design.tension_max)
    lo, hi = design.tension_min, design.tension_max
    if start is not None and S.shapes_for(np.array(start, float), Rb, cab, cw, W, 60):
        lo, hi = cw[:, S.CW_LO].copy(), cw[:, S.CW_HI].copy()
    else:
        S.straight_columns(Rb, A, full[0], full[1], full[2], design.rows, W)
    t = tensions_for_objective(W.copy(), wreq0, lo, hi, objective, weights)
    unknown = np.full((n, m), np.nan)
    for _ in range(MAX_ITERATIONS):
        if t is None:
            return None, unknown, CableState(nan, nan.copy(), nan.copy(), "no-tensions")
        if not S.shapes_for(t, Rb, cab, cw, W, 60):
            return None, unknown, CableState(nan, nan.copy(), nan.copy(), "no-catenary")
        lo, hi = cw[:, S.CW_LO].copy(), cw[:, S.CW_HI].copy()
        t2 = tensions_for_objective(W.copy(), wreq0, lo, hi, objective, weights)
        if t2 is not None and np.max(np.abs(t2 - t)) <= 1e-9 * max(1.0, np.max(np.abs(t))):
            sag = np.array([catenary_sag(cw[i, S.CW_H], cw[i, S.CW_VB], cw[i, S.CW_L0], arr.w[i], arr.EA[i])[0]
                            for i in range(m)])
            return t, W, CableState(cw[:, S.CW_TA].copy(), cw[:, S.CW_L0].copy(), sag)
        t = t2
    return None, unknown, CableState(nan, nan.copy(), nan.copy(), "not-converged")


@dataclass
class SampleStates:
    """Sagging statics of k samples (:func:`sagging_samples`); NaN where a sample has no solution.

    ``tensions`` (k, m) effector-end [N], ``outlet_tensions`` (k, m) [N],
    ``unstretched_lengths`` (k, m) [m], ``sag`` (k, m) [m], ``lengths`` (k, m)
    chords [m], ``status`` (k,) index into :data:`STATUS`, ``feasible`` (k,)
    converged with every tension within its bounds along the whole cable.
    """

    tensions: np.ndarray
    outlet_tensions: np.ndarray
    unstretched_lengths: np.ndarray
    sag: np.ndarray
    lengths: np.ndarray
    status: np.ndarray
    feasible: np.ndarray


def sagging_samples(robot: Robot, positions: np.ndarray, Rb: np.ndarray, wreq: np.ndarray) -> SampleStates:
    """Sagging cables of ``robot`` (resolved for ``motion``) at k samples of a path, each with its
    own required wrench.

    ``positions`` (k, 3) [m], ``Rb`` (k, m, 3) the rotated attachments [m],
    ``wreq`` (k, n) the wrench the cables must exert on the effector [N, N m]
    (gravity and inertia; motion's rows).  The kernel of a sweep's sagging pose
    with minimum-norm tensions (:mod:`cdpr_design.kernels.sag_path`).  A
    sample whose shapes converge with tensions outside the bounds keeps the
    numbers of the same pose under [0, inf) and is flagged infeasible; one
    whose shapes do not exist or do not converge has NaN and its status.
    """
    from cdpr_design.kernels.sag_path import SampleOutputs, sag_samples
    from cdpr_design.statics.robot import KINDS

    design = robot.design
    P = np.ascontiguousarray(positions, dtype=float)
    k, m = P.shape[0], design.m
    out = SampleOutputs(*(np.full((k, m), np.nan) for _ in range(5)), np.zeros(k, dtype=np.int8),
                        np.zeros(k, dtype=np.uint8))
    sag_samples(P, np.ascontiguousarray(Rb, dtype=float), sag_robot(robot, wreq, KINDS["static"]), out)
    return SampleStates(out.tensions, out.outlet, out.L0, out.sag, out.lengths, out.status, out.feasible.astype(bool))


def cable_shape(outlet, attachment, L0: float, w: float, EA: float, up, count: int):
    """Points (count + 1, 3) [m] of a sagging cable from its outlet to its attachment, at equal
    unstretched arc lengths, and its end forces (H, VB) [N]; None when the catenary has no
    solution (:func:`cdpr_design.kernels.catenary_inv.catenary_inverse`).

    ``outlet``, ``attachment`` (3,) [m], ``L0`` [m], ``w`` [N/m], ``EA`` [N], ``up`` (3,) unit.
    """
    from cdpr_design.kernels.catenary import catenary_profile
    from cdpr_design.kernels.catenary_inv import CAT_CONVERGED, catenary_inverse

    A, B, up = (np.asarray(v, float) for v in (outlet, attachment, up))
    d = A - B
    Z = float(d @ up)
    h = d - Z * up
    X = float(np.linalg.norm(h))
    u = h / X if X > 1e-14 * np.linalg.norm(d) else np.zeros(3)
    H, VB, status, _ = catenary_inverse(X if u.any() else 0.0, Z, L0, w, EA, np.nan, np.nan, 1e-13, 100)
    if status != CAT_CONVERGED:
        return None
    s = np.ascontiguousarray(L0 * np.linspace(1.0, 0.0, count + 1))
    x, z = catenary_profile(H, VB, L0, w, EA, s)
    return B[None, :] + x[:, None] * u[None, :] + z[:, None] * up[None, :], (H, VB)
