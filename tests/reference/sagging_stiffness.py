"""A slow, plain reference for the stiffness of sagging cables, independent of the kernels.

- :func:`irvine`: Irvine's elastic catenary in its textbook form (with the 1/w), span X and
  height Z from the end forces (H, VB) at the attachment;
- :func:`solve_ends`: the end forces of a cable of unstretched length L0 spanning (X, Z), by
  scipy on those equations;
- :func:`chain_ends`: the span and height of a chain of N point masses on elastic segments held
  by (H, VB): the midpoint rule on the closure integrals, converging to :func:`irvine` as 1/N^2
  (the check of the two above);
- :func:`wrench`: the net wrench of a robot's sagging cables and the effector's weight at a
  displaced configuration, each cable solved on its own; :func:`fd_stiffness` its central
  differences at fixed unstretched lengths;
- :func:`stiffness_matrix` and :func:`mass_matrix`: the matrices assembled with numpy from the
  solved end forces and the textbook flexibility (:func:`flexibility`).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.stiffness import mass_matrix as effector_mass
from cdpr_design.statics.stiffness import skew, weight_term
from tests.reference.stiffness import fd_stiffness as central_differences


def irvine(H, VB, L0, w, EA):
    """(X, Z) [m] of Irvine's elastic catenary (textbook form; w > 0, H > 0)."""
    VA = VB + w * L0
    X = H / w * (np.arcsinh(VA / H) - np.arcsinh(VB / H)) + H * L0 / EA
    Z = H / w * (np.sqrt(1 + (VA / H) ** 2) - np.sqrt(1 + (VB / H) ** 2)) + (VB * L0 + w * L0 ** 2 / 2) / EA
    return X, Z


def solve_ends(X, Z, L0, w, EA):
    """(H, VB) [N] of the cable spanning (X, Z) with unstretched length L0, by scipy's
    least_squares on :func:`irvine` (unknowns ln H and VB), from a few starts; the closure is
    checked to 1e-12 of the chord."""
    c = np.hypot(X, Z)
    best = None
    for T in (EA * max(c / L0 - 1, 0) + w * L0, w * L0, 10 * w * L0, 0.1 * w * L0 + 1e-3 * EA * abs(c / L0 - 1)):
        if not T > 0:
            continue
        x0 = np.array([np.log(T * X / c), T * Z / c - w * L0 / 2])

        def res(x):
            Xc, Zc = irvine(np.exp(x[0]), x[1], L0, w, EA)
            return np.array([Xc - X, Zc - Z]) / c

        r = least_squares(res, x0, xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000, method="lm")
        if best is None or r.cost < best.cost:
            best = r
        if best.cost < 1e-26:
            break
    assert np.max(np.abs(best.fun)) < 1e-12, ("catenary not solved", X, Z, L0, w, EA, best.fun)
    return float(np.exp(best.x[0])), float(best.x[1])


def chain_ends(H, VB, L0, w, EA, N):
    """(X, Z) [m] of a chain of N elastic segments (unstretched L0 / N each) whose nodes carry
    the cable's weight, held by (H, VB) at its lower end: segment j pulls (H, VB + w L0 (j + 1/2) / N)
    and is stretched by its tension over EA."""
    l = L0 / N
    V = VB + w * l * (np.arange(N) + 0.5)
    T = np.hypot(H, V)
    s = l * (1 + T / EA) / T
    return float(np.sum(H * s)), float(np.sum(V * s))


def up_of(design):
    g = np.asarray(design.gravity, float)
    return -g / np.linalg.norm(g)


def end_force(A, B, L0, w, EA, up):
    """The force (3,) [N] of a cable from outlet A to attachment B [m] on the effector, and its
    (H, VB, X, horizontal unit vector)."""
    l = A - B
    Z = l @ up
    h = l - Z * up
    X = np.linalg.norm(h)
    H, VB = solve_ends(X, Z, L0, w, EA)
    return H * h / X + VB * up, (H, VB, X, h / X)


def _cables(design):
    w = np.array([c.props.mass_per_length for c in design.cables]) * np.linalg.norm(design.gravity)
    EA = np.array([c.props.axial_stiffness for c in design.cables], float)
    return w, EA


def wrench(design, full, rotvec, L0):
    """The net wrench (6,) [N, N m] on the effector at position ``full[:3]`` and orientation
    exp([rotvec]x) R(full[3:]): each sagging cable's end force at fixed unstretched length
    ``L0`` (m,) [m] and the weight at the centre of mass, moments about the reference point."""
    w, EA = _cables(design)
    up = up_of(design)
    R = Rotation.from_rotvec(rotvec).as_matrix() @ kin.rotation_matrix(*full[3:])
    Rb = design.attachments @ R.T
    F = np.array([end_force(design.outlets[i], full[:3] + Rb[i], L0[i], w[i], EA[i], up)[0]
                  for i in range(design.m)])
    G = design.effector.mass * np.asarray(design.gravity)
    c = R @ np.asarray(design.effector.center_of_mass)
    return np.concatenate([F.sum(axis=0) + G, np.cross(Rb, F).sum(axis=0) + np.cross(c, G)])


def fd_stiffness(design, full, L0, h=1e-4):
    """-dw/dx of :func:`wrench` at fixed ``L0`` by central differences with one Richardson step,
    in the motion's coordinates."""
    return central_differences(design, full, lambda p, rotvec: wrench(design, np.concatenate([p, full[3:]]), rotvec,
                                                                      L0), h)


def flexibility(H, VB, L0, w, EA):
    """d(X, Z)/d(H, VB) [m/N]: the derivatives of :func:`irvine`'s textbook form (Irvine 1981),
    with TA, TB the end tensions:

        dX/dH  = [asinh(VA/H) - asinh(VB/H)] / w - (VA/TA - VB/TB) / w + L0/EA
        dX/dVB = dZ/dH = H (1/TA - 1/TB) / w
        dZ/dVB = (VA/TA - VB/TB) / w + L0/EA
    """
    VA = VB + w * L0
    TA, TB = np.hypot(H, VA), np.hypot(H, VB)
    xh = (np.arcsinh(VA / H) - np.arcsinh(VB / H)) / w - (VA / TA - VB / TB) / w + L0 / EA
    xv = H * (1 / TA - 1 / TB) / w
    zv = (VA / TA - VB / TB) / w + L0 / EA
    return np.array([[xh, xv], [xv, zv]])


def stiffness_matrix(design, full, L0) -> np.ndarray:
    """The full 6x6 K = -dw/dx of sagging cables at fixed ``L0``, assembled with numpy: each
    cable's in-plane stiffness the inverse of :func:`flexibility`, H / X across its plane."""
    w, EA = _cables(design)
    up = up_of(design)
    R = kin.rotation_matrix(*full[3:])
    Rb = design.attachments @ R.T
    K = np.zeros((6, 6))
    for i in range(design.m):
        F, (H, VB, X, h) = end_force(design.outlets[i], full[:3] + Rb[i], L0[i], w[i], EA[i], up)
        k = np.linalg.inv(flexibility(H, VB, L0[i], w[i], EA[i]))
        P = np.column_stack([h, up])
        Hi = P @ k @ P.T + H / X * (np.eye(3) - np.outer(h, h) - np.outer(up, up))
        r = skew(Rb[i])
        K[:3, :3] += Hi
        K[:3, 3:] -= Hi @ r
        K[3:, :3] += r @ Hi
        K[3:, 3:] -= r @ Hi @ r + skew(F) @ r
    weight = design.effector.mass * np.asarray(design.gravity)
    K[3:, 3:] += weight_term(weight, R @ np.asarray(design.effector.center_of_mass))
    return K


def mass_matrix(design, R, L0) -> np.ndarray:
    """The effector's 6x6 mass matrix with a third of each cable's mass (mu L0 / 3) as a point
    mass at its attachment."""
    M = effector_mass(design, R)
    Rb = design.attachments @ R.T
    for i, c in enumerate(design.cables):
        mc = c.props.mass_per_length * L0[i] / 3
        r = skew(Rb[i])
        M[:3, :3] += mc * np.eye(3)
        M[:3, 3:] -= mc * r
        M[3:, :3] += mc * r
        M[3:, 3:] -= mc * r @ r
    return M
