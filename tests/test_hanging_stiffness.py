"""A hanging effector's stability and stiffness on rigid and elastic cables
(statics/hanging/compliance.py), against slow obvious references written here:

* scipy BFGS, from several starts about the answer, on the total potential energy at the answer's
  unstretched lengths L0 = L / (1 + t / EA): the effector's weight plus each cable's elastic
  energy EA (|l| - L0)^2 / (2 L0) while it is stretched.  A stable answer is a minimum every start
  comes back to; an unstable one is left, downhill;
* central finite differences of the restoring force and moment (the cables' elastic forces at
  fixed L0 and the weight, moments about the platform origin) for the stiffness matrix;
* the Lagrange conditions of rigid cables (the taut ones' lengths fixed) with a small force added
  at the platform origin, solved by scipy, for the compliance of rigid cables, and the elastic
  compliance as EA grows.

Random robots: planar bodies on two cables, spatial bodies on three, and crane-like bodies on four
(hanging from three or four of them), at random positions.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from cdpr_design.statics.hanging import geometry as hg
from cdpr_design.statics.hanging.at_positions import hanging_orientations, hanging_pose_arrays
from cdpr_design.statics.hanging.compliance import hanging_stiffness

from .helpers import NO_KERNELS
from .test_hanging import G2, G3, random_planar2


def random_robot(rng, kind):
    """(A, B, c, mass, g, planar, positions (4, 3)) of a random hanging robot of ``kind``."""
    if kind == "planar2":
        A, B, c, mass, W, Hh = random_planar2(rng)
        P = np.column_stack([rng.uniform(0.25 * W, 0.75 * W, 4), rng.uniform(0.2 * Hh, 0.6 * Hh, 4), np.zeros(4)])
        return A, B, c, mass, G2, True, P
    m = 3 if kind == "three" else 4
    if m == 3:
        ang = np.array([0.0, 2.1, 4.2]) + rng.uniform(-0.2, 0.2, 3)
        A = np.column_stack([2 * np.cos(ang), 2 * np.sin(ang), np.full(3, 3.0) + rng.uniform(-0.2, 0.2, 3)])
        B = np.column_stack([0.2 * np.cos(ang + 0.3), 0.2 * np.sin(ang + 0.3), rng.uniform(0.0, 0.1, 3)])
        P = np.column_stack([rng.uniform(-0.6, 0.6, 4), rng.uniform(-0.6, 0.6, 4), rng.uniform(0.8, 2.0, 4)])
    else:
        a, b, h = rng.uniform(3.0, 6.0), rng.uniform(3.0, 5.0), rng.uniform(3.0, 5.0)
        A = np.array([[0, 0, h], [a, 0, h], [a, b, h], [0, b, h]]) + rng.uniform(-0.2, 0.2, (4, 3))
        x, y = rng.uniform(0.2, 0.5), rng.uniform(0.2, 0.4)
        B = np.array([[-x, -y, 0], [x, -y, 0], [x, y, 0], [-x, y, 0]]) + rng.uniform(-0.05, 0.05, (4, 3))
        P = np.column_stack([rng.uniform(0.25 * a, 0.75 * a, 4), rng.uniform(0.25 * b, 0.75 * b, 4),
                             rng.uniform(0.3 * h, 0.7 * h, 4)])
    c = np.array([rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), rng.uniform(-0.4, -0.1)])
    return A, B, c, rng.uniform(1.0, 80.0), G3, False, P


def dofs_of(planar):
    return hg.DOFS_PLANAR if planar else hg.DOFS_SPATIAL


def pose_of(x, p0, R0, planar):
    """(p, R): the chart x about (p0, R0): a translation, then a rotation vector on the left."""
    if planar:
        dp, w = np.array([x[0], x[1], 0.0]), np.array([0.0, 0.0, x[2]])
    else:
        dp, w = x[:3], x[3:]
    return p0 + dp, Rotation.from_rotvec(w).as_matrix() @ R0


def energy(x, robot, L0, EA, p0, R0):
    """The total potential energy [J]: the weight, and each stretched cable's elastic energy."""
    A, B, c, mass, g, planar = robot
    p, R = pose_of(x, p0, R0, planar)
    L = np.linalg.norm(A - p - B @ R.T, axis=1)
    s = np.maximum(L - L0, 0.0)
    return float(-mass * g @ (p + R @ c) + np.sum(EA / (2.0 * L0) * s * s))


def restoring(x, robot, L0, EA, p0, R0):
    """The wrench on the effector [N, N m] (moments about the platform origin), over the chart's coordinates."""
    A, B, c, mass, g, planar = robot
    p, R = pose_of(x, p0, R0, planar)
    l = A - p - B @ R.T
    L = np.linalg.norm(l, axis=1)
    t = EA * np.maximum(L - L0, 0.0) / L0
    F = (t / L)[:, None] * l
    f = F.sum(0) + mass * g
    mom = np.cross(B @ R.T, F).sum(0) + np.cross(R @ c, mass * g)
    w = np.concatenate([f, mom])
    return w[[0, 1, 5]] if planar else w


def minimise(robot, L0, EA, p0, R0, x0):
    """scipy BFGS on :func:`energy` from ``x0``; the chart's coordinates of the minimum it reaches."""
    weight = robot[3] * np.linalg.norm(robot[4])
    sol = minimize(energy, x0, args=(robot, L0, EA, p0, R0), method="BFGS", jac="3-point",
                   options={"gtol": 1e-10 * weight, "maxiter": 2000})
    return sol.x


def random_hangings(rng, per_kind, kinds=("planar2", "three", "four")):
    """(robot, geo, positions, their ideal hanging orientations) of ``per_kind`` random robots a kind."""
    for kind in kinds:
        for _ in range(per_kind):
            A, B, c, mass, g, planar, P = random_robot(rng, kind)
            geo = hg.Geometry(A, B, c, mass, g)
            yield (A, B, c, mass, g, planar), geo, P, hanging_orientations(geo, P, planar)


def hanging_cases(seed, kinds=("planar2", "three", "four")):
    """(robot, p, R, t, EA) at random positions of random robots where the effector hangs."""
    rng = np.random.default_rng(seed)
    out = []
    for robot, geo, P, h in random_hangings(rng, 3, kinds):
        for k in np.flatnonzero(h.feasible)[:2]:
            EA = geo.weight * 10.0 ** rng.uniform(2.0, 4.0, len(robot[0]))
            out.append((robot, P[k], h.rotation[k], h.tensions[k], EA))
    return out


def unstretched(robot, p, R, t, EA):
    """L0 [m] that hold the pose with tensions t: L / (1 + t / EA); a cable without tension is
    given 0.1 mm more than its length (slack: the module's softer side of a just slack cable,
    and differences across its kink would measure half its stiffness)."""
    A, B, *_ = robot
    L = np.linalg.norm(A - p - B @ R.T, axis=1)
    return np.where(t > 0, L / (1.0 + t / EA), L + 1e-4)


@pytest.mark.slow
@NO_KERNELS
def test_elastic_hanging_pose_is_the_energy_minimum_scipy_finds():
    """At its own unstretched lengths the hanging pose is a minimum of the total potential energy:
    BFGS from five starts about it (2 cm, 3 degrees) comes back to it, to 1e-6 m and 1e-6 rad,
    with its tensions; the compliance module calls it stable."""
    cases = hanging_cases(31)
    assert len(cases) >= 12
    rng = np.random.default_rng(7)
    for robot, p, R, t, EA in cases:
        planar = robot[5]
        geo = hg.Geometry(*robot[:5])
        s = hanging_stiffness(geo, p[None], R[None], t[None], dofs_of(planar), EA)
        assert s.stable[0]
        L0 = unstretched(robot, p, R, t, EA)
        n = 3 if planar else 6
        for _ in range(5):
            x0 = np.concatenate([rng.normal(0, 0.02, n // 2 if not planar else 2),
                                 rng.normal(0, 0.05, 3 if not planar else 1)])
            x = minimise(robot, L0, EA, p, R, x0)
            assert np.abs(x).max() < 1e-6, (p, x)
        # and the tensions at the minimum are the answer's
        A, B, *_ = robot
        L = np.linalg.norm(A - p - B @ R.T, axis=1)
        np.testing.assert_allclose(EA * np.maximum(L - L0, 0) / L0, t, atol=1e-9 * geo.weight)


@NO_KERNELS
def test_stiffness_matrix_is_minus_the_derivative_of_the_restoring_wrench():
    """K = -dw/dx at fixed unstretched lengths: central differences of the cables' elastic forces
    and the weight (moments about the platform origin), to 1e-6 of K's size."""
    from cdpr_design.statics.hanging.compliance import energy_hessian_many

    for robot, p, R, t, EA in hanging_cases(32):
        planar = robot[5]
        geo = hg.Geometry(*robot[:5])
        K = energy_hessian_many(geo, p[None], R[None], t[None], EA, dofs_of(planar))[0]
        L0 = unstretched(robot, p, R, t, EA)
        n = K.shape[0]
        assert np.abs(restoring(np.zeros(n), robot, L0, EA, p, R)).max() < 1e-8 * geo.weight  # an equilibrium
        Kfd = np.empty((n, n))
        h = 1e-6
        for j in range(n):
            e = np.zeros(n)
            e[j] = h
            Kfd[:, j] = -(restoring(e, robot, L0, EA, p, R) - restoring(-e, robot, L0, EA, p, R)) / (2 * h)
        np.testing.assert_allclose(K, Kfd, atol=1e-6 * np.abs(K).max())


@NO_KERNELS
def test_elastic_compliance_tends_to_the_rigid_one():
    """As EA grows the elastic cables' compliance tends to the rigid cables' (the reduced Hessian's):
    the difference falls like 1/EA."""
    for robot, p, R, t, EA in hanging_cases(33):
        planar = robot[5]
        geo = hg.Geometry(*robot[:5])
        rigid = hanging_stiffness(geo, p[None], R[None], t[None], dofs_of(planar))
        assert rigid.stable[0]
        C = rigid.compliance[0]
        errs = []
        for scale in (1e2, 1e4):
            el = hanging_stiffness(geo, p[None], R[None], t[None], dofs_of(planar), EA * scale)
            errs.append(np.abs(el.compliance[0] - C).max() / np.abs(C).max())
        assert errs[1] < 1e-2 and errs[1] < 0.03 * errs[0], errs  # first order in 1/EA


def central_gradient(fun, x, h=1e-6):
    """Central differences of a scalar or vector function of x (a row per coordinate)."""
    cols = []
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = h
        cols.append((np.asarray(fun(x + e)) - np.asarray(fun(x - e))) / (2 * h))
    return np.array(cols)


def rigid_displacement(robot, p, R, t, force):
    """The pose [chart] of rigid cables with ``force`` [N] added at the platform origin (potential
    -force . p), the taut cables' lengths held: scipy ``root`` on the Lagrange conditions
    grad U + sum lambda_i grad |l_i| = 0, |l_i| = L_i, the derivatives by central differences."""
    from scipy.optimize import root

    A, B, c, mass, g, planar = robot
    L = np.linalg.norm(A - p - B @ R.T, axis=1)
    weight = mass * np.linalg.norm(g)
    taut = np.flatnonzero(t > 1e-9 * weight)
    n = 3 if planar else 6

    def length(x):
        q, Q = pose_of(x, p, R, planar)
        return np.linalg.norm(A - q - B @ Q.T, axis=1)[taut]

    def U(x):  # relative to the hanging pose's energy [J]
        q, Q = pose_of(x, p, R, planar)
        return float(-mass * g @ (q - p + (Q - R) @ c) - force @ (q - p))

    def kkt(z):
        x, lam = z[:n], z[n:]
        return np.concatenate([(central_gradient(U, x) + central_gradient(length, x) @ lam) / weight,
                               length(x) - L[taut]])

    sol = root(kkt, np.concatenate([np.zeros(n), t[taut]]), method="hybr", options={"xtol": 1e-14})
    assert np.abs(kkt(sol.x)).max() < 1e-8, sol.message  # the differences limit it, not the solver
    return sol.x[:n]


@pytest.mark.slow
@NO_KERNELS
def test_rigid_compliance_against_the_lagrange_conditions_under_a_small_force():
    """Rigid cables: a small force f at the platform origin moves the hanging effector by C f (to
    first order; Richardson's extrapolation from f and 2 f): the Lagrange conditions of the weight
    and the force, the taut cables' lengths held, solved by scipy."""
    rng = np.random.default_rng(9)
    for robot, p, R, t, _ in hanging_cases(34):
        planar = robot[5]
        geo = hg.Geometry(*robot[:5])
        s = hanging_stiffness(geo, p[None], R[None], t[None], dofs_of(planar))
        C = s.compliance[0]
        d = 2 if planar else 3
        f = rng.normal(size=d)
        f *= 1e-3 * geo.weight / np.linalg.norm(f)
        # Richardson: the displacements under f and 2 f, their second-order terms cancelled
        x1, x2 = (rigid_displacement(robot, p, R, t, np.concatenate([s * f, np.zeros(3 - d)])) for s in (1, 2))
        x = 2 * x1 - x2 / 2
        want = C[:, :d] @ f
        assert np.abs(x - want).max() <= 1e-3 * np.abs(want).max(), (x, want)


@pytest.mark.slow
@NO_KERNELS
def test_unstable_equilibria_are_flagged_and_scipy_leaves_them():
    """A balanced pulling orientation that is not stable (an upside-down planar body, from the
    alternatives of the closed form): the compliance module calls it unstable on rigid and on
    elastic cables, and BFGS on the energy at its unstretched lengths goes downhill away from it."""
    rng = np.random.default_rng(35)
    found = 0
    for _ in range(40):
        A, B, c, mass, W, Hh = random_planar2(rng)
        p = np.array([rng.uniform(0.3 * W, 0.7 * W), rng.uniform(0.2 * Hh, 0.6 * Hh), 0.0])
        h = hanging_pose_arrays(A, B, c, mass, G2, p, True)
        for phi, t, stable in h.alternatives:
            if stable or np.any(t <= 0):
                continue
            robot = (A, B, c, mass, G2, True)
            geo = hg.Geometry(*robot[:5])
            R = hg.rot_z(phi)
            EA = geo.weight * 1e3 * np.ones(2)
            for ea in (None, EA):
                s = hanging_stiffness(geo, p[None], R[None], np.asarray(t)[None], hg.DOFS_PLANAR, ea)
                assert not s.stable[0] and np.isnan(s.min_stiffness[0])
            L0 = unstretched(robot, p, R, np.asarray(t), EA)
            x = minimise(robot, L0, EA, p, R, rng.normal(0, 1e-4, 3))
            assert np.abs(x).max() > 1e-2
            assert energy(x, robot, L0, EA, p, R) < energy(np.zeros(3), robot, L0, EA, p, R)  # downhill
            found += 1
    assert found >= 3


@NO_KERNELS
def test_soft_cables_can_unsettle_a_pose_rigid_cables_hold():
    """Stability on elastic cables is the energy Hessian's, not the rigid cables' reduced one: a
    planar body whose centre of mass is above its attachments hangs stably on rigid cables, and
    on cables soft enough it does not (K = H_L + sum k g g^T turns indefinite); BFGS agrees on both
    sides of the critical stiffness."""
    rng = np.random.default_rng(36)
    for _ in range(200):
        A, B, c, mass, W, Hh = random_planar2(rng)
        c = np.array([c[0], abs(c[1]) + 0.1, 0.0])  # well above the attachments
        geo = hg.Geometry(A, B, c, mass, G2)
        P = np.column_stack([rng.uniform(0.3 * W, 0.7 * W, 6), rng.uniform(0.2 * Hh, 0.6 * Hh, 6), np.zeros(6)])
        h = hanging_orientations(geo, P, True)
        for k in np.flatnonzero(h.feasible):
            p, R, t = P[k], h.rotation[k], h.tensions[k]
            soft = hanging_stiffness(geo, p[None], R[None], t[None], hg.DOFS_PLANAR, 1e-3 * t.max() * np.ones(2))
            if soft.stable[0]:
                continue
            robot = (A, B, c, mass, G2, True)
            hard = t.max() * 1e4 * np.ones(2)
            assert hanging_stiffness(geo, p[None], R[None], t[None], hg.DOFS_PLANAR, hard).stable[0]
            x = minimise(robot, unstretched(robot, p, R, t, hard), hard, p, R, rng.normal(0, 1e-3, 3))
            assert np.abs(x).max() < 1e-6
            EAs = 1e-3 * t.max() * np.ones(2)
            x = minimise(robot, unstretched(robot, p, R, t, EAs), EAs, p, R, rng.normal(0, 1e-4, 3))
            assert np.abs(x).max() > 1e-3
            return
    pytest.fail("no pose that soft cables unsettle was found")
