"""Stiffness and vibration of the effector (cdpr_design.statics.stiffness, kernels/stiffness.py).

- K = -dw/dx against central differences of the wrench at fixed unstretched lengths on 200
  random robots of every motion type (a reference wrench written out here);
- the kernel's least stiffness and lowest frequency against numpy/scipy on random robots;
- a closed form worked by hand (docs/algorithms.md, "Stiffness and vibration");
- the ``pose --json`` keys;
- MuJoCo: the effector released from a small displacement rings at the computed frequency.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from cdpr_design.model import spec
from cdpr_design.model.design import min_string_tension
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics import stiffness as st
from tests.helpers import invoke, resolved, write_spec
from tests.reference import stiffness as ref

MOTIONS = ("2T", "1R2T", "3T", "3R3T")


def random_robot(rng, motion):
    """A random elastic robot of ``motion``: 1-9 cables, random EA, COM, inertia and gravity."""
    d = 2 if motion in ("2T", "1R2T") else 3
    m = int(rng.integers(1, 10))
    cables = [{"name": f"c{i}", "outlet": rng.uniform(-3, 3, d).tolist(),
               "attachment": rng.uniform(-0.4, 0.4, d).tolist(),
               "axial_stiffness": float(rng.uniform(1e3, 1e6))} for i in range(m)]
    a = rng.normal(size=(3, 3))
    inertia = float(rng.uniform(0.01, 2)) if d == 2 else (a @ a.T + 0.1 * np.eye(3)).tolist()
    g = rng.normal(size=d) * rng.uniform(0, 12)
    return spec.from_dict({
        "name": "r", "motion": motion, "gravity": g.tolist(), "frame": {"lower": [-3.0] * d, "upper": [3.0] * d},
        "effector": {"mass": float(rng.uniform(0.1, 50)), "size": [0.2] * d,
                     "center_of_mass": rng.uniform(-0.3, 0.3, d).tolist(), "inertia": inertia},
        "tension": [0.0, 1e6], "cable": {"model": "elastic"}, "cables": cables})


def random_pose(rng, design):
    mot = design.motion
    return np.concatenate([rng.uniform(-0.5, 0.5, mot.dim), rng.uniform(-0.6, 0.6, len(mot.rotation_coords))])


def wrench_at(design, full, rotvec, L0, EA):
    """The wrench (6,) on the effector at fixed unstretched lengths ``L0``: the cables' pulls
    EA (L - L0) / L0 along the cables and the weight at the centre of mass, moments about the
    platform origin; the orientation is exp([rotvec]x) R(full's angles)."""
    R = Rotation.from_rotvec(rotvec).as_matrix() @ kin.rotation_matrix(*full[3:])
    Rb = design.attachments @ R.T
    l = design.outlets - (full[:3] + Rb)
    L = np.linalg.norm(l, axis=1)
    F = (EA * (L - L0) / L0)[:, None] * l / L[:, None]
    G = design.effector.mass * np.asarray(design.gravity)
    c = R @ np.asarray(design.effector.center_of_mass)
    return np.concatenate([F.sum(axis=0) + G, np.cross(Rb, F).sum(axis=0) + np.cross(c, G)])


def fd_stiffness(design, full, L0, EA, h=1e-5):
    """-dw/dx by central differences with one Richardson step, in the motion's coordinates."""
    return ref.fd_stiffness(design, full, lambda p, rotvec: wrench_at(design, np.concatenate([p, full[3:]]), rotvec,
                                                                      L0, EA), h)


@pytest.mark.slow
@pytest.mark.parametrize("motion", MOTIONS)
def test_stiffness_matrix_is_minus_wrench_derivative(motion):
    """200 random robots of each motion type, at random poses and random unstretched lengths
    (the wrench not balanced: the formula holds away from equilibrium too): relative error
    max|K - K_fd| / max|K| below 1e-6."""
    rng = np.random.default_rng(["2T", "1R2T", "3T", "3R3T"].index(motion) + 100)
    worst = 0.0
    for _ in range(200):
        design = random_robot(rng, motion)
        p = random_pose(rng, design)
        full = design.full_pose(p)
        EA = np.array([c.props.axial_stiffness for c in design.cables])
        L = kin.inverse_kinematics(design, p)
        L0 = L / (1 + rng.uniform(1e-4, 0.05, design.m))
        t = EA * (L - L0) / L0
        K = st.pose_stiffness(design, p, t).matrix
        worst = max(worst, float(np.max(np.abs(K - fd_stiffness(design, full, L0, EA))) / np.max(np.abs(K))))
    assert worst < 1e-6, worst


@pytest.mark.parametrize("motion", MOTIONS)
def test_stiffness_symmetric_at_equilibrium(motion):
    """At an equilibrium (tensions balancing the weight) K is symmetric; away from one it need not be."""
    from cdpr_design import api

    rng = np.random.default_rng(7 + MOTIONS.index(motion))
    seen = 0
    while seen < 30:
        design = random_robot(rng, motion)
        p = random_pose(rng, design)
        r = api.pose(design, p)
        if not np.all(np.isfinite(r.tensions)):
            continue
        K = st.pose_stiffness(design, p, r.tensions).matrix
        assert np.max(np.abs(K - K.T)) <= 1e-9 * np.max(np.abs(K))
        seen += 1


def random_orientation(rng, design):
    """The workspace orientation with the motion's rotations drawn in [-0.6, 0.6] rad."""
    ori = design.default_orientation_full()
    d = design.motion.dim
    if design.motion.rotational:
        ori[[i - 3 for i in design.motion.pose_index[d:]]] = rng.uniform(-0.6, 0.6, len(design.motion.rotation_coords))
    return ori


def assert_kernel_figures(design, ori, P, T, feasible, kmin, flow):
    """The kernel's ``kmin``, ``flow`` at positions ``P`` (k, 3) held by ``T`` (k, m) against
    numpy/scipy (Schur complement, generalised eigenproblem); NaN where ``feasible`` is 0 or a
    tension is NaN.  Returns the number of poses compared."""
    d = design.motion.dim
    R = kin.rotation_matrix(*ori)
    Rb = design.attachments @ R.T
    EA = st.axial_stiffnesses(design)[0]
    Mn = st.restrict(design, st.mass_matrix(design, R))
    weight = design.effector.mass * np.asarray(design.gravity)
    compared = 0
    for k in range(P.shape[0]):
        if not feasible[k] or not np.all(np.isfinite(T[k])):
            assert np.isnan(kmin[k]) and np.isnan(flow[k])
            continue
        K = st.restrict(design, ref.stiffness_matrix(design.outlets - P[k] - Rb, Rb, T[k], EA, weight,
                                                    R @ np.asarray(design.effector.center_of_mass)))
        ref_k = ref.min_stiffness(K, d)
        f = st.vibration(K, Mn)[0][0]
        scale = np.max(np.abs(K))
        assert abs(kmin[k] - ref_k) <= 1e-9 * scale, (kmin[k], ref_k)
        if np.isnan(f):
            assert np.isnan(flow[k])
        else:
            assert flow[k] == pytest.approx(f, rel=1e-8, abs=1e-9 * np.sqrt(scale / np.max(np.diag(Mn))))
        compared += 1
    return compared


@pytest.mark.parametrize("motion", MOTIONS)
def test_kernel_matches_numpy(motion):
    """The sweep kernel's least stiffness and lowest frequency against numpy/scipy on 40 random
    robots x 20 positions each."""
    rng = np.random.default_rng(30 + MOTIONS.index(motion))
    compared = 0
    for _ in range(40):
        design = random_robot(rng, motion)
        ori = random_orientation(rng, design)
        P = np.zeros((20, 3))
        P[:, :design.motion.dim] = rng.uniform(-0.5, 0.5, (20, design.motion.dim))
        T = rng.uniform(0, 500, (20, design.m))
        T[3] = np.nan  # an infeasible pose
        kmin, flow = st.sweep_figures(st.sweep_arrays(design, ori), P, T)
        compared += assert_kernel_figures(design, ori, P, T, np.ones(20), kmin, flow)
    assert compared == 40 * 19


@pytest.mark.parametrize("motion", MOTIONS)
def test_grid_kernel_matches_numpy(motion):
    """The kernel as the sweep calls it, counting a grid's indices from a row ``start`` and
    skipping the poses the sweep flags infeasible, against numpy/scipy at the grid's positions
    (C order over x, y, z) on 40 random robots and grids."""
    rng = np.random.default_rng(50 + MOTIONS.index(motion))
    d = 2 if motion in ("2T", "1R2T") else 3
    compared = 0
    for _ in range(40):
        design = random_robot(rng, motion)
        ori = random_orientation(rng, design)
        lower, step, shape = np.zeros(3), np.ones(3), np.ones(3, dtype=np.int64)
        lower[:d] = rng.uniform(-0.5, 0.0, d)
        step[:d] = rng.uniform(0.02, 0.2, d)
        shape[:d] = rng.integers(2, 6, d)
        axes = [lower[i] + np.arange(shape[i]) * step[i] for i in range(3)]
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        start = int(rng.integers(0, grid.shape[0] - 1))
        P = grid[start:]
        T = rng.uniform(0, 500, (P.shape[0], design.m))
        feasible = (rng.random(P.shape[0]) < 0.8).astype(np.uint8)
        kmin, flow = st.grid_figures(st.sweep_arrays(design, ori), (lower, step, shape), start, T, feasible)
        compared += assert_kernel_figures(design, ori, P, T, feasible, kmin, flow)
    assert compared > 40 * 3


# ----------------------------------------------------------------------------
# The closed form of docs/algorithms.md: a point mass on two elastic cables
# ----------------------------------------------------------------------------

TWO_CABLES = {
    "name": "two", "motion": "2T", "gravity": [0.0, -9.81], "frame": {"lower": [-1.0, -1.0], "upper": [1.0, 1.0]},
    "effector": {"mass": 2.0, "size": [0.05, 0.05]}, "tension": [0.0, 100.0],
    "cable": {"model": "elastic", "axial_stiffness": 1000.0, "mass_per_length": 0.01},
    "cables": [{"name": "left", "outlet": [-0.6, 0.8], "attachment": [0.0, 0.0]},
               {"name": "right", "outlet": [0.6, 0.8], "attachment": [0.0, 0.0]}],
    "workspace": {"grid": {"lower": [-0.2, -0.2], "upper": [0.2, 0.2], "step": 0.1}},
}


def test_point_mass_on_two_cables_closed_form():
    """Cables of L = 1 m at u = (-+0.6, 0.8), m = 2 kg, EA = 1000 N, mu = 0.01 kg/m (worked by
    hand in docs/algorithms.md): t = m g / (2 * 0.8) = 12.2625 N, k = EA/L0 = EA + t;
    Kxx = 0.72 k + 1.28 t = 0.72 EA + 2 t = 744.525 N/m, Kyy = 1.28 EA + 2 t = 1304.525 N/m,
    f = sqrt(K/m) / (2 pi) = 3.07075 Hz and 4.06473 Hz; strings sqrt(t/mu)/2 = 17.5089 Hz."""
    from cdpr_design import api

    design = spec.from_dict(TWO_CABLES)
    r = api.pose(design, [0.0, 0.0])
    np.testing.assert_allclose(r.tensions, [12.2625, 12.2625], rtol=1e-12)
    s = st.pose_stiffness(design, [0.0, 0.0], r.tensions)
    np.testing.assert_allclose(s.matrix, [[744.525, 0.0], [0.0, 1304.525]], rtol=1e-12, atol=1e-10)
    assert s.min_stiffness == pytest.approx(744.525, rel=1e-12)
    np.testing.assert_allclose(s.frequencies, [3.070752, 4.064727], rtol=1e-6)
    np.testing.assert_allclose(np.abs(s.modes), np.eye(2), atol=1e-12)
    np.testing.assert_allclose(s.cable_frequencies, [17.50893, 17.50893], rtol=1e-6)
    # the least tension keeping the first string mode at 20 Hz: 4 f^2 L^2 mu = 16 N
    np.testing.assert_allclose(min_string_tension([1.0, 1.0], [0.01, 0.01], 20.0), [16.0, 16.0], rtol=1e-12)
    # and that tension gives 20 Hz back
    np.testing.assert_allclose(st.string_frequencies([1.0], [16.0], [0.01]), [20.0], rtol=1e-12)


def test_pose_json_stiffness_keys(tmp_path):
    """pose --json reports the closed form's numbers; an ideal design without EA says why not."""
    res = invoke("pose", str(write_spec(tmp_path, TWO_CABLES)), "--at", "0,0", "--json")
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    np.testing.assert_allclose(data["stiffness_matrix"], [[744.525, 0.0], [0.0, 1304.525]], rtol=1e-12, atol=1e-10)
    np.testing.assert_allclose(data["translational_stiffness"], data["stiffness_matrix"])
    assert data["min_stiffness"] == pytest.approx(744.525, rel=1e-12)
    np.testing.assert_allclose(data["natural_frequencies"], [3.070752, 4.064727], rtol=1e-6)
    assert len(data["mode_shapes"]) == 2
    assert data["cable_frequencies"]["left"] == pytest.approx(17.50893, rel=1e-6)
    assert data["stiffness_reason"] is None

    ideal = dict(TWO_CABLES, cable={"model": "ideal"})
    data = json.loads(invoke("pose", str(write_spec(tmp_path, ideal, "ideal.yaml")), "--at", "0,0", "--json").output)
    assert data["stiffness_matrix"] is None and data["min_stiffness"] is None
    assert data["natural_frequencies"] is None and data["mode_shapes"] is None
    assert "axial_stiffness" in data["stiffness_reason"]
    assert data["cable_frequencies"] == {"left": None, "right": None}

    # an infeasible pose (outside the cables' span: a cable would push)
    data = json.loads(invoke("pose", str(write_spec(tmp_path, TWO_CABLES)), "--at", "0,0.9", "--json").output)
    assert data["feasible"] is False
    assert data["min_stiffness"] is None and "infeasible" in data["stiffness_reason"]


def test_min_cable_frequency_gives_a_tension_floor(tmp_path):
    """requirements.min_cable_frequency: 20 Hz on the closed form's 1 m cables of 0.01 kg/m asks
    4 f^2 L^2 mu = 16 N of each (pose --json cable_frequency_tensions); out of range: exit 2."""
    spec_ = dict(TWO_CABLES, requirements={"min_cable_frequency": 20.0})
    data = json.loads(invoke("pose", str(write_spec(tmp_path, spec_)), "--at", "0,0", "--json").output)
    assert data["cable_frequency_tensions"] == pytest.approx({"left": 16.0, "right": 16.0}, rel=1e-12)
    assert "cable_frequency_tensions" not in json.loads(
        invoke("pose", str(write_spec(tmp_path, TWO_CABLES, "plain.yaml")), "--at", "0,0", "--json").output)
    bad = dict(TWO_CABLES, requirements={"min_cable_frequency": -1.0})
    res = invoke("pose", str(write_spec(tmp_path, bad, "bad.yaml")), "--at", "0,0", "--json")
    assert res.exit_code == 2 and "requirements.min_cable_frequency" in res.output


def test_rotational_stiffness_includes_the_weight():
    """A pendulum: one cable to a body whose centre of mass hangs d below the attachment. Rotating
    it by dtheta about the attachment (= the reference point) the weight's moment gives back
    m g d dtheta: K_rr = m g d + (the cable's share, zero with the attachment at p)."""
    design = spec.from_dict({
        "name": "pend", "motion": "1R2T", "gravity": [0.0, -9.81], "frame": {"lower": [-1, -1], "upper": [1, 1]},
        "effector": {"mass": 3.0, "size": [0.1, 0.1], "center_of_mass": [0.0, -0.25], "inertia": 0.02},
        "tension": [0.0, 100.0], "cable": {"model": "elastic", "axial_stiffness": 5e4},
        "cables": [{"name": "c", "outlet": [0.0, 1.0], "attachment": [0.0, 0.0]}]})
    s = st.pose_stiffness(design, [0.0, 0.0, 0.0], [3.0 * 9.81])
    assert s.matrix[2, 2] == pytest.approx(3.0 * 9.81 * 0.25, rel=1e-12)
    # the pendulum's frequency about the cable's point: sqrt(m g d / (I + m d^2)) / 2 pi, coupled with
    # the sideways swing of the attachment on the 1 m cable (a double pendulum): the lowest below both
    assert s.frequencies[0] < np.sqrt(3 * 9.81 * 0.25 / (0.02 + 3 * 0.0625)) / (2 * np.pi)


# ----------------------------------------------------------------------------
# MuJoCo: the effector rings at the computed frequency
# ----------------------------------------------------------------------------


def ring(design, pose, mode, amplitude, duration):
    """Settle the MuJoCo robot at ``pose``, displace it by ``amplitude`` along ``mode`` (motion
    coordinates; rotations as the small rotation vector), release it with no damping and return
    (times [s], displacements (k, n) from the start pose)."""
    from cdpr_design.motion.simulation import Simulator

    sim = Simulator(resolved(design, "motion"), timestep=2e-4, servo_bandwidth=np.inf, cable_damping=0.0, joint_damping=0.0)
    s0 = sim.reset(pose, settle=2.0)
    x0 = np.asarray(s0.pose, float)
    q = sim.data.qpos
    dx = amplitude * np.asarray(mode)
    sel = list(design.motion.pose_index)
    full = np.zeros(6)
    full[sel] = dx
    if design.motion.planar:
        q[0] += full[0]
        q[1] += full[1]
        q[2] += full[5]
    else:
        q[:3] += full[:3]
        w, x, y, z = q[3:7]
        R = Rotation.from_rotvec(full[3:]) * Rotation.from_quat([x, y, z, w])
        x, y, z, w = R.as_quat()
        q[3:7] = [w, x, y, z]
    sim.data.qvel[:] = 0.0
    import mujoco

    mujoco.mj_forward(sim.model, sim.data)
    setpoints = sim.q.copy()
    times, xs = [], []
    step = 20 * sim.timestep
    for k in range(int(duration / step)):
        s = sim.advance(setpoints, step)
        times.append(s.time)
        xs.append(np.asarray(s.pose, float) - x0)
    return np.array(times), np.array(xs)


def peak_frequency(t, y):
    """The frequency [Hz] of the largest peak of y's spectrum (Hann window, 16x zero padding,
    parabolic interpolation of the log magnitude)."""
    y = (y - y.mean()) * np.hanning(y.size)
    n = 16 * y.size
    spec_ = np.abs(np.fft.rfft(y, n))
    k = int(np.argmax(spec_[1:])) + 1
    a, b, c = np.log(spec_[k - 1:k + 2])
    shift = 0.5 * (a - c) / (a - 2 * b + c)
    return (k + shift) / (n * (t[1] - t[0]))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["planar4", "cogiro"])
def test_mujoco_rings_at_the_lowest_frequency(name):
    """Released 0.1 mm (or mrad) along its lowest mode, the MuJoCo effector (tendons whose actuator
    stiffness is EA / L0, no damping) rings at the lowest computed natural frequency within 0.1 % (measured: planar4 7e-6, CoGiRo 1.8e-4).
    The mode's coordinate is the displacement's M-weighted projection on the mode shape."""
    from pathlib import Path

    from cdpr_design import api

    design = spec.load(Path(__file__).resolve().parents[1] / "designs" / f"{name}.yaml")
    if name == "planar4":
        design = spec.from_dict({**design.raw, "cable": {**design.raw.get("cable", {}), "model": "elastic"}})
    g = design.workspace.grid
    pose = np.array([(lo + hi) / 2 for lo, hi in zip(g.lower, g.upper)] + list(design.workspace.orientation))
    r = api.pose(design, pose)
    s = st.pose_stiffness(design, pose, r.tensions)
    f0 = s.frequencies[0]
    periods = 40
    t, x = ring(design, pose, s.modes[0], 1e-4, periods / f0)
    R = kin.pose_rotation(design, pose)
    M = st.restrict(design, st.mass_matrix(design, R))
    if design.motion.name == "3R3T":
        # pose angles -> small rotation vector about frame axes
        ang = design.full_pose(pose)[3:]
        E = np.column_stack([kin.euler_rates_to_omega(ang, e) for e in np.eye(3)])
        x = np.column_stack([x[:, :3], x[:, 3:] @ E.T])
    eta = x @ (M @ s.modes[0])
    f_sim = peak_frequency(t, eta)
    assert f_sim == pytest.approx(f0, rel=1e-3), (f_sim, f0, s.frequencies)


def test_least_eigenvalue_kernel_matches_numpy():
    """The kernel's least eigenvalue of a symmetric n x n matrix (closed form to 2x2, Householder
    and Newton beyond) against numpy on random matrices and on multiple and clustered spectra."""
    from cdpr_design.kernels.stiffness import min_eig_sym

    rng = np.random.default_rng(5)
    d, e2 = np.empty(6), np.empty(6)
    for n in range(1, 7):
        spectra = [rng.normal(size=n) * 10 ** rng.uniform(-3, 6) for _ in range(300)]
        spectra += [np.r_[[1.0] * min(n, 2), np.arange(n - min(n, 2)) + 2.0], np.full(n, 5.0),
                    np.r_[1e-7, 1e-7 + 1e-12, np.linspace(3, 9, max(n - 2, 0))][:n]]
        for lam in spectra:
            Q = np.linalg.qr(rng.normal(size=(n, n)))[0]
            a = Q @ np.diag(lam) @ Q.T
            a = 0.5 * (a + a.T)
            ref = np.linalg.eigvalsh(a)[0]
            got = min_eig_sym(a.copy(), n, d, e2)
            assert abs(got - ref) <= 1e-13 * np.max(np.abs(lam)), (n, lam, got, ref)
