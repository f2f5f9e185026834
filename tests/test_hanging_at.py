"""The hanging orientation at commanded positions (statics.hanging.at_positions) and the held-orientation
forward problem, against slow independent references.

References (none shares code with the implementation):

* the compiled one-position-at-a-time form of the planar two-cable method,
  ``tests/reference/hanging_kernel.py``, for the product's vectorised closed form (and, in
  test_hanging.py, the closed form against a brute-force instantaneous-centre scan);
* scipy ``least_squares`` on force and moment balance from many random starts, per set of
  taut cables, with its own rotations (scipy's Rotation) and cross products; stability by
  scipy SLSQP energy minimisation started from perturbed poses under the same lengths
  (a stable equilibrium is a strict local minimum: every run comes back);
* scipy SLSQP on min |w|^2 subject to balance for the family of a spatial body on four taut
  cables;
* scipy SLSQP energy minimisation with the orientation held, for the held forward problem.
"""

from __future__ import annotations

import importlib.util
import itertools
import math

import numpy as np
import pytest
from scipy.optimize import least_squares, minimize
from scipy.spatial.transform import Rotation

from cdpr_design.kernels.pose import Outputs, Statics
from cdpr_design.model import spec
from cdpr_design.statics import hanging as H
from cdpr_design.statics.hanging import at_positions, results
from cdpr_design.statics.hanging import geometry as hg
from cdpr_design.statics.hanging.balance import Balance
from cdpr_design.statics import kinematics as kin
from cdpr_design import api
from tests.helpers import DESIGNS, NO_KERNELS, ROOT
from tests.reference import hanging_kernel as K
from tests.test_hanging import G2, G3, check_equilibrium, random_planar2

UP3 = np.array([0.0, 0.0, 1.0])


def test_status_codes_match_the_reference():
    assert (results.OK, results.PUSHING, results.UNSTABLE, results.NO_BALANCE, results.DEGENERATE) == (
        K.TILT_OK, K.TILT_PUSHING, K.TILT_UNSTABLE, K.TILT_NO_BALANCE, K.TILT_DEGENERATE)
    assert len(results.REASONS) == len(K.TILT_REASONS)


def test_closed_form_equals_the_reference_kernel():
    """The product's closed form (at a unit weight, scaled back) and the reference: the same
    roots, tensions, stability and choice on random designs, positions inside and outside their
    frames (the closed form is also held against a brute-force scan in test_hanging)."""
    rng = np.random.default_rng(21)
    compared = 0
    for _ in range(20):
        A, B, c, mass, W, Hh = random_planar2(rng)
        P = np.column_stack([rng.uniform(-0.2 * W, 1.2 * W, 300), rng.uniform(-0.2 * Hh, 1.1 * Hh, 300)])
        phi, t, h, status, nbal = K.hanging_tilt_batch(A, B, c, mass, G2, P)
        geo = hg.Geometry(A, B, c, mass, G2)
        got = at_positions.hanging_orientations(geo, P, True)
        assert np.array_equal(got.status, status)
        ok = status == K.TILT_OK
        compared += int(ok.sum())
        np.testing.assert_allclose(got.orientation[ok], phi[ok], rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.tensions[ok], t[ok], rtol=1e-10, atol=1e-10 * mass)
        np.testing.assert_allclose(got.hessian_min[ok], h[ok], rtol=1e-8)
        assert np.isnan(got.orientation[~ok]).all() and np.isnan(got.tensions[~ok]).all()
    assert compared > 2000


@NO_KERNELS
@pytest.mark.parametrize("name", ["planar2", "pointmass3"])
def test_the_weight_scales_the_tensions_and_leaves_the_orientation(name):
    """Balance is linear in the weight: any mass hangs in the same orientation, with tensions and
    reduced Hessian in proportion (the closed forms, to rounding; the search of other bodies to about
    1e-9 deg: test_crane4s_orientation_does_not_depend_on_its_mass).  The smallest masses used to underflow the planar
    two-cable roots' tolerances (2.2e-308 kg: a LinAlgError traceback)."""
    design = spec.load(DESIGNS / f"{name}.yaml")
    A, B, c, mass, g, planar = H.design_arrays(design)
    rng = np.random.default_rng(5)
    lo, hi = np.asarray(design.frame_lower), np.asarray(design.frame_upper)
    P = lo + rng.uniform(0.1, 0.9, (60, 3)) * (hi - lo)
    P = P[:, :2] if planar else P
    ref = at_positions.hanging_orientations(hg.Geometry(A, B, c, 1.0, g), P, planar)
    ok = ref.status == results.OK
    assert ok.sum() >= 10
    for m in (2.2250738585072014e-308, 1e-200, 1e-3, 1e6, 1e200):
        got = at_positions.hanging_orientations(hg.Geometry(A, B, c, m, g), P, planar)
        assert np.array_equal(got.status, ref.status), m
        np.testing.assert_allclose(got.rotation[ok], ref.rotation[ok], rtol=0, atol=1e-15)
        np.testing.assert_allclose(got.tensions[ok] / m, ref.tensions[ok], rtol=1e-14, atol=0)
        np.testing.assert_allclose(got.hessian_min[ok] / m, ref.hessian_min[ok], rtol=1e-14, atol=0)


# ---------------------------------------------------------------------------
# reference: balance by scipy from many starts, stability by energy minimisation
# ---------------------------------------------------------------------------

def ref_balanced(A, B, c, mass, g, p, S, starts):
    """Balanced rotations of the cables S taut at position p with tensions >= 0 (distinct)."""
    f = mass * g
    weight = mass * np.linalg.norm(g)

    def residual(x):
        R = Rotation.from_rotvec(x[:3]).as_matrix()
        Rb = B[S] @ R.T
        l = A[S] - p - Rb
        u = l / np.linalg.norm(l, axis=1)[:, None]
        force = u.T @ x[3:] + f
        moment = np.cross(Rb, u).T @ x[3:] + np.cross(R @ c, f)
        return np.concatenate([force, moment / 0.3]) / weight

    out = []
    for w0 in starts:
        s = least_squares(residual, np.concatenate([w0, np.full(len(S), weight / len(S))]),
                          xtol=1e-15, ftol=1e-15, gtol=1e-15)
        if np.max(np.abs(s.fun)) > 1e-10 or s.x[3:].min() < -1e-9 * weight:
            continue
        R = Rotation.from_rotvec(s.x[:3]).as_matrix()
        if not any(np.linalg.norm(R - Q) < 1e-6 for Q, _ in out):
            out.append((R, s.x[3:]))
    return out


def ref_is_local_minimum(A, B, c, mass, g, p, R, rng, tries=4, size=0.02):
    """SLSQP energy minimisation under the lengths |a_i - p - R b_i| from perturbed poses
    comes back to (p, R): a strict local minimum (a stable equilibrium)."""
    rho = np.linalg.norm(A - p - B @ R.T, axis=1)

    def conf(x):
        return p + x[:3], Rotation.from_rotvec(x[3:]).as_matrix() @ R

    def energy(x):
        q, Q = conf(x)
        return -mass * g @ (q + Q @ c)

    def cons(x):
        q, Q = conf(x)
        return rho ** 2 - np.sum((A - q - B @ Q.T) ** 2, axis=1)

    e0 = energy(np.zeros(6))
    for _ in range(tries):
        x0 = rng.normal(size=6) * size
        s = minimize(energy, x0, method="SLSQP", constraints=[{"type": "ineq", "fun": cons}],
                     options={"ftol": 1e-15, "maxiter": 500})
        # back within 1e-3 (m, rad); SLSQP's last iterate may overstep the lengths by ~1e-6 m
        if np.linalg.norm(s.x) > 1e-3 or (cons(s.x).min() > -1e-9 and energy(s.x) < e0 - 1e-7 * mass):
            return False
    return True


def crane():
    d = spec.load(DESIGNS / "crane4.yaml")
    return d, H.design_arrays(d)


@pytest.mark.slow
@NO_KERNELS
@pytest.mark.parametrize("case", ["three", "crane"])
def test_spatial_hanging_against_scipy(case):
    """The least tilted stable pulling orientation at random positions: nothing the reference
    finds (12 starts per set of taut cables) is both stable and less tilted, and the answer
    itself is a balanced, stable pose (reference minimisation comes back to it)."""
    rng = np.random.default_rng(3 if case == "three" else 4)
    if case == "three":
        ang = np.array([0.0, 2.1, 4.2])
        A = np.column_stack([2 * np.cos(ang), 2 * np.sin(ang), np.full(3, 3.0)])
        B = np.column_stack([0.2 * np.cos(ang + 0.3), 0.2 * np.sin(ang + 0.3), np.full(3, 0.05)])
        c, mass, sets = np.array([0.02, -0.01, -0.1]), 2.0, [(0, 1, 2)]
        P = np.column_stack([rng.uniform(-0.8, 0.8, 4), rng.uniform(-0.8, 0.8, 4), rng.uniform(0.8, 2.2, 4)])
    else:
        _, (A, B, c, mass, _, _) = crane()
        sets = [tuple(s) for s in itertools.combinations(range(4), 3)]
        P = np.column_stack([rng.uniform(1.0, 4.0, 3), rng.uniform(0.8, 3.2, 3), rng.uniform(0.8, 3.3, 3)])
    geo = hg.Geometry(A, B, c, mass, G3)
    got = at_positions.hanging_orientations(geo, P, False)
    starts = [np.zeros(3)] + [rng.normal(size=3) * 0.7 for _ in range(11)]
    for k, p in enumerate(P):
        assert got.status[k] == results.OK
        R = got.rotation[k]
        assert ref_is_local_minimum(A, B, c, mass, G3, p, R, rng)
        e = H.Equilibrium(p, R, got.tensions[k], (), 0.0, True, 0.0, 0.0, planar=False)
        check_equilibrium(A, B, c, mass, G3, np.linalg.norm(A - p - B @ R.T, axis=1), e, False)
        better = []
        for S in sets:
            for Q, _ in ref_balanced(A, B, c, mass, G3, p, list(S), starts):
                tilt = math.degrees(math.acos(np.clip(UP3 @ Q @ UP3, -1, 1)))
                if tilt < got.tilt_deg[k] - 1e-6 and ref_is_local_minimum(A, B, c, mass, G3, p, Q, rng):
                    better.append(tilt)
        assert not better, (p, got.tilt_deg[k], better)


def ref_least_tilt():
    """The independent least-tilt search of scripts/check_hanging_least_tilt.py (scipy SLSQP)."""
    spec_ = importlib.util.spec_from_file_location("check_hanging_least_tilt",
                                                   ROOT / "scripts" / "check_hanging_least_tilt.py")
    module = importlib.util.module_from_spec(spec_)
    spec_.loader.exec_module(module)
    return module.least_tilt_reference


@pytest.mark.slow
@NO_KERNELS
def test_four_cables_hang_in_their_least_tilted_pulling_orientation():
    """crane4 at random positions: no balanced orientation with every tension >= 0 that is
    stable is less tilted than the answer (scipy SLSQP from 8 random starts, least tilt
    subject to balance and tensions >= 0), and at most positions SLSQP's least tilted one is
    the answer.  The Newton search alone (before the march along the four-cable family) was
    more tilted at about half of such positions, by up to 2.2 deg."""
    d, (A, B, c, mass, _, _) = crane()
    geo = hg.Geometry(A, B, c, mass, G3)
    rng = np.random.default_rng(11)
    lo, hi = np.asarray(d.frame_lower), np.asarray(d.frame_upper)
    P = lo + rng.uniform(0.1, 0.9, (10, 3)) * (hi - lo)
    got = at_positions.hanging_orientations(geo, P, False)
    assert np.all(got.status == results.OK)
    same = no_less_tilted_stable(A, B, c, mass, P, got, rng)
    four = int(np.sum(np.all(got.tensions > 1e-6 * geo.weight, axis=1)))
    assert same >= 8 and four >= 3, (same, four)


def no_less_tilted_stable(A, B, c, mass, P, got, rng) -> int:
    """Asserts that at no position of P is the least tilted orientation scipy SLSQP finds (8
    random starts) both less tilted than the answer ``got`` and stable; returns at how many
    it is the answer's tilt (to 1e-4 deg)."""
    reference = ref_least_tilt()
    same = 0
    for k, p in enumerate(P):
        tilt, R, _ = reference(A, B, c, mass, G3, p, 8, rng)
        assert math.isfinite(tilt)
        if tilt < got.tilt_deg[k] - 1e-4:  # only an unstable orientation may be less tilted
            assert not ref_is_local_minimum(A, B, c, mass, G3, p, R, rng), (p, got.tilt_deg[k], tilt)
        same += abs(tilt - got.tilt_deg[k]) <= 1e-4
    return same


@pytest.mark.slow
@NO_KERNELS
def test_five_cables_hang_in_their_least_tilted_pulling_orientation():
    """tests/data/crane5.yaml (crane4 with a fifth cable from the middle of its front top
    edge to the middle of the lifting frame's front edge) at random positions: as for four
    cables, nothing scipy SLSQP finds (8 random starts) is less tilted and stable.  Before
    the walk along the edges of its two-parameter family the answer was more tilted than
    SLSQP's at 13 of 30 such positions, by up to 2.1 deg (at (1.5, 1.5, 2) it was 14.457
    deg, more than crane4's 14.415 deg without the fifth cable, which can always hang
    slack)."""
    d, (A, B, c, mass, _, _) = crane()
    A5, B5, c5, mass5, _, _ = H.design_arrays(spec.load(ROOT / "tests" / "data" / "crane5.yaml"))
    np.testing.assert_array_equal(A5[:4], A)  # crane4's cables and load, and the fifth
    np.testing.assert_array_equal(B5[:4], B)
    assert np.array_equal(c5, c) and mass5 == mass
    geo = hg.Geometry(A5, B5, c, mass, G3)
    rng = np.random.default_rng(12)
    lo, hi = np.asarray(d.frame_lower), np.asarray(d.frame_upper)
    P = np.vstack([[1.5, 1.5, 2.0], lo + rng.uniform(0.1, 0.9, (9, 3)) * (hi - lo)])
    got = at_positions.hanging_orientations(geo, P, False)
    assert np.all(got.status == results.OK)
    four = at_positions.hanging_orientations(hg.Geometry(A, B, c, mass, G3), P[:1], False)
    assert got.tilt_deg[0] <= four.tilt_deg[0] + 1e-9
    same = no_less_tilted_stable(A5, B5, c, mass, P, got, rng)
    assert same >= 8, same


@pytest.mark.slow
@NO_KERNELS
def test_crane4s_orientation_does_not_depend_on_its_mass():
    """Balance is linear in the weight, so any mass hangs in the same orientation with
    tensions in proportion.  The Newton search from the nominal orientation alone did not
    keep to it: at 20 of these 60 positions crane4's 60 kg answer was more tilted than its
    0.5 kg one, by up to 2.2 deg (which family member it reached turned on rounding).  The
    tilt agrees to 1e-9 deg; where the answer is the least tilted member of a four-cable family
    it is a minimum along a curve, whose place is fixed only to about the square root of the
    rounding (rotations to 1e-7, tensions over the weight to 1e-6)."""
    d, (A, B, c, mass, g, _) = crane()
    rng = np.random.default_rng(5)
    lo, hi = np.asarray(d.frame_lower), np.asarray(d.frame_upper)
    P = lo + (hi - lo) * (0.1 + 0.8 * rng.random((60, 3)))
    ref = at_positions.hanging_orientations(hg.Geometry(A, B, c, mass, g), P, False)
    assert np.all(ref.status == results.OK)
    for m in (0.5, 1.0, 5000.0):
        got = at_positions.hanging_orientations(hg.Geometry(A, B, c, m, g), P, False)
        assert np.array_equal(got.status, ref.status), m
        np.testing.assert_allclose(got.tilt_deg, ref.tilt_deg, rtol=0, atol=1e-9, err_msg=str(m))
        np.testing.assert_allclose(got.rotation, ref.rotation, rtol=0, atol=1e-7, err_msg=str(m))
        np.testing.assert_allclose(got.tensions / m, ref.tensions / mass, rtol=0, atol=1e-6 * 9.81, err_msg=str(m))


@NO_KERNELS
def test_crane_below_its_centre_hangs_level_in_its_nominal_yaw():
    """Straight below the middle of its bay crane4 hangs level at every yaw of a range (its
    four-cable family is a turn about the vertical, every member equally tilted); the answer
    is the member nearest the nominal orientation: yaw 0 and four equal tensions, each
    W / (4 u_z) with u_z the vertical component of a cable's unit vector.  Before ties were
    broken the march stopped at whichever member rounding made least tilted (at z = 2.25 m
    yaw -0.03 rad, tensions 10.6 and 530.7 N instead of 270.7 N each).  With another nominal
    yaw in the range, the answer turns to it."""
    d, (A, B, c, mass, g, _) = crane()
    geo = hg.Geometry(A, B, c, mass, g)
    P = np.array([[2.5, 2.0, z] for z in (0.5, 1.0, 1.5, 2.25, 2.75, 3.5)])
    got = at_positions.hanging_orientations(geo, P, False)
    assert np.all(got.status == results.OK)
    np.testing.assert_allclose(got.rotation, np.broadcast_to(np.eye(3), got.rotation.shape), rtol=0, atol=1e-8)
    for k, p in enumerate(P):
        u = A - p - B
        uz = u[:, 2] / np.linalg.norm(u, axis=1)
        np.testing.assert_allclose(got.tensions[k], geo.weight / (4 * uz), rtol=1e-7)
    turned = at_positions.hanging_orientations(geo, P[3:4], False, nominal=hg.rot_z(0.02))
    assert turned.status[0] == results.OK and turned.tilt_deg[0] < 1e-9
    np.testing.assert_allclose(turned.rotation[0], hg.rot_z(0.02), rtol=0, atol=1e-8)
    assert np.ptp(turned.tensions[0]) > 50.0  # a member off the symmetric one carries unequal tensions


@NO_KERNELS
@pytest.mark.parametrize("position, tilt, slack", [
    ([1.0, 1.0, 2.0], 24.787, (1,)),   # the least tilted pulling orientation has c2 just slack
    ([1.5, 1.5, 2.0], 14.415, ()),     # off the symmetry planes too, all four can pull
])
def test_crane_hangs_from_three_or_four_cables_off_centre(position, tilt, slack):
    """Off its symmetry planes crane4 hangs from three cables at some positions, the fourth
    slack (zero tension, its length exactly the distance), and from all four at others; the
    lengths of the answer bring it back there (fk: the pose is where it rests)."""
    d, _ = crane()
    at = H.hanging_pose(d, position)
    assert at.feasible and at.tilt_deg == pytest.approx(tilt, abs=1e-3)
    assert tuple(np.flatnonzero(at.tensions == 0)) == slack and np.all(np.delete(at.tensions, slack) > 1.0)
    back = H.fk(d, at.lengths)
    np.testing.assert_allclose(back.position, position, atol=1e-8)
    np.testing.assert_allclose(back.rotation, at.rotation, atol=1e-8)
    assert back.slack == slack


@NO_KERNELS
def test_point_mass_positions():
    """A point mass on two cables in space hangs only in the vertical plane of its outlets
    (where the weight is in the cables' span), straight below them on one."""
    A = np.array([[0.0, 0.0, 3.0], [2.0, 0.0, 3.0]])
    geo = hg.Geometry(A, np.zeros((2, 3)), np.array([0.0, 0.0, -0.1]), 2.0, G3)
    P = np.array([[1.0, 0.0, 1.0], [1.0, 0.3, 1.0], [3.0, 0.0, 1.0]])
    h = at_positions.hanging_orientations(geo, P, False)
    assert h.status.tolist() == [results.OK, results.NO_BALANCE, results.PUSHING]
    u = (A - P[0]) / np.linalg.norm(A - P[0], axis=1)[:, None]
    np.testing.assert_allclose(u.T @ h.tensions[0], [0, 0, 2 * 9.81], atol=1e-9)
    assert h.tilt_deg[0] == 0.0  # the centre of mass is straight below the attachment


# ---------------------------------------------------------------------------
# the held-orientation forward problem (the fk of `fixed` 2T / 3T designs)
# ---------------------------------------------------------------------------

def ref_held(A, B, c, mass, g, rho, d, rng, starts=12):
    """Lowest energy over SLSQP runs, orientation held at identity (translation only)."""
    Ad, Bd = A[:, :d], B[:, :d]
    cons = lambda x: rho ** 2 - np.sum((Ad - x - Bd) ** 2, axis=1)  # noqa: E731
    best = None
    for _ in range(starts):
        x0 = rng.uniform(Ad.min(0) - rho.max(), Ad.max(0))
        s = minimize(lambda x: -mass * g[:d] @ x, x0, method="SLSQP", constraints=[{"type": "ineq", "fun": cons}],
                     options={"ftol": 1e-14, "maxiter": 500})
        if cons(s.x).min() > -1e-9 and (best is None or s.fun < best.fun):
            best = s
    return best


@pytest.mark.slow
@NO_KERNELS
def test_held_fk_against_slsqp_and_the_closed_form():
    """planar-two-cable designs with the orientation held: the lowest point of the two discs
    (SLSQP reference), the paper's closed form wherever both cables pull, a slack cable
    otherwise - never a pushing one."""
    rng = np.random.default_rng(8)
    slack = both = 0
    for _ in range(30):
        A, B, c, mass, W, Hh = random_planar2(rng)
        p = np.array([rng.uniform(-0.3 * W, 1.3 * W), rng.uniform(0.0, 0.9 * Hh), 0.0])
        rho = np.linalg.norm(A - p - B, axis=1) + (rng.uniform(0, 0.3, 2) if rng.uniform() < 0.3 else 0.0)
        r = H.fk_held_arrays(A, B, c, mass, G2, rho, True, np.eye(3))
        ref = ref_held(A, B, c, mass, G2, rho, 2, rng)
        assert -mass * G2[:2] @ r.position == pytest.approx(ref.fun, abs=1e-7 * mass)
        assert np.all(r.tensions >= 0) and r.stable and r.model == "held" and r.orientation == 0.0
        taut = r.tensions > 0
        L = np.linalg.norm(A - np.r_[r.position, 0] - B, axis=1)
        np.testing.assert_allclose(L[taut], rho[taut], atol=1e-12)
        u = (A - np.r_[r.position, 0] - B) / L[:, None]
        np.testing.assert_allclose(u[:, :2].T @ r.tensions, [0, 9.81 * mass], atol=1e-9 * mass)
        if r.slack:
            slack += 1
        else:
            both += 1
            d = spec.from_dict({"name": "r", "motion": "2T", "frame": {"lower": [0, 0], "upper": [W, Hh]},
                                "effector": {"mass": mass, "size": [0.1, 0.1]}, "tension": [0, 1e3],
                                "cables": [{"name": f"c{i}", "outlet": A[i, :2].tolist(),
                                            "attachment": B[i, :2].tolist()} for i in range(2)]})
            np.testing.assert_allclose(r.position, kin.forward_kinematics(d, rho).pose, atol=1e-9)
    assert slack >= 3 and both >= 10


@NO_KERNELS
def test_held_point_mass_fk_equals_the_free_one():
    """A point mass's orientation changes no cable: held and free give the same position."""
    A = np.array([[0.0, 0.0, 3.0], [2.0, 0.0, 3.0], [1.0, 1.5, 3.0]])
    rho = np.linalg.norm(A - [1.0, -1.0, 1.0], axis=1)
    free = H.fk_arrays(A, np.zeros((3, 3)), np.zeros(3), 1.0, G3, rho, False)
    held = H.fk_held_arrays(A, np.zeros((3, 3)), np.zeros(3), 1.0, G3, rho, False, np.eye(3))
    np.testing.assert_allclose(held.position, free.position, atol=1e-12)
    assert held.slack == free.slack == (2,)


# ---------------------------------------------------------------------------
# the statics at per-pose orientations (kernels.hanging.eval_rotated)
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["planar4.yaml", "ipanema3.yaml"])
def test_eval_rotated_equals_evaluate_pose(name):
    """Each pose at its own rotation gives what evaluate_pose gives at that pose (the
    workspace kernels, themselves tested against scipy and cvxpy)."""
    from cdpr_design.statics.robot import combinations
    from cdpr_design.statics.wrenches import wrench_vertices

    d = spec.load(DESIGNS / name)
    rng = np.random.default_rng(9)
    k = 12
    lo, hi = np.array(d.workspace.grid.lower), np.array(d.workspace.grid.upper)
    P = np.zeros((k, 3))
    P[:, : d.motion.dim] = rng.uniform(lo + 0.2 * (hi - lo), hi - 0.2 * (hi - lo), (k, d.motion.dim))
    ori = np.zeros((k, 3))
    if d.motion.planar:
        ori[:, 2] = rng.uniform(-0.2, 0.2, k)
    else:
        ori[:] = rng.uniform(-0.1, 0.1, (k, 3))
    R = np.array([kin.rotation_matrix(*o) for o in ori])
    wreq = np.array([wrench_vertices(d, "static", o) for o in ori])
    m = d.m
    feas, marg, ten, L = np.empty(k, np.uint8), np.empty(k), np.empty((k, m)), np.empty((k, m))
    R[3] = np.nan  # a pose where the effector cannot hang
    from cdpr_design.kernels.hanging import eval_rotated

    eval_rotated(P, R, np.ascontiguousarray(d.attachments),
                 Statics(d.outlets, d.rows, d.tension_min, d.tension_max, d.string_floor, combinations(m, d.n), 0),
                 wreq, Outputs(feas, marg, ten, L))
    assert feas[3] == 0 and np.isnan(marg[3]) and np.all(np.isnan(L[3]))
    n_feasible = 0
    for i in set(range(k)) - {3}:
        pose = np.concatenate([P[i], ori[i]])[list(d.motion.pose_index)]
        ref = api.pose(d, pose)
        assert bool(feas[i]) == ref.feasible
        n_feasible += ref.feasible
        assert marg[i] == pytest.approx(ref.margin, rel=1e-9, abs=1e-9)
        np.testing.assert_allclose(L[i], ref.lengths, rtol=1e-12)
        np.testing.assert_allclose(ten[i], ref.tensions, rtol=1e-9, atol=1e-9)
    assert n_feasible >= 3


def _random_geometry(rng, m):
    return hg.Geometry(rng.normal(size=(m, 3)) * 3.0, rng.normal(size=(m, 3)) * 0.4, rng.normal(size=3) * 0.2,
                       rng.uniform(1.0, 50.0), np.array([0.0, 0.0, -9.81]))


def _lagrangian(geo, t, p, R, x):
    """U + sum t_i |l_i| at p + dp, exp([dw]) R (scipy's rotation), x = (dp, dw) [m, rad]."""
    R2 = Rotation.from_rotvec(x[3:]).as_matrix() @ R
    q = p + x[:3]
    lengths = np.linalg.norm(geo.A - q - geo.B @ R2.T, axis=1)
    return -geo.mass * geo.g @ (q + R2 @ geo.c) + t @ lengths


def _reduced_hessian_min_fd(geo, p, R, t, taut, dofs, h=1e-4):
    """The reduced Hessian's smallest eigenvalue from central finite differences: the Hessian of
    the Lagrangian and the taut lengths' gradients in (dp, dw), the tangent space by scipy."""
    from scipy.linalg import null_space

    f = lambda x: _lagrangian(geo, t, p, R, x)  # noqa: E731
    E = np.eye(6) * h
    Hfd = np.array([[(f(E[i] + E[j]) - f(E[i] - E[j]) - f(E[j] - E[i]) + f(-E[i] - E[j])) / (4 * h * h)
                     for j in range(6)] for i in range(6)])
    lengths = lambda x: np.linalg.norm(  # noqa: E731
        geo.A - p - x[:3] - geo.B @ (Rotation.from_rotvec(x[3:]).as_matrix() @ R).T, axis=1)
    G = np.array([(lengths(E[j]) - lengths(-E[j])) / (2 * h) for j in range(6)]).T[taut][:, dofs]
    N = null_space(G, rcond=1e-10) if G.size else np.eye(len(dofs))
    if N.shape[1] == 0:
        return math.inf
    Hd = Hfd[np.ix_(dofs, dofs)]
    return float(np.linalg.eigvalsh(N.T @ Hd @ N)[0])


@pytest.mark.slow
@NO_KERNELS
def test_batched_reduced_hessian_against_finite_differences():
    """Geometry.reduced_hessian_min_many (one batch of random robots' configurations, any taut
    set, spatial and planar dofs) against finite differences of the Lagrangian and the lengths."""
    rng = np.random.default_rng(11)
    checked = 0
    for trial in range(60):
        m = int(rng.integers(1, 7))
        geo = _random_geometry(rng, m)
        dofs = list(hg.DOFS_SPATIAL if trial % 2 else hg.DOFS_PLANAR)
        k = 4
        P = rng.normal(size=(k, 3))
        R = Rotation.from_rotvec(rng.normal(size=(k, 3)) * 0.6).as_matrix()
        t = rng.uniform(0.0, 100.0, (k, m)) * (rng.random((k, m)) < 0.8)
        taut = rng.random((k, m)) < 0.7
        got = geo.reduced_hessian_min_many(P, R, t, taut, dofs)
        for n in range(k):
            want = _reduced_hessian_min_fd(geo, P[n], R[n], t[n], taut[n], dofs)
            one = geo.reduced_hessian_min(P[n], R[n], t[n], np.flatnonzero(taut[n]), dofs)
            assert one == pytest.approx(got[n], rel=1e-12, abs=1e-9) or (math.isinf(one) and math.isinf(got[n]))
            if math.isinf(want):
                assert math.isinf(got[n]), (trial, n, got[n])
                continue
            scale = 1.0 + np.abs(t[n]).sum() + geo.weight
            assert got[n] == pytest.approx(want, abs=1e-5 * scale), (trial, n)
            checked += 1
    assert checked > 150


@NO_KERNELS
@pytest.mark.parametrize("planar", [False, True])
def test_newton_jacobian_against_finite_differences(planar):
    """The balance Jacobian of the batched Newton search (closed forms summed with einsum)
    against central differences of its residual in the rotation coordinates and tensions."""
    rng = np.random.default_rng(5 + planar)
    for trial in range(40):
        m = int(rng.integers(1, 7))
        geo = _random_geometry(rng, m)
        bal = Balance(geo, planar)
        k = 6
        P = rng.normal(size=(k, 3))
        w = rng.normal(size=(k, 3)) * 0.7
        if planar:
            w[:, :2] = 0.0
        R0 = Rotation.from_rotvec(rng.normal(size=3) * 0.3).as_matrix()
        t = rng.uniform(0.0, 100.0, (k, m)) * (rng.random((k, m)) < 0.8)  # some slack (t = 0)
        J = bal.jacobian(P, hg.rotvec(w) @ R0, t, w)
        h = 1e-6
        cols = []
        for j in bal.rot:
            e = np.zeros(3)
            e[j] = h
            up = bal.residual(P, Rotation.from_rotvec(w + e).as_matrix() @ R0, t)
            down = bal.residual(P, Rotation.from_rotvec(w - e).as_matrix() @ R0, t)
            cols.append((up - down) / (2 * h))
        for i in range(m):
            e = np.zeros(m)
            e[i] = h * geo.weight  # the unknowns are the tensions over the weight
            R = Rotation.from_rotvec(w).as_matrix() @ R0
            cols.append((bal.residual(P, R, t + e) - bal.residual(P, R, t - e)) / (2 * h))
        np.testing.assert_allclose(J, np.stack(cols, axis=2), rtol=1e-5, atol=1e-6)


@NO_KERNELS
def test_a_cable_of_zero_length_adds_nothing_without_tension_and_nan_with_it():
    """The batched Lagrangian Hessian where a cable has length 0 (its attachment on its outlet):
    slack (t = 0) it adds nothing - the Hessian of the other cables alone, finite; pulling, its
    direction is undefined and the Hessian says so (NaN), never a finite number."""
    rng = np.random.default_rng(2)
    A, B = rng.normal(size=(3, 3)) * 2.0, rng.normal(size=(3, 3)) * 0.3
    B[0] = 0.0
    c, mass = np.array([0.0, 0.0, -0.2]), 10.0
    R, p = np.eye(3), A[0].copy()  # cable 0 has length 0, exactly
    geo = hg.Geometry(A, B, c, mass, G3)
    rest = hg.Geometry(A[1:], B[1:], c, mass, G3)
    hessian = lambda g, t: g.lagrangian_hessian_many(p[None], R[None], np.array([t]))[0]  # noqa: E731
    H = hessian(geo, [0.0, 40.0, 70.0])
    assert np.all(np.isfinite(H))
    np.testing.assert_allclose(H, hessian(rest, [40.0, 70.0]), rtol=1e-14, atol=1e-12)
    assert np.isnan(hessian(geo, [5.0, 40.0, 70.0])).any()
