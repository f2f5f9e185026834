"""A hanging effector on sagging cables (statics/hanging/sagging.py) against a slow, obvious reference
written here from Irvine's equations alone.

The reference is the total potential energy at the answer's unstretched lengths: the effector's
weight plus each cable's energy (elastic and gravitational) as a function of its span X and height
Z.  That energy is the Legendre transform of the cable's complementary energy (docs/cable-models.md)

    E(X, Z) = max over (H, VB) of  H X + VB Z - Pi*(H, VB),
    Pi*(H, VB) = (1/w) int_VB^VA sqrt(H^2 + V^2) dV + (H^2 L0 + int_0^L0 (VB + w s)^2 ds) / (2 EA),

whose maximiser is the cable's end force (dE/dX = H, dE/dZ = VB): written in closed form here, the
inner maximum found by scipy, the outer minimum by scipy BFGS from several starts (the gradient by
the envelope theorem from the inner maxima).  No kernel of the
package is called by the reference.  Checked: the answer is a minimum of that energy every start
comes back to, with its tensions; its stiffness matrix is the energy's Hessian (central second
differences); as the cables' weight goes to zero the answer tends to the elastic cables'.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize, root

from cdpr_design.statics.hanging import geometry as hg
from cdpr_design.statics.hanging.at_positions import hanging_orientations
from cdpr_design.statics.hanging.sagging import hang_on_sagging_cables

from .helpers import NO_KERNELS  # noqa: F401 (the fast path calls the catenary kernels)
from .test_hanging_stiffness import dofs_of, pose_of, random_hangings, random_robot


def complementary(H, VB, L0, w, EA):
    """Pi*(H, VB) [J] and its gradient (X, Z) [m] (closed forms)."""
    VA = VB + w * L0

    def prim(V):  # int sqrt(H^2 + V^2) dV
        return 0.5 * (V * math.hypot(H, V) + H * H * math.asinh(V / H))

    TA, TB = math.hypot(H, VA), math.hypot(H, VB)
    pi = (prim(VA) - prim(VB)) / w + (H * H * L0 + (VA ** 3 - VB ** 3) / (3 * w)) / (2 * EA)
    X = H / w * (math.asinh(VA / H) - math.asinh(VB / H)) + H * L0 / EA
    Z = (TA - TB) / w + (VA * L0 - w * L0 * L0 / 2) / EA
    return pi, np.array([X, Z])


def cable_energy(X, Z, L0, w, EA, start):
    """E(X, Z) [J] (module doc) and its maximiser (H, VB) [N], scipy from ``start``."""
    def neg(z):
        H = math.exp(min(z[0], 700.0))  # H > 0
        pi, g = complementary(H, z[1], L0, w, EA)
        val = pi - H * X - z[1] * Z
        return val, np.array([(g[0] - X) * H, g[1] - Z])

    z0 = np.array([math.log(max(start[0], 1e-6)), start[1]])
    sol = minimize(neg, z0, jac=True, method="BFGS", options={"gtol": 1e-12, "maxiter": 500})
    # the maximum's value loses digits to cancellation before its place does: polish the place on the
    # closure (the gradient), whose residual is in metres
    z = root(lambda z: neg(z)[1] / np.array([math.exp(min(z[0], 700.0)), 1.0]), sol.x, method="hybr",
             options={"xtol": 1e-15}).x
    return -neg(z)[0], (math.exp(z[0]), z[1])


class Reference:
    """The total potential energy of a hanging effector on sagging cables of lengths L0 (module doc)."""

    def __init__(self, robot, L0, w, EA, p0, R0, forces):
        self.robot, self.L0, self.w, self.EA, self.p0, self.R0 = robot, L0, w, EA, p0, R0
        self.forces = [tuple(f) for f in forces]  # warm starts of the inner maxima

    def spans(self, x):
        A, B, c, mass, g, planar = self.robot
        p, R = pose_of(x, self.p0, self.R0, planar)
        up = -g / np.linalg.norm(g)
        l = A - p - B @ R.T
        Z = l @ up
        X = np.linalg.norm(l - Z[:, None] * up, axis=1)
        return p, R, X, Z

    def energy(self, x):
        A, B, c, mass, g, planar = self.robot
        p, R, X, Z = self.spans(x)
        total = float(-mass * g @ (p + R @ c))
        for i in range(len(A)):
            e, f = cable_energy(X[i], Z[i], self.L0[i], self.w[i], self.EA[i], self.forces[i])
            total += e
        return total

    def gradient(self, x, h=1e-7):
        """dE/dx: by the envelope theorem sum_i (H_i dX_i/dx + VB_i dZ_i/dx) + the weight's, the spans'
        derivatives by central differences of the geometry alone (smooth, no inner solve)."""
        A, B, c, mass, g, planar = self.robot
        HV = self.end_forces(x)
        out = np.empty(x.size)
        for j in range(x.size):
            e = np.zeros(x.size)
            e[j] = h
            pp, Rp, Xp, Zp = self.spans(x + e)
            pm, Rm, Xm, Zm = self.spans(x - e)
            dU = -mass * g @ ((pp + Rp @ c) - (pm + Rm @ c))
            out[j] = (dU + HV[:, 0] @ (Xp - Xm) + HV[:, 1] @ (Zp - Zm)) / (2 * h)
        return out

    def end_forces(self, x):
        _, _, X, Z = self.spans(x)
        return np.array([cable_energy(X[i], Z[i], self.L0[i], self.w[i], self.EA[i], self.forces[i])[1]
                         for i in range(len(X))])


def sagging_cases(seed, kinds=("planar2", "three", "four")):
    """(robot, p, R, cables, row k, w, EA, stiffness) at random positions of random robots."""
    rng = np.random.default_rng(seed)
    out = []
    for robot, geo, P, ideal in random_hangings(rng, 2, kinds):
        A, planar = robot[0], robot[5]
        m = len(A)
        # cables weighing 2 to 20 % of the effector over their length, EA 1e3 to 1e4 weights
        L = np.linalg.norm(A - P[0] - robot[1], axis=1)
        w = geo.weight * rng.uniform(0.02, 0.2, m) / L
        EA = geo.weight * 10.0 ** rng.uniform(3.0, 4.0, m)
        h, cab, s = hang_on_sagging_cables(geo, P, planar, ideal, w, EA, dofs_of(planar))
        for k in np.flatnonzero(h.status == 0)[:2]:
            out.append((robot, P[k], h.rotation[k], cab, k, w, EA, s))
    return out


@pytest.mark.slow
def test_sagging_hanging_pose_is_the_energy_minimum_scipy_finds():
    """At its own unstretched lengths the hanging pose on sagging cables is a minimum of the total
    potential energy (weight, cables' elastic and gravitational energy): BFGS from four starts
    about it (1 cm, 2 degrees) comes back to it, and the stationary point where it stops is the
    answer (1e-6 m, 1e-6 rad: the balance is solved to 1e-9 of the weight); the reference's end forces there are the answer's (1e-7 of the
    weight)."""
    cases = sagging_cases(41)[::2]
    assert len(cases) >= 4
    rng = np.random.default_rng(3)
    for robot, p, R, cab, k, w, EA, _ in cases:
        planar = robot[5]
        weight = robot[3] * np.linalg.norm(robot[4])
        ref = Reference(robot, cab.unstretched[k], w, EA, p, R, zip(cab.H[k], cab.VB[k]))
        np.testing.assert_allclose(ref.end_forces(np.zeros(3 if planar else 6)),
                                   np.column_stack([cab.H[k], cab.VB[k]]), atol=1e-7 * weight)
        n = 3 if planar else 6
        for _ in range(4):
            x0 = np.concatenate([rng.normal(0, 0.01, 2 if planar else 3), rng.normal(0, 0.035, 1 if planar else 3)])
            sol = minimize(ref.energy, x0, method="BFGS", jac=ref.gradient,
                           options={"gtol": 1e-9 * weight, "maxiter": 3000})
            # downhill to where the energy's round-off stops the line search (a soft yaw: a few urad),
            # then the stationary point there, from the gradient alone
            assert np.abs(sol.x).max() < 1e-4, (p, sol.x, sol.message)
            x = root(ref.gradient, sol.x, method="hybr", options={"xtol": 1e-13}).x
            assert np.abs(x).max() < 1e-6, (p, x)
        assert n == len(dofs_of(planar))


@pytest.mark.slow
def test_sagging_stiffness_is_the_energys_hessian():
    """K (central differences of the kernels' wrench) against central differences of the reference
    energy's gradient, to 1e-5 of K's size; stable answers have K positive definite."""
    for robot, p, R, cab, k, w, EA, s in sagging_cases(42)[:6]:
        planar = robot[5]
        ref = Reference(robot, cab.unstretched[k], w, EA, p, R, zip(cab.H[k], cab.VB[k]))
        n = 3 if planar else 6
        h = 1e-6  # a cable near its least tension is strongly nonlinear: at 1e-4 the truncation is 3e-3 of K
        Hs = np.array([(ref.gradient(np.eye(n)[j] * h) - ref.gradient(-np.eye(n)[j] * h)) / (2 * h)
                       for j in range(n)])
        Hs = 0.5 * (Hs + Hs.T)
        K = s.matrix[k]
        np.testing.assert_allclose(K, Hs, atol=1e-5 * np.abs(K).max())
        assert s.stable[k] and np.linalg.eigvalsh(K)[0] > 0


def test_light_cables_tend_to_the_elastic_answer():
    """As the cables' weight per length goes to zero, the sagging answer tends to the elastic
    cables' (the ideal orientation, tensions and unstretched lengths L / (1 + t / EA)), first order."""
    from cdpr_design.statics.hanging.compliance import hanging_stiffness

    rng = np.random.default_rng(43)
    seen = 0
    for kind in ("planar2", "three", "four"):
        A, B, c, mass, g, planar, P = random_robot(rng, kind)
        geo = hg.Geometry(A, B, c, mass, g)
        ideal = hanging_orientations(geo, P, planar)
        m = len(A)
        EA = geo.weight * 1e3 * np.ones(m)
        errs = []
        for scale in (1e-3, 1e-5):
            w = geo.weight * scale * np.ones(m)
            h, cab, _ = hang_on_sagging_cables(geo, P, planar, ideal, w, EA, dofs_of(planar))
            ok = (h.status == 0) & (ideal.status == 0) & np.all(ideal.tensions > 1e-3 * geo.weight, axis=1)
            errs.append(max(np.abs(hg.angle_from(h.rotation[ok], ideal.rotation[ok])).max(initial=0.0),
                            np.abs(h.tensions[ok] - ideal.tensions[ok]).max(initial=0.0) / geo.weight))
            seen += int(ok.sum())
        assert errs[1] < 1e-4 and errs[1] < 0.03 * errs[0], errs  # first order in the weight
        el = hanging_stiffness(geo, P, ideal.rotation, ideal.tensions, dofs_of(planar), EA)
        assert el.stable[ok].all()
    assert seen >= 4
