"""Stiffness and vibration of the effector on its cables (straight elastic and sagging cables).

Conventions
-----------
The effector's displacement x = (dp, dtheta): dp [m] moves the reference point (the platform
origin p), dtheta [rad] is a small rotation vector about frame axes through p
(R -> exp([dtheta]x) R).  The wrench w = (f, m) [N, N m] is the total wrench on the effector --
the cables' forces F_i at the attachments and the weight m g at the centre of mass R c -- with
moments about p: the frame and the reference point of the structure matrix W of
:mod:`cdpr_design.statics.kinematics` (column i = [u_i; (R b_i) x u_i]).  The stiffness matrix is

    K = -dw/dx  at fixed unstretched lengths L0_i.

With r_i = R b_i and H_i = -dF_i/db_i the cable's stiffness at its attachment,

    K_pp = sum H_i                        K_pr = -sum H_i [r_i]x
    K_rp = sum [r_i]x H_i                 K_rr = -sum ([r_i]x H_i [r_i]x + [F_i]x [r_i]x) - [m g]x [R c]x

(Behzadipour & Khajepour, "Stiffness of cable-based parallel manipulators with application to
stability analysis", ASME J. Mech. Des. 128(1), 2006; Pott, "Cable-Driven Parallel Robots",
Springer 2018, the stiffness chapter).  A straight elastic cable of tension t_i = EA_i (L_i -
L0_i) / L0_i along u_i has H_i = k_i u_i u_i^T + (t_i / L_i)(I - u_i u_i^T), k_i = EA_i / L0_i;
a sagging cable (Irvine's elastic catenary) the inverse of its flexibility matrix d(X, Z)/d(H, VB)
in its vertical plane and H / X across it (:mod:`cdpr_design.kernels.stiffness`, the one
implementation; docs/algorithms.md).  K is symmetric at an equilibrium (the net wrench zero) and
not in general away from one.  A motion type keeps its coordinates' rows and columns (2T: x, y;
1R2T: x, y, phi; 3T: x, y, z; 3R3T all six), the others held.  For 1R2T the small rotation is
d(phi) exactly; for 3R3T it is not the increment of the pose's xyz Euler angles:
d(theta) = E(angles) d(angles) (:func:`cdpr_design.statics.kinematics.euler_rates_to_omega`), so
the stiffness in Euler angles is E^T K_rr E (at an equilibrium).

Vibration: K v = omega^2 M v with M the effector's rigid-body mass matrix at p (mass, centre of
mass offset, inertia moved to p by the parallel-axis rule), restricted like K.  Straight cables
are massless (the elastic model); a sagging cable adds a third of its mass (mu L0_i / 3) as a
point mass at its attachment (Rayleigh's lumping of a cable whose points follow its end in
proportion to their distance from the outlet).  The cables' own transverse modes are
:func:`string_frequencies`.

Cables: ``elastic`` ones with their ``axial_stiffness``, ``sagging`` ones, and ``ideal`` ones when
the spec gives an ``axial_stiffness`` (the tensions are the same).  An ideal cable without one is
rigid along its length: the stiffness is infinite and not reported (:func:`axial_stiffnesses`
says why); swivel pulleys are not modelled here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.model.design import Design
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.robot import cable_arrays, facts


def skew(v) -> np.ndarray:
    """[v]x: the matrix with [v]x y = v x y."""
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def axial_stiffnesses(design: Design) -> tuple[np.ndarray | None, str | None]:
    """(EA (m,) [N], None), or (None, the reason the stiffness is not defined for this design:
    :func:`cdpr_design.statics.robot.stiffness_reason`)."""
    reason = facts(design).stiffness
    if reason is not None:
        return None, reason
    return np.array([float(c.props.axial_stiffness) for c in design.cables]), None


def weight_term(weight, com) -> np.ndarray:
    """-[m g]x [R c]x (3, 3) [N m/rad]: the weight's share of the rotational stiffness."""
    return -skew(np.asarray(weight, float)) @ skew(np.asarray(com, float))


def mass_matrix(design: Design, R) -> np.ndarray:
    """The effector's 6x6 mass matrix at the reference point [kg, kg m, kg m^2] for rotation ``R``.

    [[m I, -m [R c]x], [m [R c]x, R I_c R^T - m [R c]x [R c]x]] (inertia about the centre of
    mass moved to p by the parallel-axis rule).
    """
    from cdpr_design.statics.hanging.compliance import mass_matrix_many

    eff = design.effector
    M = mass_matrix_many(float(eff.mass), eff.center_of_mass, eff.inertia_matrix, R, range(6))[0]
    return 0.5 * (M + M.T)


def restrict(design: Design, A: np.ndarray) -> np.ndarray:
    """A 6x6 matrix restricted to the motion's coordinates (rows and columns of ``pose_index``)."""
    sel = list(design.motion.pose_index)
    return A[np.ix_(sel, sel)]


def vibration(K: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Natural frequencies [Hz] (ascending) and mode shapes of K v = omega^2 M v (symmetric part of K).

    Returns (f (n,), V (n, n)) with mode j in row j, scaled to unit 2-norm in (m, rad) with its
    largest component positive; f is NaN for a mode with omega^2 < 0 (unstable).  None when M is
    not positive definite (a massless effector, or no inertia about a rotation it has).
    """
    from scipy.linalg import eigh

    try:
        np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        return None
    w2, V = eigh(0.5 * (K + K.T), M)
    f = np.where(w2 >= 0, np.sqrt(np.abs(w2)), np.nan) / (2 * np.pi)
    V = V.T / np.linalg.norm(V.T, axis=1)[:, None]
    big = np.argmax(np.abs(V), axis=1)
    V *= np.sign(V[np.arange(V.shape[0]), big])[:, None]
    return f, V


def string_frequencies(lengths, tensions, mass_per_length) -> np.ndarray:
    """First transverse (string) frequency of each cable f_1 = sqrt(T / mu) / (2 L) [Hz] (mode k: k f_1).

    ``lengths`` [m] the vibrating lengths, ``tensions`` [N], ``mass_per_length`` mu [kg/m]; NaN where
    mu is 0 or the tension is not a finite non-negative number.
    """
    L, T, mu = (np.asarray(v, float) for v in (lengths, tensions, mass_per_length))
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.sqrt(T / mu) / (2.0 * L)
    return np.where((mu > 0) & np.isfinite(T) & (T >= 0), f, np.nan)


def frequency_tension_floor(design: Design, lengths) -> np.ndarray | None:
    """The lower tension bound [N] that ``requirements.min_cable_frequency`` sets on each cable at
    free lengths ``lengths`` (..., m) [m] (:func:`~cdpr_design.model.design.min_string_tension`;
    0 for a cable without a mass per length), or None when the spec has no such requirement."""
    if design.requirements.min_cable_frequency is None:
        return None
    L = np.asarray(lengths, float)
    return design.string_floor * L * L


@dataclass(frozen=True)
class PoseStiffness:
    """Stiffness and vibration at one pose (module notes); None/NaN fields with ``reason`` where undefined.

    ``matrix`` (n, n) K in the motion's coordinates; ``translational`` (d, d) its block -df/dp at
    fixed orientation [N/m]; ``min_stiffness`` [N/m]; ``frequencies`` (n,) [Hz] ascending;
    ``modes`` (n, n), mode j in row j; ``cable_frequencies`` (m,) each cable's first string
    frequency [Hz] (NaN without a mass per length) over its free length (outlet to attachment).
    """

    matrix: np.ndarray | None
    translational: np.ndarray | None
    min_stiffness: float
    frequencies: np.ndarray | None
    modes: np.ndarray | None
    cable_frequencies: np.ndarray
    reason: str | None = None
    #: the lower tension bound of ``requirements.min_cable_frequency`` (m,) [N] (:func:`frequency_tension_floor`)
    frequency_floor: np.ndarray | None = None


def pose_stiffness(design: Design, pose, tensions, unstretched=None) -> PoseStiffness:
    """:class:`PoseStiffness` at a pose (motion coordinates) held by ``tensions`` (m,) [N]
    (effector-end tensions).

    Straight cables: the unstretched lengths are those the tensions stretch to the pose's lengths
    (an equilibrium when the tensions balance the pose's wrench, as
    :func:`cdpr_design.workspaces.pose.evaluate_pose`'s do).  Sagging cables: ``unstretched`` (m,)
    [m] their unstretched lengths (the pose's cable state), which fix their shapes; their
    tensions only start the catenaries' solves (NaN: the solver's own start).
    """
    g = kin.cable_geometry(design, pose)
    t = np.asarray(tensions, float)
    mu = np.array([c.props.mass_per_length or 0.0 for c in design.cables])
    free = np.linalg.norm(g.vectors, axis=1)
    strings = string_frequencies(free, t, mu)
    floor = frequency_tension_floor(design, free)
    full = design.full_pose(pose)
    arrays = sweep_arrays(design, full[3:])
    reason = arrays if isinstance(arrays, str) else None
    L0 = np.full(design.m, np.nan) if unstretched is None else np.asarray(unstretched, float)
    if reason is None:
        sags = arrays.w > 0
        if not np.all(np.isfinite(t[~sags])) or not np.all(np.isfinite(L0[sags]) | np.isfinite(t[sags])):
            reason = "no tensions hold the effector at this pose (infeasible)"
        elif not np.all(np.isfinite(L0[sags])):
            reason = ("the sagging cables have no shapes at this pose (wrench closure takes their chords, "
                      "with tensions but without unstretched lengths): no stiffness")
    if reason is None and not np.all(free > 1e-12):
        reason = "a cable has zero length at this pose"
    K6, M6 = np.empty((6, 6)), np.empty((6, 6))
    if reason is None:
        from cdpr_design.kernels.stiffness import pose_matrices

        if not pose_matrices(*full[:3], np.ascontiguousarray(t), np.ascontiguousarray(L0), arrays, K6, M6):
            reason = "a cable's shape is not known at this pose (its catenary did not converge)"
    if reason is not None:
        return PoseStiffness(None, None, float("nan"), None, None, strings, reason, floor)
    from cdpr_design.kernels.stiffness import least_stiffness

    K = restrict(design, K6)
    d = design.motion.dim
    kmin = float(least_stiffness(K6, arrays.sel, d))
    vib = vibration(K, restrict(design, 0.5 * (M6 + M6.T)))
    if vib is None:
        return PoseStiffness(K, K[:d, :d], kmin, None, None, strings,
                             "the effector's mass matrix is singular (no mass, or no inertia about a rotation "
                             "the motion has): no natural frequencies", floor)
    f, V = vib
    note = None if np.all(np.isfinite(f)) else "unstable equilibrium: K has a negative eigenvalue (frequency null)"
    if not np.isfinite(kmin):
        note = "the rotational block of K is singular: the cables do not hold the rotations (min_stiffness null)"
    return PoseStiffness(K, K[:d, :d], kmin, f, V, strings, note, floor)


# ----------------------------------------------------------------------------
# Many poses (the sweep's kernel)
# ----------------------------------------------------------------------------


def sweep_arrays(design: Design, orientation=None):
    """The stiffness kernel's :data:`~cdpr_design.kernels.stiffness.Arrays` of a design at a fixed
    orientation (rx, ry, rz) [rad] (default the workspace's), or the reason the stiffness is not
    defined (:func:`axial_stiffnesses`).  Sagging cables (``w`` > 0 [N/m]) lump a third of their
    mass per unstretched length at their attachments (``lump`` [kg/m])."""
    from cdpr_design.kernels.stiffness import Arrays

    EA, reason = axial_stiffnesses(design)
    if reason is not None:
        return reason
    ori = design.default_orientation_full() if orientation is None else np.asarray(orientation, float)
    R = kin.rotation_matrix(*ori)
    c = R @ np.asarray(design.effector.center_of_mass, float)
    weight = design.effector.mass * np.asarray(design.gravity, float)
    M0 = mass_matrix(design, R)
    try:
        Linv = np.linalg.inv(np.linalg.cholesky(restrict(design, M0)))
    except np.linalg.LinAlgError:
        Linv = np.full((len(design.motion.pose_index),) * 2, np.nan)
    cab = cable_arrays(design)
    gn = float(np.linalg.norm(design.gravity))
    lump = cab.w / (3.0 * gn) if gn > 0 else np.zeros(design.m)
    c64 = np.ascontiguousarray
    return Arrays(c64(design.attachments @ R.T), c64(design.outlets), c64(EA, dtype=float),
                  c64(weight_term(weight, c)), c64(Linv), np.array(design.motion.pose_index, dtype=np.int64),
                  design.motion.dim, c64(cab.w, dtype=float), c64(cab.up, dtype=float), c64(M0), c64(lump))


def sweep_figures(arrays, positions, tensions, unstretched=None) -> tuple[np.ndarray, np.ndarray]:
    """(min_stiffness (k,) [N/m], lowest_frequency (k,) [Hz]) at ``positions`` (k, 3) [m] held by
    ``tensions`` (k, m) [N] with ``unstretched`` (k, m) [m] lengths (needed where a cable sags;
    NaN rows give NaN), by the kernel :mod:`cdpr_design.kernels.stiffness`."""
    P = np.ascontiguousarray(positions, dtype=float)
    return _figures(arrays, 0, np.zeros(3), np.ones(3), np.ones(3, dtype=np.int64), P, tensions, unstretched,
                    np.ones(P.shape[0], dtype=np.uint8))


def grid_figures(arrays, grid3, start: int, tensions, feasible, unstretched=None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`sweep_figures` at the grid poses ``start .. start + k - 1`` of ``grid3`` = (lower (3,)
    [m], step (3,) [m], shape (3,) int64) (:func:`cdpr_design.workspaces.grid.grid3`), without
    their positions: the kernel counts the grid's indices as the sweep's kernels do.  ``feasible``
    (k,) the sweep's flags: NaN where 0, as for rows of NaN ``tensions`` (k, m) [N] (or NaN
    ``unstretched`` (k, m) [m] lengths of sagging cables)."""
    lower, step, shape = grid3
    return _figures(arrays, start, lower, step, shape, np.empty((0, 3)), tensions, unstretched,
                    np.ascontiguousarray(feasible, dtype=np.uint8))


def _figures(arrays, start, lower, step, shape, P, tensions, unstretched, feasible):
    from cdpr_design.kernels.stiffness import Poses, stiffness_rows

    T = np.ascontiguousarray(tensions, dtype=float)
    L0 = np.full(T.shape, np.nan) if unstretched is None else np.ascontiguousarray(unstretched, dtype=float)
    kmin = np.empty(T.shape[0])
    flow = np.empty(T.shape[0])
    stiffness_rows(Poses(start, lower, step, shape, P), feasible, T, L0, arrays, kmin, flow)
    return kmin, flow
