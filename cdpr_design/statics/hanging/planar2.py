"""The hanging orientation of a planar body on two taut cables, in closed form with numpy.

A planar rigid body hangs from two cables (outlets a_1, a_2 in the frame,
attachments b_1, b_2 in platform coordinates, centre of mass c, mass m,
gravity g in the x-y plane).  Its orientation phi [rad] about z is not
commanded: at a given position p of the platform origin the body turns until
it is in equilibrium with both cables taut, which happens when the two cable
lines and the vertical through the centre of mass meet in one point
(Carricato & Merlet 2013).  :func:`planar_two_cable` finds every such
orientation at many positions at once, vectorised over them, and
:func:`choose` picks the answer.

Equations (all in the plane, ``cr(a, b) = a_x b_y - a_y b_x``).  With
R = R(phi), v_i = a_i - p - R b_i (cable vector), r_i = R (b_i - c)
(attachment seen from the centre of mass) and f = -m g, force balance
tau_1 v_1 + tau_2 v_2 = f gives the force densities (tension / length)

    tau_1 = cr(f, v_2) / D,   tau_2 = cr(v_1, f) / D,   D = cr(v_1, v_2),

and the moment about the centre of mass, multiplied by D, is

    M(phi) = cr(f, v_2) cr(r_1, v_1) + cr(v_1, f) cr(r_2, v_2).

Each factor is affine in (cos phi, sin phi), so M is a trigonometric
polynomial of degree 2 and has at most four roots on the circle.  Its five
coefficients come exactly from five samples (a discrete Fourier transform);
the roots are the unit-modulus eigenvalues of the companion matrix of the
quartic z^2 M(z) (z = e^{i phi}), polished by Newton's method on M itself.
A root is an equilibrium when both tensions t_i = tau_i |v_i| are >= 0; it is
stable when the Hessian of the Lagrangian U + sum t_i (|v_i| - rho_i),
U = -m g.(p + R c), is positive on the one-dimensional tangent space of the
two length constraints in (x, y, phi) - the reduced-Hessian test of
Carricato & Merlet (2013).  Of the stable equilibria with non-negative
tensions, the one closest to level (smallest |phi|) is the answer; the
``pose`` command also lists the others (``alternatives``).

Units: SI (m, N, rad); conventions of :mod:`cdpr_design.statics.hanging.geometry`.

References
----------
M. Carricato, J.-P. Merlet, "Stability analysis of underconstrained
cable-driven parallel robots", IEEE Trans. Robotics 29(1), 288-296, 2013.
G. Abbasnejad, M. Carricato, "Direct geometrico-static problem of
underconstrained cable-driven parallel robots with n cables", IEEE Trans.
Robotics 31(2), 468-478, 2015.
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.statics.hanging.results import DEGENERATE, NO_BALANCE, OK, PUSHING, UNSTABLE


def _cr(ax, ay, bx, by):
    return ax * by - ay * bx


def _geometry2(phi, A, B, c, px, py):
    """v_1, v_2, R b_1, R b_2, R c at angles phi (broadcast with px, py)."""
    co, si = np.cos(phi), np.sin(phi)
    rb1 = (co * B[0, 0] - si * B[0, 1], si * B[0, 0] + co * B[0, 1])
    rb2 = (co * B[1, 0] - si * B[1, 1], si * B[1, 0] + co * B[1, 1])
    rc = (co * c[0] - si * c[1], si * c[0] + co * c[1])
    v1 = (A[0, 0] - px - rb1[0], A[0, 1] - py - rb1[1])
    v2 = (A[1, 0] - px - rb2[0], A[1, 1] - py - rb2[1])
    return v1, v2, rb1, rb2, rc


def _moment2(phi, A, B, c, fx, fy, px, py):
    """M(phi) [N^2 m^3] (module notes): D times the moment about the centre of mass of the cable
    forces that balance the weight, zero at a balanced orientation; broadcast over arrays."""
    v1, v2, rb1, rb2, rc = _geometry2(phi, A, B, c, px, py)
    m1 = _cr(rb1[0] - rc[0], rb1[1] - rc[1], v1[0], v1[1])
    m2 = _cr(rb2[0] - rc[0], rb2[1] - rc[1], v2[0], v2[1])
    return _cr(fx, fy, v2[0], v2[1]) * m1 + _cr(v1[0], v1[1], fx, fy) * m2


def _trig_roots(coef):
    """Roots phi (k, 4) (NaN padded) of the trigonometric polynomial with coefficients
    ``coef`` (5, k) and a flag (k,) where M vanishes identically: the unit-modulus (within 1e-3)
    eigenvalues of the companion matrix of z^2 M(z), its degree lowered where the leading
    coefficients vanish (relative 1e-13)."""
    k = coef.shape[1]
    scale = np.abs(coef).sum(axis=0)
    c4 = 0.5 * (coef[3] - 1j * coef[4])
    c3 = 0.5 * (coef[1] - 1j * coef[2])
    c2 = coef[0] + 0j
    c1, c0 = np.conj(c3), np.conj(c4)
    tiny = 1e-13 * scale
    quart = np.abs(c4) > tiny
    quad = ~quart & (np.abs(c3) > tiny)
    degenerate = ~(scale > 0) | ~np.isfinite(scale) | ~(quart | quad)
    z = np.full((k, 4), np.nan + 0j)
    q = np.flatnonzero(quart & ~degenerate)
    if q.size:
        C = np.zeros((q.size, 4, 4), complex)
        C[:, 0] = -np.stack([c3[q], c2[q], c1[q], c0[q]], axis=1) / c4[q, None]
        C[:, 1, 0] = C[:, 2, 1] = C[:, 3, 2] = 1.0
        z[q] = np.linalg.eigvals(C)
    q = np.flatnonzero(quad & ~degenerate)
    if q.size:
        C = np.zeros((q.size, 2, 2), complex)
        C[:, 0] = -np.stack([c2[q], c1[q]], axis=1) / c3[q, None]
        C[:, 1, 0] = 1.0
        z[q, :2] = np.linalg.eigvals(C)
    near = np.abs(np.abs(z) - 1.0) < 1e-3
    return np.where(near, np.arctan2(z.imag, z.real), np.nan), degenerate


def _polish2(phi, coef, A, B, c, fx, fy, px, py):
    """Newton's method on M (derivative from the coefficients), eight steps at most; (phi in
    (-pi, pi], |M(phi)|)."""
    active = np.isfinite(phi)
    for _ in range(8):
        if not active.any():
            break
        f = _moment2(phi, A, B, c, fx, fy, px, py)
        d = (-coef[1] * np.sin(phi) + coef[2] * np.cos(phi) - 2.0 * coef[3] * np.sin(2.0 * phi)
             + 2.0 * coef[4] * np.cos(2.0 * phi))
        active &= d != 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(active, f / d, 0.0)
        phi = phi - step
        active &= np.abs(step) >= 1e-15
    phi = np.arctan2(np.sin(phi), np.cos(phi))
    return phi, np.abs(_moment2(phi, A, B, c, fx, fy, px, py))


def _equilibrium2(phi, A, B, c, mass, gx, gy, px, py):
    """Tensions t1, t2 [N] from force balance, the reduced Hessian h (the Lagrangian's second
    derivative along the unit tangent of the two length constraints in (x, y, phi); > 0: stable)
    and ok, False where a cable has zero length or the cables are parallel."""
    fx, fy = -mass * gx, -mass * gy
    v1, v2, rb1, rb2, rc = _geometry2(phi, A, B, c, px, py)
    L1, L2 = np.hypot(*v1), np.hypot(*v2)
    D = _cr(v1[0], v1[1], v2[0], v2[1])
    ok = (L1 > 1e-12) & (L2 > 1e-12) & (np.abs(D) > 1e-12 * L1 * L2)
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = _cr(fx, fy, v2[0], v2[1]) / D * L1
        t2 = _cr(v1[0], v1[1], fx, fy) / D * L2
        u1, u2 = (v1[0] / L1, v1[1] / L1), (v2[0] / L2, v2[1] / L2)
        g1 = (-u1[0], -u1[1], -_cr(rb1[0], rb1[1], u1[0], u1[1]))
        g2 = (-u2[0], -u2[1], -_cr(rb2[0], rb2[1], u2[0], u2[1]))
        nx = g1[1] * g2[2] - g1[2] * g2[1]
        ny = g1[2] * g2[0] - g1[0] * g2[2]
        nt = g1[0] * g2[1] - g1[1] * g2[0]
        nn = nx * nx + ny * ny + nt * nt
        h = (mass * (gx * rc[0] + gy * rc[1])) * nt * nt
        q1 = u1[1] * nx - u1[0] * ny - (rb1[0] * u1[0] + rb1[1] * u1[1]) * nt
        q2 = u2[1] * nx - u2[0] * ny - (rb2[0] * u2[0] + rb2[1] * u2[1]) * nt
        h = h + t1 * (q1 * q1 / L1 + (u1[0] * rb1[0] + u1[1] * rb1[1]) * nt * nt)
        h = h + t2 * (q2 * q2 / L2 + (u2[0] * rb2[0] + u2[1] * rb2[1]) * nt * nt)
        h = h / nn
    return t1, t2, h, ok


def planar_two_cable(A, B, c, mass, g, P):
    """Every balanced orientation of a planar body on two taut cables at positions P (k, >=2) [m].

    ``A``, ``B`` (2, >=2) outlets and attachments [m], ``c`` centre of mass
    (platform) [m], ``mass`` [kg], ``g`` gravity [m/s^2].  Returns (phi (k, 4)
    [rad], tensions (k, 4, 2) [N], h (k, 4) reduced Hessian, ok (k, 4): a real
    root with a proper geometry, degenerate (k,): M is constant -- no orientation or every
    one balances -- or not finite).  NaN-padded where a position has fewer than four roots.
    """
    A, B, c, g, P = (np.asarray(x, float) for x in (A, B, c, g, P))
    px, py = P[:, 0], P[:, 1]
    fx, fy = -mass * g[0], -mass * g[1]
    coef = np.zeros((5, P.shape[0]))
    for k in range(5):
        t = 2.0 * math.pi * k / 5.0
        mk = _moment2(t, A, B, c, fx, fy, px, py)
        coef += np.array([mk / 5.0, 0.4 * mk * math.cos(t), 0.4 * mk * math.sin(t),
                          0.4 * mk * math.cos(2.0 * t), 0.4 * mk * math.sin(2.0 * t)])
    phi0, degenerate = _trig_roots(coef)
    X = lambda v: v[:, None]  # noqa: E731 - broadcast per-position values over the roots
    phi, res = _polish2(phi0, X(coef.T).transpose(2, 0, 1), A, B, c, fx, fy, X(px), X(py))
    scale = np.abs(coef).sum(axis=0)
    real = res <= 1e-9 * X(scale)
    t1, t2, h, ok = _equilibrium2(phi, A, B, c, mass, g[0], g[1], X(px), X(py))
    ok &= real
    return phi, np.stack([t1, t2], axis=-1), h, ok, degenerate


def choose(phi, t, h, ok, degenerate, weight):
    """The answer among the roots of :func:`planar_two_cable` (phi, t, h, ok (k, 4),
    degenerate (k,); ``weight`` [N]): of the stable roots with t >= 0, the one closest to level.
    Returns (its column j (k,), status (k,) int8, pulling (k, 4), stable (k, 4))."""
    ttol = 1e-9 * weight
    pull = ok & np.all(t >= -ttol, axis=-1)
    stable = pull & (h > 1e-10 * weight)
    key = np.where(stable, np.abs(phi), np.inf)
    j = np.argmin(key, axis=1)
    rows = np.arange(phi.shape[0])
    found = np.isfinite(key[rows, j])
    status = np.where(found, OK, np.where(pull.any(1), UNSTABLE, np.where(ok.any(1), PUSHING, NO_BALANCE)))
    status = np.where(degenerate, DEGENERATE, status).astype(np.int8)
    return j, status, pull, stable
