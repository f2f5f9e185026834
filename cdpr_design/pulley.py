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
