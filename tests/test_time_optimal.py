"""Time-optimal timing of a path (``trajectory --time-optimal``): the seed paper's square on planar2,
checked by an independent inverse dynamics, tight and faster than the paper's 1 m/s profile."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from cdpr_design.model import spec
from cdpr_design.motion import time_optimal as to
from cdpr_design.motion import trajectory as tr
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.robot import Analysis, resolve
from tests.helpers import DESIGNS, invoke, planar2_raw, write_spec


def _free_square(raw: dict) -> dict:
    """planar2 with ``square_free``: the paper's square without a speed or an acceleration of its own."""
    t = dict(raw["trajectories"]["square_fast"])
    t.pop("speed")
    t.pop("acceleration")
    raw["trajectories"]["square_free"] = t
    return raw


def _robot(design):
    return resolve(design, Analysis(command="motion", time_optimal=True))


@pytest.fixture(scope="module")
def planar2_free():
    return spec.from_dict(_free_square(planar2_raw()))


@pytest.fixture(scope="module")
def timed(planar2_free):
    return to.sample(_robot(planar2_free), "square_free")


def _inverse_dynamics(design, samples):
    """Each sample's tensions from W t = -(w_gravity + w_inertial), plain numpy pose by pose (m = n)."""
    out = np.empty((len(samples), design.m))
    for k in range(len(samples)):
        p, a = samples.pose[k], samples.acceleration[k]
        W = kin.structure_matrix(design, p)
        w = -(kin.gravity_wrench(design, p) + kin.inertial_wrench(design, p, a))
        out[k] = np.linalg.solve(W, w)
    return out


def test_every_sample_is_within_the_tension_bounds_by_inverse_dynamics(planar2_free, timed):
    samples, timing = timed
    t = _inverse_dynamics(planar2_free, samples)
    assert np.all(t >= planar2_free.tension_min - 1e-9) and np.all(t <= planar2_free.tension_max + 1e-9)
    np.testing.assert_allclose(t, samples.tensions, rtol=1e-9, atol=1e-9)  # the samples' own tensions
    assert samples.all_feasible and timing.torque_exceeded == 0
    # the bounds are reached: a cable near slack and one near its 20 N somewhere
    assert t.min() < 0.05 and t.max() > 19.5


def test_motor_torques_within_peak_by_finite_differences(planar2_free, timed):
    """The motor torque T r / (i eta) - J (i / r) L'' with L'' the lengths' second difference
    (independent of the analytic cable accelerations) stays within the motor's usable peak."""
    samples, _ = timed
    lim = to.winch_limits(planar2_free)
    dt = samples.cycle_time
    Ldd = np.gradient(np.gradient(samples.lengths, dt, axis=0), dt, axis=0)
    tau = samples.tensions * lim.rho - lim.kappa * Ldd
    inner = slice(2, -2)  # the one-sided differences at the ends
    assert np.all(np.abs(tau[inner]) <= lim.torque * (1 + 1e-3))
    assert np.abs(tau).max() > 0.95 * lim.torque.min()  # the torque limit is reached somewhere


def test_tight_and_faster_than_the_papers_profile(planar2_free, timed):
    samples, timing = timed
    shares = timing.active_shares()
    assert shares["none"] < 0.02
    assert max(v for k, v in shares.items() if k != "none") > 0.5  # one constraint along most of the path
    profiled = tr.sample(_robot(planar2_free), "square_fast")
    assert samples.duration < 0.8 * profiled.duration
    assert np.linalg.norm(samples.acceleration, axis=1).max() > 5.0  # beyond the profile's 5 m/s^2
    # a sample on every corner, at rest
    for seg in samples.segments:
        assert np.allclose(samples.pose[seg.last], seg.end) and np.allclose(samples.velocity[seg.last], 0.0)


def test_the_paths_own_limits_bound_it(planar2_free):
    """square_fast's 1 m/s and 5 m/s^2 are upper limits: the profile's own time-optimal answer, with
    the path's acceleration active along most of it."""
    samples, timing = to.sample(_robot(planar2_free), "square_fast")
    assert np.abs(samples.acceleration).max() <= 5.0 * (1 + 1e-9)
    assert np.linalg.norm(samples.velocity, axis=1).max() <= 1.0 * (1 + 1e-9)
    assert timing.active_shares()["path_acceleration"] > 0.9
    assert timing.profiled_duration == pytest.approx(tr.sample(_robot(planar2_free), "square_fast").duration)
    assert samples.duration <= timing.profiled_duration + 4 * samples.cycle_time


def test_cli_writes_the_timing_and_the_profile_picture(tmp_path):
    p = write_spec(tmp_path, _free_square(planar2_raw()))
    r = invoke("trajectory", p, "square_free", "--time-optimal", "--out", tmp_path / "out", "--json")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    t = s["time_optimal"]
    assert s["duration"] < 1.2 and t["profiled_duration"] is None and t["limits_note"] is None
    assert set(t["limits"]) == {"tension", "motor_torque", "cable_speed"}
    assert t["active_intervals"] and {"segment", "from", "to", "constraint"} <= set(t["active_intervals"][0])
    assert (tmp_path / "out" / "time_optimal.png").stat().st_size > 0
    header = (tmp_path / "out" / "trajectory.csv").read_text().splitlines()[0].split(",")
    assert "x_vel" in header and "x_acc" in header


def test_without_motor_data_it_is_timed_on_the_tensions_and_says_so(tmp_path):
    raw = _free_square(planar2_raw())
    raw["winch"].pop("motor")
    r = invoke("trajectory", write_spec(tmp_path, raw), "square_free", "--time-optimal", "--out", tmp_path / "o",
               "--json")
    assert r.exit_code == 0, r.output
    t = json.loads(r.stdout)["time_optimal"]
    assert t["limits"] == ["tension"] and "tensions alone" in t["limits_note"]
    r = invoke("trajectory", write_spec(tmp_path, raw), "square_free", "--time-optimal", "--out", tmp_path / "o2")
    assert r.exit_code == 0 and "tensions alone" in r.stderr


def test_a_path_through_an_infeasible_pose_is_exit_2_naming_it(tmp_path):
    raw = planar2_raw()
    raw["trajectories"]["up"] = {"type": "polyline", "waypoints": [[0.75, 0.8], [0.75, 1.2], [0.75, 1.45]]}
    r = invoke("trajectory", write_spec(tmp_path, raw), "up", "--time-optimal", "--out", tmp_path / "o")
    assert r.exit_code == 2 and "Traceback" not in r.stderr
    assert "trajectories.up: segment 2" in r.stderr and "not statically feasible" in r.stderr, r.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("args,names", [
    (["square_free"], "trajectories.square_free: speed and acceleration: needed"),
    (["circle_free"], "trajectories.circle_free: speed and acceleration: needed"),
])
def test_bad_uses_are_exit_2(tmp_path, args, names):
    r = invoke("trajectory", write_spec(tmp_path, _circles(_free_square(planar2_raw()))), *args, "--out", tmp_path / "o")
    assert r.exit_code == 2 and names in r.stderr and "Traceback" not in r.stderr, r.stderr


# ---------------------------------------------------------------- circles and turning segments


def _circles(raw: dict) -> dict:
    """planar2 with a circle of 0.1 m about the middle of the paper's square, profiled at 0.5 m/s and
    2 m/s^2 (``circle``) and without limits of its own (``circle_free``)."""
    raw["trajectories"]["circle"] = {"type": "circle", "center": [0.75, 0.85], "radius": 0.1, "speed": 0.5,
                                     "acceleration": 2.0}
    raw["trajectories"]["circle_free"] = {"type": "circle", "center": [0.75, 0.85], "radius": 0.1}
    return raw


def test_a_circle_is_timed_within_the_bounds_tight_and_faster(tmp_path):
    d = spec.from_dict(_circles(planar2_raw()))
    samples, timing = to.sample(_robot(d), "circle_free")
    # on the circle, at rest at its start and end, one whole lap
    r = np.linalg.norm(samples.pose - [0.75, 0.85], axis=1)
    np.testing.assert_allclose(r[1:], 0.1, rtol=1e-12)
    assert np.allclose(samples.pose[-1], [0.85, 0.85]) and np.allclose(samples.velocity[[0, -1]], 0.0)
    assert len(timing.segments) == 1 and timing.segments[0].s[-1] == pytest.approx(2 * np.pi * 0.1)
    # the velocity and acceleration are the pose's own: its differences, centripetal part included
    dt = samples.cycle_time
    vel = np.gradient(samples.pose, dt, axis=0)
    inner = slice(2, -2)
    assert np.abs(vel[inner] - samples.velocity[inner]).max() < 0.02 * np.abs(samples.velocity).max()
    # every sample within the tension bounds by plain inverse dynamics, the bounds reached
    t = _inverse_dynamics(d, samples)
    assert np.all(t >= d.tension_min - 1e-9) and np.all(t <= d.tension_max + 1e-9)
    np.testing.assert_allclose(t, samples.tensions, rtol=1e-9, atol=1e-9)
    assert samples.all_feasible and timing.torque_exceeded == 0
    assert t.min() < 0.05 and t.max() > 19.5
    # tight: a constraint active along most of the arc
    shares = timing.active_shares()
    assert shares["none"] < 0.02 and max(v for k, v in shares.items() if k != "none") > 0.5
    # faster than the path's own profile, and that profile's limits bind it when given
    profiled = tr.sample(_robot(d), "circle")
    assert samples.duration < 0.5 * profiled.duration
    limited, lt = to.sample(_robot(d), "circle")
    assert lt.profiled_duration == pytest.approx(profiled.duration)
    assert limited.duration <= profiled.duration + 2 * dt
    assert np.linalg.norm(limited.acceleration, axis=1).max() <= 2.0 * (1 + 1e-9)
    assert lt.active_shares()["path_acceleration"] > 0.9


def _angular_motion(angles, rates, accels, h=1e-4):
    """Angular velocity and acceleration [rad/s, rad/s^2] of R = Rx Ry Rz along the angles' Taylor
    path angles + rates t + accels t^2 / 2, by central differences of the rotation matrices."""
    def R(t):
        return kin.rotation_matrix(*(angles + rates * t + 0.5 * accels * t * t))

    def omega(t):
        S = (R(t + h) - R(t - h)) / (2 * h) @ R(t).T
        return np.array([S[2, 1], S[0, 2], S[1, 0]])

    return omega(0.0), (omega(h) - omega(-h)) / (2 * h)


def _spatial_wrenches(design, samples):
    """What the cables must supply at each sample of a 3R3T path, -(gravity + inertia), with the
    angular velocity and acceleration from the rotation matrices (:func:`_angular_motion`)."""
    out = np.empty((len(samples), design.n))
    for k in range(len(samples)):
        p, v, a = samples.pose[k], samples.velocity[k], samples.acceleration[k]
        w, al = _angular_motion(p[3:], v[3:], a[3:])
        out[k] = -(kin.gravity_wrench(design, p)
                   + kin.inertial_wrench(design, p, a[:3], angular_velocity=w, angular_acceleration=al))
    return out


@pytest.mark.slow
def test_a_turning_3r3t_segment_and_a_spatial_circle_are_timed_within_the_bounds():
    """IPAnema 3 (8 cables): a segment that turns the effector while it moves, and a circle of 1 m; every
    sample's wrench (angular motion from the rotation matrices) is held by tensions within the bounds
    (an LP, scipy HiGHS), the samples' own tensions balance it, and a tension bound is active."""
    from scipy.optimize import linprog

    raw = yaml.safe_load((DESIGNS / "ipanema3.yaml").read_text())
    raw["trajectories"] = {
        "turn": {"type": "polyline", "waypoints": [[0, 0, 1.0, 0, 0, 0], [1.0, 0.5, 1.2, 0.2, -0.1, 0.4]]},
        "ring": {"type": "circle", "center": [0.0, 0.0, 1.0], "radius": 1.0}}
    d = spec.from_dict(raw)
    for name in ("turn", "ring"):
        samples, timing = to.sample(_robot(d), name)
        assert samples.all_feasible and timing.note and timing.limits == ("tension",)
        wreq = _spatial_wrenches(d, samples)
        W = np.stack([kin.structure_matrix(d, p) for p in samples.pose])
        resid = np.einsum("kij,kj->ki", W, samples.tensions) - wreq
        assert np.abs(resid).max() < 1e-5 * np.abs(wreq).max(), name
        for k in range(0, len(samples), 3):
            lp = linprog(np.zeros(d.m), A_eq=W[k], b_eq=wreq[k], bounds=list(zip(d.tension_min, d.tension_max)),
                         method="highs")
            assert lp.status == 0, (name, k)
        shares = timing.active_shares()
        assert shares["tension"] > 0.9 and shares["none"] < 0.02, (name, shares)
        assert samples.tensions.max() > 0.99 * d.tension_max.max()
        if name == "turn":
            assert np.allclose(samples.pose[-1], [1.0, 0.5, 1.2, 0.2, -0.1, 0.4])
            assert np.abs(samples.velocity[:, 3:]).max() > 0.1  # it turns while it moves


def test_size_motors_on_the_fastest_cycle(tmp_path):
    p = write_spec(tmp_path, _free_square(planar2_raw()))
    runs = {}
    for name, extra in (("square_fast", []), ("square_free", ["--time-optimal"])):
        r = invoke("size-motors", p, "--trajectory", name, *extra, "--out", tmp_path / name, "--json")
        assert r.exit_code == 0, r.output
        runs[name] = json.loads(r.stdout)
    fast, free = runs["square_fast"], runs["square_free"]
    assert free["cycle"] == "trajectory square_free"
    # the fastest cycle works the motors harder: more RMS torque, faster cables
    for a, b in zip(fast["axes"], free["axes"]):
        assert b["rms_motor_torque"] > 1.2 * a["rms_motor_torque"] and b["peak_cable_speed"] > a["peak_cable_speed"]
    r = invoke("size-motors", p, "--time-optimal", "--out", tmp_path / "x")
    assert r.exit_code == 2 and "--time-optimal" in r.stderr
