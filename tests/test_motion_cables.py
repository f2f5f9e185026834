"""Real cables along a path: the set-points of `trajectory` and `simulate` with elastic and sagging
cables, and the MuJoCo model's massive cables against the static catenary.

References that do not share the code under test: L / (1 + T/EA) from the straight tensions; the
per-pose sagging statics (``reference_pose.sagging_pose``) for the batched kernel;
the shallow-cable expansion of the catenary's length for a sag-dominated cable; the lumped-mass
chain's known second-order convergence for the simulation.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from cdpr_design.model import spec
from cdpr_design.motion import simulation as S
from cdpr_design.motion import trajectory as tr
from cdpr_design import api
from cdpr_design.statics.robot import combinations

from .helpers import PLANAR2, invoke, read_csv, write_spec, resolved
from .reference_pose import sagging_pose

G = 9.81


def hanging_data(mu=0.2, EA=1e8, mass=2.0, model="sagging", waypoints=((0.0, -1.0), (0.0, -1.2)), **keys):
    """Two cables from (-5, 0) and (5, 0) to a point effector: a 10 m span, the effector below."""
    return {
        "name": "hanging", "motion": "2T", "gravity": [0.0, -G],
        "frame": {"lower": [-5.0, -6.0], "upper": [5.0, 1.0]},
        "effector": {"mass": mass, "size": [0.0, 0.0]},
        "tension": [0.0, 1000.0],
        "cable": {"model": model, "mass_per_length": mu, "axial_stiffness": EA},
        "cables": [{"name": "c1", "outlet": [-5.0, 0.0], "attachment": [0.0, 0.0]},
                   {"name": "c2", "outlet": [5.0, 0.0], "attachment": [0.0, 0.0]}],
        "trajectories": {"down": {"type": "polyline", "waypoints": [list(p) for p in waypoints],
                                  "speed": 0.5, "acceleration": 2.0, "cycle_time": 0.005}},
        **keys,
    }


def planar2_as(model):
    return spec.with_cable_model(spec.load(PLANAR2), model)


# ----------------------------------------------------------------------------
# trajectory set-points
# ----------------------------------------------------------------------------


def test_ideal_samples_have_no_cable_model_outputs(planar2):
    s = tr.sample(resolved(planar2, "motion"), "square_fast")
    assert s.cables is None
    assert not any(k.startswith(("unstretched", "setpoint", "outlet", "sag_", "cable_status")) for k in s.columns())
    assert "cable_model" not in s.summary()


def test_elastic_setpoints_are_the_stretched_chords_shortened(planar2):
    """Elastic cables: tensions, lengths and every historical column are the ideal ones; the
    set-point is L0 = L / (1 + T/EA) (EA = 2e4 N in planar2), the ideal set-point's error
    L - L0 = L T / (EA + T) > 0."""
    ideal = tr.sample(resolved(planar2, "motion"), "square_fast")
    el = tr.sample(resolved(planar2_as("elastic"), "motion"), "square_fast")
    ci, ce = ideal.columns(), el.columns()
    for key, col in ci.items():
        np.testing.assert_array_equal(ce[key], col, err_msg=key)
    EA = 20000.0
    L, T = ideal.lengths, ideal.tensions
    assert np.all(np.isfinite(T)) and T.shape == (len(ideal), 2)
    np.testing.assert_allclose(el.cables.unstretched, L / (1.0 + T / EA), rtol=1e-15)
    np.testing.assert_allclose(el.cables.setpoint_error, L * T / (EA + T), rtol=1e-9, atol=1e-15)
    assert np.all(el.cables.setpoint_error > 0)
    np.testing.assert_array_equal(ce["unstretched_length_c1"], el.cables.unstretched[:, 0])
    np.testing.assert_array_equal(ce["setpoint_error_c2"], L[:, 1] - el.cables.unstretched[:, 1])
    summ = el.summary()
    assert summ["cable_model"] == "elastic" and summ["unsolved_samples"] == 0
    for i, c in enumerate(("c1", "c2")):
        assert summ["max_setpoint_error"][c] == pytest.approx(np.max(L[:, i] * T[:, i] / (EA + T[:, i])), rel=1e-9)


def test_sagging_samples_match_the_per_pose_statics():
    """The batched kernel along a path (inertia included) against the per-pose sagging statics with
    the same required wrench, sample by sample: same tensions, outlet tensions, lengths and sag."""
    d = planar2_as("sagging")
    s = tr.sample(resolved(d, "motion"), "square_fast", cycle_time=0.01)
    st = tr.states(resolved(d, "motion"), s.pose, s.velocity, s.acceleration)
    assert len(s) > 100 and np.all(s.cables.status == 0) and s.all_feasible
    combos = combinations(d.m, d.n)
    for j in range(0, len(s), 7):
        full = d.full_pose(s.pose[j])
        feas, _, t, L, _, state = sagging_pose(d, full, st["wrench"][j:j + 1].copy(), combos, 0)
        assert feas and state.status == "ok"
        np.testing.assert_allclose(s.tensions[j], t, rtol=1e-12)
        np.testing.assert_allclose(s.cables.outlet_tensions[j], state.outlet_tensions, rtol=1e-12)
        np.testing.assert_allclose(s.cables.unstretched[j], state.unstretched_lengths, rtol=1e-13)
        np.testing.assert_allclose(s.cables.sag[j], state.sag, rtol=1e-9)
        np.testing.assert_allclose(s.lengths[j], L, rtol=1e-13)
    # at rest (the first sample) the set-points are the pose command's
    p0 = api.pose(d, s.pose[0])
    np.testing.assert_allclose(s.cables.unstretched[0], p0.cable_state.unstretched_lengths, rtol=1e-13)


def test_sag_dominated_setpoint_error_has_the_catenarys_size():
    """A stiff (EA = 1e8 N), heavy (0.2 kg/m) cable over a 5 m span: its unstretched length is its
    arc, longer than the chord, so the ideal set-point (the chord) is too short: L - L0 < 0, by
    the shallow catenary's excess length w^2 X^4 / (24 H^2 c) (from L^2 = Z^2 + X^2 (sinh a / a)^2,
    a = w X / 2H) less the stretch T c / EA.  The neglected terms are O(a^2) relative (a = 0.07
    here), the tolerance."""
    d = spec.from_dict(hanging_data())
    s = tr.sample(resolved(d, "motion"), "down")
    c = s.cables
    j = 0  # at rest
    assert c.status[j] == 0
    tB, tA = s.tensions[j], c.outlet_tensions[j]
    H = np.sqrt(tB ** 2 - (2.0 * G / 2) ** 2)  # by symmetry each cable holds half the weight
    X, Z, w = 5.0, 1.0, 0.2 * G
    chord = np.hypot(X, Z)
    a = w * X / (2 * H)
    expected = 0.5 * (tA + tB) * chord / 1e8 - w ** 2 * X ** 4 / (24 * H ** 2 * chord)
    assert np.all(expected < -1e-3)  # millimetres, sag-dominated (the stretch term is 3e-6 m)
    np.testing.assert_allclose(c.setpoint_error[j], expected, rtol=float(np.max(a)) ** 2)
    np.testing.assert_allclose(c.setpoint_error[j], s.lengths[j] - c.unstretched[j], rtol=0, atol=0)


@pytest.mark.slow
def test_a_sample_without_a_solution_is_flagged_never_a_number(tmp_path):
    """The path leaves the robot's reach (the effector above the outlets' line): those samples have
    no sagging statics.  They carry a status, empty cells and feasible 0; trajectory.json counts
    them; simulate refuses to command them (exit 2 naming the trajectory)."""
    data = hanging_data(mu=0.05, waypoints=((0.0, -1.0), (0.0, 0.5)))
    s = tr.sample(resolved(spec.from_dict(data), "motion"), "down")
    bad = s.cables.status != 0
    assert bad.any() and (~bad).any()
    assert not s.feasible[bad].any()
    for arr in (s.tensions, s.cables.unstretched, s.cables.setpoint_error, s.cables.outlet_tensions, s.cables.sag):
        assert np.all(np.isnan(arr[bad])) and np.all(np.isfinite(arr[~bad]))
    p = write_spec(tmp_path, data)
    res = invoke("trajectory", p, "down", "--out", tmp_path / "t", "--json", "--quiet")
    assert res.exit_code == 0, res.output
    summ = json.loads(res.stdout)
    assert summ["unsolved_samples"] == int(bad.sum()) and not summ["feasible"]
    head, rows = read_csv(tmp_path / "t" / "trajectory.csv")
    assert head == trajectory_header("sagging")
    k, u = head.index("cable_status"), head.index("unstretched_length_c1")
    flagged = [r for r in rows if r[k] != "0"]
    assert len(flagged) == int(bad.sum()) and all(r[u] == "" for r in flagged)
    assert all(r[head.index("feasible")] == "0" for r in flagged)
    res = invoke("simulate", p, "down", "--out", tmp_path / "s", "--quiet")
    assert res.exit_code == 2
    assert "trajectories.down" in res.output and "no sagging cable set-points" in res.output
    assert "Traceback" not in res.output
    # the gateway's test PLC would play the same set-points: refused before any connection or file
    data["plc"] = {"ams_net_id": "127.0.0.1.1.1", "port": 851, "host": "127.0.0.1", "cycle_time": 0.01,
                   "setpoints": ["MAIN.fLen1", "MAIN.fLen2"], "actuals": ["MAIN.fAct1", "MAIN.fAct2"]}
    p = write_spec(tmp_path, data, "plc.yaml")
    res = invoke("bridge", p, "--test-plc", "down", "--out", tmp_path / "b", "--quiet")
    assert res.exit_code == 2, res.output
    assert "--test-plc down" in res.output and "no sagging cable set-points" in res.output
    assert "Traceback" not in res.output and not (tmp_path / "b").exists()


def trajectory_header(model=None) -> list:
    """trajectory.csv's header for a 2T robot with cables c1, c2: the historical columns, then the
    cable model's (elastic, sagging)."""
    head = ["time", "x", "y", "x_vel", "y_vel"]
    for c in ("c1", "c2"):
        head += [f"length_{c}", f"cable_speed_{c}", f"motor_angle_{c}", f"tension_{c}"]
    head += ["feasible", "x_acc", "y_acc", "cable_accel_c1", "cable_accel_c2", "segment"]
    if model is not None:
        head += [f"{k}_{c}" for k in ("outlet_tension", "unstretched_length", "sag", "setpoint_error")
                 for c in ("c1", "c2")]
    return head + (["cable_status"] if model == "sagging" else [])


@pytest.mark.slow
def test_cli_columns_and_keys(tmp_path):
    """Ideal: the historical header and keys; elastic: the same columns first, then the cable model's
    (sagging: tests/test_motion_cables.py::test_a_sample_without_a_solution_is_flagged_never_a_number)."""
    for model in (None, "elastic"):
        args = ["trajectory", PLANAR2, "square_fast", "--out", tmp_path / str(model), "--json", "--quiet"]
        res = invoke(*args, *(["--cable-model", model] if model else []))
        assert res.exit_code == 0, res.output
        head, _ = read_csv(tmp_path / str(model) / "trajectory.csv")
        assert head == trajectory_header(model)
        summ = json.loads(res.stdout)
        assert ("cable_model" in summ) == (model is not None)
        if model:
            assert summ["cable_model"] == model and set(summ["max_setpoint_error"]) == {"c1", "c2"}
            assert all(v > 0 for v in summ["max_setpoint_error"].values())
            assert summ["unsolved_samples"] == 0


# ----------------------------------------------------------------------------
# simulation
# ----------------------------------------------------------------------------


def test_elastic_simulation_holds_the_pose_with_unstretched_setpoints():
    """Straight elastic cables at rest: commanded L0 the effector sits on the target; commanded the
    chords (no compensation) it sinks until each cable is stretched by T L / EA more: by about
    (L - L0) / sin(angle) for this symmetric pose (planar2, 1 kg, EA = 2e4 N)."""
    d = planar2_as("elastic")
    pose = [0.75, 0.8486]
    L0 = api.pose(d, pose).cable_state.unstretched_lengths
    chord = api.pose(d, pose).lengths
    sim = S.Simulator(resolved(d, "motion"))
    sim.reset(pose)
    st = sim.advance(L0, 0.5)
    np.testing.assert_allclose(st.pose, pose, atol=1e-6)
    np.testing.assert_allclose(st.axis, L0, rtol=1e-12)
    sim = S.Simulator(resolved(d, "motion"), compensate_stretch=False)
    sim.reset(pose, setpoints=chord)
    st = sim.advance(chord, 0.5)
    B = np.array(pose) + np.array([0.06, 0.06])  # c2's attachment
    sin = (1.5 - B[1]) / chord[1]
    drop = pose[1] - st.pose[1]
    assert drop == pytest.approx((chord[1] - L0[1]) / sin, rel=2e-2)


def _sim_at_rest(d, pose, segments):
    """The robot settled (6 s with the simulator's settling damping) holding the static L0.
    A 4 ms step: the massive cables' springs run on their own sub-steps (mjcf.Chains.update)."""
    L0 = api.pose(d, pose).cable_state.unstretched_lengths
    sim = S.Simulator(resolved(d, "motion"), cable_segments=segments, servo_bandwidth=np.inf, timestep=4e-3)
    return sim.reset(pose, setpoints=L0, settle=6.0)


@pytest.mark.slow
def test_massive_cables_at_rest_agree_with_the_static_catenary():
    """Sagging cables as 1-D flexes (mu = 0.5 kg/m, EA = 1e5 N, 10 m span, 5 kg effector, sag
    0.13-0.44 m).  Commanded the static solution's unstretched lengths, the simulated robot comes to
    rest where the statics put it, with the static effector-end and outlet tensions.

    Tolerance: the chain of N segments is the midpoint rule of the catenary (docs/cable-models.md):
    each straight segment of length l is shorter than its arc by l^3 kappa^2 / 24 (kappa = w H / T^2,
    the catenary's curvature), so the effector moves by about L l^2 kappa^2 / 24 per cable; the
    bound used is the sum over the cables of L l^2 kappa_max^2 / 12, and halving l must divide the
    error by 4 (3 to 5 accepted).  The tensions are the statics' at a pose moved by that much: within
    2 bound / L_min relative.  (Measured: 1.3 and 0.32 mm against bounds of 2.7 and 0.68 mm;
    tensions within 3e-4 and 8e-5.)
    """
    d = spec.from_dict(hanging_data(mu=0.5, EA=1e5, mass=5.0))
    pose = np.array([1.5, -3.0])
    ref = api.pose(d, pose)
    assert ref.feasible and ref.cable_state.status == "ok"
    assert np.min(ref.cable_state.sag) > 0.1
    w = 0.5 * G
    L = ref.cable_state.unstretched_lengths
    Tmin = np.minimum(ref.tensions, ref.cable_state.outlet_tensions)
    H = np.abs(ref.W[0]) * ref.tensions  # horizontal force: |x component of the end-force direction| T_B
    kappa = w * H / Tmin ** 2
    errs = {}
    for N in (8, 16):
        st = _sim_at_rest(d, pose, N)
        bound = float(np.sum(L * (L / N) ** 2 * kappa ** 2 / 12))
        errs[N] = float(np.linalg.norm(st.pose - pose))
        assert errs[N] <= bound, (N, errs[N], bound)
        rtol = 2 * bound / float(np.min(L))
        np.testing.assert_allclose(st.tensions, ref.tensions, rtol=rtol)
        np.testing.assert_allclose(st.outlet_tensions, ref.cable_state.outlet_tensions, rtol=rtol)
        assert np.all(st.outlet_tensions > st.tensions)  # the winch holds the cable's weight too
    assert 3.0 <= errs[8] / errs[16] <= 5.0, errs


def test_massive_cable_model_builds_flexes():
    d = spec.from_dict(hanging_data(mu=0.5, EA=1e5, mass=5.0))
    sim = S.Simulator(resolved(d, "motion"), cable_segments=6)
    m = sim.model
    assert m.nflex == 2 and m.nflexedge == 12 and list(m.flex_dim) == [1, 1]
    assert m.nv == 3 + 2 * 5 * 2  # effector (x, y, phi) + 5 inner vertices per cable on 2 slides
    with pytest.raises(ValueError, match="cable_segments"):
        S.Simulator(resolved(d, "motion"), cable_segments=1)
    # an ideal design has no flex at all (its model is the historical one)
    assert S.Simulator(resolved(spec.from_dict(hanging_data(model="ideal")), "motion")).model.nflex == 0
