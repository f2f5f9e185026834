"""Kinematics and statics: closed forms, the paper's equations, finite differences."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cdpr_design import kernels as K
from cdpr_design.statics import kinematics as kin
from cdpr_design.model import spec
from cdpr_design import api
from cdpr_design.statics.robot import combinations

from .helpers import PLANAR2, point_mass
from .reference.hsm import hsm_margin
from .reference.kinematics import length_rates


@pytest.mark.parametrize("half_span,depth,mass", [(1.0, 1.0, 1.0), (0.75, 0.3, 2.5), (2.0, 3.0, 0.4)])
def test_symmetric_point_mass_closed_form(half_span, depth, mass):
    """Two symmetric cables holding a point mass: T = m g / (2 sin theta)."""
    d = point_mass([(-half_span, 0.0), (half_span, 0.0)], mass)
    r = api.pose(d, [0.0, -depth])
    theta = np.arctan2(depth, half_span)
    expected = mass * 9.81 / (2 * np.sin(theta))
    np.testing.assert_allclose(r.tensions, [expected, expected], rtol=1e-12)
    assert r.feasible


@pytest.mark.slow
def test_algorithms_reference_point():
    """algorithms.md: outlets (0,2),(3,2), point (1,1), m g = 9.81 N, t in [1, 40]:
    t = (9.2489567, 7.3119423) N, capacity margin 5.9880342 N."""
    d = point_mass([(0.0, 2.0), (3.0, 2.0)], 1.0, (1.0, 40.0))
    r = api.pose(d, [1.0, 1.0])
    np.testing.assert_allclose(r.tensions, [9.2489567, 7.3119423], atol=5e-8)
    assert r.margin == pytest.approx(5.9880342, abs=5e-8)
    # the general hyperplane-shifting margin gives the same figure
    ok, margin = hsm_margin(r.W, r.wrench[None, :], d.tension_min, d.tension_max,
                              combinations(2, 2))
    assert ok and margin == pytest.approx(5.9880342, abs=5e-8)


def paper_fk(design, l1, l2):
    """The seed paper's eq. (4)-(5) written literally (outlets at equal height,
    attachments at (-Bx/2, By/2) and (Bx/2, By/2))."""
    A1x, A1y = design.outlets[0, :2]
    A2x = design.outlets[1, 0]
    Bx, By = design.effector.size[0], design.effector.size[1]
    px = (A1x**2 - A2x**2 + Bx * A1x + Bx * A2x - l1**2 + l2**2) / (2 * (A1x - A2x + Bx))
    py = A1y - np.sqrt(l1**2 - (px - Bx / 2 - A1x) ** 2) - By / 2
    return np.array([px, py])


def paper_ik(design, p):
    """The seed paper's eq. (2)-(3)."""
    A = design.outlets
    Bx, By = design.effector.size[0], design.effector.size[1]
    l1 = np.hypot(p[0] - Bx / 2 - A[0, 0], p[1] + By / 2 - A[0, 1])
    l2 = np.hypot(p[0] + Bx / 2 - A[1, 0], p[1] + By / 2 - A[1, 1])
    return np.array([l1, l2])


def test_ik_and_fk_match_paper_equations(planar2):
    rng = np.random.default_rng(1)
    for p in rng.uniform([0.1, 0.05], [1.4, 1.35], size=(300, 2)):
        L = kin.inverse_kinematics(planar2, p)
        np.testing.assert_allclose(L, paper_ik(planar2, p), rtol=1e-13)
        np.testing.assert_allclose(kin.forward_kinematics(planar2, L).pose, paper_fk(planar2, *L),
                                   atol=1e-10)


def test_fk_ik_round_trip_over_paper_workspace(planar2):
    """FK(IK(p)) = p over the whole grid of the paper's workspace (closed form)."""
    xs = np.linspace(0.0, 1.5, 31)
    ys = np.linspace(0.0, 1.42, 31)  # below the outlets' height minus the attachment offset
    worst = 0.0
    for x in xs:
        for y in ys:
            L = kin.inverse_kinematics(planar2, [x, y])
            r = kin.forward_kinematics(planar2, L)
            assert r.method == "closed-form"
            worst = max(worst, float(np.max(np.abs(r.pose - [x, y]))))
            assert r.residual < 1e-9
    assert worst < 1e-9


def random_design(rng, motion, m):
    d = 2 if motion in ("2T", "1R2T") else 3
    cables = [{"name": f"c{i}", "outlet": rng.uniform(-2, 2, d).tolist(),
               "attachment": rng.uniform(-0.3, 0.3, d).tolist()} for i in range(m)]
    return spec.from_dict({
        "name": "r", "motion": motion, "frame": {"lower": [-2.0] * d, "upper": [2.0] * d},
        "effector": {"mass": 1.0, "size": [0.2] * d, "center_of_mass": rng.uniform(-0.05, 0.05, d).tolist()},
        "tension": [0.0, 100.0], "cables": cables})


def random_pose(rng, design):
    mot = design.motion
    pos = rng.uniform(-0.5, 0.5, mot.dim)
    rot = rng.uniform(-0.4, 0.4, len(mot.rotation_coords))
    return np.concatenate([pos, rot])


@pytest.mark.parametrize("motion,m", [("2T", 3), ("1R2T", 4), ("3T", 5), ("3R3T", 8)])
def test_fk_numerical_round_trip(motion, m):
    rng = np.random.default_rng(7)
    design = random_design(rng, motion, m)
    for _ in range(10):
        p = random_pose(rng, design)
        L = kin.inverse_kinematics(design, p)
        r = kin.forward_kinematics(design, L, guess=p + rng.normal(0, 0.02, p.size))
        assert r.residual < 1e-9
        np.testing.assert_allclose(r.pose, p, atol=1e-7)


@pytest.mark.parametrize("motion,m", [("2T", 2), ("1R2T", 4), ("3T", 4), ("3R3T", 8)])
def test_structure_matrix_is_minus_length_jacobian(motion, m):
    """dL/dt = -W_full^T [v; omega]: the structure matrix against finite differences of IK."""
    rng = np.random.default_rng(3)
    design = random_design(rng, motion, m)
    h = 1e-6
    for _ in range(20):
        p = random_pose(rng, design)
        v = rng.normal(size=p.size)
        fd = (kin.inverse_kinematics(design, p + h * v) - kin.inverse_kinematics(design, p - h * v)) / (2 * h)
        np.testing.assert_allclose(length_rates(design, p, v), fd, atol=1e-7)
        # the structure matrix's translational rows are -dL/dx
        W = kin.structure_matrix(design, p)
        for k in range(design.motion.dim):
            e = np.zeros(p.size)
            e[k] = 1.0
            dk = (kin.inverse_kinematics(design, p + h * e) - kin.inverse_kinematics(design, p - h * e)) / (2 * h)
            np.testing.assert_allclose(W[k], -dk, atol=1e-7)


@pytest.mark.parametrize("motion,m", [("2T", 3), ("1R2T", 4), ("3T", 6), ("3R3T", 8)])
def test_kernel_structure_matrix_matches_numpy(motion, m):
    rng = np.random.default_rng(11)
    design = random_design(rng, motion, m)
    for _ in range(50):
        p = random_pose(rng, design)
        full = design.full_pose(p)
        R = kin.rotation_matrix(*full[3:])
        Wk = np.empty((design.n, design.m))
        Lk = np.empty(design.m)
        K.structure_matrix(full[0], full[1], full[2], design.attachments @ R.T, design.outlets,
                           design.rows, Wk, Lk)
        np.testing.assert_allclose(Wk, kin.structure_matrix(design, p), atol=1e-14)
        np.testing.assert_allclose(Lk, kin.inverse_kinematics(design, p), rtol=1e-14)
        R2 = np.empty((3, 3))
        K.rotation(*full[3:], R2)
        np.testing.assert_allclose(R2, R, atol=1e-15)


def test_zero_length_cable_is_rank_deficient(planar2):
    # the platform origin placed so that c1's attachment sits on its outlet
    r = api.pose(planar2, [0.06, 1.44])
    assert not r.feasible and np.isnan(r.margin) and np.isnan(r.tensions).all()
    assert r.lengths[0] == pytest.approx(0.0, abs=1e-15)


@settings(max_examples=60, deadline=None)
@given(dx=st.floats(-10, 10), dy=st.floats(-10, 10),
       px=st.floats(0.1, 1.4), py=st.floats(0.05, 1.3))
def test_translation_invariance(dx, dy, px, py):
    """Moving the whole robot (frame, outlets and pose) changes no tension or margin."""
    base = spec.load(PLANAR2)
    moved_raw = copy.deepcopy(base.raw)
    for c in moved_raw["cables"]:
        c["outlet"] = [c["outlet"][0] + dx, c["outlet"][1] + dy]
    moved_raw["frame"] = {"lower": [dx, dy], "upper": [1.5 + dx, 1.5 + dy]}
    moved_raw["workspace"]["grid"] = {"step": 0.01}
    moved = spec.from_dict(moved_raw)
    a = api.pose(base, [px, py])
    b = api.pose(moved, [px + dx, py + dy])
    assert a.feasible == b.feasible
    np.testing.assert_allclose(b.tensions, a.tensions, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(b.margin, a.margin, rtol=1e-9, atol=1e-9)


def test_gravity_and_inertial_wrench_planar_rigid_body():
    d = spec.from_dict({
        "name": "b", "motion": "1R2T", "frame": {"lower": [0, 0], "upper": [2, 2]},
        "effector": {"mass": 2.0, "size": [0.2, 0.1], "center_of_mass": [0.1, 0.0], "inertia": 0.05},
        "tension": [0, 100],
        "cables": [{"name": f"c{i}", "outlet": [float(i % 2) * 2, 2.0], "attachment": [0, 0]} for i in range(3)],
    })
    # COM at (0.1, 0) rotated by 90 degrees sits at (0, 0.1): gravity's moment is zero there
    w = kin.gravity_wrench(d, [1.0, 1.0, np.pi / 2])
    np.testing.assert_allclose(w, [0.0, -2 * 9.81, 0.0], atol=1e-12)
    w0 = kin.gravity_wrench(d, [1.0, 1.0, 0.0])
    np.testing.assert_allclose(w0, [0.0, -2 * 9.81, 0.1 * -2 * 9.81], atol=1e-12)
    # d'Alembert: accelerating the origin at 1 m/s^2 in x with the body at rest
    wi = kin.inertial_wrench(d, [1.0, 1.0, 0.0], [1.0, 0.0])
    np.testing.assert_allclose(wi, [-2.0, 0.0, 0.0], atol=1e-12)
    # angular acceleration about z: -I_com alpha plus the COM's tangential acceleration moment
    wa = kin.inertial_wrench(d, [1.0, 1.0, 0.0], [0.0, 0.0], angular_acceleration=[0, 0, 1.0])
    np.testing.assert_allclose(wa, [0.0, -2 * 0.1, -(0.05 + 2 * 0.1**2)], atol=1e-12)


@pytest.mark.parametrize("name", ["ipanema3", "crane4", "sagging40"])
@pytest.mark.parametrize("value", [1e300, 1e5, -1.0, float("nan")])
def test_every_fk_refuses_lengths_out_of_range(name, value):
    """The library's three forward kinematics (straight cables, a hanging effector, elastic and
    sagging cables) take the range ``--lengths`` takes, 0 to 10 km: 1e300 m overflowed the first
    two (numpy's warnings on stderr, a "pose" 1e300 m away) and made the third raise scipy's own
    "initial guess outside of bounds"."""
    import warnings

    from cdpr_design.errors import InputError
    from cdpr_design.jobs import hanging as hjob
    from cdpr_design.jobs import pose as job

    from .helpers import ROOT, resolved

    design = spec.load(ROOT / "designs" / f"{name}.yaml")
    solve = {"ipanema3": kin.forward_kinematics, "crane4": hjob.fk_data, "sagging40": job.cable_fk_data}[name]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(InputError, match=r"cable lengths must be finite and in [\[(]0, 10000\] m"):
            solve(design if name == "ipanema3" else resolved(design, "fk"), [value] * design.m)
