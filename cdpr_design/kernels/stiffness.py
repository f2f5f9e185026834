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

The least eigenvalues come from :func:`min_eig_sym` (closed form up to 2x2, Householder and
Newton's method beyond), with no allocation per pose; a 2T robot's 2x2 K_pp is summed in scalars
(:func:`planar_figures`, the same numbers).  In a sweep the kernel counts the grid's indices as
the sweep's kernels do (no positions) and skips the poses the sweep found infeasible.  A pose
whose tensions are not all finite gives NaN.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import njit, njit_inline
from cdpr_design.kernels.geometry import grid_index, next_grid_index
from cdpr_design.kernels.parallel import run_blocks

#: The least eigenvalue's Newton steps stop below this fraction of the matrix's Gershgorin norm
EIG_TOL = 1e-15
#: ... or after this many (a double root halves the distance per step: 1e-15 after 50)
NEWTON_STEPS = 80


@njit_inline
def min_eig_2(a00, a01, a11):
    """The least eigenvalue of the symmetric [[a00, a01], [a01, a11]], in closed form."""
    h = 0.5 * (a00 - a11)
    return 0.5 * (a00 + a11) - math.sqrt(h * h + a01 * a01)


@njit_inline
def frequency(w2):
    """The frequency [Hz] sqrt(w2) / (2 pi) of an eigenvalue ``w2`` = omega^2 [1/s^2]; NaN below 0
    (an unstable mode)."""
    return math.sqrt(w2) / (2.0 * math.pi) if w2 >= 0.0 else np.nan


@njit_inline
def min_eig_sym(a, n, d, e2):
    """The least eigenvalue of the symmetric ``a[:n, :n]`` (destroyed); ``d``, ``e2`` (>= n,) scratch.

    n <= 2 in closed form; beyond, Householder reflections to a tridiagonal matrix T (diagonal ``d``,
    squared off-diagonal ``e2``), then Newton's method on det(T - x I) (three-term recurrence) from
    Gershgorin's lower bound, to a step of EIG_TOL times the matrix's Gershgorin norm.
    """
    if n == 1:
        return a[0, 0]
    if n == 2:
        return min_eig_2(a[0, 0], a[0, 1], a[1, 1])
    for k in range(n - 2):
        s = 0.0
        for i in range(k + 1, n):
            s += a[i, k] * a[i, k]
        x0 = a[k + 1, k]
        alpha = -math.sqrt(s) if x0 >= 0.0 else math.sqrt(s)
        v0 = x0 - alpha  # v = x - alpha e_1, kept in a[k+1:, k]
        beta = s - x0 * x0 + v0 * v0  # |v|^2
        if beta > 0.0:
            a[k + 1, k] = v0
            vp = 0.0
            for i in range(k + 1, n):  # p = 2 A22 v / |v|^2, in d
                acc = 0.0
                for j in range(k + 1, n):
                    acc += a[i, j] * a[j, k]
                acc *= 2.0 / beta
                d[i] = acc
                vp += a[i, k] * acc
            c = vp / beta
            for i in range(k + 1, n):  # q = p - (v.p / |v|^2) v
                d[i] -= c * a[i, k]
            for i in range(k + 1, n):  # A22 <- A22 - v q^T - q v^T
                for j in range(k + 1, n):
                    a[i, j] -= a[i, k] * d[j] + d[i] * a[j, k]
        e2[k] = alpha * alpha
    e2[n - 2] = a[n - 1, n - 2] * a[n - 1, n - 2]
    for i in range(n):
        d[i] = a[i, i]
    # Newton on det(T - x I) from Gershgorin's lower bound: left of every root of a polynomial whose
    # roots are all real, the steps increase x and never pass the least root (quadratic convergence
    # at a simple root, halving the distance at a double one)
    x = d[0]
    scale = 0.0
    for i in range(n):
        r = 0.0
        if i > 0:
            r += math.sqrt(e2[i - 1])
        if i < n - 1:
            r += math.sqrt(e2[i])
        x = min(x, d[i] - r)
        scale = max(scale, abs(d[i]) + r)
    for _ in range(NEWTON_STEPS):
        p0, p1, q0, q1 = 1.0, d[0] - x, 0.0, -1.0
        for i in range(1, n):
            p2 = (d[i] - x) * p1 - e2[i - 1] * p0
            q2 = -p1 + (d[i] - x) * q1 - e2[i - 1] * q0
            p0, p1, q0, q1 = p1, p2, q1, q2
        if p1 == 0.0 or q1 == 0.0:
            break
        step = -p1 / q1
        if not step > EIG_TOL * scale:
            break
        x += step
    return x


@njit_inline
def full_stiffness(px, py, pz, Rb, A, t, EA, Kg, rot, K):
    """Write the 6x6 stiffness matrix K = -dw/dx (module notes) of one pose into ``K`` (its
    translational block K_pp alone unless ``rot``).

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
        K[0, 0] += h00
        K[0, 1] += h01
        K[0, 2] += h02
        K[1, 0] += h01
        K[1, 1] += h11
        K[1, 2] += h12
        K[2, 0] += h02
        K[2, 1] += h12
        K[2, 2] += h22
        if not rot:
            continue
        # C = H [r]x, [r]x = [[0, -rz, ry], [rz, 0, -rx], [-ry, rx, 0]]
        c00, c01, c02 = h01 * rz - h02 * ry, -h00 * rz + h02 * rx, h00 * ry - h01 * rx
        c10, c11, c12 = h11 * rz - h12 * ry, -h01 * rz + h12 * rx, h01 * ry - h11 * rx
        c20, c21, c22 = h12 * rz - h22 * ry, -h02 * rz + h22 * rx, h02 * ry - h12 * rx
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
def pose_figures(K, sel, d, Linv, S, B, v1, v2):
    """(min_stiffness [N/m], lowest_frequency [Hz]) of the full 6x6 ``K`` restricted to ``sel`` (its
    first ``d`` entries the translations, the rest rotations); ``S``, ``B`` (6, 6) and ``v1``,
    ``v2`` (6,) scratch.

    The matrix is symmetrised first.  The Schur complement eliminates the rotations by
    Gauss-Jordan steps with partial pivoting (NaN when K_rr is singular).  Without rotations
    M = m I: the lowest frequency is sqrt(min_stiffness / m) / (2 pi).
    """
    n = sel.shape[0]
    for r in range(n):
        for c in range(n):
            B[r, c] = 0.5 * (K[sel[r], sel[c]] + K[sel[c], sel[r]])
    # B[:d, :d] <- K_pp - K_pr K_rr^-1 K_rp: eliminate the columns d..n-1 with pivots in rows d..n-1
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
    for r in range(d):
        for c in range(r, d):
            v = 0.5 * (B[r, c] + B[c, r])
            S[r, c] = v
            S[c, r] = v
    lo = min_eig_sym(S, d, v1, v2)
    if n == d:
        w2 = lo * Linv[0, 0] * Linv[0, 0]
    else:
        # the least eigenvalue of Linv Ks Linv^T
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
        w2 = min_eig_sym(S, n, v1, v2)
    return lo, frequency(w2)


@njit_inline
def planar_figures(px, py, pz, A, Rb, t, EA, Linv):
    """(min_stiffness [N/m], lowest_frequency [Hz]) of a 2T robot at position (px, py, pz) [m]:
    :func:`full_stiffness` then :func:`pose_figures` with ``sel`` = (0, 1), to the bit, with the
    2 x 2 K_pp summed in scalars (pose_figures' symmetrisations 0.5 (x + x) of this symmetric
    block give x back exactly, short of an overflow, and are left out).  (NaN, NaN) where
    full_stiffness is False (a tension that is not finite, a cable of zero length).
    """
    k00 = k01 = k11 = 0.0
    for i in range(A.shape[0]):
        ti = t[i]
        if not math.isfinite(ti):
            return np.nan, np.nan
        lx, ly, lz = A[i, 0] - px - Rb[i, 0], A[i, 1] - py - Rb[i, 1], A[i, 2] - pz - Rb[i, 2]
        L = math.sqrt(lx * lx + ly * ly + lz * lz)
        if not L > 0.0:
            return np.nan, np.nan
        u0, u1 = lx / L, ly / L
        g = ti / L
        e = (EA[i] + ti) / L - g
        k00 += e * u0 * u0 + g
        k01 += e * u0 * u1
        k11 += e * u1 * u1 + g
    lo = min_eig_2(k00, k01, k11)
    return lo, frequency(lo * Linv[0, 0] * Linv[0, 0])


#: The poses of :func:`stiffness_rows`: with ``P`` (0, 3), the grid poses ``start .. start + k - 1`` of
#: the grid ``lower``, ``step`` (3,) [m], ``shape`` (3,) int64 (C order over x, y, z, as the sweep
#: kernels count them); else ``P`` (k, 3) the positions [m].
Poses = namedtuple("Poses", "start lower step shape P")
#: The robot's arrays of :func:`stiffness_rows`: ``Rb`` (m, 3) rotated attachments R b_i [m] (one
#: orientation for every pose); ``A`` (m, 3) outlets [m]; ``EA`` (m,) [N]; ``Kg`` (3, 3) the weight's
#: rotational stiffness -[m g]x [R c]x [N m]; ``Linv`` (n, n) the inverse of the mass matrix's
#: Cholesky factor; ``sel`` (n,) int64 the motion's coordinates in [x, y, z, rx, ry, rz], the first
#: ``d`` of them translations (0 .. d-1).
Arrays = namedtuple("Arrays", "Rb A EA Kg Linv sel d")
#: A block's work arrays: the stiffness K, S and B (6, 6) and two 6-vectors.
_Work = namedtuple("_Work", "K S B v1 v2")


@njit
def _stiffness_loop(k0, k1, poses, feasible, T, ar, kmin, flow, work):
    start, lower, step, shape, P = poses
    Rb, A, EA, Kg, Linv, sel, d = ar
    K, S, B, v1, v2 = work
    grid = P.shape[0] == 0
    rot = sel.shape[0] > d
    planar = d == 2 and not rot
    ny = shape[1]
    nz = shape[2]
    ix, iy, iz = grid_index(start + k0, ny, nz)
    for k in range(k0, k1):
        if grid:
            px = lower[0] + ix * step[0]
            py = lower[1] + iy * step[1]
            pz = lower[2] + iz * step[2]
            ix, iy, iz = next_grid_index(ix, iy, iz, ny, nz)
        else:
            px, py, pz = P[k, 0], P[k, 1], P[k, 2]
        if feasible[k] == 0:
            kmin[k] = np.nan
            flow[k] = np.nan
        elif planar:
            kmin[k], flow[k] = planar_figures(px, py, pz, A, Rb, T[k], EA, Linv)
        elif full_stiffness(px, py, pz, Rb, A, T[k], EA, Kg, rot, K):
            kmin[k], flow[k] = pose_figures(K, sel, d, Linv, S, B, v1, v2)
        else:
            kmin[k] = np.nan
            flow[k] = np.nan


def _stiffness_block(k0, k1, *args):
    """Rows k0..k1-1 of :func:`stiffness_rows`: the block's work arrays, then the compiled loop."""
    _stiffness_loop(k0, k1, *args, _Work(np.empty((6, 6)), np.empty((6, 6)), np.empty((6, 6)), np.empty(6),
                                         np.empty(6)))


def stiffness_rows(poses, feasible, T, arrays, kmin, flow):
    """Least stiffness [N/m] and lowest natural frequency [Hz] at ``k`` poses (module notes).

    The poses :class:`Poses`; ``feasible`` (k,) uint8: rows where it is 0 get NaN; ``T`` (k, m)
    tensions [N]; the robot's :class:`Arrays`.  Writes ``kmin`` and ``flow`` (k,).
    """
    run_blocks(_stiffness_block, kmin.shape[0], poses, feasible, T, arrays, kmin, flow)
