"""Stiffness and lowest natural frequency of the effector at many poses, and one pose's matrices.

The one implementation of the effector's stiffness (docs/algorithms.md, "Stiffness and
vibration"; :mod:`cdpr_design.statics.stiffness` calls it for a single pose and documents the
conventions).  Per pose, with r_i = R b_i and each cable's stiffness at its attachment
H_i = -dF_i/db_i (3 x 3, symmetric) and its force F_i on the effector:

    K_pp = sum H_i                      K_pt = -sum H_i [r_i]x
    K_tp = sum [r_i]x H_i               K_tt = -sum ([r_i]x H_i [r_i]x + [F_i]x [r_i]x) + Kg

with Kg = -[m g]x [R c]x the weight's term (constant at a fixed orientation), at fixed unstretched
lengths (:func:`cable_term`):

- a straight elastic cable, l_i = a_i - (p + r_i), L_i = |l_i|, u_i = l_i / L_i, tension t_i and
  k_i = EA_i / L0_i = (EA_i + t_i) / L_i:  H_i = k_i u_i u_i^T + (t_i / L_i)(I - u_i u_i^T),
  F_i = t_i u_i;
- a sagging cable (Irvine's elastic catenary, :mod:`cdpr_design.kernels.catenary`) in its vertical
  plane (span X along the horizontal unit vector h_i, height Z along ``up``), end forces (H, VB)
  from its unstretched length: the in-plane stiffness k = (d(X, Z)/d(H, VB))^-1 (the inverse of
  the flexibility matrix) in the plane's axes, and H / X across it (the lateral string term),

      H_i = [h up] k [h up]^T + (H / X)(I - h h^T - up up^T),     F_i = H h + VB up.

The matrix is restricted to the motion's coordinates ``sel``, symmetrised (it is symmetric at an
equilibrium) and then

- ``min_stiffness`` [N/m]: the least eigenvalue of the translational Schur complement
  K_pp - K_pt K_tt^-1 K_tp (of K_pp itself when the motion has no rotation);
- ``lowest_frequency`` [Hz]: sqrt(lambda_min(L^-1 K L^-T)) / (2 pi) for the mass matrix
  M = L L^T, NaN when lambda_min < 0 (an unstable equilibrium).  M is the effector's, plus a
  third of each sagging cable's mass as a point mass at its attachment (:func:`lumped_mass_matrix`),
  factored per pose (:func:`inverse_cholesky`); without sagging cables it is constant (``Linv``).

The least eigenvalues come from :func:`min_eig_sym` (closed form up to 2x2, Householder and
Newton's method beyond), with no allocation per pose; a 2T robot's 2x2 K_pp on straight cables is
summed in scalars (:func:`planar_figures`, the same numbers).  In a sweep the kernel counts the
grid's indices as the sweep's kernels do (no positions) and skips the poses the sweep found
infeasible.  A pose whose tensions (straight cables) or unstretched lengths (sagging ones) are
not all finite gives NaN.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import njit, njit_inline
from cdpr_design.kernels.catenary import closure_jac
from cdpr_design.kernels.catenary_inv import CAT_CONVERGED, catenary_inverse
from cdpr_design.kernels.geometry import cable_vector, grid_index, next_grid_index
from cdpr_design.kernels.parallel import run_blocks

#: The least eigenvalue's Newton steps stop below this fraction of the matrix's Gershgorin norm
EIG_TOL = 1e-15
#: ... or after this many (a double root halves the distance per step: 1e-15 after 50)
NEWTON_STEPS = 80
#: A sagging cable's end forces from its unstretched length: the catenary inverse's relative
#: force tolerance and its iterations allowed
CATENARY_TOL = 1e-12
CATENARY_STEPS = 100


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
def cable_term(i, px, py, pz, Rb, A, ti, L0i, EA, w, up):
    """Cable i's stiffness at its attachment and its force on the effector at position (px, py,
    pz) [m]: (ok, h00, h01, h02, h11, h12, h22, f0, f1, f2), H_i = -dF_i/db_i (3x3 symmetric)
    [N/m] and F_i [N] (module notes).

    A straight cable (``w[i]`` = 0) from its tension ``ti`` [N]; a sagging one (``w[i]`` > 0
    [N/m]) from its unstretched length ``L0i`` [m]: its end forces by
    :func:`~cdpr_design.kernels.catenary_inv.catenary_inverse` (started from ``ti`` where it is
    finite), its in-plane stiffness the inverse of the flexibility
    :func:`~cdpr_design.kernels.catenary.closure_jac`, H / X across the plane.  ``ok`` False
    (and NaN) for a zero-length cable, a tension or length that is not finite, or a catenary
    that did not converge.
    """
    nan = math.nan
    lx, ly, lz, L = cable_vector(A, Rb, i, px, py, pz)
    if not L > 0.0:
        return False, nan, nan, nan, nan, nan, nan, nan, nan, nan
    wi = w[i]
    if wi == 0.0:
        if not math.isfinite(ti):
            return False, nan, nan, nan, nan, nan, nan, nan, nan, nan
        u0, u1, u2 = lx / L, ly / L, lz / L
        g = ti / L
        e = (EA[i] + ti) / L - g  # k_i - t_i / L_i; H = e u u^T + g I
        return (True, e * u0 * u0 + g, e * u0 * u1, e * u0 * u2, e * u1 * u1 + g, e * u1 * u2, e * u2 * u2 + g,
                ti * u0, ti * u1, ti * u2)
    # the cable's vertical plane: height Z along up, span X along the horizontal unit vector h
    z0, z1, z2 = up[0], up[1], up[2]
    Z = lx * z0 + ly * z1 + lz * z2
    hx, hy, hz = lx - Z * z0, ly - Z * z1, lz - Z * z2
    X = math.sqrt(hx * hx + hy * hy + hz * hz)
    if X > 1e-14 * L:
        hx, hy, hz = hx / X, hy / X, hz / X
    else:
        X, hx, hy, hz = 0.0, 0.0, 0.0, 0.0
    if math.isfinite(ti) and ti > 0.0:  # the chord's direction, lowered by half the cable's weight
        H0, VB0 = ti * X / L, ti * Z / L - 0.5 * wi * L0i
    else:
        H0, VB0 = nan, nan
    H, VB, status, _ = catenary_inverse(X, Z, L0i, wi, EA[i], H0, VB0, CATENARY_TOL, CATENARY_STEPS)
    if status != CAT_CONVERGED:
        return False, nan, nan, nan, nan, nan, nan, nan, nan, nan
    _, _, j11, j12, _, j22 = closure_jac(H, VB, L0i, wi, EA[i])
    if math.isinf(j11):  # folded vertical cable: no horizontal stiffness
        k11, k12, k22 = 0.0, 0.0, 1.0 / j22
    else:
        det = j11 * j22 - j12 * j12
        k11, k12, k22 = j22 / det, -j12 / det, j11 / det
    # across the plane H / X; a vertical cable (X = 0, H = 0): the limit, k11, in every horizontal direction
    lat = H / X if X > 0.0 else k11
    # H_i = k11 h h^T + k12 (h up^T + up h^T) + k22 up up^T + lat (I - h h^T - up up^T)
    a, b, c = k11 - lat, k22 - lat, k12
    h00 = a * hx * hx + 2.0 * c * hx * z0 + b * z0 * z0 + lat
    h01 = a * hx * hy + c * (hx * z1 + z0 * hy) + b * z0 * z1
    h02 = a * hx * hz + c * (hx * z2 + z0 * hz) + b * z0 * z2
    h11 = a * hy * hy + 2.0 * c * hy * z1 + b * z1 * z1 + lat
    h12 = a * hy * hz + c * (hy * z2 + z1 * hz) + b * z1 * z2
    h22 = a * hz * hz + 2.0 * c * hz * z2 + b * z2 * z2 + lat
    return True, h00, h01, h02, h11, h12, h22, H * hx + VB * z0, H * hy + VB * z1, H * hz + VB * z2


@njit_inline
def full_stiffness(px, py, pz, t, L0, ar, rot, K):
    """Write the 6x6 stiffness matrix K = -dw/dx (module notes) of one pose into ``K`` (its
    translational block K_pp alone unless ``rot``): the effector at (px, py, pz) [m], the cables'
    effector-end tensions ``t`` (m,) [N] and unstretched lengths ``L0`` (m,) [m] (read for the
    sagging cables only), the robot's :data:`Arrays` ``ar``.

    Returns False when a cable has zero length, a tension or length that is not finite, or a
    catenary that did not converge (:func:`cable_term`).
    """
    Rb, A, EA, Kg, w, up = ar.Rb, ar.A, ar.EA, ar.Kg, ar.w, ar.up
    for r in range(6):
        for c in range(6):
            K[r, c] = 0.0
    for r in range(3):
        for c in range(3):
            K[3 + r, 3 + c] = Kg[r, c]
    for i in range(A.shape[0]):
        ok, h00, h01, h02, h11, h12, h22, f0, f1, f2 = cable_term(i, px, py, pz, Rb, A, t[i], L0[i], EA, w, up)
        if not ok:
            return False
        rx, ry, rz = Rb[i, 0], Rb[i, 1], Rb[i, 2]
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
        # -[F]x [r]x = -(r F^T - (F . r) I)
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
def lumped_mass_matrix(L0, ar, M):
    """Write the 6x6 mass matrix [kg, kg m, kg m^2] of the effector with its cables' lumped
    masses into ``M``: ``ar.M0`` (the effector's, at the reference point) plus, per cable, a
    point mass ``ar.lump[i]`` L0_i (a third of the cable's mass, ``lump`` = mu / 3 [kg/m]) at
    its attachment r_i = ``ar.Rb[i]``: [[m I, -m [r]x], [m [r]x, m (|r|^2 I - r r^T)]].
    Returns False when a lumped cable's ``L0`` (m,) [m] is not finite."""
    Rb, M0, lump = ar.Rb, ar.M0, ar.lump
    for r in range(6):
        for c in range(6):
            M[r, c] = M0[r, c]
    for i in range(Rb.shape[0]):
        if lump[i] == 0.0:
            continue
        mc = lump[i] * L0[i]
        if not math.isfinite(mc):
            return False
        rx, ry, rz = Rb[i, 0], Rb[i, 1], Rb[i, 2]
        rr = rx * rx + ry * ry + rz * rz
        for k in range(3):
            M[k, k] += mc
            M[3 + k, 3 + k] += mc * rr
        r = (rx, ry, rz)
        for a in range(3):
            for b in range(3):
                M[3 + a, 3 + b] -= mc * r[a] * r[b]
        # m [r]x below the diagonal, -m [r]x above
        M[3, 1] -= mc * rz
        M[3, 2] += mc * ry
        M[4, 0] += mc * rz
        M[4, 2] -= mc * rx
        M[5, 0] -= mc * ry
        M[5, 1] += mc * rx
        M[1, 3] -= mc * rz
        M[2, 3] += mc * ry
        M[0, 4] += mc * rz
        M[2, 4] -= mc * rx
        M[0, 5] -= mc * ry
        M[1, 5] += mc * rx
    return True


@njit_inline
def inverse_cholesky(M, sel, F, Li):
    """Write L^-1 into ``Li`` (n, n) for M[sel][:, sel] = L L^T (L lower triangular, in ``F``
    (>= n, >= n) scratch); ``sel`` (n,) the motion's coordinates.  Returns False when that
    matrix is not positive definite."""
    n = sel.shape[0]
    for r in range(n):
        for c in range(r + 1):
            acc = M[sel[r], sel[c]]
            for k in range(c):
                acc -= F[r, k] * F[c, k]
            if r == c:
                if not acc > 0.0:
                    return False
                F[r, r] = math.sqrt(acc)
            else:
                F[r, c] = acc / F[c, c]
    for c in range(n):  # forward substitution L X = I, column by column
        for r in range(n):
            if r < c:
                Li[r, c] = 0.0
                continue
            acc = 1.0 if r == c else 0.0
            for k in range(c, r):
                acc -= F[r, k] * Li[k, c]
            Li[r, c] = acc / F[r, r]
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
        lx, ly, lz, L = cable_vector(A, Rb, i, px, py, pz)
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
#: rotational stiffness -[m g]x [R c]x [N m]; ``Linv`` (n, n) the inverse of the Cholesky factor of
#: the restricted mass matrix M0[sel][:, sel] (used where no cable's mass is lumped); ``sel`` (n,)
#: int64 the motion's coordinates in [x, y, z, rx, ry, rz], the first ``d`` of them translations
#: (0 .. d-1); ``w`` (m,) weight per unstretched length [N/m], 0 for a straight cable (its stiffness
#: from its tension), > 0 for a sagging one (from its unstretched length: an elastic catenary);
#: ``up`` (3,) the unit vector against gravity; ``M0`` (6, 6) the effector's mass matrix at the
#: reference point [kg, kg m, kg m^2]; ``lump`` (m,) [kg/m] the mass per unstretched length lumped
#: at each attachment (a third of a sagging cable's, 0 for a massless one).
Arrays = namedtuple("Arrays", "Rb A EA Kg Linv sel d w up M0 lump")
#: A block's work arrays: the stiffness K, S, B, the mass matrix M, the factor F and the
#: inverse factor Li (6, 6), and two 6-vectors.
_Work = namedtuple("_Work", "K S B M F Li v1 v2")


def make_work():
    """A :data:`_Work` of fresh arrays."""
    e = np.empty
    return _Work(e((6, 6)), e((6, 6)), e((6, 6)), e((6, 6)), e((6, 6)), e((6, 6)), e(6), e(6))


@njit_inline
def any_nonzero(a):
    """Whether any entry of ``a`` is not 0 (``lump``: the mass matrix changes per pose; ``w``: a
    cable sags)."""
    for i in range(a.shape[0]):
        if a[i] != 0.0:
            return True
    return False


@njit_inline
def figures_at(px, py, pz, t, L0, ar, rot, lumped, work):
    """(min_stiffness [N/m], lowest_frequency [Hz]) of one pose (:func:`full_stiffness`,
    :func:`lumped_mass_matrix` where ``lumped``, :func:`pose_figures`); NaN where K or M is undefined."""
    if not full_stiffness(px, py, pz, t, L0, ar, rot, work.K):
        return np.nan, np.nan
    Linv = ar.Linv
    if lumped:
        if not (lumped_mass_matrix(L0, ar, work.M) and inverse_cholesky(work.M, ar.sel, work.F, work.Li)):
            return np.nan, np.nan
        Linv = work.Li
    return pose_figures(work.K, ar.sel, ar.d, Linv, work.S, work.B, work.v1, work.v2)


@njit
def _stiffness_loop(k0, k1, poses, feasible, T, L0, ar, kmin, flow, work):
    start, lower, step, shape, P = poses
    grid = P.shape[0] == 0
    rot = ar.sel.shape[0] > ar.d
    lumped = any_nonzero(ar.lump)
    planar = ar.d == 2 and not rot and not lumped and not any_nonzero(ar.w)
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
            kmin[k], flow[k] = planar_figures(px, py, pz, ar.A, ar.Rb, T[k], ar.EA, ar.Linv)
        else:
            kmin[k], flow[k] = figures_at(px, py, pz, T[k], L0[k], ar, rot, lumped, work)


def _stiffness_block(k0, k1, *args):
    """Rows k0..k1-1 of :func:`stiffness_rows`: the block's work arrays, then the compiled loop."""
    _stiffness_loop(k0, k1, *args, make_work())


def stiffness_rows(poses, feasible, T, L0, arrays, kmin, flow):
    """Least stiffness [N/m] and lowest natural frequency [Hz] at ``k`` poses (module notes).

    The poses :class:`Poses`; ``feasible`` (k,) uint8: rows where it is 0 get NaN; ``T`` (k, m)
    effector-end tensions [N]; ``L0`` (k, m) unstretched lengths [m] (read for the sagging cables,
    ``arrays.w`` > 0, only); the robot's :class:`Arrays`.  Writes ``kmin`` and ``flow`` (k,).
    """
    run_blocks(_stiffness_block, kmin.shape[0], poses, feasible, T, L0, arrays, kmin, flow)


@njit
def pose_matrices(px, py, pz, t, L0, ar, K, M):
    """One pose's full 6x6 stiffness ``K`` = -dw/dx (:func:`full_stiffness`, with rotations) and
    mass matrix ``M`` (:func:`lumped_mass_matrix`) written in place, at (px, py, pz) [m] with tensions
    ``t`` (m,) [N] and unstretched lengths ``L0`` (m,) [m].  Returns False where either is undefined."""
    return full_stiffness(px, py, pz, t, L0, ar, True, K) and lumped_mass_matrix(L0, ar, M)


@njit
def least_stiffness(K, sel, d):
    """:func:`pose_figures`' least stiffness [N/m] of the full 6x6 ``K`` restricted to ``sel`` (its
    first ``d`` entries translations): the least eigenvalue of the translational Schur complement's
    symmetric part (NaN where the rotational block is singular)."""
    S, B, v1, v2 = np.empty((6, 6)), np.empty((6, 6)), np.empty(6), np.empty(6)
    Linv = np.eye(6)
    return pose_figures(K, sel, d, Linv, S, B, v1, v2)[0]
