"""Swivel-pulley outlets: where a cable really leaves the frame, and its length.

A cable coming from its winch runs along the pulley's *swivel axis* into the
pulley, wraps an arc of it and leaves tangentially towards the effector.  The
pulley's fork swivels freely about that axis, so the pulley plane always
contains the axis and the cable's attachment point (Pott, "Cable-Driven
Parallel Robots: Theory and Application", Springer 2018, sec. 3.x "pulley
kinematics"; Bruckmann, Pott, Hiller, Franitza: "A modular controller for
redundantly actuated tendon-based Stewart platforms", 2006).

Convention used throughout cdpr-design (``cables[i].pulley`` in the spec)
----------------------------------------------------------------------------
- ``outlet`` a_i is the **swivel point**: the point on the swivel axis where
  the cable, arriving from the winch along the axis, first touches the pulley.
- ``axis`` k (unit) points along the swivel axis in the direction the cable
  travels from the winch into the pulley (the winch is on the -k side).  The
  default ``[0, 0, 1]`` is a pulley on top of a post with its winch below.
- The pulley centre is M = a_i + r e, with e the unit component of
  (B - a_i) perpendicular to k (the pulley plane contains k and the
  attachment point B = p + R b_i; ``r`` the pulley radius).
- In the pulley plane, with x along e and z along k and M at the origin,
  B = (x, z), D = |B - M|: the cable leaves at the tangent point C at the polar
  angle theta_C = atan2(z, x) + arccos(r / D), having wrapped
  beta = pi - theta_C (entry point at theta = pi).  Free length
  l_f = sqrt(D^2 - r^2); total length seen by the winch L = r beta + l_f.
- B always lies on the pulley's side of the axis (x >= -r), so beta is in
  [0, 2 pi): 0 when B is straight ahead on the axis (+k), pi / 2 level with
  the pulley's top far away, pi straight back on the far side; a rounding
  below 0 is clamped to beta = 0, C = a_i.
- Where B is on the swivel axis (the swivel angle is undefined), e is a fixed
  reference direction perpendicular to k; the length does not depend on it.
- B inside the pulley circle (D < r) has no taut cable: NaN.

The gradient of L with respect to B is -u, u the unit vector from B to C
(the free segment's direction): the structure matrix keeps its form
[u ; (R b) x u] with the true outlet point C.  r -> 0 gives the point outlet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def reference_perpendicular(axis) -> np.ndarray:
    """A fixed unit vector perpendicular to ``axis`` (used when B is on the axis).

    The frame axis least aligned with ``axis``, made perpendicular (Gram-Schmidt).
    """
    k = np.asarray(axis, float)
    k = k / np.linalg.norm(k)
    j = int(np.argmin(np.abs(k)))
    e = np.zeros(3)
    e[j] = 1.0
    e = e - (e @ k) * k
    return e / np.linalg.norm(e)


@dataclass(frozen=True)
class PulleyGeometry:
    """Pulley outlet geometry for many attachment points (one cable).

    Attributes
    ----------
    exits : (k, 3) array
        Tangent points C where the free cable leaves the pulley [m].
    lengths : (k,) array
        Total length r beta + l_f [m] (NaN where D < r).
    free_lengths : (k,) array
        |B - C| [m].
    wrap : (k,) array
        Wrap angle beta [rad], in [0, 2 pi).
    swivel : (k, 3) array
        Unit radial direction e of the pulley plane.
    centres : (k, 3) array
        Pulley centres M [m].
    """

    exits: np.ndarray
    lengths: np.ndarray
    free_lengths: np.ndarray
    wrap: np.ndarray
    swivel: np.ndarray
    centres: np.ndarray


def outlet_geometry(outlet, axis, radius: float, points) -> PulleyGeometry:
    """Tangent points, wrap angles and lengths of one swivel pulley (module docstring).

    Parameters
    ----------
    outlet : (3,) swivel point a_i [m].
    axis : (3,) swivel axis k (normalised here).
    radius : float
        Pulley radius r [m]; 0 gives the point outlet.
    points : (k, 3) or (3,) attachment points B in the frame [m].
    """
    a = np.asarray(outlet, float)
    k = np.asarray(axis, float)
    k = k / np.linalg.norm(k)
    B = np.atleast_2d(np.asarray(points, float))
    r = float(radius)
    d = B - a
    z_a = d @ k
    radial = d - z_a[:, None] * k
    s = np.linalg.norm(radial, axis=1)
    e = np.empty_like(radial)
    on_axis = s <= 1e-12
    e[~on_axis] = radial[~on_axis] / s[~on_axis, None]
    e[on_axis] = reference_perpendicular(k)
    M = a + r * e
    x = s - r
    z = z_a
    D = np.hypot(x, z)
    with np.errstate(invalid="ignore", divide="ignore"):
        alpha = np.arccos(np.clip(r / D, -1.0, 1.0)) if r > 0 else np.full_like(D, np.pi / 2)
    theta = np.arctan2(z, x) + alpha
    beta = np.pi - theta
    C = M + r * (np.cos(theta)[:, None] * e + np.sin(theta)[:, None] * k)
    lift = beta < 0.0
    beta = np.where(lift, 0.0, beta)
    C[lift] = a
    free = np.linalg.norm(B - C, axis=1)
    L = r * beta + free
    bad = D < r * (1.0 - 1e-12)
    L[bad] = np.nan
    free[bad] = np.nan
    return PulleyGeometry(C, L, free, beta, e, M)


# ----------------------------------------------------------------------------
# Many cables at once (trajectories, sizing, simulation)
# ----------------------------------------------------------------------------


def design_pulleys(design):
    """(outlets (m, 3), axes (m, 3) unit, radii (m,)) of a design's cables.

    A cable without a pulley gets radius 0 (the point outlet) and axis +z.
    """
    A = np.asarray(design.outlets, float)
    axes = np.empty_like(A)
    radii = np.zeros(A.shape[0])
    for i, c in enumerate(design.cables):
        if c.pulley is not None and c.pulley.radius > 0:
            k = np.asarray(c.pulley.axis, float)
            axes[i] = k / np.linalg.norm(k)
            radii[i] = float(c.pulley.radius)
        else:
            axes[i] = (0.0, 0.0, 1.0)
    return A, axes, radii


@dataclass(frozen=True)
class CablePaths:
    """Cable paths of every cable at many poses (arrays (k, m, ...)).

    Attributes
    ----------
    exits : (k, m, 3)
        Where the free cable leaves the outlet (tangent point C; a_i for r = 0) [m].
    lengths : (k, m)
        Total lengths r beta + l_f [m].
    free_lengths : (k, m)
        l_f = |B - C| [m].
    directions : (k, m, 3)
        u = (C - B) / l_f, the free segment's unit vector (the way the cable pulls).
    wrap : (k, m)
        Wrap angles beta [rad].
    normals : (k, m, 3)
        t = k x e, the unit normal of each pulley plane (zero for a point outlet).
    swivel_curvature : (k, m)
        kappa_t = -(u . e) / s [1/m], the second derivative of L along t (see
        :func:`cable_paths`); 1 / l_f for a point outlet.
    """

    exits: np.ndarray
    lengths: np.ndarray
    free_lengths: np.ndarray
    directions: np.ndarray
    wrap: np.ndarray
    normals: np.ndarray
    swivel_curvature: np.ndarray

    def second_derivative(self, v: np.ndarray) -> np.ndarray:
        """v^T H v for attachment-point velocities v (k, m, 3): the centripetal part of L''.

        H = (n n^T) / l_f + kappa_t t t^T (module notes of :func:`cable_paths`),
        so v^T H v = (|v_perp|^2 - (v . t)^2) / l_f + kappa_t (v . t)^2 with
        v_perp the part of v perpendicular to u.  r -> 0 gives |v_perp|^2 / L.
        """
        vu = np.einsum("kmi,kmi->km", v, self.directions)
        vt = np.einsum("kmi,kmi->km", v, self.normals)
        vperp2 = np.einsum("kmi,kmi->km", v, v) - vu * vu
        with np.errstate(invalid="ignore", divide="ignore"):
            swivel = np.where(vt == 0.0, 0.0, self.swivel_curvature * vt * vt)
            return (vperp2 - vt * vt) / self.free_lengths + swivel

    def max_curvature(self) -> np.ndarray:
        """Largest |eigenvalue| of H, max(1 / l_f, |kappa_t|) (k, m) [1/m]: |v^T H v| <= this |v|^2."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.fmax(1.0 / self.free_lengths, np.abs(self.swivel_curvature))


def cable_paths(outlets, axes, radii, points) -> CablePaths:
    """Outlet geometry of m cables at k poses at once (vectorised :func:`outlet_geometry`).

    Parameters
    ----------
    outlets, axes : (m, 3)
        Swivel points a_i [m] and unit swivel axes k_i.
    radii : (m,)
        Pulley radii r_i [m] (0: point outlet).
    points : (k, m, 3)
        Attachment points B in the frame [m].

    Notes
    -----
    The length L(B) = r beta + l_f has gradient -u and Hessian H with H u = 0
    (moving B along the free segment only shortens it), in the pulley plane
    the curvature of its level sets, the involutes of the pulley circle, whose
    radius of curvature is the tangent length l_f: n^T H n = 1 / l_f; and
    along the plane's normal t, since L is unchanged when B turns about the
    swivel axis (B'' = -s e at unit angular rate, s the distance of B from
    the axis): t^T H t = -(u . e) / s.  The mirror symmetry of L about the
    pulley plane makes n^T H t = 0.  For a point outlet both are 1 / L
    (u . e = -s / L), H = (I - u u^T) / L.  On the swivel axis (s = 0) the
    swivel angle is undefined and kappa_t is NaN for a pulley.
    """
    a = np.asarray(outlets, float)[None]
    k = np.asarray(axes, float)[None]
    r = np.asarray(radii, float)[None]
    B = np.asarray(points, float)
    if B.ndim == 2:
        B = B[None]
    d = B - a
    z = np.einsum("kmi,kmi->km", d, k)
    radial = d - z[..., None] * k
    s = np.linalg.norm(radial, axis=2)
    on_axis = s <= 1e-12
    with np.errstate(invalid="ignore", divide="ignore"):
        e = radial / s[..., None]
    if on_axis.any():
        ref = np.array([reference_perpendicular(kk) for kk in k[0]])
        e[on_axis] = np.broadcast_to(ref[None], e.shape)[on_axis]
    M = a + r[..., None] * e
    x = s - r
    D = np.hypot(x, z)
    with np.errstate(invalid="ignore", divide="ignore"):
        alpha = np.where(r > 0, np.arccos(np.clip(r / D, -1.0, 1.0)), np.pi / 2)
    theta = np.arctan2(z, x) + alpha
    beta = np.pi - theta
    C = M + r[..., None] * (np.cos(theta)[..., None] * e + np.sin(theta)[..., None] * k)
    lift = beta < 0.0
    beta = np.where(lift, 0.0, beta)
    C = np.where(lift[..., None], a, C)
    vec = C - B
    free = np.linalg.norm(vec, axis=2)
    L = r * beta + free
    bad = D < r * (1.0 - 1e-12)
    L = np.where(bad, np.nan, L)
    free = np.where(bad, np.nan, free)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = vec / free[..., None]
        kappa = -np.einsum("kmi,kmi->km", u, e) / s
    point = np.broadcast_to(r <= 0, L.shape)
    with np.errstate(invalid="ignore", divide="ignore"):
        kappa = np.where(point, 1.0 / free, np.where(on_axis, np.nan, kappa))
    t = np.cross(np.broadcast_to(k, e.shape), e)
    t = np.where(point[..., None], 0.0, t)
    return CablePaths(C, L, free, u, beta, t, kappa)


def has_pulleys(design) -> bool:
    """Whether any cable of ``design`` leaves its outlet over a swivel pulley of positive radius."""
    return any(c.pulley is not None and c.pulley.radius > 0 for c in design.cables)


def design_cable_paths(design, points) -> CablePaths:
    """:func:`cable_paths` of a design's cables for attachment points (k, m, 3) [m]."""
    A, axes, radii = design_pulleys(design)
    return cable_paths(A, axes, radii, points)


def exit_point(outlet, axis, radius: float, point):
    """Tangent point C (3-tuple) [m] and wrap angle beta [rad] of one cable at one point.

    The scalar form of :func:`outlet_geometry` (no arrays: cheap enough to run
    every physics step of :mod:`cdpr_design.motion.simulation`).  ``axis`` must be a
    unit vector.  Returns (None, nan) when B is inside the pulley circle.
    """
    ax, ay, az = outlet
    kx, ky, kz = axis
    dx, dy, dz = point[0] - ax, point[1] - ay, point[2] - az
    z = dx * kx + dy * ky + dz * kz
    rx, ry, rz = dx - z * kx, dy - z * ky, dz - z * kz
    s = math.sqrt(rx * rx + ry * ry + rz * rz)
    if s <= 1e-12:
        rx, ry, rz = reference_perpendicular(axis)
    else:
        rx, ry, rz = rx / s, ry / s, rz / s
    r = float(radius)
    x = s - r
    D = math.hypot(x, z)
    if D < r * (1.0 - 1e-12):
        return None, math.nan
    alpha = math.acos(min(r / D, 1.0)) if r > 0 else 0.5 * math.pi
    theta = math.atan2(z, x) + alpha
    beta = math.pi - theta
    if beta < 0.0:
        return (ax, ay, az), 0.0
    c, sn = r * (1.0 + math.cos(theta)), r * math.sin(theta)
    return (ax + c * rx + sn * kx, ay + c * ry + sn * ky, az + c * rz + sn * kz), beta
