"""Stiffness and vibration of the effector on its cables (straight elastic cables).

Conventions
-----------
The effector's displacement x = (dp, dtheta): dp [m] moves the reference point (the platform
origin p), dtheta [rad] is a small rotation vector about frame axes through p
(R -> exp([dtheta]x) R).  The wrench w = (f, m) [N, N m] is the total wrench on the effector --
the cables' pulls t_i u_i and the weight m g at the centre of mass R c -- with moments about p:
the frame and the reference point of the structure matrix W of
:mod:`cdpr_design.statics.kinematics` (column i = [u_i; (R b_i) x u_i]).  The stiffness matrix is

    K = -dw/dx  at fixed unstretched lengths L0_i,

for a cable tension t_i = EA_i (L_i - L0_i) / L0_i.  With r_i = R b_i, F_i = t_i u_i and
k_i = EA_i / L0_i (= (EA_i + t_i) / L_i), and the cable's stiffness at its attachment

    H_i = k_i u_i u_i^T + (t_i / L_i) (I - u_i u_i^T)       (elastic + geometric part)

    K_pp = sum H_i                        K_pr = -sum H_i [r_i]x
    K_rp = sum [r_i]x H_i                 K_rr = -sum ([r_i]x H_i [r_i]x + [F_i]x [r_i]x) - [m g]x [R c]x

(Behzadipour & Khajepour, "Stiffness of cable-based parallel manipulators with application to
stability analysis", ASME J. Mech. Des. 128(1), 2006; Pott, "Cable-Driven Parallel Robots",
Springer 2018, the stiffness chapter).  The elastic part is sum k_i w_i w_i^T with w_i the
columns of W; the rest grows with the tensions.  K is symmetric at an equilibrium (the net
wrench zero) and not in general away from one.  A motion type keeps its coordinates' rows and
columns (2T: x, y; 1R2T: x, y, phi; 3T: x, y, z; 3R3T all six), the others held.  For 1R2T the
small rotation is d(phi) exactly; for 3R3T it is not the increment of the pose's xyz Euler
angles: d(theta) = E(angles) d(angles) (:func:`cdpr_design.statics.kinematics.euler_rates_to_omega`),
so the stiffness in Euler angles is E^T K_rr E (at an equilibrium).

Vibration: K v = omega^2 M v with M the effector's rigid-body mass matrix at p (mass, centre of
mass offset, inertia moved to p by the parallel-axis rule), restricted like K.  Cable mass is
neglected (massless springs): the effector's modes are right while the cables weigh much less
than the effector; their own transverse modes are :func:`string_frequencies`.

Cables: ``elastic`` ones with their ``axial_stiffness``, and ``ideal`` ones when the spec gives
an ``axial_stiffness`` (the tensions are the same).  An ideal cable without one is rigid along
its length: the stiffness is infinite and not reported (:func:`axial_stiffnesses` says why);
``sagging`` cables and swivel pulleys are not modelled here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.model.design import Design
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.robot import facts


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


def stiffness_matrix(vectors, Rb, tensions, EA, weight, com) -> np.ndarray:
    """The full 6x6 K = -dw/dx [N/m, N/rad, N m/m, N m/rad] (module notes) at any configuration.

    ``vectors`` (m, 3) l_i = a_i - (p + R b_i) [m]; ``Rb`` (m, 3) R b_i [m]; ``tensions`` (m,)
    t_i = EA_i (L_i - L0_i) / L0_i [N]; ``EA`` (m,) [N]; ``weight`` (3,) m g [N]; ``com`` (3,)
    R c [m].
    """
    l = np.asarray(vectors, float)
    L = np.linalg.norm(l, axis=1)
    u = l / L[:, None]
    t = np.asarray(tensions, float)
    k = (np.asarray(EA, float) + t) / L
    K = np.zeros((6, 6))
    eye = np.eye(3)
    for i in range(l.shape[0]):
        uu = np.outer(u[i], u[i])
        H = k[i] * uu + t[i] / L[i] * (eye - uu)
        r = skew(Rb[i])
        K[:3, :3] += H
        K[:3, 3:] -= H @ r
        K[3:, :3] += r @ H
        K[3:, 3:] -= r @ H @ r + skew(t[i] * u[i]) @ r
    K[3:, 3:] += weight_term(weight, com)
    return K


def weight_term(weight, com) -> np.ndarray:
    """-[m g]x [R c]x (3, 3) [N m/rad]: the weight's share of the rotational stiffness."""
    return -skew(np.asarray(weight, float)) @ skew(np.asarray(com, float))


def mass_matrix(design: Design, R) -> np.ndarray:
    """The effector's 6x6 mass matrix at the reference point [kg, kg m, kg m^2] for rotation ``R``.

    [[m I, -m [R c]x], [m [R c]x, R I_c R^T - m [R c]x [R c]x]] (inertia about the centre of
    mass moved to p by the parallel-axis rule).
    """
    eff = design.effector
    m = float(eff.mass)
    c = skew(R @ np.asarray(eff.center_of_mass, float))
    M = np.zeros((6, 6))
    M[:3, :3] = m * np.eye(3)
    M[:3, 3:] = -m * c
    M[3:, :3] = m * c
    M[3:, 3:] = R @ eff.inertia_matrix @ R.T - m * c @ c
    return 0.5 * (M + M.T)


def restrict(design: Design, A: np.ndarray) -> np.ndarray:
    """A 6x6 matrix restricted to the motion's coordinates (rows and columns of ``pose_index``)."""
    sel = list(design.motion.pose_index)
    return A[np.ix_(sel, sel)]


def min_stiffness(K: np.ndarray, d: int) -> float:
    """The least stiffness [N/m] against a force at the reference point, the effector free to rotate.

    ``K`` (n, n) restricted, its first ``d`` coordinates translations: the least eigenvalue of the
    symmetric part of the Schur complement K_pp - K_pr K_rr^-1 K_rp (the inverse of the compliance's
    translational block), of K_pp itself without rotations.  Negative: unstable; NaN where K_rr is
    singular.
    """
    Ks = 0.5 * (K + K.T)
    S = Ks[:d, :d]
    if K.shape[0] > d:
        try:
            S = S - Ks[:d, d:] @ np.linalg.solve(Ks[d:, d:], Ks[d:, :d])
        except np.linalg.LinAlgError:
            return float("nan")
    return float(np.linalg.eigvalsh(0.5 * (S + S.T))[0])


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


def pose_stiffness(design: Design, pose, tensions) -> PoseStiffness:
    """:class:`PoseStiffness` at a pose (motion coordinates) held by ``tensions`` (m,) [N].

    The unstretched lengths are those the tensions stretch to the pose's lengths (an equilibrium
    when the tensions balance the pose's wrench, as :func:`cdpr_design.workspaces.pose.evaluate_pose`'s do).
    """
    g = kin.cable_geometry(design, pose)
    t = np.asarray(tensions, float)
    mu = np.array([c.props.mass_per_length or 0.0 for c in design.cables])
    free = np.linalg.norm(g.vectors, axis=1)
    strings = string_frequencies(free, t, mu)
    floor = frequency_tension_floor(design, free)
    EA, reason = axial_stiffnesses(design)
    if reason is None and not np.all(np.isfinite(t)):
        reason = "no tensions hold the effector at this pose (infeasible)"
    if reason is None and not np.all(free > 1e-12):
        reason = "a cable has zero length at this pose"
    if reason is not None:
        return PoseStiffness(None, None, float("nan"), None, None, strings, reason, floor)
    R = kin.pose_rotation(design, pose)
    c = R @ np.asarray(design.effector.center_of_mass, float)
    weight = design.effector.mass * np.asarray(design.gravity, float)
    K = restrict(design, stiffness_matrix(g.vectors, g.attachments, t, EA, weight, c))
    d = design.motion.dim
    kmin = min_stiffness(K, d)
    vib = vibration(K, restrict(design, mass_matrix(design, R)))
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


@dataclass(frozen=True)
class SweepStiffness:
    """What the kernel needs at one orientation, built once per sweep (:func:`sweep_arrays`).

    ``Rb`` (m, 3) R b_i [m]; ``A`` (m, 3) outlets [m]; ``EA`` (m,) [N]; ``Kg`` (3, 3) the weight's
    term [N m/rad]; ``Linv`` (n, n) the inverse Cholesky factor of the restricted mass matrix (NaN
    when it is singular); ``sel`` (n,) the motion's coordinates; ``d`` the translations among them.
    """

    Rb: np.ndarray
    A: np.ndarray
    EA: np.ndarray
    Kg: np.ndarray
    Linv: np.ndarray
    sel: np.ndarray
    d: int


def sweep_arrays(design: Design, orientation=None) -> SweepStiffness | str:
    """The :class:`SweepStiffness` of a design at a fixed orientation (rx, ry, rz) [rad] (default the
    workspace's), or the reason the stiffness is not defined (:func:`axial_stiffnesses`)."""
    EA, reason = axial_stiffnesses(design)
    if reason is not None:
        return reason
    ori = design.default_orientation_full() if orientation is None else np.asarray(orientation, float)
    R = kin.rotation_matrix(*ori)
    c = R @ np.asarray(design.effector.center_of_mass, float)
    weight = design.effector.mass * np.asarray(design.gravity, float)
    M = restrict(design, mass_matrix(design, R))
    try:
        Linv = np.linalg.inv(np.linalg.cholesky(M))
    except np.linalg.LinAlgError:
        Linv = np.full(M.shape, np.nan)
    c64 = np.ascontiguousarray
    return SweepStiffness(c64(design.attachments @ R.T), c64(design.outlets), c64(EA), c64(weight_term(weight, c)),
                          c64(Linv), np.array(design.motion.pose_index, dtype=np.int64), design.motion.dim)


def sweep_figures(arrays: SweepStiffness, positions, tensions) -> tuple[np.ndarray, np.ndarray]:
    """(min_stiffness (k,) [N/m], lowest_frequency (k,) [Hz]) at ``positions`` (k, 3) [m] held by
    ``tensions`` (k, m) [N] (NaN rows give NaN), by the kernel :mod:`cdpr_design.kernels.stiffness`."""
    P = np.ascontiguousarray(positions, dtype=float)
    return _figures(arrays, 0, np.zeros(3), np.ones(3), np.ones(3, dtype=np.int64), P, tensions,
                    np.ones(P.shape[0], dtype=np.uint8))


def grid_figures(arrays: SweepStiffness, grid3, start: int, tensions, feasible) -> tuple[np.ndarray, np.ndarray]:
    """:func:`sweep_figures` at the grid poses ``start .. start + k - 1`` of ``grid3`` = (lower (3,)
    [m], step (3,) [m], shape (3,) int64) (:func:`cdpr_design.workspaces.grid.grid3`), without
    their positions: the kernel counts the grid's indices as the sweep's kernels do.  ``feasible``
    (k,) the sweep's flags: NaN where 0, as for rows of NaN ``tensions`` (k, m) [N]."""
    lower, step, shape = grid3
    return _figures(arrays, start, lower, step, shape, np.empty((0, 3)), tensions,
                    np.ascontiguousarray(feasible, dtype=np.uint8))


def _figures(a: SweepStiffness, start, lower, step, shape, P, tensions, feasible):
    from cdpr_design.kernels.stiffness import Arrays, Poses, stiffness_rows

    T = np.ascontiguousarray(tensions, dtype=float)
    kmin = np.empty(T.shape[0])
    flow = np.empty(T.shape[0])
    stiffness_rows(Poses(start, lower, step, shape, P), feasible, T, Arrays(a.Rb, a.A, a.EA, a.Kg, a.Linv, a.sel, a.d),
                   kmin, flow)
    return kmin, flow
