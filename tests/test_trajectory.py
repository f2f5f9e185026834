"""Trajectory sampling: profiles within their limits, exact waypoints, kinematics and
inertial tensions checked against finite differences and the per-pose kinematics API."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cdpr_design.statics import kinematics as kin
from cdpr_design.model import spec
from cdpr_design.motion import paths
from cdpr_design.motion import profile
from cdpr_design.motion import trajectory as tr
from cdpr_design.model.design import Trajectory

from .helpers import PLANAR2, csv_header, invoke, point_mass, static_tensions, write_spec, resolved
from .reference.kinematics import length_rates

REL = 1e-9


# ----------------------------------------------------------------------------
# Profiles
# ----------------------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(D=st.floats(1e-4, 3.0), v=st.floats(0.01, 2.0), a=st.floats(0.1, 20.0),
       j=st.one_of(st.none(), st.floats(5.0, 500.0)), dt=st.sampled_from([1e-3, 5e-4, 2e-3]))
def test_profile_limits_and_exact_end(D, v, a, j, dt):
    """Speed and acceleration never exceed the limits; the profile ends at rest exactly at D,
    after a whole number of cycles."""
    prof = profile.trapezoid(D, v, a) if j is None else profile.double_s(D, v, a, j)
    prof = profile.fit_to_cycle(prof, dt)
    n = prof.duration / dt
    assert abs(n - round(n)) < 1e-6
    t = dt * np.arange(int(round(n)) + 1)
    s, sd, sdd = prof.evaluate(t)
    assert s[0] == 0.0 and s[-1] == D and sd[-1] == 0.0
    assert np.all(np.diff(s) >= -1e-15)
    assert np.all(np.abs(sd) <= v * (1 + REL))
    assert np.all(np.abs(sdd) <= a * (1 + REL))
    # the speed is the derivative of the position (trapezoid rule, error <= a dt / 4)
    fd = np.diff(s) / dt
    assert np.all(np.abs(fd - 0.5 * (sd[1:] + sd[:-1])) <= a * dt / 4 * (1 + 1e-6) + 1e-12)
    if j is not None:  # jerk-limited: the acceleration is continuous, |da/dt| <= j
        assert np.all(np.abs(np.diff(sdd)) <= j * dt * (1 + 1e-6) + 1e-12)


def test_trapezoid_minimum_time_closed_form():
    """Rest-to-rest minimum time: D/v + v/a when the cruise speed is reached, 2 sqrt(D/a) otherwise."""
    assert profile.trapezoid(0.3, 1.0, 5.0).raw_duration == pytest.approx(0.3 / 1.0 + 1.0 / 5.0, rel=1e-12)
    # the paper's 198 mm side at 1 m/s and 5 m/s^2 is just too short to cruise: v_peak = sqrt(a D)
    p = profile.trapezoid(0.198, 1.0, 5.0)
    assert p.raw_duration == pytest.approx(2 * np.sqrt(0.198 / 5.0), rel=1e-12)
    assert p.evaluate([p.duration / 2])[1][0] == pytest.approx(np.sqrt(5.0 * 0.198), rel=1e-12)
    assert profile.trapezoid(0.05, 1.0, 5.0).raw_duration == pytest.approx(2 * np.sqrt(0.05 / 5.0), rel=1e-12)
    # double S with a huge jerk tends to the trapezoid
    assert profile.double_s(0.3, 1.0, 5.0, 1e7).raw_duration == pytest.approx(0.5, rel=1e-4)
    # double S that never reaches amax: v = j Tj^2, D = v * 2 Tj  (no cruise)
    p = profile.double_s(2 * 0.1 ** 3 * 10.0, 1.0, 100.0, 10.0)  # Tj = 0.1 s
    assert p.raw_duration == pytest.approx(0.4, rel=1e-9)


# ----------------------------------------------------------------------------
# Paths on the paper's robot
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["square_slow", "square_fast"])
def test_square_hits_every_corner_within_limits(planar2, name):
    traj = planar2.trajectories[name]
    s = tr.sample(resolved(planar2, "motion"), name)
    corners = paths.path_waypoints(planar2, traj)
    assert corners.shape == (5, 2)
    np.testing.assert_array_equal(s.pose[0], corners[0])
    for seg, corner in zip(s.segments, corners[1:]):
        np.testing.assert_array_equal(s.pose[seg.last], corner)  # exactly, not approximately
        assert np.all(s.velocity[seg.last] == 0.0)
    speed = np.linalg.norm(s.velocity, axis=1)
    acc = np.linalg.norm(s.acceleration, axis=1)
    assert speed.max() <= traj.speed * (1 + REL)
    # peak speed: the cruise speed, or sqrt(a D) on a side too short to reach it
    assert speed.max() == pytest.approx(min(traj.speed, np.sqrt(traj.acceleration * traj.side)), rel=1e-3)
    assert acc.max() <= traj.acceleration * (1 + REL)
    np.testing.assert_allclose(np.diff(s.time), 1e-3, rtol=1e-9)
    # horizontal segments at the paper's mean target heights
    ys = sorted({round(c[1], 6) for c in corners})
    assert ys == [0.7496, 0.9476]
    assert s.all_feasible


@pytest.mark.parametrize("name", ["square_slow", "square_fast"])
def test_cable_speed_is_the_derivative_of_length(planar2, name):
    """dL/dt (analytic) against finite differences of the lengths: the trapezoid-rule bound
    |dL/dt_fd - mean of the two speeds| <= max|d2L/dt2| dt / 4, and d2L/dt2 likewise."""
    s = tr.sample(resolved(planar2, "motion"), name)
    dt = s.cycle_time
    fd = np.diff(s.lengths, axis=0) / dt
    avg = 0.5 * (s.cable_speed[1:] + s.cable_speed[:-1])
    bound = np.abs(s.cable_accel).max() * dt / 4
    assert np.abs(fd - avg).max() <= bound * (1 + 1e-6)
    assert np.abs(fd - avg).max() < 1e-3  # not vacuous: well below the 0.1-1 m/s cable speeds
    # accelerations: away from the profile's acceleration steps
    fd2 = np.diff(s.cable_speed, axis=0) / dt
    avg2 = 0.5 * (s.cable_accel[1:] + s.cable_accel[:-1])
    smooth = np.all(np.abs(np.diff(s.acceleration, axis=0)) < 1e-9, axis=1)
    assert smooth.sum() > 0.5 * smooth.size
    assert np.abs(fd2 - avg2)[smooth].max() < 1e-3 * max(1.0, np.abs(s.cable_accel).max())


def test_motor_angle_sign_and_zero(planar2):
    s = tr.sample(resolved(planar2, "motion"), "square_fast")
    r = planar2.cables[0].winch.drum_radius
    gr = planar2.cables[0].winch.gear_ratio
    np.testing.assert_array_equal(s.motor_angle[0], 0.0)
    np.testing.assert_allclose(s.motor_angle, (s.lengths - s.lengths[0]) / r * gr, rtol=1e-12)
    # moving right pays out the left cable c1: its angle grows (cable paid out = positive)
    first = s.segments[0]
    assert s.pose[first.last, 0] > s.pose[0, 0]
    assert s.motor_angle[first.last, 0] > 0 > s.motor_angle[first.last, 1]


def test_static_tensions_reference_point():
    """algorithms.md: outlets (0,2),(3,2), point mass at (1,1), m g = 9.81 N:
    t = (9.2489567, 7.3119423) N.  At rest the trajectory's tensions are these."""
    d = point_mass([(0.0, 2.0), (3.0, 2.0)], 1.0, (1.0, 40.0), size=[0.1, 0.1])
    traj = Trajectory(name="t", type="polyline", speed=0.5, acceleration=2.0,
                      waypoints=((1.0, 1.0), (1.5, 1.0)))
    s = tr.sample(resolved(d, "motion"), traj)
    np.testing.assert_allclose(s.tensions[0], [9.2489567, 7.3119423], atol=5e-8)
    np.testing.assert_allclose(s.tensions[-1], static_tensions(d, [1.5, 1.0]), rtol=1e-12)


@settings(max_examples=25, deadline=None)
@given(ax=st.floats(-4, 4), ay=st.floats(-4, 4), x=st.floats(0.6, 2.4), y=st.floats(0.2, 1.6))
def test_inertial_tension_equals_static_under_shifted_gravity(ax, ay, x, y):
    """d'Alembert: a point mass accelerating by a needs the tensions of a mass at rest under g - a."""
    outlets = [(0.0, 2.0), (3.0, 2.0)]
    d = point_mass(outlets, 1.3, size=[0.1, 0.1])
    g = np.array([0.0, -9.81])
    dg = point_mass(outlets, 1.3, gravity=list(g - [ax, ay]), size=[0.1, 0.1])
    st_ = tr.states(resolved(d, "motion"), [[x, y]], [[0.3, -0.2]], [[ax, ay]])
    np.testing.assert_allclose(st_["tensions"][0], static_tensions(dg, [x, y]), rtol=1e-10, atol=1e-10)


def rigid_1r2t():
    return point_mass([(0.0, 2.0), (3.0, 2.0), (3.0, 0.0)], 2.0, (0.0, 500.0), motion="1R2T",
                      attachments=[(-0.1, 0.1), (0.1, 0.1), (0.1, -0.1)], size=[0.2, 0.2], inertia=0.05)


def test_rotating_path_against_per_pose_kinematics():
    """1R2T polyline that turns while it moves: vectorised lengths, speeds and inertial tensions
    against reference.kinematics.length_rates / inertial_wrench / structure_matrix pose by pose."""
    d = rigid_1r2t()
    traj = Trajectory(name="r", type="polyline", speed=0.4, acceleration=3.0,
                      waypoints=((1.2, 1.0, 0.0), (1.6, 1.2, 0.3), (1.4, 0.9, -0.2)))
    s = tr.sample(resolved(d, "motion"), traj)
    idx = np.linspace(0, len(s) - 1, 41).astype(int)
    for k in idx:
        p, v, a = s.pose[k], s.velocity[k], s.acceleration[k]
        np.testing.assert_allclose(s.lengths[k], kin.inverse_kinematics(d, p), rtol=1e-12)
        np.testing.assert_allclose(s.cable_speed[k], length_rates(d, p, v), atol=1e-12)
        W = kin.structure_matrix(d, p)
        w_req = kin.required_wrench(d, p) - kin.inertial_wrench(
            d, p, a[:2], angular_velocity=[0, 0, v[2]], angular_acceleration=[0, 0, a[2]])
        np.testing.assert_allclose(s.tensions[k], np.linalg.solve(W, w_req), rtol=1e-9, atol=1e-9)
    fd = np.diff(s.lengths, axis=0) / s.cycle_time
    avg = 0.5 * (s.cable_speed[1:] + s.cable_speed[:-1])
    assert np.abs(fd - avg).max() <= np.abs(s.cable_accel).max() * s.cycle_time / 4 * (1 + 1e-6)


def test_circle_total_acceleration_and_closure(planar2):
    traj = Trajectory(name="c", type="circle", speed=1.0, acceleration=5.0, center=(0.75, 0.8), radius=0.1,
                      laps=2)
    s = tr.sample(resolved(planar2, "motion"), traj)
    r = np.linalg.norm(s.pose - [0.75, 0.8], axis=1)
    np.testing.assert_allclose(r, 0.1, rtol=1e-12)
    assert np.linalg.norm(s.acceleration, axis=1).max() <= 5.0 * (1 + REL)
    assert np.linalg.norm(s.velocity, axis=1).max() <= 1.0 * (1 + REL)
    np.testing.assert_allclose(s.pose[-1], [0.85, 0.8], atol=1e-15)
    # velocity is the derivative of the pose
    fd = np.diff(s.pose, axis=0) / s.cycle_time
    avg = 0.5 * (s.velocity[1:] + s.velocity[:-1])
    assert np.abs(fd - avg).max() < 5.0 * s.cycle_time
    # a whole circle has no straight segment
    assert [g.kind for g in s.segments] == ["arc"]


def test_start_laps_holds_and_csv(planar2):
    traj = Trajectory(name="p", type="polyline", speed=0.5, acceleration=2.0,
                      waypoints=((0.6, 0.7), (0.9, 0.7)), start=(0.75, 0.9), laps=2)
    s = tr.sample(resolved(planar2, "motion"), traj, hold_start=0.1, hold_end=0.2)
    kinds = [g.kind for g in s.segments]
    assert kinds == ["approach", "line", "line", "line"]  # approach, out, back (closing), out
    np.testing.assert_array_equal(s.pose[0], [0.75, 0.9])
    np.testing.assert_array_equal(s.pose[:101], np.repeat([[0.75, 0.9]], 101, axis=0))
    np.testing.assert_array_equal(s.pose[-201:], np.repeat([[0.9, 0.7]], 201, axis=0))
    # a csv path is the polyline through the given poses
    c = Trajectory(name="c", type="csv", speed=0.5, acceleration=2.0, file="x.csv")
    s2 = tr.sample(resolved(planar2, "motion"), c, csv_poses=np.array([[0.6, 0.7], [0.9, 0.7]]))
    s3 = tr.sample(resolved(planar2, "motion"), Trajectory(name="c", type="polyline", speed=0.5, acceleration=2.0,
                                       waypoints=((0.6, 0.7), (0.9, 0.7))))
    np.testing.assert_array_equal(s2.pose, s3.pose)
    with pytest.raises(ValueError, match="csv"):
        tr.sample(resolved(planar2, "motion"), c)
    with pytest.raises(KeyError, match="square_slow"):
        tr.sample(resolved(planar2, "motion"), "nope")


def test_feasibility_flag_tracks_tension_bounds(planar2):
    """A fast drop accelerates the effector downwards faster than the cables can follow
    without going slack: those samples are infeasible (tension below t_min = 0)."""
    traj = Trajectory(name="drop", type="polyline", speed=2.0, acceleration=15.0,
                      waypoints=((0.75, 1.0), (0.75, 0.5)))
    s = tr.sample(resolved(planar2, "motion"), traj)
    low = np.any(s.tensions < planar2.tension_min - 1e-9, axis=1)
    assert low.any()
    np.testing.assert_array_equal(s.feasible, ~low & np.all(s.tensions <= planar2.tension_max + 1e-9, axis=1))
    cols = s.columns()
    assert list(cols)[:7] == ["time", "x", "y", "x_vel", "y_vel", "length_c1", "cable_speed_c1"]


def test_spatial_3r3t_speeds_match_per_pose():
    """3R3T: vectorised cable speeds against reference.kinematics.length_rates (Euler rates)."""
    outs = [(-1, -1, 2), (1, -1, 2), (1, 1, 2), (-1, 1, 2), (-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
    att = [(-.1, -.1, .1), (.1, -.1, .1), (.1, .1, .1), (-.1, .1, .1),
           (-.1, -.1, -.1), (.1, -.1, -.1), (.1, .1, -.1), (-.1, .1, -.1)]
    d = point_mass(outs, 5.0, (0.0, 1000.0), motion="3R3T", attachments=att, size=[0.2, 0.2, 0.2])
    traj = Trajectory(name="s", type="polyline", speed=0.3, acceleration=2.0,
                      waypoints=((0, 0, 1, 0, 0, 0), (0.2, 0.1, 1.1, 0.1, -0.1, 0.2)))
    s = tr.sample(resolved(d, "motion"), traj)
    for k in np.linspace(0, len(s) - 1, 15).astype(int):
        np.testing.assert_allclose(s.cable_speed[k], length_rates(d, s.pose[k], s.velocity[k]),
                                   atol=1e-12)


# ----------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------


def test_cli_trajectory_writes_contract_columns(tmp_path):
    import json

    res = invoke("trajectory", PLANAR2, "square_fast", "--out", tmp_path, "--json")
    assert res.exit_code == 0, res.output
    summ = json.loads(res.stdout)
    assert summ["feasible"] is True and summ["samples"] > 1000
    header = csv_header(tmp_path / "trajectory.csv")
    assert header[:14] == ["time", "x", "y", "x_vel", "y_vel",
                           "length_c1", "cable_speed_c1", "motor_angle_c1", "tension_c1",
                           "length_c2", "cable_speed_c2", "motor_angle_c2", "tension_c2", "feasible"]
    for f in ("trajectory.png", "trajectory_axes.png", "trajectory.json"):
        assert (tmp_path / f).stat().st_size > 0


def test_cli_trajectory_bad_input_and_check(tmp_path, planar2_data):
    res = invoke("trajectory", PLANAR2, "nope", "--out", tmp_path)
    assert res.exit_code == 2 and "square_fast" in res.output and "Traceback" not in res.output
    res = invoke("trajectory", PLANAR2, "square_fast", "--cycle-time", "-1", "--out", tmp_path)
    assert res.exit_code == 2
    data = dict(planar2_data)
    data["trajectories"] = {
        "drop": {"type": "polyline", "waypoints": [[0.75, 1.0], [0.75, 0.5]], "speed": 2.0, "acceleration": 15.0},
        "fromfile": {"type": "csv", "file": "poses.csv", "speed": 0.5, "acceleration": 2.0},
        "missing": {"type": "csv", "file": "nothere.csv", "speed": 0.5, "acceleration": 2.0},
    }
    p = write_spec(tmp_path, data)
    (tmp_path / "poses.csv").write_text("x,y\n0.6,0.7\n0.9,0.7\n0.9,0.9\n")
    res = invoke("trajectory", p, "drop", "--out", tmp_path / "o", "--check", "--quiet")
    assert res.exit_code == 1
    res = invoke("trajectory", p, "fromfile", "--out", tmp_path / "o", "--json")
    assert res.exit_code == 0, res.output
    res = invoke("trajectory", p, "missing", "--out", tmp_path / "o")
    assert res.exit_code == 2 and "nothere.csv" in res.output


@pytest.mark.parametrize("command", ["trajectory", "simulate"])
def test_cli_a_long_trajectory_name_is_shortened(tmp_path, command):
    """An unknown name of 5,000 characters is quoted shortened in the message, never whole."""
    res = invoke(command, PLANAR2, "a" * 5000, "--out", tmp_path)
    assert res.exit_code == 2 and "square_fast" in res.output and "Traceback" not in res.output
    assert "a" * 100 not in res.output and len(res.output) < 400, res.output


def redundant_4_cable():
    """A planar 1R2T robot with 4 crossed cables (m = 4 > n = 3)."""
    return spec.from_dict({
        "name": "r4", "motion": "1R2T", "frame": {"lower": [0, 0], "upper": [2, 1.5]},
        "effector": {"mass": 2.0, "size": [0.2, 0.1], "inertia": 0.0083},
        "tension": [2.0, 100.0],
        "cables": [{"name": "c1", "outlet": [0, 0], "attachment": [0.1, -0.05]},
                   {"name": "c2", "outlet": [2, 0], "attachment": [-0.1, -0.05]},
                   {"name": "c3", "outlet": [2, 1.5], "attachment": [0.1, 0.05]},
                   {"name": "c4", "outlet": [0, 1.5], "attachment": [-0.1, 0.05]}],
    })


@pytest.mark.slow
def test_redundant_robot_min_norm_tensions_against_cvxpy():
    """m > n: the trajectory's tensions are the bounded minimum 2-norm ones (W t = w_req with
    inertia), checked against cvxpy pose by pose."""
    import cvxpy as cp

    d = redundant_4_cable()
    traj = Trajectory(name="r", type="polyline", speed=0.5, acceleration=4.0,
                      waypoints=((0.8, 0.6, 0.0), (1.2, 0.9, 0.2)))
    s = tr.sample(resolved(d, "motion"), traj, cycle_time=0.01)
    st_ = tr.states(resolved(d, "motion"), s.pose, s.velocity, s.acceleration)
    assert s.all_feasible
    for k in np.linspace(0, len(s) - 1, 12).astype(int):
        W = st_["structure"][k]
        w = W @ s.tensions[k]
        x = cp.Variable(4)
        cp.Problem(cp.Minimize(cp.sum_squares(x)), [W @ x == w, x >= d.tension_min, x <= d.tension_max]).solve()
        np.testing.assert_allclose(s.tensions[k], x.value, atol=1e-4)
        # and w is the required wrench with the effector's inertia
        p, v, a = s.pose[k], s.velocity[k], s.acceleration[k]
        w_req = kin.required_wrench(d, p) - kin.inertial_wrench(
            d, p, a[:2], angular_velocity=[0, 0, v[2]], angular_acceleration=[0, 0, a[2]])
        np.testing.assert_allclose(w, w_req, atol=1e-8)


def test_summary_tension_extremes_skip_nan_samples_without_a_warning(planar2):
    """A cable whose every sample is infeasible (NaN tension) has no extreme (None) in the
    trajectory's summary, and the summary says so without numpy's all-NaN RuntimeWarning (which
    np.nanmax gave); the other cable's extremes skip its NaN samples."""
    import dataclasses
    import warnings

    s = tr.sample(resolved(planar2, "motion"), "square_slow")
    T = np.full_like(s.tensions, np.nan)
    T[:3, 0] = [1.0, 3.0, np.nan]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        summary = dataclasses.replace(s, tensions=T).summary()
        a, b = s.cable_names
        assert summary["max_tension"] == {a: 3.0, b: None}
        assert summary["min_tension"] == {a: 1.0, b: None}
