"""Motor sizing: hand computations, the catalogue, monotonicity, the m = n closed form."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from cdpr_design.design import envelope as ev
from cdpr_design.design import sizing as sz
from cdpr_design.model import catalogue as cat
from cdpr_design.model import spec
from cdpr_design.errors import InputError, SpecError

from .helpers import planar2_raw, resolved

G = 9.81


@pytest.fixture(scope="module")
def base() -> dict:
    return planar2_raw()


def one_pose(data: dict, x=0.75, y=0.75, **winch) -> dict:
    d = copy.deepcopy(data)
    d["requirements"]["task_box"] = {"lower": [x, y], "upper": [x, y]}
    d["winch"].update(winch)
    return d


# ----------------------------------------------------------------------------
# Hand-computed sizing of the paper's planar robot
# ----------------------------------------------------------------------------


def test_planar2_hand_computed_sizing(base, catalogue):
    """planar2 at (0.75, 0.75): symmetric 45 deg cables, worked by hand.

    l_1 = a_1 - p - b_1 = (-0.69, 0.69), l_2 = (0.69, 0.69): u = (-+1, 1)/sqrt 2,
    L = 0.69 sqrt 2.  Static: t = m g / (2 sin 45) = 9.81/sqrt 2 each.  W^-1 has
    rows of norm 1, so accelerating at A = 5 m/s^2 in the worst direction adds
    m A = 5 N.  Winch: r = 0.036 m, i = 3 (catalogue planetary-3, J = 3e-6),
    spec efficiency 0.9, drum 2e-5 kg m^2, AM8112 rotor 7.5e-6 kg m^2.
    """
    d = spec.from_dict(one_pose(base, gear_ratio=3.0, efficiency=0.9))
    res = sz.size_motors(resolved(d, "size-motors"), catalogue)
    r, i, eta, A, V = 0.036, 3.0, 0.9, 5.0, 1.0
    L = 0.69 * math.sqrt(2)
    t0 = G / math.sqrt(2)
    T = t0 + 1.0 * A
    a_cable = A + V * V / L
    J = 7.5e-6 + 3e-6 + 2e-5 / i ** 2
    peak = T * r / (i * eta) + J * i * a_cable / r
    # default cycle: accelerate (t0 + A, reel-in at A), cruise (t0), decelerate (t0 - A), dwell (t0)
    taus = [(t0 + A) * r / (i * eta) + J * i * A / r, t0 * r / (i * eta),
            (t0 - A) * r / (i * eta) - J * i * A / r, t0 * r / (i * eta)]
    rms = math.sqrt(sum(x * x for x in taus) / 4)
    rpm = i * V / r * 60 / (2 * math.pi)
    for a in res.axes:
        assert a.peak_tension == pytest.approx(T, abs=1e-9)
        assert a.static_tension == pytest.approx(t0, abs=1e-9)
        assert a.drum_torque == pytest.approx(T * r, abs=1e-9)
        assert a.reflected_inertia == pytest.approx(J, abs=1e-15)
        assert a.peak_motor_torque == pytest.approx(peak, abs=1e-9)
        assert a.rms_motor_torque == pytest.approx(rms, abs=1e-9)
        assert a.peak_motor_speed == pytest.approx(rpm, abs=1e-9)
        assert a.peak_cable_speed == pytest.approx(V, abs=1e-12)
        assert a.motor == "AM8112-0F21-EL7211" and a.motor_from == "spec"
        assert a.usable_peak_torque == pytest.approx(0.080 * 9.0)  # EL7211: 9 A peak
        assert a.implied_tension_max == pytest.approx(0.72 * i * eta / r, abs=1e-9)
        assert a.peak_torque_margin == pytest.approx(0.72 / peak, abs=1e-9)
        assert a.rms_torque_margin == pytest.approx(0.36 / rms, abs=1e-9)
        assert a.speed_margin == pytest.approx(3885 / rpm, abs=1e-9)


def test_paper_tension_limit_from_the_motor(base, catalogue):
    """The paper's 0 <= T <= 20 N "due to the maximum torque of the motors" (Rivera et al.,
    section 3): an AM8112 on an EL7211 (0.72 N m usable peak, robots.md) on a direct
    36 mm drum holds exactly 20 N; its own 1.32 N m peak would need a 66 mm drum."""
    d = spec.from_dict(base)
    res = sz.size_motors(resolved(d, "size-motors"), catalogue)
    assert all(a.implied_tension_max == pytest.approx(20.0, rel=1e-12) for a in res.axes)
    assert all(a.tension_max == 20.0 for a in res.axes)
    # the drum radius at which a torque holds 20 N: r = tau / t
    assert catalogue.motor("AM8112-0F21-EL7211").usable_peak_torque / 20.0 == pytest.approx(0.036)
    assert catalogue.motor("AM8112-0F21").usable_peak_torque / 20.0 == pytest.approx(0.066)
    # the peak tension over the task box with the acceleration requirement stays below it
    assert all(a.peak_tension < 20.0 and a.peak_torque_margin > 1.0 for a in res.axes)


# ----------------------------------------------------------------------------
# The m = n closed form against brute force
# ----------------------------------------------------------------------------


def _brute_peak(design, pose, A, ndirs=720):
    from cdpr_design.statics import kinematics as kin

    W = kin.structure_matrix(design, pose)
    best = np.full(design.m, -np.inf)
    for ang in np.linspace(0, 2 * np.pi, ndirs, endpoint=False):
        a = A * np.array([np.cos(ang), np.sin(ang)])
        w = -(kin.gravity_wrench(design, pose) + kin.inertial_wrench(design, pose, a))
        best = np.maximum(best, np.linalg.solve(W, w))
    return best


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(6))
def test_square_closed_form_matches_brute_force(seed):
    """t0 + A ||row_i(W^-1 M)|| is the max over |a| <= A (dense sampling from below)."""
    rng = np.random.default_rng(seed)
    rigid = seed % 2 == 1
    m = 3 if rigid else 2
    cables = [{"name": f"k{i}", "outlet": [float(rng.uniform(0, 2)), float(rng.uniform(1.5, 2))],
               "attachment": [float(rng.uniform(-0.1, 0.1)), float(rng.uniform(0, 0.1))]} for i in range(m)]
    data = {"name": "r", "motion": "1R2T" if rigid else "2T", "frame": {"lower": [0, 0], "upper": [2, 2]},
            "effector": {"mass": float(rng.uniform(0.5, 3)), "size": [0.2, 0.2],
                         "center_of_mass": [float(rng.uniform(-0.05, 0.05)), float(rng.uniform(-0.05, 0.05))]},
            "tension": [0, 1000], "cables": cables}
    d = spec.from_dict(data)
    pos = np.array([[float(rng.uniform(0.6, 1.4)), float(rng.uniform(0.5, 1.2))]])
    A = float(rng.uniform(1, 8))
    e = ev.envelope_chunk(resolved(d, "size-motors"), pos, d.default_orientation_full(), A, 0.0)
    pose = np.concatenate([pos[0], [0.0]]) if rigid else pos[0]
    brute = _brute_peak(d, pose, A)
    assert np.all(brute <= e["peak"][0] + 1e-9)
    np.testing.assert_allclose(brute, e["peak"][0], rtol=1e-4)  # 1 - cos(pi / 720) < 1e-5


@pytest.mark.slow
def test_redundant_envelope_against_cvxpy():
    """m > n: the per-vertex minimum-norm tensions equal a cvxpy QP's."""
    import cvxpy as cp

    from cdpr_design.statics import kinematics as kin

    data = {"name": "p4", "motion": "2T", "frame": {"lower": [0, 0], "upper": [2, 2]},
            "effector": {"mass": 2.0, "size": [0.1, 0.1]}, "tension": [1.0, 60.0],
            "cables": [{"name": n, "outlet": o, "attachment": [0, 0]} for n, o in
                       (("a", [0, 2]), ("b", [2, 2]), ("c", [0, 0]), ("d", [2, 0]))]}
    d = spec.from_dict(data)
    A = 5.0
    pos = np.array([[0.7, 1.2], [1.3, 0.8]])
    e = ev.envelope_chunk(resolved(d, "size-motors"), pos, np.zeros(3), A, 0.0)
    dirs = ev.acceleration_directions(2)
    for k, p in enumerate(pos):
        W = kin.structure_matrix(d, p)
        peaks = []
        for a in np.vstack([np.zeros(2), A * dirs]):
            w = -(kin.gravity_wrench(d, p) + kin.inertial_wrench(d, p, a))
            t = cp.Variable(4)
            cp.Problem(cp.Minimize(cp.sum_squares(t)), [W @ t == w, t >= 1.0, t <= 60.0]).solve()
            peaks.append(t.value)
        np.testing.assert_allclose(e["peak"][k], np.max(peaks, axis=0), atol=1e-5)
        np.testing.assert_allclose(e["static"][k], peaks[0], atol=1e-5)


# ----------------------------------------------------------------------------
# Monotonicity
# ----------------------------------------------------------------------------


@settings(max_examples=15, deadline=None)
@given(m1=st.floats(0.2, 3.0), dm=st.floats(0.0, 2.0), x=st.floats(0.4, 1.1), y=st.floats(0.4, 1.1))
def test_heavier_effector_needs_no_less_torque(base, catalogue, m1, dm, x, y):
    d1 = one_pose(base, x, y)
    d1["effector"]["mass"] = m1
    d2 = copy.deepcopy(d1)
    d2["effector"]["mass"] = m1 + dm
    a = sz.size_motors(resolved(spec.from_dict(d1), "size-motors"), catalogue).axes
    b = sz.size_motors(resolved(spec.from_dict(d2), "size-motors"), catalogue).axes
    assert len(a) == len(b) == 2
    for p, q in zip(a, b):
        assert q.peak_tension >= p.peak_tension - 1e-12
        assert q.peak_motor_torque >= p.peak_motor_torque - 1e-12
        assert q.rms_motor_torque >= p.rms_motor_torque - 1e-12


@settings(max_examples=15, deadline=None)
@given(r=st.floats(0.005, 0.1), f=st.floats(1.01, 3.0), x=st.floats(0.4, 1.1), y=st.floats(0.4, 1.1))
def test_larger_drum_more_torque_less_speed(base, catalogue, r, f, x, y):
    """With a light drum the load term T r / (i eta) dominates the inertia term."""
    a = sz.size_motors(resolved(spec.from_dict(one_pose(base, x, y, drum_radius=r, drum_inertia=0.0)), "size-motors"), catalogue).axes
    b = sz.size_motors(resolved(spec.from_dict(one_pose(base, x, y, drum_radius=r * f, drum_inertia=0.0)), "size-motors"), catalogue).axes
    assert len(a) == len(b) == 2
    for p, q in zip(a, b):
        assert q.drum_torque > p.drum_torque
        assert q.peak_motor_speed < p.peak_motor_speed
        if p.peak_tension * r ** 2 > 10 * 7.5e-6 * (p.peak_cable_accel):  # load term dominant
            assert q.peak_motor_torque > p.peak_motor_torque


# ----------------------------------------------------------------------------
# Choosing a motor; limits exactly at the edge
# ----------------------------------------------------------------------------


def _exact_catalogue(peak, rms, rpm, shave=None):
    """A catalogue with one motor exactly at the requirement (and one a hair under, if asked)."""
    motors = [{"name": "exact", "rated_torque": rms, "peak_torque": peak, "max_speed": rpm, "rotor_inertia": 0.0}]
    if shave is not None:
        p, r_, n = peak, rms, rpm
        if shave == "peak":
            p = np.nextafter(peak, 0)
        elif shave == "rms":
            r_ = np.nextafter(rms, 0)
        else:
            n = np.nextafter(rpm, 0)
        motors.append({"name": "under", "rated_torque": float(r_), "peak_torque": float(p), "max_speed": float(n),
                       "rotor_inertia": 0.0})
    return cat.catalogue_from_dict({"motors": motors})


@pytest.mark.parametrize("shave", ["peak", "rms", "speed"])
def test_motor_exactly_at_the_limit_passes_just_under_fails(base, shave):
    data = one_pose(base, 0.6, 0.9)
    data["winch"].pop("motor")
    d = spec.from_dict(data)
    probe = sz.size_motors(resolved(d, "size-motors"), _exact_catalogue(100.0, 100.0, 1e6)).axes  # rotor inertia 0 for all
    for k, p in enumerate(probe):  # one catalogue per axis, at that axis's requirement
        cat = _exact_catalogue(p.peak_motor_torque, p.rms_motor_torque, p.peak_motor_speed, shave)
        a = sz.size_motors(resolved(d, "size-motors"), cat).axes[k]
        assert a.motor == "exact" and a.fits
        assert min(a.peak_torque_margin, a.rms_torque_margin, a.speed_margin) == 1.0
        under = sz.size_motors(resolved(d, "size-motors"), cat, motor="under").axes[k]
        assert not under.fits and under.motor == "under"
        assert min(under.peak_torque_margin, under.rms_torque_margin, under.speed_margin) < 1.0


def test_smallest_fitting_motor_and_best_combination(base, catalogue):
    data = one_pose(base, 0.75, 0.9, drum_radius=[0.02, 0.05, 0.1], gear_ratio=[1, 5])
    data["winch"].pop("motor")
    data["winch"].pop("efficiency")
    res = sz.size_motors(resolved(spec.from_dict(data), "size-motors"), catalogue)
    order = [m.name for m in catalogue.by_size()]
    for a in res.axes:
        assert a.fits and a.motor == order[0]  # the smallest motor fits on some winch
        assert a.motor_from == "catalogue"
        if a.gear_ratio == 5:
            assert a.efficiency == pytest.approx(0.97) and a.gearbox == "planetary-5"
    # nothing fits: the motor column is empty and the margins are those of the closest candidate
    heavy = copy.deepcopy(data)
    heavy["effector"]["mass"] = 500.0
    heavy["winch"]["drum_radius"] = 0.2
    heavy["winch"]["gear_ratio"] = 1
    res = sz.size_motors(resolved(spec.from_dict(heavy), "size-motors"), catalogue)
    assert not res.ok and all(a.motor == "" and a.torque_margin < 1 for a in res.axes)


def test_safety_factor_scales_margins(base, catalogue):
    d = spec.from_dict(one_pose(base))
    a = sz.size_motors(resolved(d, "size-motors"), catalogue).axes[0]
    b = sz.size_motors(resolved(d, "size-motors"), catalogue, safety_factor=2.0).axes[0]
    assert b.torque_margin == pytest.approx(a.torque_margin / 2)
    assert b.speed_margin == pytest.approx(a.speed_margin / 2)
    with pytest.raises(InputError, match="safety-factor"):
        sz.size_motors(resolved(d, "size-motors"), catalogue, safety_factor=0.5)


def test_unknown_motor_is_input_error(base, catalogue):
    data = one_pose(base)
    data["winch"]["motor"] = "NoSuchMotor"
    with pytest.raises(InputError, match=r"winch.motor: 'NoSuchMotor'"):
        sz.size_motors(resolved(spec.from_dict(data), "size-motors"), catalogue)
    with pytest.raises(InputError, match="--motor"):
        sz.size_motors(resolved(spec.from_dict(one_pose(base)), "size-motors"), catalogue, motor="nope")


def test_trajectory_duty_cycle_rms(base, catalogue):
    """RMS over a given duty cycle equals the hand computation, time-weighted."""
    d = spec.from_dict(one_pose(base))

    class S:
        name = "fake"
        time = np.array([0.0, 1.0, 3.0, 4.0])
        tensions = np.array([[5.0, 6.0], [7.0, 6.0], [5.0, 5.0], [6.0, 8.0]])
        cable_speed = np.array([[0.0, 0.0], [-2.0, 0.5], [0.0, 0.0], [0.0, 0.0]])
        cable_accel = np.array([[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0], [0.0, 0.0]])
        feasible = np.ones(4, bool)

    res = sz.size_motors(resolved(d, "size-motors"), catalogue, samples=S())
    a = res.axes[0]
    r, J = 0.036, 7.5e-6 + 2e-5
    tau = S.tensions[:, 0] * r - J / r * S.cable_accel[:, 0]
    # each sample stands for the mean of its neighbouring intervals (ends: one interval)
    w = np.array([1.0, 1.5, 1.5, 1.0]) / 5.0
    assert a.rms_motor_torque == pytest.approx(math.sqrt(np.sum(w * tau ** 2)), abs=1e-12)
    assert a.peak_motor_speed == pytest.approx(2.0 / r * 60 / (2 * math.pi))  # trajectory beats max_speed
    assert res.cycle == "trajectory fake"


# ----------------------------------------------------------------------------
# Catalogue validation
# ----------------------------------------------------------------------------


def test_shipped_catalogue_has_the_reference_motors(catalogue):
    names = {m.name for m in catalogue.motors}
    assert {"AM8111-0F20", "AM8112-0F21", "AM8113-0F21", "AM8121-0F00", "SGMP-01"} <= names
    m = catalogue.motor("AM8112-0F21")
    assert (m.rated_torque, m.peak_torque, m.rotor_inertia) == (0.36, 1.32, 7.5e-6)
    assert all(x.source for x in catalogue.motors + catalogue.gearboxes + catalogue.drives)
    assert catalogue.gearbox(1.0).efficiency == 1.0


@pytest.mark.parametrize("entry, path", [
    ({"name": "x", "rated_torque": 1.0, "peak_torque": 0.5, "max_speed": 3000, "rotor_inertia": 0}, "motors[0].peak_torque"),
    ({"name": "x", "rated_torque": 1.0, "peak_torque": 2.0, "max_speed": -1, "rotor_inertia": 0}, "motors[0].max_speed"),
    ({"name": "x", "rated_torque": 1.0, "peak_torque": 2.0, "max_speed": 3000, "rotor_inertia": 0,
      "drive": "nope", "torque_constant": 0.1}, "motors[0].drive"),
    ({"name": "x", "rated_torque": 1.0, "peak_torque": 2.0, "max_speed": 3000, "rotor_inertia": 0,
      "drive": "EL7211"}, "motors[0].torque_constant"),
    ({"name": "x", "rated_torque": 1.0, "peak_torque": 2.0, "max_speed": 3000}, "motors[0].rotor_inertia"),
    ({"name": "x", "rated_torque": 1.0, "peak_torque": 2.0, "max_speed": 3000, "rotor_inertia": 0, "colour": 1},
     "motors[0].colour"),
])
def test_bad_catalogue_entries_name_the_key(tmp_path, entry, path):
    f = tmp_path / "cat.yaml"
    f.write_text(yaml.safe_dump({"motors": [entry]}))
    with pytest.raises(SpecError) as exc:
        spec.load_catalogue(f)
    assert path in [p for p, _ in exc.value.problems]


def test_user_catalogue_extends_and_replaces(tmp_path):
    f = tmp_path / "cat.yaml"
    f.write_text(yaml.safe_dump({"motors": [
        {"name": "Mine", "rated_torque": 2.0, "peak_torque": 6.0, "max_speed": 3000, "rotor_inertia": 1e-4,
         "torque_constant": 0.5, "drive": "EL7211", "source": "test"},
        {"name": "SGMP-01", "rated_torque": 0.3, "peak_torque": 0.9, "max_speed": 5000, "rotor_inertia": 6.5e-6}]}))
    cat = spec.load_catalogue(f)
    assert cat.motor("Mine").usable_peak_torque == pytest.approx(4.5)  # 0.5 N m/A x 9 A
    assert cat.motor("Mine").usable_rated_torque == pytest.approx(2.0)
    assert cat.motor("SGMP-01").max_speed == 5000
    assert cat.motor("AM8112-0F21") is not None
    with pytest.raises(SpecError, match="no such file"):
        spec.load_catalogue(tmp_path / "missing.yaml")
