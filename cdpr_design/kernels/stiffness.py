"""Stiffness and lowest natural frequency of the effector at many poses (straight elastic cables).

The kernel twin of :mod:`cdpr_design.statics.stiffness` (which derives the matrix and
documents the conventions; docs/algorithms.md, "Stiffness and vibration").  Per pose, with
l_i = a_i - (p + R b_i), L_i = |l_i|, u_i = l_i / L_i, r_i = R b_i and the cable's axial
stiffness k_i = EA_i / L0_i = (EA_i + t_i) / L_i (the elastic cable's unstretched length
L0 = L / (1 + t / EA)):

    H_i  = k_i u_i u_i^T + (t_i / L_i) (I - u_i u_i^T)
    K_pp = sum H_i                      K_pt = -sum H_i [r_i]x
    K_tp = sum [r_i]x H_i               K_tt = -sum ([r_i]x H_i [r_i]x + [t_i u_i]x [r_i]x) + Kg

with Kg = -[m g]x [R c]x the weight's term (constant at a fixed orientation).  The matrix is
restricted to the motion's coordinates ``sel``, symmetrised (it is symmetric at an equilibrium)
and then

- ``min_stiffness`` [N/m]: the least eigenvalue of the translational Schur complement
  K_pp - K_pt K_tt^-1 K_tp (of K_pp itself when the motion has no rotation);
- ``lowest_frequency`` [Hz]: sqrt(lambda_min(L^-1 K L^-T)) / (2 pi) for the mass matrix
  M = L L^T (``Linv`` = L^-1), NaN when lambda_min < 0 (an unstable equilibrium).

The eigenvalues are those of cyclic Jacobi rotations on the small symmetric matrices (n <= 6), no
allocation per pose.  A pose whose tensions are not all finite gives NaN.
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit_inline, njit_noref
from cdpr_design.kernels.parallel import run_blocks

#: Jacobi sweeps stop when the off-diagonal mass is below this fraction of the matrix's
JACOBI_TOL = 1e-28
JACOBI_SWEEPS = 30


@njit_inline
def min_eig_sym(a, n):
    """The least eigenvalue of the symmetric ``a[:n, :n]`` (destroyed: cyclic Jacobi rotations)."""
    for _ in range(JACOBI_SWEEPS):
        off = 0.0
        tot = 0.0
        for p in range(n):
            tot += a[p, p] * a[p, p]
            for q in range(p + 1, n):
                off += a[p, q] * a[p, q]
        if not off > JACOBI_TOL * (tot + off):
            break
        for p in range(n - 1):
            for q in range(p + 1, n):
                apq = a[p, q]
                if apq == 0.0:
                    continue
                theta = (a[q, q] - a[p, p]) / (2.0 * apq)
                t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                if theta < 0.0:
                    t = -t
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for r in range(n):
                    arp = a[r, p]
                    arq = a[r, q]
                    a[r, p] = c * arp - s * arq
                    a[r, q] = s * arp + c * arq
                for r in range(n):
                    apr = a[p, r]
                    aqr = a[q, r]
                    a[p, r] = c * apr - s * aqr
                    a[q, r] = s * apr + c * aqr
    lo = a[0, 0]
    for p in range(1, n):
        if a[p, p] < lo:
            lo = a[p, p]
    return lo


@njit_inline
def full_stiffness(px, py, pz, Rb, A, t, EA, Kg, K):
    """Write the 6x6 stiffness matrix K = -dw/dx (module notes) of one pose into ``K``.

    Returns False when a cable has zero length or a tension that is not finite.
    """
    for r in range(6):
        for c in range(6):
            K[r, c] = 0.0
    for r in range(3):
        for c in range(3):
            K[3 + r, 3 + c] = Kg[r, c]
    for i in range(A.shape[0]):
        ti = t[i]
        if not math.isfinite(ti):
            return False
        rx, ry, rz = Rb[i, 0], Rb[i, 1], Rb[i, 2]
        lx, ly, lz = A[i, 0] - px - rx, A[i, 1] - py - ry, A[i, 2] - pz - rz
        L = math.sqrt(lx * lx + ly * ly + lz * lz)
        if not L > 0.0:
            return False
        u0, u1, u2 = lx / L, ly / L, lz / L
        g = ti / L
        e = (EA[i] + ti) / L - g  # k_i - t_i / L_i
        # H = e u u^T + g I
        h00, h01, h02 = e * u0 * u0 + g, e * u0 * u1, e * u0 * u2
        h11, h12, h22 = e * u1 * u1 + g, e * u1 * u2, e * u2 * u2 + g
        # C = H [r]x, [r]x = [[0, -rz, ry], [rz, 0, -rx], [-ry, rx, 0]]
        c00, c01, c02 = h01 * rz - h02 * ry, -h00 * rz + h02 * rx, h00 * ry - h01 * rx
        c10, c11, c12 = h11 * rz - h12 * ry, -h01 * rz + h12 * rx, h01 * ry - h11 * rx
        c20, c21, c22 = h12 * rz - h22 * ry, -h02 * rz + h22 * rx, h02 * ry - h12 * rx
        K[0, 0] += h00
        K[0, 1] += h01
        K[0, 2] += h02
        K[1, 0] += h01
        K[1, 1] += h11
        K[1, 2] += h12
        K[2, 0] += h02
        K[2, 1] += h12
        K[2, 2] += h22
        # K_pt = -H [r]x ; K_tp = [r]x H = -(H [r]x)^T = K_pt^T
        K[0, 3] -= c00
        K[0, 4] -= c01
        K[0, 5] -= c02
        K[1, 3] -= c10
        K[1, 4] -= c11
        K[1, 5] -= c12
        K[2, 3] -= c20
        K[2, 4] -= c21
        K[2, 5] -= c22
        K[3, 0] -= c00
        K[4, 0] -= c01
        K[5, 0] -= c02
        K[3, 1] -= c10
        K[4, 1] -= c11
        K[5, 1] -= c12
        K[3, 2] -= c20
        K[4, 2] -= c21
        K[5, 2] -= c22
        # -[r]x H [r]x = -[r]x C ; rows of [r]x: (0, -rz, ry), (rz, 0, -rx), (-ry, rx, 0)
        K[3, 3] -= -rz * c10 + ry * c20
        K[3, 4] -= -rz * c11 + ry * c21
        K[3, 5] -= -rz * c12 + ry * c22
        K[4, 3] -= rz * c00 - rx * c20
        K[4, 4] -= rz * c01 - rx * c21
        K[4, 5] -= rz * c02 - rx * c22
        K[5, 3] -= -ry * c00 + rx * c10
        K[5, 4] -= -ry * c01 + rx * c11
        K[5, 5] -= -ry * c02 + rx * c12
        # -[F]x [r]x = -(r F^T - (F . r) I), F = t u
        f0, f1, f2 = ti * u0, ti * u1, ti * u2
        fr = f0 * rx + f1 * ry + f2 * rz
        K[3, 3] -= rx * f0 - fr
        K[3, 4] -= rx * f1
        K[3, 5] -= rx * f2
        K[4, 3] -= ry * f0
        K[4, 4] -= ry * f1 - fr
        K[4, 5] -= ry * f2
        K[5, 3] -= rz * f0
        K[5, 4] -= rz * f1
        K[5, 5] -= rz * f2 - fr
    return True


@njit_inline
def pose_figures(K, sel, d, Linv, S, B):
    """(min_stiffness [N/m], lowest_frequency [Hz]) of the full 6x6 ``K`` restricted to ``sel`` (its
    first ``d`` entries the translations, the rest rotations); ``S``, ``B`` (6, 6) scratch.

    The matrix is symmetrised first.  The Schur complement solves K_tt X = K_tp by Gauss-Jordan
    elimination with partial pivoting (NaN when K_tt is singular).
    """
    n = sel.shape[0]
    for r in range(n):
        for c in range(n):
            B[r, c] = 0.5 * (K[sel[r], sel[c]] + K[sel[c], sel[r]])
    # S[:d, :d] = K_pp - K_pt K_tt^-1 K_tp, eliminating in the rows d..n-1 of B (B is overwritten)
    for j in range(d, n):
        piv = j
        for r in range(j + 1, n):
            if abs(B[r, j]) > abs(B[piv, j]):
                piv = r
        if not abs(B[piv, j]) > 0.0:
            return np.nan, np.nan
        if piv != j:
            for c in range(n):
                tmp = B[j, c]
                B[j, c] = B[piv, c]
                B[piv, c] = tmp
        inv = 1.0 / B[j, j]
        for c in range(n):
            B[j, c] *= inv
        for r in range(n):
            if r != j:
                f = B[r, j]
                if f != 0.0:
                    for c in range(n):
                        B[r, c] -= f * B[j, c]
    # rows 0..d-1, columns 0..d-1 of B now hold K_pp - K_pt K_tt^-1 K_tp
    for r in range(d):
        for c in range(r, d):
            v = 0.5 * (B[r, c] + B[c, r])
            S[r, c] = v
            S[c, r] = v
    lo = min_eig_sym(S, d)
    # lowest frequency: the least eigenvalue of Linv Ks Linv^T
    for r in range(n):
        for c in range(n):
            acc = 0.0
            for k in range(n):
                acc += Linv[r, k] * 0.5 * (K[sel[k], sel[c]] + K[sel[c], sel[k]])
            B[r, c] = acc
    for r in range(n):
        for c in range(r, n):
            acc = 0.0
            for k in range(n):
                acc += B[r, k] * Linv[c, k]
            S[r, c] = acc
            S[c, r] = acc
    w2 = min_eig_sym(S, n)
    f = math.sqrt(w2) / (2.0 * math.pi) if w2 >= 0.0 else np.nan
    return lo, f


@njit_noref
def _stiffness_loop(k0, k1, P, Rb, A, T, EA, Kg, Linv, sel, d, kmin, flow, K, S, B):
    for k in range(k0, k1):
        if full_stiffness(P[k, 0], P[k, 1], P[k, 2], Rb, A, T[k], EA, Kg, K):
            kmin[k], flow[k] = pose_figures(K, sel, d, Linv, S, B)
        else:
            kmin[k] = np.nan
            flow[k] = np.nan


def _stiffness_block(k0, k1, P, Rb, A, T, EA, Kg, Linv, sel, d, kmin, flow):
    """Rows k0..k1-1 of :func:`stiffness_points`: the block's scratch, then the compiled loop."""
    _stiffness_loop(k0, k1, P, Rb, A, T, EA, Kg, Linv, sel, d, kmin, flow,
                    np.empty((6, 6)), np.empty((6, 6)), np.empty((6, 6)))


def stiffness_points(P, Rb, A, T, EA, Kg, Linv, sel, d, kmin, flow):
    """Least stiffness [N/m] and lowest natural frequency [Hz] at ``k`` poses (module notes).

    Parameters: ``P`` (k, 3) positions [m]; ``Rb`` (m, 3) rotated attachments R b_i [m] (one
    orientation for every pose); ``A`` (m, 3) outlets [m]; ``T`` (k, m) tensions [N]; ``EA`` (m,)
    [N]; ``Kg`` (3, 3) the weight's rotational stiffness -[m g]x [R c]x [N m]; ``Linv`` (n, n)
    the inverse of the mass matrix's Cholesky factor; ``sel`` (n,) int64 the motion's coordinates
    in [x, y, z, rx, ry, rz], the first ``d`` of them translations.  Writes ``kmin`` and ``flow``
    (k,).
    """
    run_blocks(_stiffness_block, P.shape[0], P, Rb, A, T, EA, Kg, Linv, sel, d, kmin, flow)
