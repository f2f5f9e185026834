"""Acceleration capability at a pose and the dynamic workspace, against an independent linear
program (scipy's HiGHS on W t = M a - w_g - w_e with the tensions in their bounds)."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
import yaml
from scipy.optimize import linprog

from cdpr_design.model import spec
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.acceleration import capability
from cdpr_design.statics.robot import Analysis, resolve
from tests.helpers import DESIGNS, invoke, planar2_raw, random_planar_data, random_spatial_data, write_spec

HIGHS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}


def _spatial_data(rng, m: int, motion: str) -> dict:
    """A random spatial robot (:func:`~tests.helpers.random_spatial_data`, attachments moved by up
    to 2 cm) with its centre of mass off the effector's centre."""
    data = random_spatial_data(rng, m, motion, jitter=0.02)
    data["effector"]["center_of_mass"] = [float(v) for v in rng.uniform(-0.03, 0.03, 3)]
    return data


def random_robot(seed: int):
    """A random planar (2T, 1R2T) or spatial (3T, 3R3T) robot, an external wrench box on half of them."""
    data, rng = random_data(seed)
    return spec.from_dict(data), rng


def random_data(seed: int):
    """The spec data of :func:`random_robot` and its random generator."""
    rng = np.random.default_rng(seed)
    motion = ("2T", "1R2T", "3T", "3R3T")[seed % 4]
    if motion in ("2T", "1R2T"):
        data = random_planar_data(rng, int(rng.integers(2, 6)) if motion == "2T" else int(rng.integers(3, 6)),
                                  motion)
        data["effector"]["center_of_mass"] = [float(v) for v in rng.uniform(-0.03, 0.03, 2)]
        if motion == "1R2T":
            data["workspace"]["orientation"] = [float(rng.uniform(-0.2, 0.2))]
    else:
        data = _spatial_data(rng, int(rng.integers(3, 6)) if motion == "3T" else int(rng.integers(6, 9)), motion)
    if seed % 8 >= 4:
        n = {"2T": 2, "1R2T": 3, "3T": 3, "3R3T": 6}[motion]
        data["workspace"]["external_wrench"] = {"lower": [float(-v) for v in rng.uniform(0, 1, n)],
                                                "upper": [float(v) for v in rng.uniform(0, 1, n)]}
    return data, rng


def _random_pose(design, rng):
    """A random position inside the frame (a tenth of it off each side) at the workspace's orientation."""
    lo, hi = np.array(design.frame_lower), np.array(design.frame_upper)
    p3 = np.zeros(3)
    p3[: lo.size] = rng.uniform(lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo))
    return kin.pose_at(design, p3, design.default_orientation_full())


def _problem(design, pose):
    """W (n, m), the tension bounds, the required wrenches at rest (K, n) (gravity and every vertex of
    the external box) and the mass matrix (n, ncoords), from the plain numpy kinematics."""
    W = kin.structure_matrix(design, pose)
    full = design.full_pose(pose)
    rows = [-kin.gravity_wrench(design, pose)]
    box = design.workspace.external_wrench
    if box is not None:
        rows = [rows[0] - np.array(v) for v in itertools.product(*zip(box.lower, box.upper))]
    return W, design.tension_min, design.tension_max, np.array(rows), kin.mass_matrix(design, full[3:])


def lp_reach(W, lo, hi, R, Mt, d, sense=-1.0):
    """The largest (sense -1) or least (+1) s with s d reachable for every required wrench of R:
    W t_k = Mt (s d) + R_k, lo <= t_k <= hi; None when no s is, +-inf when unbounded."""
    n, m = W.shape
    K = R.shape[0]
    c = np.zeros(1 + K * m)
    c[0] = sense
    A = np.zeros((K * n, 1 + K * m))
    b = np.zeros(K * n)
    for k in range(K):
        A[k * n:(k + 1) * n, 0] = -Mt @ d
        A[k * n:(k + 1) * n, 1 + k * m:1 + (k + 1) * m] = W
        b[k * n:(k + 1) * n] = R[k]
    bounds = [(None, None)] + [(lo[i % m], hi[i % m]) for i in range(K * m)]
    res = linprog(c, A_eq=A, b_eq=b, bounds=bounds, method="highs", options=HIGHS)
    if res.status == 2:
        return None
    if res.status == 3:
        return -sense * np.inf
    assert res.status == 0, res.message
    return float(res.x[0])


def lp_feasible(W, lo, hi, w) -> bool:
    """Whether some tensions lo <= t <= hi give W t = w."""
    res = linprog(np.zeros(W.shape[1]), A_eq=W, b_eq=w, bounds=list(zip(lo, hi)), method="highs", options=HIGHS)
    return res.status == 0


def _close(a, b, scale) -> bool:
    return abs(a - b) <= 1e-6 * max(abs(b), scale)


@pytest.mark.parametrize("seed", range(16))
def test_capability_matches_the_lp_on_random_robots(seed):
    design, rng = random_robot(seed)
    robot = resolve(design, Analysis(command="pose"))
    d = design.motion.dim
    lo_f, hi_f = np.array(design.frame_lower), np.array(design.frame_upper)
    checked = 0
    for _ in range(12):
        pose = _random_pose(design, rng)
        cap = capability(robot, pose)
        W, lo, hi, R, M = _problem(design, pose)
        Mt = M[:, :d]
        scale = float(np.abs(hi).max() / design.effector.mass) * 1e-3  # the accelerations' scale [m/s^2]
        at_rest = all(lp_feasible(W, lo, hi, r) for r in R)
        assert (cap.radius > 0) == at_rest or (at_rest and cap.radius < 1e-9 * scale * 1e3)
        for k in range(d):  # each axis: least and greatest, by the LP
            e = np.eye(d)[k]
            top, bottom = lp_reach(W, lo, hi, R, Mt, e, -1.0), lp_reach(W, lo, hi, R, Mt, e, 1.0)
            if top is None:
                assert np.isnan(cap.axes[k]).all()
                continue
            assert _close(cap.axes[k, 1], top, scale), (k, cap.axes[k], top, bottom)
            assert _close(cap.axes[k, 0], bottom, scale), (k, cap.axes[k], top, bottom)
        checked += 1
        if not at_rest:
            assert cap.radius == 0.0
            continue
        # the ball: every direction reaches at least the radius, and the direction of least reach exactly it
        for u in rng.normal(size=(24, d)):
            u /= np.linalg.norm(u)
            assert lp_reach(W, lo, hi, R, Mt, u) >= cap.radius * (1 - 1e-6) - 1e-9
        assert _close(lp_reach(W, lo, hi, R, Mt, cap.direction), cap.radius, scale)
    assert checked == 12


def test_some_random_robots_hold_and_some_do_not():
    """The random poses of the test above cover both cases (a test that cannot fail is a defect)."""
    held = free = 0
    for seed in range(16):
        design, rng = random_robot(seed)
        robot = resolve(design, Analysis(command="pose"))
        lo_f, hi_f = np.array(design.frame_lower), np.array(design.frame_upper)
        for _ in range(12):
            pose = _random_pose(design, rng)
            r = capability(robot, pose).radius
            held += r > 0
            free += r == 0
    assert held > 20 and free > 20


def design_planar(motion: str) -> bool:
    return motion in ("2T", "1R2T")


def _crossed_planar_data(rng) -> dict:
    """A random 1R2T robot of four crossed cables (outlets near the frame's corners, attachments at
    the effector's), which holds its orientation over much of the frame."""
    w, h = rng.uniform(1.0, 3.0), rng.uniform(1.0, 3.0)
    outlets = [(0, h), (w, h), (0, 0), (w, 0)]
    attach = [(0.1, 0.1), (-0.1, 0.1), (0.1, -0.1), (-0.1, -0.1)]
    cables = [{"name": f"k{i}", "outlet": [float(x + rng.uniform(-0.05, 0.05)), float(y + rng.uniform(-0.05, 0.05))],
               "attachment": [float(a), float(b)], "tension": [float(rng.uniform(0, 2)), float(rng.uniform(40, 80))]}
              for i, ((x, y), (a, b)) in enumerate(zip(outlets, attach))]
    return {"name": "crossed", "motion": "1R2T", "frame": {"lower": [0.0, 0.0], "upper": [w, h]},
            "effector": {"mass": float(rng.uniform(0.2, 2.0)), "size": [0.2, 0.2], "inertia": 0.01},
            "cables": cables, "workspace": {"grid": {"step": float(min(w, h) / 12)}}}


#: one robot of each motion, with and without an external wrench box (the rotational ones and those
#: with a box take thousands of linear programs: the slow tier)
SEEDS = (0, 2, *(pytest.param(seed, marks=pytest.mark.slow) for seed in (1, 3, 4, 5, 6, 7)))


@pytest.mark.parametrize("seed", SEEDS)
def test_dynamic_workspace_matches_the_lp_at_every_vertex(seed):
    from cdpr_design import workspaces as ws
    from cdpr_design.model.spec import from_dict

    rng0 = np.random.default_rng(seed)
    motion = ("2T", "1R2T", "3T", "3R3T")[seed % 4]
    if motion == "2T":
        data = random_planar_data(rng0, 3, motion)
    elif motion == "1R2T":
        data = _crossed_planar_data(rng0)
    else:
        data = _spatial_data(rng0, 4 if motion == "3T" else 8, motion)
    data["workspace"]["grid"]["step"] = float(min(data["frame"]["upper"]) / (12 if design_planar(motion) else 3))
    nc = len({"2T": "xy", "1R2T": "xyp", "3T": "xyz", "3R3T": "xyzabc"}[motion])
    dim = 2 if design_planar(motion) else 3
    # rotations: a small box in 1R2T, none in 3R3T (a flat box keeps its vertices few: 8, not 64)
    acc = [float(v) for v in rng0.uniform(0.2, 2.0, dim)] + [0.05 if motion == "1R2T" else 0.0] * (nc - dim)
    data["requirements"] = {"acceleration": {"lower": [-a for a in acc], "upper": acc}}
    if seed % 2:  # forces only (no moments: fewer vertices)
        n = {"2T": 2, "1R2T": 3, "3T": 3, "3R3T": 6}[motion]
        data["workspace"]["external_wrench"] = {"lower": [-0.3] * dim + [0.0] * (n - dim),
                                                "upper": [0.3] * dim + [0.0] * (n - dim)}
    design = from_dict(data)
    rows = []
    res = ws.run(design, ws.Analysis(kind="dynamic"), on_chunk=rows.append, tilt=False)
    poses = np.vstack([c.poses for c in rows])
    feas = np.concatenate([c.feasible for c in rows]).astype(bool)
    margin = np.concatenate([c.margin for c in rows])
    accs = [np.array(v) for v in itertools.product(*zip([-a for a in acc], acc))]
    agree = near = 0
    for pose, f, mg in zip(poses, feas, margin):
        W, lo, hi, R, M = _problem(design, pose)
        # at rest under gravity alone, and every vertex of the external box plus every acceleration's
        lp = lp_feasible(W, lo, hi, -kin.gravity_wrench(design, pose)) and all(
            lp_feasible(W, lo, hi, r + M @ a) for r in R for a in accs)
        if np.isfinite(mg) and abs(mg) < 1e-7:
            near += 1  # on the boundary: either answer is the LP's within its tolerance
            continue
        assert bool(f) == lp, (pose, f, lp, mg)
        agree += 1
    assert res.poses == poses.shape[0] and near <= poses.shape[0] // 50
    assert 0 < feas.sum() < feas.size, "the grid crosses the dynamic workspace's boundary"


@pytest.mark.parametrize("seed", [2, 3, 6, 7])
@pytest.mark.parametrize("kind,box", [("static", "around zero"), ("wrench-feasible", "around zero"),
                                      ("static", "off zero"), ("wrench-feasible", "off zero")])
def test_the_sweeps_radius_is_every_poses_capability(seed, kind, box):
    """workspace --accelerations: the column is the capability at each grid pose (its kernel, pose by
    pose), the poses the sweep's margin finds not held included (0 there: a box about the zero
    wrench, or the nominal wrench alone, is held at none of its wrenches) and a box that leaves the
    zero wrench out (the sweep's margin then decides nothing)."""
    from cdpr_design import workspaces as ws
    from cdpr_design.statics import acceleration as acc

    data, rng = random_data(seed)
    n = {"2T": 2, "1R2T": 3, "3T": 3, "3R3T": 6}[data["motion"]]
    lower = rng.uniform(-0.3, 0.0, n) + (0.0 if box == "around zero" else 0.4)
    data["workspace"]["external_wrench"] = {"lower": [float(v) for v in lower],
                                            "upper": [float(v) for v in lower + rng.uniform(0.3, 0.6, n)]}
    design = spec.from_dict(data)
    dim = design.motion.dim
    chunks = []
    ws.run(design, ws.Analysis(kind=kind, accelerations=True), tilt=False, on_chunk=chunks.append)
    radius = np.concatenate([c.extra["acceleration_radius"] for c in chunks])
    margin = np.concatenate([c.margin for c in chunks])
    poses = np.vstack([c.poses for c in chunks])
    robot = resolve(design, Analysis(accelerations=True))
    want = acc.at_positions(robot, acc.loads(robot, design.default_orientation_full()),
                            np.pad(poses[:, :dim], ((0, 0), (0, 3 - dim))))[0]
    np.testing.assert_array_equal(radius, want)
    assert (margin < 0).any() and (want > 0).any()


# ----------------------------------------------------------------------------
# The command line
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("key,value,names", [
    ("lower", [-1.0], "requirements.acceleration.lower"),
    ("upper", [1.0, 1.0, 1.0], "requirements.acceleration.upper"),
    ("upper", [1.0, float("nan")], "requirements.acceleration.upper"),
    ("upper", [1.0, float("inf")], "requirements.acceleration.upper"),
    ("upper", [-2.0, 1.0], "requirements.acceleration.upper[0]"),
])
def test_a_bad_acceleration_box_is_exit_2_naming_the_key(tmp_path, key, value, names):
    raw = planar2_raw()
    raw["requirements"]["acceleration"] = {"lower": [-1.0, -1.0], "upper": [1.0, 1.0]}
    raw["requirements"]["acceleration"][key] = value
    r = invoke("workspace", write_spec(tmp_path, raw), "--kind", "dynamic", "--out", tmp_path / "out")
    assert r.exit_code == 2 and names in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert not (tmp_path / "out").exists()


def test_dynamic_without_the_box_is_exit_2_naming_it(tmp_path):
    r = invoke("workspace", write_spec(tmp_path, planar2_raw()), "--kind", "dynamic", "--out", tmp_path / "out")
    assert r.exit_code == 2 and r.stderr.startswith("error: requirements.acceleration: --kind dynamic"), r.stderr


def test_accelerations_column_is_the_pose_and_the_margin_over_the_mass(tmp_path):
    """planar2's effector is a point mass at the platform origin (M_t = m I): the radius is the capacity
    margin over the mass wherever the pose is held, 0 elsewhere; the rows are pose --json's, and the
    summary's extremes are the column's over the feasible rows."""
    import csv

    out = tmp_path / "out"
    r = invoke("workspace", "designs/planar2.yaml", "--accelerations", "--step", "0.05", "--out", out, "--json")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    rows = list(csv.DictReader((out / "workspace.csv").open()))
    assert rows and (out / "acceleration_map.png").stat().st_size > 0
    radius = np.array([float(x["acceleration_radius"]) for x in rows])
    margin = np.array([float(x["margin"]) if x["margin"] else np.nan for x in rows])
    feas = np.array([x["feasible"] == "1" for x in rows])
    np.testing.assert_allclose(radius[feas], margin[feas] / 1.0, rtol=1e-9, atol=1e-9)
    assert np.all(radius[margin < 0] == 0.0)
    assert s["min_acceleration_radius"] == pytest.approx(radius[feas].min())
    assert s["max_acceleration_radius"] == pytest.approx(radius[feas].max())
    for i in (int(np.argmax(radius)), len(rows) // 3):
        at = f"{rows[i]['x']},{rows[i]['y']}"
        p = json.loads(invoke("pose", "designs/planar2.yaml", "--at", at, "--json").stdout)
        assert p["acceleration_radius"] == pytest.approx(radius[i], rel=1e-9, abs=1e-9)  # the CSV has 10 digits


def test_check_on_sagging_cables_names_the_requirement(tmp_path):
    """A design whose accelerations are not modelled (sagging cables) and asks for them by
    requirements.min_acceleration: check refuses naming the requirement, not workspace's
    --accelerations option; the workspace command names its option."""
    raw = yaml.safe_load((DESIGNS / "sagging40.yaml").read_text())
    raw["requirements"] = {"task_box": {"lower": [15.0, 5.0], "upper": [25.0, 10.0]}, "min_acceleration": 1.0}
    spec_path = write_spec(tmp_path, raw)
    r = invoke("check", spec_path)
    assert r.exit_code == 2 and "Traceback" not in r.stderr, r.output
    assert r.stderr.startswith("error: requirements.min_acceleration: sagging cables"), r.stderr
    assert "--accelerations" not in r.stderr
    r = invoke("workspace", spec_path, "--accelerations", "--out", tmp_path / "w")
    assert r.exit_code == 2 and r.stderr.startswith("error: --accelerations: sagging cables"), r.stderr
    # with straight cables the requirement is checked
    r = invoke("check", spec_path, "--cable-model", "elastic", "--json")
    assert r.exit_code in (0, 1) and json.loads(r.stdout)["figures"]["task_min_acceleration"] is not None, r.output


def test_check_min_acceleration(tmp_path):
    raw = planar2_raw()
    raw["winch"].pop("motor")  # the motors check apart
    raw["requirements"].pop("max_speed")
    raw["requirements"].pop("max_acceleration")
    for need, code in ((2.0, 0), (50.0, 1)):
        raw["requirements"]["min_acceleration"] = need
        r = invoke("check", write_spec(tmp_path, raw), "--json")
        assert r.exit_code == code, r.output
        row = json.loads(r.stdout)["figures"]
        # the task box's least margin over the unit mass (a point mass, as above)
        assert row["task_min_acceleration"] == pytest.approx(row["task_min_margin"], rel=1e-9)
        assert row["check_min_acceleration"] is (code == 0)
