"""The hanging orientation of a planar body on two taut cables, one position at a time, in numba.

The reference of the product's closed form (:mod:`cdpr_design.statics.hanging.planar2`,
vectorised with numpy over many positions): the same method -- the moment residual
M(phi) a degree-2 trigonometric polynomial, its five coefficients from five samples, the
roots the unit-modulus eigenvalues of its companion matrix, polished by Newton's method,
the reduced-Hessian stability test of Carricato & Merlet (2013), of the stable roots with
tensions >= 0 the one closest to level -- written one position at a time in scalars, as a
compiled loop (fast enough for the tests' grids).  The product never imports it.

Status codes (:data:`TILT_OK` ...) say why a position has no orientation; the product's
(:mod:`cdpr_design.statics.hanging.results`) equal them (a test checks).

References
----------
M. Carricato, J.-P. Merlet, "Stability analysis of underconstrained
cable-driven parallel robots", IEEE Trans. Robotics 29(1), 288-296, 2013.
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: numba's documented options only: compiled on first use, cached on disk
njit = numba.njit(cache=True)

#: A stable equilibrium with both tensions >= 0 was found.
TILT_OK = 0
#: Moment-balanced orientations exist, but each needs a pushing (negative) cable.
TILT_PUSHING = 1
#: Balanced orientations with tensions >= 0 exist, but none is stable.
TILT_UNSTABLE = 2
#: No orientation balances the moment (with non-parallel cables).
TILT_NO_BALANCE = 3
#: Degenerate input: a zero-length cable, or every orientation balances.
TILT_DEGENERATE = 4

#: Human-readable reasons, indexed by status code.
TILT_REASONS = (
    "ok",
    "every moment-balanced orientation needs a pushing cable",
    "the moment-balanced orientations with pulling cables are unstable",
    "no orientation balances the moment with both cables taut",
    "degenerate geometry (zero-length cable or indifferent balance)",
)

_TWO_PI = 2.0 * math.pi


@njit
def _cr(ax, ay, bx, by):
    return ax * by - ay * bx


@njit
def _geometry(phi, A, B, c, px, py):
    """v_1, v_2 (cable vectors), Rb_1, Rb_2 and r_i = R (b_i - c) at phi."""
    co = math.cos(phi)
    si = math.sin(phi)
    rb1x = co * B[0, 0] - si * B[0, 1]
    rb1y = si * B[0, 0] + co * B[0, 1]
    rb2x = co * B[1, 0] - si * B[1, 1]
    rb2y = si * B[1, 0] + co * B[1, 1]
    rcx = co * c[0] - si * c[1]
    rcy = si * c[0] + co * c[1]
    v1x = A[0, 0] - px - rb1x
    v1y = A[0, 1] - py - rb1y
    v2x = A[1, 0] - px - rb2x
    v2y = A[1, 1] - py - rb2y
    return v1x, v1y, v2x, v2y, rb1x, rb1y, rb2x, rb2y, rcx, rcy


@njit
def moment_residual(phi, A, B, c, fx, fy, px, py):
    """M(phi) [N^2 m^3]: D times the moment about the COM of the cable forces
    that balance the weight (zero at a balanced orientation)."""
    v1x, v1y, v2x, v2y, rb1x, rb1y, rb2x, rb2y, rcx, rcy = _geometry(phi, A, B, c, px, py)
    m1 = _cr(rb1x - rcx, rb1y - rcy, v1x, v1y)
    m2 = _cr(rb2x - rcx, rb2y - rcy, v2x, v2y)
    return _cr(fx, fy, v2x, v2y) * m1 + _cr(v1x, v1y, fx, fy) * m2


@njit
def trig_coefficients(A, B, c, fx, fy, px, py, coef):
    """The degree-2 trigonometric polynomial M(phi) = a0 + a1 cos + b1 sin +
    a2 cos 2phi + b2 sin 2phi, from five samples; ``coef`` = [a0, a1, b1, a2, b2]."""
    for k in range(5):
        coef[k] = 0.0
    for k in range(5):
        t = _TWO_PI * k / 5.0
        mk = moment_residual(t, A, B, c, fx, fy, px, py)
        coef[0] += mk / 5.0
        coef[1] += 0.4 * mk * math.cos(t)
        coef[2] += 0.4 * mk * math.sin(t)
        coef[3] += 0.4 * mk * math.cos(2.0 * t)
        coef[4] += 0.4 * mk * math.sin(2.0 * t)


@njit
def _dtrig(phi, coef):
    return (-coef[1] * math.sin(phi) + coef[2] * math.cos(phi)
            - 2.0 * coef[3] * math.sin(2.0 * phi) + 2.0 * coef[4] * math.cos(2.0 * phi))


@njit
def trig_roots(coef, out):
    """Angles (in (-pi, pi]) of the roots z = e^{i phi} of z^2 M(z) near the
    unit circle, written to ``out`` (length >= 4); returns how many.

    z^2 M = c4 z^4 + c3 z^3 + a0 z^2 + c1 z + c0 with c4 = (a2 - i b2)/2,
    c3 = (a1 - i b1)/2, c1 = conj(c3), c0 = conj(c4); the roots are the
    eigenvalues of its companion matrix.  Leading coefficients that vanish
    (relative 1e-13) lower the degree.  Returns -1 when M vanishes identically.
    """
    scale = abs(coef[0]) + abs(coef[1]) + abs(coef[2]) + abs(coef[3]) + abs(coef[4])
    if scale == 0.0 or not np.isfinite(scale):
        return -1
    c4 = complex(0.5 * coef[3], -0.5 * coef[4])
    c3 = complex(0.5 * coef[1], -0.5 * coef[2])
    c2 = complex(coef[0], 0.0)
    c1 = complex(0.5 * coef[1], 0.5 * coef[2])
    c0 = complex(0.5 * coef[3], 0.5 * coef[4])
    tiny = 1e-13 * scale
    n = 0
    if abs(c4) > tiny:
        # quartic
        C = np.zeros((4, 4), dtype=np.complex128)
        C[0, 0] = -c3 / c4
        C[0, 1] = -c2 / c4
        C[0, 2] = -c1 / c4
        C[0, 3] = -c0 / c4
        for i in range(1, 4):
            C[i, i - 1] = 1.0
        z = np.linalg.eigvals(C)
    elif abs(c3) > tiny:
        # c4 = c0 = 0: z (c3 z^2 + c2 z + c1)
        C = np.zeros((2, 2), dtype=np.complex128)
        C[0, 0] = -c2 / c3
        C[0, 1] = -c1 / c3
        C[1, 0] = 1.0
        z = np.linalg.eigvals(C)
    else:
        return -1  # M is the constant a0: no root, or (a0 = 0) every phi
    for k in range(z.shape[0]):
        r = abs(z[k])
        if abs(r - 1.0) < 1e-3:
            out[n] = math.atan2(z[k].imag, z[k].real)
            n += 1
    return n


@njit
def polish_root(phi, A, B, c, fx, fy, px, py, coef):
    """Newton's method on M (derivative from the coefficients), at most 8 steps;
    returns (phi in (-pi, pi], |M(phi)|)."""
    for _ in range(8):
        f = moment_residual(phi, A, B, c, fx, fy, px, py)
        d = _dtrig(phi, coef)
        if d == 0.0:
            break
        step = f / d
        phi -= step
        if abs(step) < 1e-15:
            break
    phi = math.atan2(math.sin(phi), math.cos(phi))
    return phi, abs(moment_residual(phi, A, B, c, fx, fy, px, py))


@njit
def equilibrium_at(phi, A, B, c, mass, gx, gy, px, py):
    """Tensions and the reduced Hessian at a balanced orientation phi.

    Returns (t1, t2, h, ok): tensions [N] from force balance, h the second
    derivative of the Lagrangian along the unit tangent of the two length
    constraints in (x [m], y [m], phi [rad]) (> 0: stable), ok False when a
    cable has zero length or the cables are parallel.
    """
    fx = -mass * gx
    fy = -mass * gy
    v1x, v1y, v2x, v2y, rb1x, rb1y, rb2x, rb2y, rcx, rcy = _geometry(phi, A, B, c, px, py)
    L1 = math.hypot(v1x, v1y)
    L2 = math.hypot(v2x, v2y)
    D = _cr(v1x, v1y, v2x, v2y)
    if L1 <= 1e-12 or L2 <= 1e-12 or abs(D) <= 1e-12 * L1 * L2:
        return math.nan, math.nan, math.nan, False
    t1 = _cr(fx, fy, v2x, v2y) / D * L1
    t2 = _cr(v1x, v1y, fx, fy) / D * L2
    u1x, u1y = v1x / L1, v1y / L1
    u2x, u2y = v2x / L2, v2y / L2
    # constraint gradients G_i = (-u, -cr(Rb_i, u_i)) and the tangent N = G_1 x G_2
    g1 = (-u1x, -u1y, -_cr(rb1x, rb1y, u1x, u1y))
    g2 = (-u2x, -u2y, -_cr(rb2x, rb2y, u2x, u2y))
    nx = g1[1] * g2[2] - g1[2] * g2[1]
    ny = g1[2] * g2[0] - g1[0] * g2[2]
    nt = g1[0] * g2[1] - g1[1] * g2[0]
    nn = nx * nx + ny * ny + nt * nt
    # H = m g.(R c) e_phi e_phi^T + sum t_i (q_i q_i^T / L_i + (u_i . R b_i) e_phi e_phi^T),
    # q_i = (u_y, -u_x, -(R b_i . u_i))
    h = (mass * (gx * rcx + gy * rcy)) * nt * nt
    q1 = u1y * nx - u1x * ny - (rb1x * u1x + rb1y * u1y) * nt
    q2 = u2y * nx - u2x * ny - (rb2x * u2x + rb2y * u2y) * nt
    h += t1 * (q1 * q1 / L1 + (u1x * rb1x + u1y * rb1y) * nt * nt)
    h += t2 * (q2 * q2 / L2 + (u2x * rb2x + u2y * rb2y) * nt * nt)
    return t1, t2, h / nn, True


@njit
def hanging_tilt(A, B, c, mass, gx, gy, px, py, coef, roots):
    """The hanging orientation at one position (px, py).

    Returns (phi [rad], t1 [N], t2 [N], h, status, n_balanced): the stable
    equilibrium with tensions >= 0 closest to level, its reduced Hessian h,
    a TILT_* status and how many balanced orientations exist.  ``coef`` (5)
    and ``roots`` (4) are scratch.  phi, t, h are NaN unless status is TILT_OK.
    """
    fx = -mass * gx
    fy = -mass * gy
    trig_coefficients(A, B, c, fx, fy, px, py, coef)
    nr = trig_roots(coef, roots)
    if nr < 0:
        return math.nan, math.nan, math.nan, math.nan, TILT_DEGENERATE, 0
    scale = abs(coef[0]) + abs(coef[1]) + abs(coef[2]) + abs(coef[3]) + abs(coef[4])
    wscale = mass * math.hypot(gx, gy)
    best = math.inf
    bphi = math.nan
    bt1 = math.nan
    bt2 = math.nan
    bh = math.nan
    nbal = 0
    pulling = False
    for k in range(nr):
        phi, res = polish_root(roots[k], A, B, c, fx, fy, px, py, coef)
        if not res <= 1e-9 * scale:
            continue  # a complex pair near the circle (no real root)
        t1, t2, h, ok = equilibrium_at(phi, A, B, c, mass, gx, gy, px, py)
        if not ok:
            continue
        nbal += 1
        ttol = 1e-9 * wscale
        if t1 < -ttol or t2 < -ttol:
            continue
        pulling = True
        if not h > 1e-10 * wscale:
            continue
        if abs(phi) < best:
            best = abs(phi)
            bphi = phi
            bt1 = max(t1, 0.0)
            bt2 = max(t2, 0.0)
            bh = h
    if best < math.inf:
        return bphi, bt1, bt2, bh, TILT_OK, nbal
    if pulling:
        return math.nan, math.nan, math.nan, math.nan, TILT_UNSTABLE, nbal
    if nbal > 0:
        return math.nan, math.nan, math.nan, math.nan, TILT_PUSHING, nbal
    return math.nan, math.nan, math.nan, math.nan, TILT_NO_BALANCE, nbal


def hanging_tilt_batch(A, B, c, mass, g, P):
    """:func:`hanging_tilt` at every position P[k] = (x, y[, ...]) [m].

    ``A``, ``B`` (2, >=2) outlets and attachments [m] (x, y used), ``c`` (>=2)
    centre of mass in platform coordinates [m], ``mass`` [kg], ``g`` (>=2)
    gravity [m/s^2].  Returns (phi (k,) [rad], tensions (k, 2) [N], h (k,),
    status (k,) int8, n_balanced (k,) int8).
    """
    P = np.ascontiguousarray(P, dtype=float)
    k = P.shape[0]
    phi = np.empty(k)
    t = np.empty((k, 2))
    h = np.empty(k)
    status = np.empty(k, dtype=np.int8)
    nbal = np.empty(k, dtype=np.int8)
    _tilt_loop(np.ascontiguousarray(A, dtype=float), np.ascontiguousarray(B, dtype=float),
               np.ascontiguousarray(c, dtype=float), float(mass), float(g[0]), float(g[1]), P, phi, t, h, status,
               nbal)
    return phi, t, h, status, nbal


@njit
def _tilt_loop(A, B, c, mass, gx, gy, P, phi, t, h, status, nbal):
    coef = np.empty(5)
    roots = np.empty(4)
    for i in range(P.shape[0]):
        p_, t1, t2, hh, st, nb_ = hanging_tilt(A, B, c, mass, gx, gy, P[i, 0], P[i, 1], coef, roots)
        phi[i] = p_
        t[i, 0] = t1
        t[i, 1] = t2
        h[i] = hh
        status[i] = st
        nbal[i] = nb_
