"""cdpr_design.statics.tension: per-pose analysis, objectives, published figures, invariances."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog

import cdpr_design as cd
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics import tension as T

from .reference.tension import capacity_margin
from .reference_pose import analyse_pose

from .helpers import DESIGNS, invoke

IPANEMA1 = cd.load(DESIGNS / "ipanema1.yaml")
PLANAR4 = cd.load(DESIGNS / "planar4.yaml")


def test_wirex_ipanema1_cable_lengths():
    """WireX unit test values for IPAnema 1 (config/robots/IPAnema.wcrfx; docs/sources.md)."""
    L = kin.inverse_kinematics(IPANEMA1, [0, 0, 1, 0, 0, 0])
    assert np.allclose(L, 2.6148040079516472, rtol=0, atol=1e-12)
    L = kin.inverse_kinematics(IPANEMA1, [0.1, 0.2, 1, 0, 0, 0])
    four = [2.5882812830138846, 2.433762519228201, 2.659924810967408, 2.8019992862240346]
    assert np.allclose(L, four + four, rtol=0, atol=1e-12)


def test_algorithms_md_planar_point_mass():
    """algorithms.md: outlets (0, 2), (3, 2), point mass at (1, 1), m g = 9.81 N, t in [1, 40]."""
    d = cd.from_dict({
        "name": "pm", "motion": "2T", "gravity": [0, -9.81],
        "frame": {"lower": [0, 0], "upper": [3, 2]},
        "effector": {"mass": 1.0, "size": [0, 0]}, "tension": [1, 40],
        "cables": [{"name": "a", "outlet": [0, 2], "attachment": [0, 0]},
                   {"name": "b", "outlet": [3, 2], "attachment": [0, 0]}]})
    r = analyse_pose(d, [1, 1])
    assert r.feasible
    assert np.allclose(r.tensions, [9.2489567, 7.3119423], atol=1e-7)
    assert r.margin == pytest.approx(5.9880342, abs=1e-7)


def test_zero_length_cable_is_flagged():
    r = analyse_pose(PLANAR4, [-0.1, 0.05, 0.0])  # attachment of c1 on its outlet
    assert r.lengths[0] == pytest.approx(0.0, abs=1e-12)
    assert not r.feasible and np.isnan(r.margin) and np.all(np.isnan(r.tensions))


def _random_W(rng, n, m):
    W = rng.normal(size=(n, m))
    return W / np.linalg.norm(W, axis=0)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(40))
def test_objectives_against_linprog_and_cvxpy(seed):
    """min-norm (kernel, weighted too) vs cvxpy; min-max and min-sum vs scipy linprog."""
    rng = np.random.default_rng(seed)
    n = int(rng.choice([2, 3, 6]))
    m = n + int(rng.integers(2, 5))
    W = _random_W(rng, n, m)
    tmin = rng.uniform(0, 5, m)
    tmax = tmin + rng.uniform(20, 80, m)
    w = W @ rng.uniform(tmin + 2, tmax - 2)  # feasible by construction
    c = rng.uniform(0.5, 3.0, m)
    for weights in (None, c):
        t = T.min_norm(W, w, tmin, tmax, weights=weights)
        ref = T.solve_cvxpy(W, w, tmin, tmax, "min-norm", weights, accurate=True)
        assert np.max(np.abs(t - ref)) <= 1e-6
        osqp = T.solve_cvxpy(W, w, tmin, tmax, "min-norm", weights)  # the default OSQP path
        assert np.max(np.abs(osqp - ref)) <= 1e-3
    cw = np.ones(m) if seed % 2 else c
    # min-max: min s, c_i t_i <= s (variables t, s)
    A_ub = np.hstack([np.diag(cw), -np.ones((m, 1))])
    res = linprog(np.r_[np.zeros(m), 1.0], A_ub=A_ub, b_ub=np.zeros(m),
                  A_eq=np.hstack([W, np.zeros((n, 1))]), b_eq=w,
                  bounds=list(zip(tmin, tmax)) + [(None, None)], method="highs")
    t = T.solve_cvxpy(W, w, tmin, tmax, "min-max", cw)
    assert np.max(cw * t) == pytest.approx(res.fun, rel=1e-6, abs=1e-6)
    assert np.allclose(W @ t, w, atol=1e-6)
    res = linprog(cw, A_eq=W, b_eq=w, bounds=list(zip(tmin, tmax)), method="highs")
    t = T.solve_cvxpy(W, w, tmin, tmax, "min-sum", cw)
    assert cw @ t == pytest.approx(res.fun, rel=1e-6, abs=1e-6)


def test_infeasible_objectives_give_none():
    W = np.array([[1.0, -1.0, 0.5], [0.0, 1.0, 1.0]])
    tmin, tmax = np.zeros(3), np.ones(3)
    w = np.array([0.0, 10.0])  # beyond any tension in [0, 1]
    assert T.min_norm(W, w, tmin, tmax) is None
    for obj in T.OBJECTIVES:
        assert T.solve_cvxpy(W, w, tmin, tmax, obj) is None


def test_analyse_pose_objectives_and_weights():
    pose = [0.5, 0.3, 1.0, 0.0, 0.0, 0.0]
    r = analyse_pose(IPANEMA1, pose)
    assert r.feasible and r.closure and r.rank_ok
    assert np.allclose(r.W @ r.tensions, r.wrenches[0], atol=1e-8)
    for obj in ("min-max", "min-sum"):
        ro = analyse_pose(IPANEMA1, pose, objective=obj)
        assert ro.feasible and ro.margin == r.margin
        assert np.allclose(ro.W @ ro.tensions, ro.wrenches[0], atol=1e-5)
    rmax = analyse_pose(IPANEMA1, pose, objective="min-max")
    assert rmax.tensions.max() <= r.tensions.max() + 1e-6
    rsum = analyse_pose(IPANEMA1, pose, objective="min-sum")
    assert rsum.tensions.sum() <= r.tensions.sum() + 1e-6
    with pytest.raises(ValueError, match="weights"):
        analyse_pose(IPANEMA1, pose, weights=[1, 2])
    with pytest.raises(ValueError, match="objective"):
        analyse_pose(IPANEMA1, pose, objective="min-foo")


def test_wrench_feasible_kind_uses_every_vertex():
    pose = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    rs = analyse_pose(IPANEMA1, pose, kind="static")
    rw = analyse_pose(IPANEMA1, pose, kind="wrench-feasible")
    assert rw.wrenches.shape == (1 + 2 ** 6, 6)
    assert rw.margin <= rs.margin
    assert rw.margin == pytest.approx(capacity_margin(rw.W, rw.wrenches, IPANEMA1.tension_min,
                                                     IPANEMA1.tension_max))


# ----------------------------------------------------------------------------
# Invariance: moving or turning the whole robot changes nothing
# ----------------------------------------------------------------------------


def _moved(design, shift, angle):
    """The same robot translated by ``shift`` and turned by ``angle`` about the gravity axis."""
    raw = copy.deepcopy(design.raw)
    dim = design.motion.dim
    c, s = np.cos(angle), np.sin(angle)
    R2 = np.array([[c, -s], [s, c]])

    def turn(v, translate):
        v = np.asarray(v, float)
        out = v.copy()
        out[:2] = R2 @ v[:2]
        if translate:
            out = out + np.asarray(shift)[:dim]
        return [float(x) for x in out]

    for cab in raw["cables"]:
        cab["outlet"] = turn(cab["outlet"], True)
        cab["attachment"] = turn(cab["attachment"], False)
    eff = raw["effector"]
    if "center_of_mass" in eff:
        eff["center_of_mass"] = turn(eff["center_of_mass"], False)
    if dim == 2:  # planar: gravity lies in the plane of the turn
        raw["gravity"] = turn(raw.get("gravity", [0.0, -9.81]), False)
    raw.pop("workspace", None)  # the box of external wrench is not turned
    raw["frame"] = {"lower": [-50.0] * dim, "upper": [50.0] * dim}
    return cd.from_dict(raw), R2


@settings(max_examples=40, deadline=None)
@given(x=st.floats(-1.5, 1.5), y=st.floats(-1.2, 1.2), z=st.floats(0.2, 1.8),
       sx=st.floats(-5, 5), sy=st.floats(-5, 5), sz=st.floats(-5, 5),
       ang=st.floats(-np.pi, np.pi))
def test_spatial_invariance(x, y, z, sx, sy, sz, ang):
    base = analyse_pose(IPANEMA1, [x, y, z, 0, 0, 0], kind="wrench-closure")
    moved, R2 = _moved(IPANEMA1, [sx, sy, sz], ang)
    p = np.r_[R2 @ [x, y], z] + [sx, sy, sz]
    # the platform frame turned with the robot: same attachments in the frame
    r = analyse_pose(moved, list(p) + [0, 0, 0], kind="wrench-closure")
    assert r.feasible == base.feasible
    assert r.closure == base.closure
    assert r.margin == pytest.approx(base.margin, rel=1e-9, abs=1e-9)
    assert np.allclose(r.lengths, base.lengths, atol=1e-12)
    if base.feasible and np.all(np.isfinite(base.tensions)):
        assert np.allclose(r.tensions, base.tensions, atol=1e-6)


@settings(max_examples=40, deadline=None)
@given(x=st.floats(0.3, 1.7), y=st.floats(0.3, 1.2), phi=st.floats(-0.3, 0.3),
       sx=st.floats(-5, 5), sy=st.floats(-5, 5), ang=st.floats(-np.pi, np.pi))
def test_planar_invariance(x, y, phi, sx, sy, ang):
    base = analyse_pose(PLANAR4, [x, y, phi])
    moved, R2 = _moved(PLANAR4, [sx, sy], ang)
    p = R2 @ [x, y] + [sx, sy]
    r = analyse_pose(moved, [p[0], p[1], phi])
    assert r.feasible == base.feasible
    assert r.margin == pytest.approx(base.margin, rel=1e-9, abs=1e-9)
    if base.feasible:
        assert np.allclose(r.tensions, base.tensions, atol=1e-6)


def test_cli_pose_objective_and_weights():
    import json

    spec = str(DESIGNS / "ipanema1.yaml")
    at = "0.5,0.3,1,0,0,0"
    base = json.loads(invoke("pose", spec, "--at", at, "--json").stdout)
    assert base["objective"] == "min-norm"
    for obj in ("min-max", "min-sum"):
        res = invoke("pose", spec, "--at", at, "--objective", obj, "--json")
        assert res.exit_code == 0, res.output
        data = json.loads(res.stdout)
        assert data["objective"] == obj and data["feasible"] and data["margin"] == base["margin"]
        t = np.array(list(data["tensions"].values()))
        t0 = np.array(list(base["tensions"].values()))
        if obj == "min-max":
            assert t.max() <= t0.max() + 1e-6
        else:
            assert t.sum() <= t0.sum() + 1e-6
    res = invoke("pose", spec, "--at", at, "--weights", "1,2")
    assert res.exit_code == 2 and "--weights" in res.output
    res = invoke("pose", spec, "--at", at, "--weights", "1,1,1,1,1,1,1,-1")
    assert res.exit_code == 2 and "positive" in res.output
    res = invoke("pose", spec, "--at", at, "--objective", "min-foo")
    assert res.exit_code == 2
