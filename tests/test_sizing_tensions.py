"""The sizing's minimum-norm tensions: the exact kernel, against a slow BVLS reference.

The reference is scipy's bounded least squares (``lsq_linear``, BVLS) on the
equality as a heavily weighted block, polished on the active set BVLS finds
(the free tensions are the least-norm solution of W t = w with the active
ones at their bounds) and certified by the KKT conditions, so that it is
exact to round-off and independent of the kernel.
"""

from __future__ import annotations


import numpy as np
import pytest

from cdpr_design.design import envelope as ev
from cdpr_design.model import spec
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics import tension as T

from .helpers import DESIGNS, random_planar_data, resolved

RTOL = 1e-9  # relative to the largest tension (at least 1 N)


def bvls_min_norm(W, w, lo, hi):
    """min |t|^2, W t = w, lo <= t <= hi (``hi`` may hold inf) by BVLS + active-set polish; None if infeasible."""
    from scipy.optimize import lsq_linear

    n, m = W.shape
    rho = 1e6 / max(np.linalg.norm(W), 1e-300)
    A = np.vstack([rho * W, np.eye(m)])
    b = np.concatenate([rho * w, np.zeros(m)])
    t = lsq_linear(A, b, bounds=(lo, hi), method="bvls", tol=1e-14, lsmr_tol=None).x
    if np.linalg.norm(W @ t - w) > 1e-7 * (1.0 + np.linalg.norm(w)):
        return None
    tol = 1e-9 * max(1.0, np.max(np.abs(t)))
    at_lo, at_hi = t <= lo + tol, t >= hi - tol
    fixed = at_lo | at_hi
    t = np.where(at_lo, lo, np.where(at_hi, hi, t))
    free = ~fixed
    t[free] = np.linalg.lstsq(W[:, free], w - W[:, fixed] @ t[fixed], rcond=None)[0]
    _assert_kkt(W, w, lo, hi, t, at_lo, at_hi)
    return t


def _assert_kkt(W, w, lo, hi, t, at_lo, at_hi):
    """Certificate of optimality: t = -W^T lam + mu_lo - mu_hi with mu >= 0 on the active bounds."""
    scale = max(1.0, np.max(np.abs(t)))
    free = ~(at_lo | at_hi)
    assert np.linalg.norm(W @ t - w) <= 1e-10 * scale * (1 + np.linalg.norm(W))
    assert np.all(t >= lo - 1e-10 * scale) and np.all(t <= hi + 1e-10 * scale)
    lam = np.linalg.lstsq(-W[:, free].T, t[free], rcond=None)[0]
    g = t + W.T @ lam  # = mu_lo - mu_hi
    np.testing.assert_allclose(g[free], 0.0, atol=1e-8 * scale)
    assert np.all(g[at_lo] >= -1e-8 * scale) and np.all(g[at_hi] <= 1e-8 * scale)


def _compare(W, wrenches, tmin, tmax):
    """Kernel vs reference for every row; returns the largest relative difference."""
    got = T.min_norm_many(W, wrenches, tmin, tmax)
    worst = 0.0
    for k, w in enumerate(wrenches):
        ref = bvls_min_norm(W, w, tmin, tmax)
        if ref is None:
            assert not np.all(np.isfinite(got[k])), "the kernel balances a wrench BVLS cannot"
            continue
        assert np.all(np.isfinite(got[k])), "BVLS balances a wrench the kernel cannot"
        worst = max(worst, np.max(np.abs(got[k] - ref)) / max(1.0, np.max(np.abs(ref))))
    return worst


def _planar_poses(d, rng, count):
    lo, hi = np.array(d.frame_lower[:2]), np.array(d.frame_upper[:2])
    xy = lo + (hi - lo) * rng.uniform(0.15, 0.85, size=(count, 2))
    if d.motion.name == "1R2T":
        return np.column_stack([xy, rng.uniform(-0.3, 0.3, count)])
    return xy


def _wrenches(d, pose, rng, count):
    """-gravity, then -gravity - inertial at random accelerations (up to 3 g)."""
    g = kin.gravity_wrench(d, pose)
    rows = [-g]
    for _ in range(count):
        a = rng.normal(size=d.motion.dim) * rng.uniform(0, 30)
        rows.append(-(g + kin.inertial_wrench(d, pose, a)))
    return np.array(rows)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(12))
def test_kernel_equals_bvls_on_random_planar_robots(seed):
    rng = np.random.default_rng(1000 + seed)
    motion = "1R2T" if seed % 2 else "2T"
    data = random_planar_data(rng, m=int(rng.integers(4, 7)) if motion == "1R2T" else int(rng.integers(3, 6)),
                              motion=motion)
    d = spec.from_dict(data)
    solved = 0
    for pose in _planar_poses(d, rng, 15):
        W = kin.structure_matrix(d, pose)
        wr = _wrenches(d, pose, rng, 4)
        assert _compare(W, wr, d.tension_min, d.tension_max) <= RTOL
        solved += int(np.all(np.isfinite(T.min_norm_many(W, wr[:1], d.tension_min, d.tension_max))))
    assert solved > 0


@pytest.mark.slow
@pytest.mark.parametrize("name", ["planar4", "ipanema1", "ipanema2", "ipanema3", "cogiro"])
def test_kernel_equals_bvls_on_shipped_designs(name):
    d = spec.load(DESIGNS / f"{name}.yaml")
    rng = np.random.default_rng(7)
    g = d.workspace.grid
    lo, hi = np.array(g.lower), np.array(g.upper)
    solved = 0
    for _ in range(40):
        pos = lo + (hi - lo) * rng.uniform(0.1, 0.9, size=lo.size)
        pose = np.concatenate([pos, d.workspace.orientation])
        W = kin.structure_matrix(d, pose)
        wr = _wrenches(d, pose, rng, 2)
        assert _compare(W, wr, d.tension_min, d.tension_max) <= RTOL
        solved += int(np.all(np.isfinite(T.min_norm_many(W, wr, d.tension_min, d.tension_max))))
    assert solved > 0, "no pose had feasible tensions: the comparison tested nothing"


@pytest.mark.parametrize("seed", range(6))
def test_lower_bounds_only_equals_bvls(seed):
    """min_norm_above (the kernel with t_max = inf) = BVLS with t_max = inf."""
    rng = np.random.default_rng(2000 + seed)
    d = spec.from_dict(random_planar_data(rng, m=4))
    inf = np.full(d.m, np.inf)
    compared = 0
    for pose in _planar_poses(d, rng, 10):
        W = kin.structure_matrix(d, pose)
        for w in _wrenches(d, pose, rng, 3):
            ref = bvls_min_norm(W, w, d.tension_min, inf)
            got = T.min_norm_above(W, w, d.tension_min)
            if ref is None:
                assert got is None
                continue
            assert got is not None
            assert np.max(np.abs(got - ref)) <= RTOL * max(1.0, np.max(np.abs(ref)))
            compared += 1
    assert compared > 0, "every wrench was infeasible: the comparison tested nothing"


def _redundant_planar(tmax: float) -> dict:
    return {"name": "p4", "motion": "2T", "frame": {"lower": [0, 0], "upper": [2, 2]},
            "effector": {"mass": 2.0, "size": [0.1, 0.1]}, "tension": [1.0, tmax],
            "cables": [{"name": n, "outlet": o, "attachment": [0, 0]} for n, o in
                       (("a", [0, 2]), ("b", [2, 2]), ("c", [0, 0]), ("d", [2, 0]))],
            "requirements": {"task_box": {"lower": [0.5, 0.5], "upper": [1.5, 1.5]}, "max_acceleration": 5.0},
            "workspace": {"grid": {"step": 0.25}}}


@pytest.mark.parametrize("tmax", [60.0, 25.0])
def test_sizing_calls_the_kernel(monkeypatch, tmax):
    """Every task pose goes through statics.tension.min_norm_many, and the envelope is its result
    (with t_max = 25 N some accelerations need more: min_norm_above then gives the tension to hold)."""
    d = spec.from_dict(_redundant_planar(tmax))
    calls = []
    real = T.min_norm_many

    def spy(W, wrenches, tmin, tmax):
        out = real(W, wrenches, tmin, tmax)
        calls.append((np.array(W), np.array(wrenches), out))
        return out

    monkeypatch.setattr(T, "min_norm_many", spy)
    env = ev.task_envelope(resolved(d, "size-motors"))
    assert len(calls) == env.poses == 25
    lo, inf = d.tension_min, np.full(d.m, np.inf)
    peak = np.full(d.m, -np.inf)
    static = np.full(d.m, -np.inf)
    for W, wrenches, out in calls:
        rows = [o if np.all(np.isfinite(o)) else bvls_min_norm(W, w, lo, inf) for o, w in zip(out, wrenches)]
        peak = np.maximum(peak, np.max(rows, axis=0))
        static = np.maximum(static, rows[0])
    np.testing.assert_allclose(env.peak_tension, peak, rtol=RTOL)
    np.testing.assert_allclose(env.static_tension, static, rtol=RTOL)
    if tmax == 25.0:
        assert np.max(env.peak_tension) > tmax
