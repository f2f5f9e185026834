"""The effector's stiffness written out plainly with numpy: the slow reference the stiffness
kernel (:mod:`cdpr_design.kernels.stiffness`) is held to for straight elastic cables.

K = -dw/dx at fixed unstretched lengths, with H_i = k_i u_i u_i^T + (t_i / L_i)(I - u_i u_i^T),
k_i = (EA_i + t_i) / L_i (docs/algorithms.md, "Stiffness and vibration"), and the least stiffness
as the least eigenvalue of the translational Schur complement.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.statics.stiffness import skew, weight_term


def stiffness_matrix(vectors, Rb, tensions, EA, weight, com) -> np.ndarray:
    """The full 6x6 K = -dw/dx [N/m, N/rad, N m/m, N m/rad] at any configuration.

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


def min_stiffness(K: np.ndarray, d: int) -> float:
    """The least stiffness [N/m] against a force at the reference point, the effector free to rotate:
    the least eigenvalue of the symmetric part of K_pp - K_pr K_rr^-1 K_rp (``K`` (n, n), its first
    ``d`` coordinates translations), of K_pp itself without rotations; NaN where K_rr is singular."""
    Ks = 0.5 * (K + K.T)
    S = Ks[:d, :d]
    if K.shape[0] > d:
        try:
            S = S - Ks[:d, d:] @ np.linalg.solve(Ks[d:, d:], Ks[d:, :d])
        except np.linalg.LinAlgError:
            return float("nan")
    return float(np.linalg.eigvalsh(0.5 * (S + S.T))[0])


def fd_stiffness(design, full, wrench, h) -> np.ndarray:
    """-dw/dx by central differences with one Richardson step, in the motion's coordinates:
    ``wrench(position (3,), rotvec (3,))`` the net wrench (6,) with the effector moved to
    ``position`` [m] and turned by exp([rotvec]x) from the orientation of ``full`` (6,); steps
    ``h`` [m, rad] and h / 2."""
    sel = list(design.motion.pose_index)
    J = np.empty((6, len(sel)))
    for j, s in enumerate(sel):
        def at(e):
            x = np.zeros(6)
            x[s] = e
            return wrench(full[:3] + x[:3], x[3:])
        d1 = (at(h) - at(-h)) / (2 * h)
        d2 = (at(h / 2) - at(-h / 2)) / h
        J[:, j] = -(4 * d2 - d1) / 3
    return J[sel]
