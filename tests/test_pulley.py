"""Swivel-pulley outlets: IK against an independent construction, r -> 0, FK o IK, sweeps.

Geometry conventions: cdpr_design/pulley.py (Pott, "Cable-Driven Parallel
Robots", Springer 2018, pulley kinematics).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from cdpr_design.statics import kinematics as kin
from cdpr_design.statics import pulley as pl
from cdpr_design.model import spec
from cdpr_design import workspaces as ws
from cdpr_design import api
from cdpr_design.errors import SpecError

from .helpers import add_pulleys, ipanema3_data as _ipanema3_data, planar2_raw
from .reference.kinematics import length_rates, lengths_many

def ipanema3_data(radius=0.05):
    """IPAnema 3 geometry with swivel pulleys: the top cables come up their posts
    (axis +z), the bottom cables come down (axis -z)."""
    return _ipanema3_data("ipanema3p", radius,
                          workspace={"grid": {"lower": [-6, -4, 0.2], "upper": [6, 4, 2.6], "step": 1.2}})


def planar2_data(radius=0.02):
    """The seed paper's planar robot with pulleys at the top corners; the cables
    come up the frame's posts (axis +y)."""
    d = planar2_raw()
    d = {k: d[k] for k in ("name", "motion", "gravity", "frame", "effector", "tension", "cables", "workspace")}
    add_pulleys(d["cables"], radius, [[0.0, 1.0, 0.0]] * len(d["cables"]))
    d["workspace"]["grid"]["step"] = 0.05
    return d


# ----------------------------------------------------------------------------
# Independent construction: the taut cable is the shortest path that wraps the
# pulley from the entry point; it leaves tangentially, in the swivel plane.
# ----------------------------------------------------------------------------


def independent(a, k, r, B):
    """Tangent point by root finding on the circle (no closed form): the free
    segment B - C is perpendicular to the radius C - M and leaves C in the
    wrapping direction; L = r beta + |B - C|."""
    a, k, B = map(np.asarray, (a, k, B))
    k = k / np.linalg.norm(k)
    d = B - a
    rad = d - (d @ k) * k
    e = rad / np.linalg.norm(rad)       # swivel plane: contains the axis and B
    M = a + r * e

    def C(beta):  # entry point a = M - r e at beta = 0, wrapping towards +k then +e
        return M + r * (-np.cos(beta) * e + np.sin(beta) * k)

    def tangent(beta):
        return np.sin(beta) * e + np.cos(beta) * k

    def g(beta):
        c = C(beta)
        return (B - c) @ (c - M)

    grid = np.linspace(0.0, 2 * np.pi, 721)
    vals = np.array([g(b) for b in grid])
    roots = [brentq(g, grid[j], grid[j + 1], xtol=1e-15)
             for j in range(grid.size - 1) if vals[j] == 0 or vals[j] * vals[j + 1] < 0]
    good = [b for b in roots if (B - C(b)) @ tangent(b) > 0]
    assert len(good) == 1, (roots, good)
    beta = good[0]
    return r * beta + np.linalg.norm(B - C(beta)), C(beta), beta, M


def random_case(rng):
    a = rng.uniform(-2, 2, 3)
    k = rng.normal(size=3)
    k /= np.linalg.norm(k)
    r = rng.uniform(0.01, 0.3)
    while True:
        B = a + rng.uniform(-3, 3, 3)
        g = pl.outlet_geometry(a, k, r, B)
        # keep cases that wrap (beta > 0) and are not inside the circle
        if np.isfinite(g.lengths[0]) and g.wrap[0] > 1e-3:
            return a, k, r, B


@pytest.mark.slow
def test_ik_matches_shortest_wrapping_path_on_random_pulleys():
    rng = np.random.default_rng(7)
    for _ in range(80):
        a, k, r, B = random_case(rng)
        g = pl.outlet_geometry(a, k, r, B)
        L_ref, C_ref, beta_ref, M = independent(a, k, r, B)
        assert g.lengths[0] == pytest.approx(L_ref, abs=1e-9)
        assert g.wrap[0] == pytest.approx(beta_ref, abs=1e-5)
        np.testing.assert_allclose(g.exits[0], C_ref, atol=1e-5)
        C = g.exits[0]
        # the exit lies on the pulley circle, the free segment is tangent to it,
        # and a, k, C, B are coplanar (the swivel plane)
        assert np.linalg.norm(C - M) == pytest.approx(r, rel=1e-10)
        assert abs((B - C) @ (C - M)) <= 1e-9 * np.linalg.norm(B - C) * r + 1e-12
        assert abs(np.linalg.det(np.array([k, C - a, B - a]))) < 1e-9
        assert g.free_lengths[0] == pytest.approx(np.linalg.norm(B - C), rel=1e-12)


def test_hand_computed_wraps():
    a = np.array([1.0, 2.0, 3.0])
    k = np.array([0.0, 0.0, 1.0])
    r = 0.1
    e = np.array([1.0, 0.0, 0.0])
    # far away at the height of the pulley's top: a quarter wrap, L = r pi/2 + X
    X = 4.0
    g = pl.outlet_geometry(a, k, r, a + (r + X) * e + r * k)
    assert g.wrap[0] == pytest.approx(np.pi / 2, abs=1e-12)
    assert g.lengths[0] == pytest.approx(r * np.pi / 2 + X, abs=1e-12)
    np.testing.assert_allclose(g.exits[0], a + r * e + r * k, atol=1e-12)
    # straight down on the far side: half a turn, L = pi r + h
    h = 2.5
    g = pl.outlet_geometry(a, k, r, a + 2 * r * e - h * k)
    assert g.wrap[0] == pytest.approx(np.pi, abs=1e-12)
    assert g.lengths[0] == pytest.approx(np.pi * r + h, abs=1e-12)
    # straight ahead on the axis (+k): no wrap, the cable runs on from the swivel point
    g = pl.outlet_geometry(a, k, r, a + 3.0 * k)
    assert g.wrap[0] == pytest.approx(0.0, abs=1e-12)
    assert g.lengths[0] == pytest.approx(3.0, abs=1e-12)
    np.testing.assert_allclose(g.exits[0], a, atol=1e-12)
    # slightly off the axis ahead: a small wrap towards the attachment
    g = pl.outlet_geometry(a, k, r, a + 0.5 * r * e + 3.0 * k)
    assert 0 < g.wrap[0] < 0.05
    # on the swivel axis below: the swivel angle does not matter
    g = pl.outlet_geometry(a, k, r, a - 2.0 * k)
    L_ref, _, _, _ = independent(a, k, r, a - 2.0 * k + 1e-9 * e)
    assert g.lengths[0] == pytest.approx(L_ref, abs=1e-7)
    # inside the pulley circle: no taut cable
    assert np.isnan(pl.outlet_geometry(a, k, r, a + r * e + 0.5 * r * k).lengths[0])


@settings(max_examples=60, deadline=None)
@given(st.floats(0.0, 1.0), st.integers(0, 10_000))
def test_radius_to_zero_is_the_point_outlet(t, seed):
    rng = np.random.default_rng(seed)
    a = rng.uniform(-2, 2, 3)
    k = rng.normal(size=3)
    B = a + rng.uniform(-3, 3, 3)
    r = 1e-9 * t
    g = pl.outlet_geometry(a, k, r, B)
    assert g.lengths[0] == pytest.approx(np.linalg.norm(B - a), abs=1e-8)
    np.testing.assert_allclose(g.exits[0], a, atol=1e-8)
    # and the length error is first order in r (at most r (beta + 1))
    r = 1e-3
    g = pl.outlet_geometry(a, k, r, B)
    assert abs(g.lengths[0] - np.linalg.norm(B - a)) <= r * (2 * np.pi + 1)


def test_zero_radius_design_equals_point_outlet_design_in_every_api():
    d0 = spec.from_dict(ipanema3_data(None))
    dz = spec.from_dict(ipanema3_data(0.0))
    pose = [0.3, -0.4, 1.2, 0.05, -0.03, 0.1]
    np.testing.assert_array_equal(kin.inverse_kinematics(d0, pose), kin.inverse_kinematics(dz, pose))
    np.testing.assert_allclose(kin.structure_matrix(d0, pose), kin.structure_matrix(dz, pose))
    a = api.pose(d0, pose)
    b = api.pose(dz, pose)
    assert a.feasible == b.feasible
    np.testing.assert_allclose(a.tensions, b.tensions, rtol=1e-9)


def test_structure_matrix_uses_the_true_outlet_points():
    d = spec.from_dict(ipanema3_data(0.05))
    rng = np.random.default_rng(3)
    for _ in range(20):
        pose = np.concatenate([rng.uniform([-5, -3, 0.3], [5, 3, 2.5]), rng.uniform(-0.2, 0.2, 3)])
        g = kin.cable_geometry(d, pose)
        R = kin.rotation_matrix(*pose[3:])
        for i, c in enumerate(d.cables):
            ref = pl.outlet_geometry(c.outlet, c.pulley.axis, c.pulley.radius,
                                     pose[:3] + R @ np.asarray(c.attachment))
            np.testing.assert_allclose(g.exits[i], ref.exits[0], atol=1e-12)
            assert g.lengths[i] == pytest.approx(ref.lengths[0], rel=1e-13)
        u = (g.exits - g.anchors) / np.linalg.norm(g.exits - g.anchors, axis=1)[:, None]
        W_ref = np.vstack([u.T, np.cross(g.attachments, u).T])
        W = kin.structure_matrix(d, pose)
        np.testing.assert_allclose(W, W_ref, atol=1e-13)
        # the numba kernel (sweeps, pose command) gives the same W and lengths
        r = api.pose(d, pose)
        np.testing.assert_allclose(r.W, W, atol=1e-12)
        np.testing.assert_allclose(r.lengths, g.lengths, rtol=1e-12)


def test_length_gradient_is_minus_the_free_direction():
    """dL/dt = -W^T [v; omega]: finite differences of the pulley-aware lengths."""
    d = spec.from_dict(ipanema3_data(0.08))
    rng = np.random.default_rng(11)
    for _ in range(10):
        pose = np.concatenate([rng.uniform([-5, -3, 0.3], [5, 3, 2.5]), rng.uniform(-0.2, 0.2, 3)])
        vel = rng.normal(size=6)
        h = 1e-6
        fd = (kin.inverse_kinematics(d, pose + h * vel) - kin.inverse_kinematics(d, pose - h * vel)) / (2 * h)
        np.testing.assert_allclose(length_rates(d, pose, vel), fd, rtol=1e-6, atol=1e-7)


def test_fk_inverts_pulley_ik_spatial():
    d = spec.from_dict(ipanema3_data(0.05))
    rng = np.random.default_rng(5)
    for _ in range(8):
        pose = np.concatenate([rng.uniform([-5, -3, 0.3], [5, 3, 2.5]), rng.uniform(-0.2, 0.2, 3)])
        L = kin.inverse_kinematics(d, pose)
        guess = pose + np.concatenate([rng.normal(scale=0.05, size=3), rng.normal(scale=0.02, size=3)])
        res = kin.forward_kinematics(d, L, guess=guess)
        assert res.residual < 1e-9
        np.testing.assert_allclose(res.pose, pose, atol=1e-7)
        # and the point-outlet FK would be off by the pulley effect
        d0 = spec.from_dict(ipanema3_data(None))
        assert np.linalg.norm(kin.inverse_kinematics(d0, pose) - L) > 1e-3


def test_fk_inverts_pulley_ik_planar2():
    d = spec.from_dict(planar2_data(0.02))
    for p in ([0.75, 0.75], [0.4, 1.0], [1.1, 0.3]):
        L = kin.inverse_kinematics(d, p)
        res = kin.forward_kinematics(d, L)  # starts from the point-outlet closed form
        assert res.residual < 1e-10
        np.testing.assert_allclose(res.pose, p, atol=1e-8)


def test_sweep_honours_pulleys():
    d = spec.from_dict(planar2_data(0.02))
    chunks = []
    res = ws.run(d, on_chunk=chunks.append)
    poses = np.vstack([c.poses for c in chunks])
    L = np.vstack([c.lengths for c in chunks])
    np.testing.assert_allclose(L, lengths_many(d, poses), rtol=1e-12)
    feas = np.concatenate([c.feasible for c in chunks])
    # spot-check feasibility and tensions against the per-pose evaluation
    for j in range(0, poses.shape[0], 37):
        r = api.pose(d, poses[j])
        assert bool(feas[j]) == r.feasible
    assert res.extra["pulleys"] is True
    # pulleys of radius 0 give the point-outlet sweep exactly
    dz = spec.from_dict(planar2_data(0.0))
    d0 = spec.from_dict({**planar2_data(0.0), "cables": [
        {k: v for k, v in c.items() if k != "pulley"} for c in planar2_data(0.0)["cables"]]})
    a, b = [], []
    ws.run(dz, on_chunk=a.append)
    ws.run(d0, on_chunk=b.append)
    assert len(a) == len(b) > 0  # zip() would compare nothing, or stop at the shorter
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x.feasible, y.feasible)
        np.testing.assert_allclose(x.tensions, y.tensions, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(x.lengths, y.lengths, rtol=1e-14)


def test_planar_pulley_axis_must_lie_in_the_plane():
    data = planar2_data(0.02)
    data["cables"][1]["pulley"]["axis"] = [0.0, 0.0, 1.0]
    with pytest.raises(SpecError) as e:
        spec.from_dict(data)
    assert e.value.problems[0][0] == "cables[1].pulley.axis"
