"""MuJoCo simulation: statics at rest, cables that never push, servo lag and transport delay,
tracking of the paper's square at 1 m/s."""

from __future__ import annotations

import numpy as np
import pytest

from cdpr_design.statics import kinematics as kin
from cdpr_design.motion import simulation as S
from cdpr_design.motion.run import simulate
from cdpr_design.model import spec
from cdpr_design.motion import trajectory as tr
from cdpr_design.motion.compare import estimate_delay

from .helpers import PLANAR2, csv_header, invoke, static_tensions, resolved


def test_model_builds_with_tendons_that_only_pull(planar2):
    sim = S.Simulator(resolved(planar2, "motion"))
    m = sim.model
    assert m.ntendon == 2 and m.nu == 2 and m.nv == 3  # slide x, slide y, hinge z
    np.testing.assert_array_equal(m.actuator_forcelimited, [1, 1])
    assert np.all(m.actuator_forcerange[:, 1] == 0.0) and np.all(m.actuator_forcerange[:, 0] < 0)
    assert m.body_mass[1] == pytest.approx(1.0)


def test_rest_at_symmetric_pose_matches_static_tensions(planar2):
    """At x = 0.75 the cable lines meet above the centre of mass: no tilt, and the simulated
    tensions equal the statics A T = B of the paper (eq. 6-9) within 1 % (in fact 1e-6)."""
    sim = S.Simulator(resolved(planar2, "motion"))
    pose = [0.75, 0.8486]
    st = sim.reset(pose)
    st = sim.advance(kin.inverse_kinematics(planar2, pose), 1.0)
    t_static = static_tensions(planar2, pose)
    np.testing.assert_allclose(st.tensions, t_static, rtol=1e-2)
    np.testing.assert_allclose(st.tensions, t_static, rtol=1e-6)
    np.testing.assert_allclose(st.pose, pose, atol=1e-6)
    assert abs(st.orientation[2]) < 1e-9


@pytest.mark.parametrize("pose", [[0.55, 0.75], [0.95, 0.9], [0.65, 1.1]])
def test_rest_off_centre_tilts_and_balances(planar2, pose):
    """Off centre the rigid effector tilts (three-force equilibrium); its tensions are within 1 %
    of the point-mass statics, and exactly those of the statics at the tilted pose."""
    sim = S.Simulator(resolved(planar2, "motion"))
    sim.reset(pose, settle=4.0)
    st = sim.advance(kin.inverse_kinematics(planar2, pose), 0.5)
    t_static = static_tensions(planar2, pose)
    assert abs(st.orientation[2]) > 1e-3  # it does tilt
    # statics of the tilted rigid body, forces and moment (1R2T rows) at the simulated pose
    rigid = spec.from_dict({**planar2.raw, "motion": "1R2T", "trajectories": None, "requirements": None})
    p3 = [st.pose[0], st.pose[1], st.orientation[2]]
    W = kin.structure_matrix(rigid, p3)
    w = kin.required_wrench(rigid, p3)
    np.testing.assert_allclose(W @ st.tensions, w, atol=2e-3)  # moment balanced too
    np.testing.assert_allclose(st.tensions, t_static, rtol=2.5e-2)
    t_tilted = np.linalg.lstsq(W, w, rcond=None)[0]
    np.testing.assert_allclose(st.tensions, t_tilted, rtol=1e-3)


def test_cable_commanded_too_long_goes_slack(planar2):
    """Pay out 2 m more of c1 than the pose needs (a 2-cable robot simply moves to the pose of
    any lengths both cables can reach, so slack needs more than the effector can hang away):
    the effector ends up swinging on c2 alone, c1 goes slack with tension exactly 0, and no
    tension is ever negative."""
    sim = S.Simulator(resolved(planar2, "motion"))
    pose = [0.75, 0.8]
    sim.reset(pose)
    L = kin.inverse_kinematics(planar2, pose)
    tens = []
    for k in range(300):
        extra = min(k / 100, 1.0) * 2.0  # ramp over 1 s, then hold 2 s
        st = sim.advance(L + [extra, 0.0], 0.01)
        tens.append(st.tensions)
    tens = np.array(tens)
    assert tens.min() >= 0.0
    assert np.all(tens[-150:, 0] == 0.0)
    assert np.all(tens[-150:, 1] > 0.0)
    # the axis paid the cable out; the geometric length is far shorter than the unstretched cable
    assert st.axis[0] == pytest.approx(L[0] + 2.0, abs=1e-6)
    assert st.lengths[0] < st.axis[0] - 0.1
    # while both were taut (before the ramp) the tensions were the static ones
    np.testing.assert_allclose(tens[0], static_tensions(planar2, pose), rtol=1e-2)


def test_servo_without_feedforward_lags_by_one_over_bandwidth(planar2):
    """A first-order position loop without velocity feed-forward follows a ramp 1/omega late;
    with a transport delay added, the lag is 1/omega + delay."""
    s = tr.sample(resolved(planar2, "motion"), "square_slow", hold_end=0.3)
    s = _truncate(s, 3000)
    for wc, delay in [(20.0, 0.0), (50.0, 0.05)]:
        r = simulate(resolved(planar2, "motion"), s, servo_bandwidth=wc, feedforward=False, delay=delay, settle=0.0)
        for i in range(2):
            d = estimate_delay(s.cycle_time, s.lengths[:, i], r.axis[:, i])
            assert d == pytest.approx(1 / wc + delay, abs=2e-3)


def _truncate(s, k):
    from dataclasses import replace

    fields = ["time", "pose", "velocity", "acceleration", "lengths", "cable_speed", "cable_accel",
              "motor_angle", "tensions", "feasible", "segment"]
    return replace(s, **{f: getattr(s, f)[:k] for f in fields})


@pytest.mark.slow
def test_square_fast_tracking_and_delay(planar2):
    """The paper's square at 1 m/s: tracking below 1.5 mm RMS with the trapezoidal profile and
    feed-forward; with a 130 ms transport delay the measured axis delay is 130 ms."""
    s = tr.sample(resolved(planar2, "motion"), "square_fast", hold_end=0.4)
    r = simulate(resolved(planar2, "motion"), s)
    summ = r.summary()
    assert summ["rms_error"] < 1.5e-3
    assert min(summ["min_tension"].values()) >= 0.0
    assert len(summ["segments"]) == 4
    for row in summ["segments"]:
        assert row["error_pct"] < 0.5
    for c in ("length_c1", "length_c2"):
        assert abs(summ["delay"][c]) < 2e-3
    rd = simulate(resolved(planar2, "motion"), s, delay=0.13)
    sd = rd.summary()
    for c in ("length_c1", "length_c2"):
        assert sd["delay"][c] == pytest.approx(0.13, abs=2e-3)
    cols = rd.columns()
    assert list(cols)[:11] == ["time", "x_target", "y_target", "x", "y", "length_c1_target",
                               "length_c2_target", "length_c1", "length_c2", "tension_c1", "tension_c2"]


def test_spatial_point_mass_at_rest():
    """3T, three cables meeting at the effector's origin (no tilt torque): free joint model,
    tensions equal the statics at rest."""
    d = spec.from_dict({
        "name": "tri", "motion": "3T",
        "frame": {"lower": [-2, -2, 0], "upper": [2, 2, 3]},
        "effector": {"mass": 2.0, "size": [0.1, 0.1, 0.1]},
        "tension": [0.0, 200.0],
        "cable": {"axial_stiffness": 50000.0},
        "cables": [{"name": f"k{i}", "outlet": [1.5 * np.cos(a), 1.5 * np.sin(a), 3.0],
                    "attachment": [0.0, 0.0, 0.0]} for i, a in enumerate([0.0, 2.1, 4.2])],
    })
    sim = S.Simulator(resolved(d, "motion"))
    assert sim.model.nq == 7
    pose = [0.2, -0.1, 1.5]
    sim.reset(pose)
    st = sim.advance(kin.inverse_kinematics(d, pose), 1.0)
    t_static = static_tensions(d, pose)
    np.testing.assert_allclose(st.tensions, t_static, rtol=1e-2)
    np.testing.assert_allclose(st.pose, pose, atol=1e-4)


def test_bad_arguments(planar2):
    with pytest.raises(ValueError, match="delay"):
        S.Simulator(resolved(planar2, "motion"), delay=-1.0)
    sim = S.Simulator(resolved(planar2, "motion"))
    sim.reset()
    with pytest.raises(ValueError, match="expected 2 set-points"):
        sim.advance([1.0], 0.01)


def test_cli_simulate(tmp_path):
    import json

    res = invoke("simulate", PLANAR2, "square_fast", "--delay", "0.05", "--out", tmp_path, "--json")
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert set(s) >= {"rms_error", "max_error", "delay", "segments"}
    assert s["delay"]["length_c1"] == pytest.approx(0.05, abs=2e-3)
    assert [row["axis"] for row in s["segments"]] == ["y", "x", "y", "x"]
    header = csv_header(tmp_path / "simulation.csv")
    assert header[:11] == ["time", "x_target", "y_target", "x", "y", "length_c1_target", "length_c2_target",
                           "length_c1", "length_c2", "tension_c1", "tension_c2"]
    assert (tmp_path / "simulation.png").stat().st_size > 0
    # compare reads what simulate wrote
    res = invoke("compare", tmp_path / "simulation.csv", tmp_path / "simulation.csv", "--columns", "x,y", "--json")
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["max_error"] == 0.0
    res = invoke("simulate", PLANAR2, "square_fast", "--delay", "-1", "--out", tmp_path)
    assert res.exit_code == 2
