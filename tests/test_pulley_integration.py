"""Swivel pulleys in sizing, trajectories and the simulation; orientation-mode collision counts.

The pulley geometry (cdpr_design/pulley.py: length = arc + free segment, the
free segment leaves the pulley's tangent point) must reach every analysis:

- r -> 0 gives back the point-outlet sizing rows and trajectory samples;
- with pulleys, trajectory cable speeds and accelerations are the time
  derivatives (central finite differences) of the pulley-aware lengths of
  ``kinematics.inverse_kinematics`` (built on ``pulley.outlet_geometry``, an
  independent code path from the vectorised ``pulley.cable_paths``);
- the sizing envelope's tensions are those of the pose evaluation (``cd.pose``)
  (pulley-aware numba kernel) at the same poses;
- the Hessian of the length used for the cable-acceleration terms matches
  finite differences (Pott 2018, pulley kinematics: the level sets of L in
  the pulley plane are involutes of the pulley circle).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cdpr_design.statics import kinematics as kin
from cdpr_design.statics import pulley as pl
from cdpr_design.motion import simulation as sim
from cdpr_design.motion.run import simulate
from cdpr_design.design import envelope as ev
from cdpr_design.design import sizing as sz
from cdpr_design.model import spec
from cdpr_design.motion import trajectory as tr
from cdpr_design.workspaces import orientation as hwm
from cdpr_design import workspaces as ws
from cdpr_design.workspaces import grid as wsg
from cdpr_design import api
from cdpr_design.statics.interference import HIT_NAMES, check_pose

from .helpers import add_pulleys, invoke, ipanema3_data, planar2_raw, planar4_cables, planar4_orient, write_spec, resolved
from .reference.kinematics import lengths_many


def planar2(radius=None):
    """The seed paper's planar robot; pulleys at the top corners fed up the posts (axis +y)."""
    d = planar2_raw()
    d.pop("plc", None)
    add_pulleys(d["cables"], radius, [[0.0, 1.0, 0.0]] * len(d["cables"]))
    return spec.from_dict(d)


def planar4(radius=None, axes=None):
    """A 1R2T robot with four cables (m > n), pulleys at the four corners."""
    cables = add_pulleys(planar4_cables(), radius, axes or [[0, 1, 0], [0, 1, 0], [0, -1, 0], [0, -1, 0]])
    return spec.from_dict({
        "name": "p4", "motion": "1R2T", "gravity": [0, -9.81],
        "frame": {"lower": [0, 0], "upper": [2, 2]},
        "effector": {"mass": 1.5, "size": [0.2, 0.1], "inertia": 0.01},
        "tension": [1, 80], "cables": cables,
        "winch": {"drum_radius": 0.02, "gear_ratio": 1.0},
        "workspace": {"grid": {"step": 0.1}, "orientation": [0.05]},
        "requirements": {"task_box": {"lower": [0.6, 0.6], "upper": [1.4, 1.4]},
                         "max_speed": 0.5, "max_acceleration": 2.0},
        "trajectories": {
            "tilt": {"type": "polyline", "speed": 0.4, "acceleration": 3.0,
                     "waypoints": [[0.7, 0.8, 0.0], [1.3, 0.9, 0.15], [1.1, 1.3, -0.1]]},
            "ring": {"type": "circle", "center": [1.0, 1.0], "radius": 0.25, "speed": 0.5,
                     "acceleration": 3.0}},
    })


def ipanema3(radius=None):
    """IPAnema 3 (docs/sources.md: cdpyr sample); upper cables come up their posts (+z),
    lower cables come down (-z)."""
    return spec.from_dict(ipanema3_data(
        "ip3", radius,
        winch={"drum_radius": 0.05, "gear_ratio": 10.0},
        workspace={"grid": {"lower": [-2, -2, 0.8], "upper": [2, 2, 2.0], "step": 2.0}},
        requirements={"max_speed": 1.0, "max_acceleration": 2.0},
        trajectories={"swing": {"type": "polyline", "speed": 1.0, "acceleration": 2.0,
                                "waypoints": [[0, 0, 1.2, 0, 0, 0], [1.0, 0.5, 1.5, 0.1, -0.08, 0.2],
                                              [-0.5, 0.8, 1.0, -0.1, 0.1, -0.15]]}},
    ))


def _rows_close(a, b, rtol):
    assert len(a) == len(b) > 0  # zip() would compare nothing, or stop at the shorter
    for ra, rb in zip(a, b):
        assert ra.keys() == rb.keys()
        for k in ra:
            va, vb = ra[k], rb[k]
            if isinstance(va, float) and np.isfinite(va):
                assert vb == pytest.approx(va, rel=rtol, abs=rtol), (ra["cable"], k)
            else:
                assert va == vb, (ra["cable"], k)


# ----------------------------------------------------------------------------
# Pulley geometry for many cables: against the per-cable construction
# ----------------------------------------------------------------------------


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2 ** 31 - 1))
def test_cable_paths_equal_outlet_geometry_and_exit_point(seed):
    rng = np.random.default_rng(seed)
    m = 4
    A = rng.normal(size=(m, 3))
    K = rng.normal(size=(m, 3))
    K /= np.linalg.norm(K, axis=1)[:, None]
    r = np.array([0.0, 0.05, 0.3, 0.01])
    B = A[None] + rng.normal(size=(6, m, 3)) * 1.5
    p = pl.cable_paths(A, K, r, B)
    for i in range(m):
        g = pl.outlet_geometry(A[i], K[i], r[i], B[:, i])
        np.testing.assert_allclose(p.lengths[:, i], g.lengths, rtol=0, atol=1e-12)
        np.testing.assert_allclose(p.exits[:, i], g.exits, rtol=0, atol=1e-12)
        np.testing.assert_allclose(p.wrap[:, i], g.wrap, rtol=0, atol=1e-12)
        for j in range(B.shape[0]):
            C, beta = pl.exit_point(tuple(A[i]), tuple(K[i]), r[i], tuple(B[j, i]))
            if np.isnan(g.lengths[j]):
                assert C is None
            else:
                np.testing.assert_allclose(C, g.exits[j], atol=1e-12)
                assert beta == pytest.approx(g.wrap[j], abs=1e-12)


@pytest.mark.slow
@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2 ** 31 - 1), st.sampled_from([0.0, 0.02, 0.3]))
def test_length_hessian_matches_finite_differences(seed, radius):
    """v^T H v of CablePaths (arc + free length) against a central second difference,
    and max_curvature against the largest |eigenvalue| of the finite-difference Hessian."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=3)
    k = rng.normal(size=3)
    k /= np.linalg.norm(k)
    b = a + rng.normal(size=3) * 1.5
    if np.linalg.norm(b - a) < 4 * radius + 0.2:
        b = a + (b - a) / np.linalg.norm(b - a) * (4 * radius + 0.2)

    def L(x):
        return pl.outlet_geometry(a, k, radius, x).lengths[0]

    h = 1e-4
    H = np.empty((3, 3))
    E = np.eye(3) * h
    for i in range(3):
        for j in range(3):
            H[i, j] = (L(b + E[i] + E[j]) - L(b + E[i] - E[j]) - L(b - E[i] + E[j]) + L(b - E[i] - E[j])) / (4 * h * h)
    p = pl.cable_paths(a[None], k[None], [radius], b[None, None])
    v = rng.normal(size=3)
    assert p.second_derivative(v[None, None])[0, 0] == pytest.approx(v @ H @ v, rel=1e-4, abs=1e-5)
    assert p.max_curvature()[0, 0] == pytest.approx(np.abs(np.linalg.eigvalsh(H)).max(), rel=1e-4, abs=1e-5)


# ----------------------------------------------------------------------------
# Trajectories
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("make,name", [(planar2, "square_fast"), (planar4, "tilt"), (planar4, "ring"),
                                       (ipanema3, "swing")])
def test_trajectory_radius_to_zero_is_point_outlet(make, name):
    d0, d1 = make(None), make(1e-9)
    from cdpr_design.statics.robot import resolve

    assert resolve(d0).outlets.name == "points" and resolve(d1).outlets.name == "pulleys"
    s0, s1 = tr.sample(resolved(d0, "motion"), name), tr.sample(resolved(d1, "motion"), name)
    np.testing.assert_array_equal(s0.time, s1.time)
    np.testing.assert_allclose(s1.lengths, s0.lengths, rtol=0, atol=1e-8)
    np.testing.assert_allclose(s1.cable_speed, s0.cable_speed, rtol=0, atol=1e-7)
    np.testing.assert_allclose(s1.cable_accel, s0.cable_accel, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(s1.tensions, s0.tensions, rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(s1.feasible, s0.feasible)


@pytest.mark.slow
@pytest.mark.parametrize("make,radius,name", [(planar2, 0.05, "square_fast"), (planar4, 0.08, "tilt"),
                                              (planar4, 0.08, "ring"), (ipanema3, 0.1, "swing")])
def test_trajectory_speeds_are_derivatives_of_pulley_lengths(make, radius, name):
    d, d0 = make(radius), make(None)
    s = tr.sample(resolved(d, "motion"), name)
    ik = lengths_many(d, s.pose) if not d.motion.rotational else \
        np.array([kin.inverse_kinematics(d, p) for p in s.pose[::5]])
    np.testing.assert_allclose(s.lengths[:: (1 if not d.motion.rotational else 5)], ik, rtol=0, atol=1e-10)
    t, L = s.time, s.lengths
    dt = np.diff(t)
    assert np.allclose(dt, dt[0])
    # central differences at samples whose neighbours lie in the same profile phase (the
    # trapezoid's acceleration jumps cost O(dt * jump) there); error O(dt^2 |L'''|) elsewhere
    jumps = np.abs(np.diff(s.acceleration, axis=0)).max(axis=1) > 0.05 * np.abs(s.acceleration).max() + 1e-9
    smooth = ~(jumps[1:] | jumps[:-1])
    assert smooth.sum() > len(smooth) // 2
    fd = ((L[2:] - L[:-2]) / (2 * dt[0]))[smooth]
    speed = s.cable_speed[1:-1][smooth]
    err = np.abs(fd - speed)
    assert err.max() < 1e-5 * max(1.0, np.abs(speed).max())
    # the point-outlet speeds differ from the pulley lengths' derivatives by far more
    s0 = tr.sample(resolved(d0, "motion"), name)
    assert np.abs(s0.cable_speed[1:-1][smooth] - fd).max() > 20 * err.max()
    # accelerations: second differences
    fd2 = ((L[2:] - 2 * L[1:-1] + L[:-2]) / dt[0] ** 2)[smooth]
    acc = s.cable_accel[1:-1][smooth]
    err2 = np.abs(fd2 - acc)
    assert err2.max() < 1e-3 * max(1.0, np.abs(acc).max())
    assert np.abs(s0.cable_accel[1:-1][smooth] - fd2).max() > 5 * err2.max()
    # the structure matrix the tensions solve uses the pulley's tangent point
    st = tr.states(resolved(d, "motion"), s.pose[::50], s.velocity[::50], s.acceleration[::50])
    for j, p in enumerate(s.pose[::50]):
        np.testing.assert_allclose(st["structure"][j], kin.structure_matrix(d, p), atol=1e-12)


# ----------------------------------------------------------------------------
# Sizing
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("make", [planar2, planar4])
def test_sizing_radius_to_zero_is_point_outlet(make, catalogue):
    d0, d1 = make(None), make(1e-9)
    r0 = sz.size_motors(resolved(d0, "size-motors"), catalogue, step=0.05).rows()
    r1 = sz.size_motors(resolved(d1, "size-motors"), catalogue, step=0.05).rows()
    _rows_close(r0, r1, 1e-6)


def test_sizing_radius_to_zero_is_point_outlet_spatial(catalogue):
    d0, d1 = ipanema3(None), ipanema3(1e-9)
    pos = np.array([[0.0, 0.0, 1.2], [1.5, -1.0, 1.8], [-2.0, 1.0, 0.8]])
    e0 = ev.task_envelope(resolved(d0, "size-motors"), positions=pos)
    e1 = ev.task_envelope(resolved(d1, "size-motors"), positions=pos)
    r0 = sz.size_motors(resolved(d0, "size-motors"), catalogue, envelope=e0).rows()
    r1 = sz.size_motors(resolved(d1, "size-motors"), catalogue, envelope=e1).rows()
    _rows_close(r0, r1, 1e-6)


@pytest.mark.slow
@pytest.mark.parametrize("make,radius", [(planar2, 0.05), (planar4, 0.08), (ipanema3, 0.1)])
def test_sizing_tensions_equal_per_pose_evaluation(make, radius):
    """Static tensions of the sizing envelope (A = V = 0) = the pose evaluation (``cd.pose``) at every pose,
    and the envelope's peak is their maximum."""
    d = make(radius)
    d0 = make(None)
    if d.motion.name == "3R3T":
        pos = np.array([[0.0, 0.0, 1.2], [1.5, -1.0, 1.8], [-2.0, 1.0, 0.8], [0.5, 0.5, 1.0]])
    else:
        g = ev.task_grid(d, 0.1)
        pos = wsg.grid_positions(g, 0, g.size)
    ori = d.default_orientation_full()
    e = ev.envelope_chunk(resolved(d, "size-motors"), pos, ori, 0.0, 0.0)
    e0 = ev.envelope_chunk(resolved(d0, "size-motors"), pos, ori, 0.0, 0.0)
    rot = ev.rotation_coords(d, ori)
    ref = np.full((pos.shape[0], d.m), np.nan)
    for j, p in enumerate(pos):
        r = api.pose(d, np.concatenate([p, rot]))
        if r.feasible:
            ref[j] = r.tensions
    feas = np.all(np.isfinite(ref), axis=1)
    assert feas.sum() >= min(3, pos.shape[0])
    np.testing.assert_allclose(e["static"][feas], ref[feas], rtol=1e-6, atol=1e-6)
    env = ev.task_envelope(resolved(d, "size-motors"), positions=pos[feas])
    assert env.static_tension == pytest.approx(ref[feas].max(axis=0), rel=1e-6, abs=1e-6)
    # not the point-outlet figures: the pulley changes the tensions
    assert np.nanmax(np.abs(e0["static"][feas] - ref[feas])) > 1e-4


@pytest.mark.slow
def test_sizing_cable_acceleration_bound_with_pulleys():
    """accel = A + V^2 max(1/l_f, |kappa_t|) bounds |L''| = |v^T H v - u . a| over |v| <= V, |a| <= A,
    and is attained (v along H's top eigenvector, a along -/+u)."""
    d = planar4(0.08, axes=[[1, 0, 0], [0, 1, 0], [0, -1, 0], [-1, 0, 0]])
    A, V = 2.0, 0.5
    pos = np.array([[0.7, 0.8], [1.2, 1.3], [1.0, 0.6]])
    ori = d.default_orientation_full()
    e = ev.envelope_chunk(resolved(d, "size-motors"), pos, ori, A, V)
    rng = np.random.default_rng(3)
    rot = ev.rotation_coords(d, ori)
    for j, p in enumerate(pos):
        pose = np.concatenate([p, rot])
        best = np.zeros(d.m)
        for _ in range(400):
            v = rng.normal(size=2)
            v *= V / np.linalg.norm(v)
            a = rng.normal(size=2)
            a *= A / np.linalg.norm(a)
            st = tr.states(resolved(d, "motion"), pose[None], np.r_[v, 0.0][None], np.r_[a, 0.0][None])
            best = np.maximum(best, np.abs(st["cable_accel"][0]))
        assert np.all(best <= e["accel"][j] + 1e-9)
        assert np.all(best >= 0.97 * e["accel"][j])


# ----------------------------------------------------------------------------
# Simulation
# ----------------------------------------------------------------------------


@pytest.mark.slow
def test_simulation_uses_pulley_lengths():
    """The MuJoCo model's cable lengths are arc + free segment (tendon from the tangent point)."""
    d = planar4(0.08)
    s = tr.sample(resolved(d, "motion"), "tilt")
    res = simulate(resolved(d, "motion"), s)
    # the lengths the model reports are the pulley-aware lengths at the simulated pose (where
    # it is nearly at rest: MuJoCo's tendon lengths are those of the step's start)
    rest = np.flatnonzero(np.linalg.norm(s.velocity, axis=1) < 1e-3)
    assert rest.size >= 3
    for j in rest[::max(1, rest.size // 20)]:
        np.testing.assert_allclose(res.lengths[j], kin.inverse_kinematics(d, res.pose[j]), atol=1e-5)
    # and it tracks the pulley-aware set-points: the pose error is what the servo lag and
    # the cable stretch make (sub-millimetre); a straight outlet tendon would be off by ~r
    assert res.summary()["max_error"] < 2e-3
    assert np.abs(res.lengths - res.target_lengths).max() < 1e-3
    sm = sim.Simulator(resolved(d, "motion"))
    st0 = sm.reset([1.0, 1.0, 0.05], settle=0.0)
    np.testing.assert_allclose(st0.lengths, kin.inverse_kinematics(d, [1.0, 1.0, 0.05]), atol=1e-12)
    assert np.all(np.abs(st0.lengths - kin.inverse_kinematics(planar4(None), [1.0, 1.0, 0.05])) > 0.01)


# ----------------------------------------------------------------------------
# --orientations with --collisions: summary counts
# ----------------------------------------------------------------------------


def _orient_design(**wsx):
    """A 1R2T robot whose grid (the frame box) reaches the frame: effector-frame hits at the
    border, cable-effector hits where the platform turns against its cables."""
    return planar4_orient("p4c", **wsx)


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["total", "range"])
def test_orientation_summary_has_collision_counts(mode):
    """collision_free / feasible_statics / collisions_by_kind equal counts from the per-orientation
    sweeps (total: collision free and statics feasible at every set orientation, a kind hits a
    pose at any of them; range: the nominal orientation's sweep)."""
    d = _orient_design(orientation_set={"lower": [-0.3], "upper": [0.3], "count": 3},
                       orientation_range={"max": [0.3], "levels": 3, "count": 3})
    res = ws.run(d, ws.Analysis(orientations=mode, collisions=True), keep_maps=False)
    s = res.summary()
    oris = hwm.orientation_set(d) if mode == "total" else d.default_orientation_full()[None]
    free = stat = None
    kinds = {name: None for name in HIT_NAMES.values()}
    for o in oris:
        chunks = []
        r = ws.run(d, ws.Analysis(collisions=True), orientation=o, on_chunk=chunks.append, keep_maps=False)
        cf = np.concatenate([c.collision_free for c in chunks]).astype(bool)
        poses = np.vstack([c.poses for c in chunks])
        st_ = np.zeros(len(poses), bool)
        hit = {name: np.zeros(len(poses), bool) for name in kinds}
        for j, p in enumerate(poses):
            pose = np.r_[p[:2], o[2]]
            st_[j] = api.pose(d, pose).feasible
            for name in check_pose(d, pose).kinds:
                hit[name][j] = True
        np.testing.assert_array_equal(cf, ~np.any(list(hit.values()), axis=0))
        free = cf if free is None else free & cf
        stat = st_ if stat is None else stat & st_
        for name in kinds:
            kinds[name] = hit[name] if kinds[name] is None else kinds[name] | hit[name]
        assert r.extra["collision_free"] == int(cf.sum())
    assert s["collision_free"] == int(free.sum())
    assert s["feasible_statics"] == int(stat.sum())
    assert s["collisions_by_kind"] == {k: int(v.sum()) for k, v in kinds.items()}
    assert 0 < s["collision_free"] < s["poses"]
    assert s["feasible"] <= min(s["collision_free"], s["feasible_statics"])


def test_cli_orientations_collisions_json(tmp_path):
    d = _orient_design(orientation_set={"lower": [-0.3], "upper": [0.3], "count": 3})
    path = write_spec(tmp_path, d.raw, "p4c.yaml")
    out = tmp_path / "out"
    r = invoke("workspace", path, "--orientations", "total", "--collisions", "--json", "--quiet", "--out", out)
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    for key in ("collision_free", "feasible_statics", "collisions_by_kind"):
        assert key in s
    assert json.loads((out / "summary.json").read_text())["collision_free"] == s["collision_free"]
    assert s["feasible"] <= s["collision_free"]
