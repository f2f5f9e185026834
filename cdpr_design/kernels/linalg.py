"""Small dense linear algebra for the kernels: determinants, inverses, Householder QR."""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit, njit_folded, njit_inline


#: Relative tolerance below which a facet normal or a pivot counts as zero.
RANK_TOL = 1e-10

#: Relative tolerance of the wrench-closure sign test (|l_j| against |w_j|).
CLOSURE_TOL = 1e-12


@njit_inline
def orthogonalize_column(A, k, rows):
    """Column ``k`` of ``A`` made orthogonal, over its first ``rows`` entries, to columns 0..k-1
    (orthonormal) by classical Gram-Schmidt, applied twice (the second pass restores the
    orthogonality the first loses to rounding); returns the column's Euclidean norm after it
    (the column is not normalised)."""
    for _ in range(2):
        for p in range(k):
            d = 0.0
            for i in range(rows):
                d += A[i, p] * A[i, k]
            for i in range(rows):
                A[i, k] -= d * A[i, p]
    s = 0.0
    for i in range(rows):
        s += A[i, k] * A[i, k]
    return math.sqrt(s)


@njit
def gram_of_inverse(tab, n, m, M):
    """M = G G^T (n x n) of the basis inverse G held in columns ``m..m+n-1`` of the
    factored tableau ``tab`` (:func:`cdpr_design.kernels.hsm.basis_factor`): the metric
    of facet normals nu = G^T mu, ||nu||^2 = mu^T M mu [1/N^2]."""
    for i in range(n):
        for j in range(i, n):
            s = 0.0
            for k in range(n):
                s += tab[i, m + k] * tab[j, m + k]
            M[i, j] = s
            M[j, i] = s


@njit
def det_small(M, k):
    """Determinant of the leading k x k block of ``M`` (copied, then :func:`det_in_place`)."""
    a = np.empty((k, k))
    for i in range(k):
        for j in range(k):
            a[i, j] = M[i, j]
    return det_in_place(a, k)


@njit_folded
def pivot_rows(a, c, k, width):
    """Partial pivoting in column ``c`` of the leading ``k`` rows of ``a``: the row r >= c with the
    largest |a[r, c]| (the first of equals) swapped with row c over the first ``width`` columns.
    Returns (that largest |a[r, c]|, whether rows were swapped)."""
    piv = c
    best = abs(a[c, c])
    for r in range(c + 1, k):
        if abs(a[r, c]) > best:
            best = abs(a[r, c])
            piv = r
    if piv != c:
        for j in range(width):
            tmp = a[c, j]
            a[c, j] = a[piv, j]
            a[piv, j] = tmp
    return best, piv != c


@njit
def det_in_place(a, k):
    """Determinant of the leading k x k block of ``a``, which it overwrites (partial pivoting;
    allocates nothing)."""
    d = 1.0
    for c in range(k):
        best, swapped = pivot_rows(a, c, k, k)
        if best == 0.0:
            return 0.0
        if swapped:
            d = -d
        d *= a[c, c]
        for r in range(c + 1, k):
            f = a[r, c] / a[c, c]
            for j in range(c + 1, k):
                a[r, j] -= f * a[c, j]
    return d


@njit_folded
def inverse_into(W, Winv, a):
    """Invert the square ``W`` (n, n) into ``Winv`` by Gauss-Jordan with pivoting, in the work
    array ``a`` (n, >= 2n) (allocates nothing).  Returns False when W is singular to working
    precision (relative pivot below ``RANK_TOL``)."""
    n = W.shape[0]
    scale = 0.0
    for i in range(n):
        for j in range(n):
            a[i, j] = W[i, j]
            a[i, n + j] = 1.0 if i == j else 0.0
            if abs(W[i, j]) > scale:
                scale = abs(W[i, j])
    if scale == 0.0:
        return False
    for c in range(n):
        best, _ = pivot_rows(a, c, n, 2 * n)
        if best <= RANK_TOL * scale:
            return False
        inv = 1.0 / a[c, c]
        for j in range(2 * n):
            a[c, j] *= inv
        for r in range(n):
            if r != c and a[r, c] != 0.0:
                f = a[r, c]
                for j in range(2 * n):
                    a[r, j] -= f * a[c, j]
    for i in range(n):
        for j in range(n):
            Winv[i, j] = a[i, n + j]
    return True


@njit
def householder_qr(A, p, q, Q, R, V):
    """Full QR of the leading (p, q) block of ``A`` (p >= q): A = Q [R; 0].

    ``A`` is overwritten; ``Q`` (p, p) orthogonal, ``R`` (q, q) upper
    triangular, ``V`` (p, q) scratch for the reflectors.  Returns the
    smallest |R_ii| (inf for q = 0).
    """
    rmin = np.inf
    for c in range(q):
        s = 0.0
        for i in range(c, p):
            s += A[i, c] * A[i, c]
        nx = math.sqrt(s)
        alpha = -nx if A[c, c] >= 0.0 else nx
        for i in range(c, p):
            V[i, c] = A[i, c]
        V[c, c] -= alpha
        vn = 0.0
        for i in range(c, p):
            vn += V[i, c] * V[i, c]
        if vn > 0.0:
            vn = math.sqrt(vn)
            for i in range(c, p):
                V[i, c] /= vn
            for j in range(c, q):
                d = 0.0
                for i in range(c, p):
                    d += V[i, c] * A[i, j]
                for i in range(c, p):
                    A[i, j] -= 2.0 * V[i, c] * d
        for i in range(c + 1, p):
            A[i, c] = 0.0
        if abs(A[c, c]) < rmin:
            rmin = abs(A[c, c])
    for i in range(q):
        for j in range(q):
            R[i, j] = A[i, j] if j >= i else 0.0
    for i in range(p):
        for j in range(p):
            Q[i, j] = 1.0 if i == j else 0.0
    for c in range(q - 1, -1, -1):
        for j in range(p):
            d = 0.0
            for i in range(c, p):
                d += V[i, c] * Q[i, j]
            if d != 0.0:
                for i in range(c, p):
                    Q[i, j] -= 2.0 * V[i, c] * d
    return rmin
