"""The general (m != n) kernels against slow obvious references.

- capacity margin: a brute-force hyperplane-shifting method written plainly in
  numpy (an SVD per subset of n-1 columns; Gouttefarde & Krut, ARK 2010;
  Bouchard, Gosselin & Moore, ASME JMR 2010);
- feasibility: scipy ``linprog`` (HiGHS) on W t = w, t_min <= t <= t_max;
- minimum 2-norm tensions: cvxpy (Clarabel, tight tolerances), the problem
  definition of :func:`cdpr_design.statics.tension.cvxpy_problem`;
- wrench closure: the linear program max s, W t = 0, t_i >= s, sum t = 1.

Random robots of every motion type (2T, 1R2T, 3T, 3R3T) with m = n .. n+4
cables; 10,000 poses in all.  Feasibility must agree outside a band of 1e-7
(relative to the largest tension bound) around the boundary.
"""

from __future__ import annotations

import itertools

import cvxpy as cp
import numpy as np
import pytest
from scipy.optimize import linprog

from cdpr_design import kernels as K
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.tension import combinations
from tests.reference.hsm import square_eval

MOTIONS = {  # (dim, wrench rows of [fx, fy, fz, mx, my, mz])
    "2T": (2, (0, 1)),
    "1R2T": (2, (0, 1, 5)),
    "3T": (3, (0, 1, 2)),
    "3R3T": (3, (0, 1, 2, 3, 4, 5)),
}
POSES_PER_CASE = 500  # 4 motions x 5 cable counts x 500 = 10,000 poses
BAND = 1e-7


# ----------------------------------------------------------------------------
# Slow obvious references
# ----------------------------------------------------------------------------


def plain_W(A, B, p, R, rows):
    """Structure matrix written out: column i = [u_i ; (R b_i) x u_i][rows]."""
    Rb = B @ R.T
    l = A - p[None, :] - Rb
    u = l / np.linalg.norm(l, axis=1)[:, None]
    full = np.hstack([u, np.cross(Rb, u)])
    return np.ascontiguousarray(full[:, rows].T)


def hsm_bruteforce(W, wreq, tmin, tmax, subsets=None):
    """Hyperplane shifting, plainly: for every n-1 columns the normal from an SVD.

    Returns the margin of every row of ``wreq`` (NaN when rank W < n).
    """
    n, m = W.shape
    if np.linalg.matrix_rank(W) < n:
        return np.full(len(wreq), np.nan)
    if subsets is None:
        subsets = np.array(list(itertools.combinations(range(m), n - 1)), dtype=int)
    Ws = W[:, subsets].transpose(1, 0, 2)                       # (C, n, n-1)
    U, s, _ = np.linalg.svd(Ws, full_matrices=True)
    nus = U[:, :, -1]                                           # (C, n)
    keep = s[:, -1] > 1e-10 * s[:, 0]
    nus = nus[keep]
    L = nus @ W                                                 # l_j per facet
    half = 0.5 * np.abs(L) @ (tmax - tmin)
    c = nus @ (W @ (0.5 * (tmin + tmax)))
    d = np.abs(c[:, None] - nus @ wreq.T)                       # (C, nv)
    return np.min(half[:, None] - d, axis=0)


def lp_feasible(W, w, tmin, tmax):
    res = linprog(np.zeros(W.shape[1]), A_eq=W, b_eq=w, bounds=list(zip(tmin, tmax)),
                  method="highs")
    return res.status == 0


def lp_closure(W):
    """max s: W t = 0, t_i >= s, sum t = 1; the columns positively span iff s > 0 (rank n)."""
    n, m = W.shape
    c = np.zeros(m + 1)
    c[-1] = -1.0
    A_eq = np.zeros((n + 1, m + 1))
    A_eq[:n, :m] = W
    A_eq[n, :m] = 1.0
    b_eq = np.zeros(n + 1)
    b_eq[n] = 1.0
    A_ub = np.hstack([-np.eye(m), np.ones((m, 1))])
    res = linprog(c, A_ub=A_ub, b_ub=np.zeros(m), A_eq=A_eq, b_eq=b_eq,
                  bounds=[(0, None)] * m + [(None, 1.0)], method="highs")
    if res.status == 2:  # no t >= 0, t != 0 with W t = 0: no positive spanning
        return -1.0
    assert res.status == 0
    return -res.fun


class MinNormOracle:
    """cvxpy min 1/2 |t|^2, W t = w, bounds, with Parameters (compiled once per shape)."""

    def __init__(self, n, m):
        self.W = cp.Parameter((n, m))
        self.w = cp.Parameter(n)
        self.lo = cp.Parameter(m)
        self.hi = cp.Parameter(m)
        self.t = cp.Variable(m)
        self.prob = cp.Problem(cp.Minimize(cp.sum_squares(self.t)),
                               [self.W @ self.t == self.w, self.t >= self.lo, self.t <= self.hi])

    def __call__(self, W, w, tmin, tmax):
        self.W.value, self.w.value, self.lo.value, self.hi.value = W, w, tmin, tmax
        self.prob.solve(solver=cp.CLARABEL, tol_gap_abs=1e-13, tol_gap_rel=1e-13,
                        tol_feas=1e-13, tol_ktratio=1e-10)
        return None if self.t.value is None else np.asarray(self.t.value)


def random_robot(rng, motion, m):
    dim, rows = MOTIONS[motion]
    A = np.zeros((m, 3))
    B = np.zeros((m, 3))
    A[:, :dim] = rng.uniform(-2.0, 2.0, (m, dim))
    B[:, :dim] = rng.uniform(-0.3, 0.3, (m, dim))
    tmin = rng.uniform(0.0, 10.0, m)
    tmax = tmin + rng.uniform(20.0, 200.0, m)
    return A, B, np.array(rows), tmin, tmax


def random_pose(rng, motion):
    dim, _ = MOTIONS[motion]
    p = np.zeros(3)
    p[:dim] = rng.uniform(-1.0, 1.0, dim)
    ang = np.zeros(3)
    if motion == "1R2T":
        ang[2] = rng.uniform(-0.5, 0.5)
    elif motion == "3R3T":
        ang[:] = rng.uniform(-0.4, 0.4, 3)
    return p, kin.rotation_matrix(*ang)


CASES = [(mo, k) for mo in MOTIONS for k in range(5)]


@pytest.mark.slow
@pytest.mark.parametrize("motion,extra", CASES, ids=[f"{mo}-m=n+{k}" for mo, k in CASES])
def test_against_references(motion, extra):
    rng = np.random.default_rng(1000 + 10 * list(MOTIONS).index(motion) + extra)
    n = len(MOTIONS[motion][1])
    m = n + extra
    combos = combinations(m, n)
    subsets = np.array(list(itertools.combinations(range(m), n - 1)), dtype=int)
    oracle = MinNormOracle(n, m)
    t = np.empty(m)
    scr = K.make_scratch(n, m, 3)
    counts = dict(feasible=0, infeasible=0, band=0, tensions=0, closure=0)
    robot = None
    for k in range(POSES_PER_CASE):
        if k % 25 == 0:
            robot = random_robot(rng, motion, m)
        A, B, rows, tmin, tmax = robot
        p, R = random_pose(rng, motion)
        W = plain_W(A, B, p, R, rows)
        # required wrenches: W t0 for t0 around the bounds (about half feasible),
        # plus two more vertices for the wrench-feasible kind
        # (half of them pushed off by a random wrench: mostly infeasible)
        push = (k % 2) * rng.uniform(0.0, 0.5) * float(np.sum(tmax))
        wreq = np.array([W @ rng.uniform(tmin, tmax) + push * rng.normal(size=n)
                         for _ in range(3)])
        scale = float(tmax.max())

        # --- static: row 0 only
        f, mg = K.eval_pose(W, wreq, tmin, tmax, combos, K.KIND_STATIC, t)
        f2, mg2 = K.eval_general(W, wreq, tmin, tmax, combos, K.KIND_STATIC, t.copy(), scr, m - n)
        refs = hsm_bruteforce(W, wreq, tmin, tmax, subsets)
        ref = refs[0]
        assert np.isfinite(mg) and np.isfinite(ref)
        assert abs(mg - ref) <= 1e-9 * max(1.0, abs(ref)), (mg, ref)
        assert abs(mg2 - ref) <= 1e-9 * max(1.0, abs(ref)), (mg2, ref)
        assert f == f2
        if f:  # feasible => tensions, balanced and within the bounds
            assert np.all(np.isfinite(t))
            assert np.all(t >= tmin) and np.all(t <= tmax)
            assert np.allclose(W @ t, wreq[0], atol=1e-8 * scale)
        if abs(ref) <= BAND * scale:
            counts["band"] += 1
        else:
            lpf = lp_feasible(W, wreq[0], tmin, tmax)
            assert f == lpf == (ref >= 0), (f, lpf, ref)
            counts["feasible" if f else "infeasible"] += 1
            if f:
                tref = oracle(W, wreq[0], tmin, tmax)
                assert tref is not None
                assert np.max(np.abs(t - tref)) <= 1e-6, np.max(np.abs(t - tref))
                counts["tensions"] += 1
            else:
                assert np.all(np.isnan(t))

        # --- wrench-feasible: every row; the margin is the minimum over the rows
        f, mg = K.eval_pose(W, wreq, tmin, tmax, combos, K.KIND_WRENCH_FEASIBLE, t)
        ref = refs.min()
        assert abs(mg - ref) <= 1e-9 * max(1.0, abs(ref)), (mg, ref)
        if abs(ref) > BAND * scale:
            assert f == (ref >= 0)
            if f:
                assert np.all(np.isfinite(t))
                if k % 10 == 0:
                    assert all(lp_feasible(W, w, tmin, tmax) for w in wreq)

        # --- wrench closure (bounds ignored); m = n never positively spans
        f, mg = K.eval_pose(W, wreq, tmin, tmax, combos, K.KIND_WRENCH_CLOSURE, t)
        if k % 10 == 0 or m == n:
            s = lp_closure(W) if m > n else -1.0
            if abs(s) > BAND:
                assert f == (s > 0), (f, s)
            counts["closure"] += int(f)
    # the random cases exercise both sides of the boundary
    assert counts["feasible"] > 0.2 * POSES_PER_CASE, counts
    assert counts["infeasible"] > 0.2 * POSES_PER_CASE, counts


def test_square_matches_closed_form():
    """eval_general on m = n agrees with the lead's closed form square_eval."""
    rng = np.random.default_rng(7)
    for n in (2, 3, 6):
        for _ in range(200):
            W = rng.normal(size=(n, n))
            w = W @ rng.uniform(-5, 25, n)
            tmin, tmax = np.zeros(n), np.full(n, 20.0)
            t1 = np.empty(n)
            ok, mg = square_eval(W, w[None, :], tmin, tmax, t1)
            t2 = np.empty(n)
            f, mg2 = K.eval_general(W, w[None, :], tmin, tmax, combinations(n, n), 0, t2,
                                    K.make_scratch(n, n, 1), 0)
            assert abs(mg - mg2) <= 1e-9 * max(1.0, abs(mg))
            assert f == (mg2 >= 0)
            if f:
                assert np.allclose(t1, t2, atol=1e-9)


@pytest.mark.parametrize("motion", list(MOTIONS))
def test_rank_deficient_poses_are_infeasible(motion):
    """Coincident cables, a zero-length cable, a planar cable set in 3T: flagged, NaN margin."""
    rng = np.random.default_rng(3)
    n = len(MOTIONS[motion][1])
    m = n + 2
    A, B, rows, tmin, tmax = random_robot(rng, motion, m)
    p, R = random_pose(rng, motion)
    W = plain_W(A, B, p, R, rows)
    combos = combinations(m, n)
    t = np.empty(m)
    w = np.zeros(n)
    # all columns copies of two cables: rank 2 < n (n >= 3), or parallel ones for n = 2
    Wc = W.copy()
    if n == 2:
        Wc[:, :] = W[:, [0]]
        Wc[:, 1::2] *= 2.0
    else:
        Wc[:, 2:] = W[:, [0, 1] * ((m - 2) // 2) + [0] * ((m - 2) % 2)]
    for kind in (0, 1, 2):
        f, mg = K.eval_pose(np.ascontiguousarray(Wc), w[None, :], tmin, tmax, combos, kind, t)
        assert not f and np.isnan(mg) and np.all(np.isnan(t))
    # a zero column (zero-length cable)
    Wz = W.copy()
    Wz[:, 1] = 0.0
    for kind in (0, 1, 2):
        f, mg = K.eval_pose(Wz, (W @ (0.5 * (tmin + tmax)))[None, :], tmin, tmax, combos, kind, t)
        assert not f and np.isnan(mg) and np.all(np.isnan(t))


@pytest.mark.slow
def test_min_norm_kernel_detects_infeasibility_and_is_exact():
    """min_norm_tensions alone: infeasible <=> linprog infeasible; optimum = cvxpy's."""
    rng = np.random.default_rng(11)
    outcomes = set()
    for _ in range(150):
        n = int(rng.choice([2, 3, 6]))
        m = n + int(rng.integers(1, 5))
        W = rng.normal(size=(n, m))
        tmin = rng.uniform(0, 5, m)
        tmax = tmin + rng.uniform(1, 30, m)
        w = W @ rng.uniform(tmin - 5, tmax + 5)
        t = np.empty(m)
        ok = K.min_norm_tensions(W, w, tmin, tmax, t, K.make_scratch(n, m, 1))
        ref = hsm_bruteforce(W, w[None, :], tmin, tmax)[0]
        if abs(ref) < 1e-7 * tmax.max():
            continue
        assert ok == lp_feasible(W, w, tmin, tmax)
        outcomes.add(bool(ok))
        if ok:
            tref = MinNormOracle(n, m)(W, w, tmin, tmax)
            assert np.max(np.abs(t - tref)) <= 1e-6
        else:
            assert np.all(np.isnan(t))
    assert outcomes == {True, False}, "both feasible and infeasible cases must be compared"


def small_redundancy_problem(rng, trial: int, r: int):
    """(n, m, W, tmin, tmax): a random n x (n + r) structure matrix with bounds; every third
    trial has exact zeros in W, every fifth two parallel columns (degenerate facets)."""
    n = int(rng.choice([2, 3, 4, 6]))
    m = n + r
    W = rng.normal(size=(n, m))
    if trial % 3 == 1:
        W[rng.random((n, m)) < 0.3] = 0.0
    if trial % 5 == 2:
        W[:, 1] = 2.0 * W[:, 0]
    tmin = rng.uniform(0.0, 5.0, m)
    tmax = tmin + rng.uniform(1.0, 30.0, m)
    return n, m, W, tmin, tmax


@pytest.mark.slow
@pytest.mark.parametrize("r", [1, 2])
def test_small_redundancy_closed_forms_match_enumeration(r):
    """hsm_one / hsm_two (m - n = 1, 2, behind hsm_factored) against the general enumeration
    hsm_enumerate on the same factorisation: same margins (v = 0 and every row) and closure,
    on random matrices and on degenerate ones (exact zeros, parallel columns: facets dropped
    by the rank tests); the margins without the closure test are the same (to rounding: a
    separately compiled copy)."""
    rng = np.random.default_rng(50 + r)
    counts = dict(cases=0, closure=0, degenerate=0)
    for trial in range(600):
        n, m, W, tmin, tmax = small_redundancy_problem(rng, trial, r)
        wreq = np.array([W @ rng.uniform(tmin - 3.0, tmax + 3.0) for _ in range(3)])
        scr = K.make_scratch(n, m, 3)
        if not K.basis_factor(W, scr[0], scr[18], scr[19], scr[20]):
            continue
        ref = K.hsm_enumerate(W, wreq, 3, tmin, tmax, scr)
        fast = (K.hsm_one if r == 1 else K.hsm_two)(W, wreq, 3, tmin, tmax, scr, True)
        disp = K.hsm_factored(W, wreq, 3, tmin, tmax, scr, True)
        quiet = K.hsm_factored(W, wreq, 3, tmin, tmax, scr, False)
        for a, b, c, d in zip(ref[:2], fast[:2], quiet[:2], disp[:2]):
            # the closed form, its copy without the closure test, and both behind hsm_factored
            for x in (b, c, d):
                assert abs(a - x) <= 1e-12 * max(1.0, abs(a)), (a, x)
        assert fast[2] == ref[2] and disp[2] == ref[2]
        static = (K.hsm_one if r == 1 else K.hsm_two)(W, wreq, 1, tmin, tmax, scr, False)
        assert abs(static[0] - ref[0]) <= 1e-12 * max(1.0, abs(ref[0]))
        counts["cases"] += 1
        counts["closure"] += int(ref[2])
        counts["degenerate"] += int(trial % 3 == 1 or trial % 5 == 2)
    assert counts["cases"] > 400 and 0 < counts["closure"] < counts["cases"] and counts["degenerate"] > 150, counts


def reduced(n, m, W, w):
    """The scratch holding the null-space reduction of W t = w (basis factorisation, null basis,
    t_p) that the projections read; None where W is rank deficient."""
    scr = K.make_scratch(n, m, 1)
    red = K.reduction(scr)
    if not K.basis_factor(W, red.tab, red.slot, red.nbc, red.bcol):
        return None
    K.null_space(n, m, w, red.tab, red.N, red.tp, red.tb, red.nbc, red.bcol)
    return scr


@pytest.mark.slow
@pytest.mark.parametrize("r", [1, 2])
def test_small_redundancy_tensions_match_the_active_set_method(r):
    """project_one / project_two (m - n = 1, 2, behind project_null) against the general dual
    active-set method goldfarb_idnani on the same null space: the same verdict and the same
    tensions, on random problems and on degenerate ones (exact zeros in W, parallel columns,
    an unbounded t_max, a required wrench at a corner of the feasible set); and, on a sample,
    against cvxpy's minimum and scipy's feasibility."""
    rng = np.random.default_rng(70 + r)
    counts = dict(feasible=0, infeasible=0, degenerate=0, active=0)
    for trial in range(3000):
        n, m, W, tmin, tmax = small_redundancy_problem(rng, trial, r)
        t0 = rng.uniform(tmin - 4.0, tmax + 4.0)
        if trial % 7 == 3:
            t0 = np.where(rng.random(m) < 0.5, tmin, tmax)  # a corner: several bounds met exactly
        if trial % 11 == 4:
            tmax[rng.integers(m)] = np.inf
        w = W @ t0
        scr = reduced(n, m, W, w)
        if scr is None:
            continue
        t_ref, t = np.empty(m), np.empty(m)
        ok_ref = K.goldfarb_idnani(m, r, tmin, tmax, t_ref, scr)
        ok = K.project_null(m, r, tmin, tmax, t, scr)
        assert ok == ok_ref, (trial, ok, ok_ref)
        if ok:
            assert np.max(np.abs(t - t_ref)) <= 1e-9 * max(1.0, float(np.max(np.abs(t_ref)))), trial
            assert np.all(t >= tmin) and np.all(t <= tmax)
            counts["active"] += int(np.any(np.isclose(t, tmin) | np.isclose(t, tmax)))
        else:
            assert np.all(np.isnan(t))
        counts["feasible" if ok else "infeasible"] += 1
        counts["degenerate"] += int(trial % 3 == 1 or trial % 5 == 2 or trial % 7 == 3)
        if trial % 20 == 0 and np.all(np.isfinite(tmax)):
            ref = hsm_bruteforce(W, w[None, :], tmin, tmax)[0]
            if np.isfinite(ref) and abs(ref) > 1e-7 * tmax.max():
                assert ok == lp_feasible(W, w, tmin, tmax)
                if ok:
                    assert np.max(np.abs(t - MinNormOracle(n, m)(W, w, tmin, tmax))) <= 1e-6
    assert counts["feasible"] > 500 and counts["infeasible"] > 500, counts
    assert counts["active"] > 300 and counts["degenerate"] > 1000, counts


def test_square_tensions_equal_the_active_set_method():
    """m = n: square_projection (behind project_null for r = 0, and min_norm_tensions_square, which
    the sagging kernels of a square robot call) against the general dual active-set method
    goldfarb_idnani with r = 0 on the same factorisation, to the bit: the same verdict, the same
    tensions (clipped into the bounds) or NaN; random problems with the load inside, near and
    outside the bounds, exact zeros in W, an unbounded t_max; and min_norm_tensions (any m) equal
    to min_norm_tensions_square there."""
    rng = np.random.default_rng(80)
    counts = dict(feasible=0, infeasible=0)
    for trial in range(2000):
        n, m, W, tmin, tmax = small_redundancy_problem(rng, trial, 0)
        t0 = rng.uniform(tmin - 4.0, tmax + 4.0)
        if trial % 7 == 3:  # within the tolerance of a bound
            j = rng.integers(m)
            t0[j] = tmin[j] - 1e-12 * tmax.max()
        if trial % 11 == 4:
            tmax[rng.integers(m)] = np.inf
        w = W @ t0
        scr = reduced(n, m, W, w)
        if scr is None:
            continue
        t_ref, t, t_sq, t_any = (np.empty(m) for _ in range(4))
        ok_ref = K.goldfarb_idnani(m, 0, tmin, tmax, t_ref, scr)
        ok = K.project_null(m, 0, tmin, tmax, t, scr)
        assert ok == ok_ref and np.array_equal(t, t_ref, equal_nan=True), trial
        ok_sq = K.min_norm_tensions_square(W, w, tmin, tmax, t_sq, K.reduction(K.make_scratch(n, m, 1)))
        ok_any = K.min_norm_tensions(W, w, tmin, tmax, t_any, K.make_scratch(n, m, 1))
        assert ok_sq == ok_any == ok_ref, trial
        assert np.array_equal(t_sq, t_ref, equal_nan=True) and np.array_equal(t_any, t_ref, equal_nan=True), trial
        counts["feasible" if ok else "infeasible"] += 1
    assert counts["feasible"] > 300 and counts["infeasible"] > 300, counts


@pytest.mark.slow
@pytest.mark.parametrize("motion,extra", CASES, ids=[f"{mo}-m=n+{k}" for mo, k in CASES])
def test_grid_kernel_of_each_redundancy_equals_the_pose_kernel(motion, extra):
    """The grid sweep runs one kernel per m - n (0, 1, 2, any other: ``sweep.grid_block``), each
    compiled with its own methods, and so does the hanging effector's (``hanging.rotated_block``);
    every row of both equals the per-pose kernel (``eval_pose``, whose
    choice of method happens at run time, checked against the references above) for all three
    kinds -- including poses on an outlet (zero-length cable): feasibility, lengths and where the
    NaNs are exactly, margins and tensions to the last bits (1e-12 relative: the methods' sums
    may be reassociated (``_jit.FAST``), and LLVM orders them in each compiled loop as it sees fit).
    A kernel with the wrong methods for its r gives other numbers or none.

    Each kind runs twice: with the plain bounds, and with a lower bound that grows with the cable's
    length (``requirements.min_cable_frequency``'s c_i L_i^2 on some cables, ``raise_floor``),
    against the pose kernel given max(t_min, c L^2) computed here with numpy; the floor must
    change some verdicts."""
    rng = np.random.default_rng(700 + 10 * extra + list(MOTIONS).index(motion))
    dim, _ = MOTIONS[motion]
    n = len(MOTIONS[motion][1])
    m = n + extra
    A, B, rows, tmin, tmax = random_robot(rng, motion, m)
    _, R = random_pose(rng, motion)
    Rb = rotated(R, B)
    shape = np.array([7, 6, 4 if dim == 3 else 1])
    lower = np.array([-1.0, -1.0, -1.0 if dim == 3 else 0.0])
    step = np.array([1 / 3, 0.4, 2 / 3])
    A[0] = lower + step * np.array([2, 3, 1 if dim == 3 else 0]) + Rb[0]  # grid pose 2,3,(1) reaches outlet 0
    count = int(np.prod(shape))
    combos = combinations(m, n)
    W0 = plain_W(A, B, lower + step * np.array([3, 2, 1 if dim == 3 else 0]), R, rows)
    for kind in (K.KIND_STATIC, K.KIND_WRENCH_FEASIBLE, K.KIND_WRENCH_CLOSURE):
        # balanced by tensions inside the bounds at grid pose 3,2,(1): feasible there
        wreq = np.array([W0 @ rng.uniform(tmin + 1.0, tmax - 1.0) for _ in range(3)])
        plain = _grid_equals_pose_kernel(kind, count, lower, step, shape, R, B, A, rows, wreq, tmin, tmax,
                                         np.zeros(m), combos, dim)
        # a floor c L^2 reaching the middle of the bounds at L = 1.5 m, on every other cable
        floor = np.where(np.arange(m) % 2 == 0, 0.5 * (tmin + tmax) / 1.5**2, 0.0)
        raised = _grid_equals_pose_kernel(kind, count, lower, step, shape, R, B, A, rows, wreq, tmin, tmax,
                                          floor, combos, dim)
        if kind != K.KIND_WRENCH_CLOSURE:  # closure ignores the bounds
            assert not np.array_equal(plain, raised) and not np.any(raised & ~plain)
        else:
            np.testing.assert_array_equal(plain, raised)
        got = plain
        if kind != K.KIND_WRENCH_CLOSURE:
            assert got[3 * shape[1] * shape[2] + 2 * shape[2] + (1 if dim == 3 else 0)]
            assert not got.all()


def rotated(R, B):
    """R b_i (m, 3) as the kernels rotate them (``rotate_attachments``: the hanging kernel rotates
    each pose's attachments itself, so every kernel here sees the same bits)."""
    Rb = np.empty(B.shape)
    K.rotate_attachments(np.ascontiguousarray(R), np.ascontiguousarray(B), Rb)
    return Rb


def _grid_equals_pose_kernel(kind, count, lower, step, shape, R, B, A, rows, wreq, tmin, tmax, floor, combos, dim):
    """Sweep the grid with ``sweep_grid`` and check every row against ``eval_pose`` with the pose's
    lower bounds max(tmin, floor L^2) computed with numpy; the same for the hanging effector's
    kernel (``hanging.eval_rotated``, one loop per m - n as well) given the grid's positions, each
    with the rotation ``R`` of attachments ``B``; returns the feasibility flags (bool)."""
    from cdpr_design.kernels.hanging import eval_rotated
    from cdpr_design.statics.robot import tension_lower

    n, m = rows.shape[0], A.shape[0]
    Rb = rotated(R, B)
    got = (np.empty(count, np.uint8), np.empty(count), np.empty((count, m)), np.empty((count, m)))
    statics = K.Statics(A, rows, tmin, tmax, floor, combos, kind)
    K.sweep_grid(K.GridPoses(0, lower, step, shape, Rb), statics, wreq, K.Outputs(*got))
    P = np.array([lower + step * np.array(ijk) for ijk in itertools.product(*map(range, shape))])
    rot = (np.empty(count, np.uint8), np.empty(count), np.empty((count, m)), np.empty((count, m)))
    eval_rotated(P, np.ascontiguousarray(np.broadcast_to(R, (count, 3, 3))), np.ascontiguousarray(B), statics,
                 np.ascontiguousarray(np.broadcast_to(wreq, (count,) + wreq.shape)), K.Outputs(*rot))
    W = np.empty((n, m))
    L = np.empty(m)
    t = np.empty(m)
    on_outlet = 0
    for k, (ix, iy, iz) in enumerate(itertools.product(*map(range, shape))):
        p = lower + step * np.array([ix, iy, iz])
        ok = K.structure_matrix(p[0], p[1], p[2], Rb, A, rows, W, L)
        if ok:
            f, mg = K.eval_pose(W, wreq, tension_lower(tmin, floor, L), tmax, combos, kind, t)
        else:
            on_outlet += 1
            f, mg, t[:] = False, np.nan, np.nan
        for rows_ in (got, rot):
            np.testing.assert_array_equal(rows_[3][k], L)
            assert rows_[0][k] == f, (kind, k)
            np.testing.assert_allclose(rows_[1][k], mg, rtol=1e-12, atol=1e-10)
            np.testing.assert_allclose(rows_[2][k], t, rtol=1e-12, atol=1e-10)
            assert np.array_equal(np.isnan(rows_[2][k]), np.isnan(t)) and np.isnan(rows_[1][k]) == np.isnan(mg)
    assert on_outlet == 1
    return got[0].astype(bool)
