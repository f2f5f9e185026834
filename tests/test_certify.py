"""Certified workspaces (workspaces/certify.py): an exact closed-form region, and random robots
checked by an independent LP at random points of the proven boxes."""

from __future__ import annotations

import itertools
import zlib

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import linprog

from cdpr_design.errors import InputError
from cdpr_design.model import spec
from cdpr_design.api import certify

G = 9.81


def two_outlet_point_mass(D=2.0, H=1.5, mass=1.0, tmax=30.0, step=0.05):
    return spec.from_dict({
        "name": "pm2", "motion": "2T", "gravity": [0.0, -G],
        "frame": {"lower": [0.0, 0.0], "upper": [D, H]},
        "effector": {"mass": mass, "size": [0.01, 0.01]}, "tension": [0.0, tmax],
        "cables": [{"name": "c1", "outlet": [0.0, H], "attachment": [0.0, 0.0]},
                   {"name": "c2", "outlet": [D, H], "attachment": [0.0, 0.0]}],
        "workspace": {"grid": {"lower": [0.0, 0.0], "upper": [D, H], "step": step}}})


def exact_area(D=2.0, H=1.5, mass=1.0, tmax=30.0) -> float:
    """The area of {y <= H - h_min(x)} in [0, D] x [0, H] (docs/algorithms.md): the cables'
    common horizontal tension component is h = m g x (D - x) / (D (H - y)), so t_1 = h L_1 / x,
    t_2 = h L_2 / (D - x), and t_i <= t_max holds for H - y >= h_min(x) =
    m g x (D - x) / sqrt((t_max D)^2 - (m g max(x, D - x))^2)."""
    w = mass * G

    def h_min(x):
        return w * x * (D - x) / np.sqrt((tmax * D) ** 2 - (w * max(x, D - x)) ** 2)

    val, err = quad(lambda x: max(0.0, H - h_min(x)), 0.0, D, points=[D / 2], epsabs=1e-13, limit=200)
    assert err < 1e-10
    return val


def test_closed_form_region_lies_between_inner_and_outer_and_the_boundary_shrinks():
    d = two_outlet_point_mass()
    exact = exact_area()
    assert 1.0 < exact < 3.0
    boundaries = []
    for res in (0.04, 0.02, 0.01, 0.005, 0.0025):
        s = certify(d, resolution=res).summary()
        assert s["inner_measure"] <= exact <= s["outer_measure"], (res, s)
        assert s["outer_measure"] == pytest.approx(s["inner_measure"] + s["boundary_measure"])
        boundaries.append(s["boundary_measure"])
    assert all(b2 < 0.7 * b1 for b1, b2 in zip(boundaries, boundaries[1:])), boundaries
    assert boundaries[-1] < 0.005 * exact


def test_boxes_tile_the_box_exactly():
    r = certify(two_outlet_point_mass(), resolution=0.02)
    total = float(np.prod(r.upper - r.lower, axis=1).sum())
    assert total == pytest.approx(2.0 * 1.5, rel=1e-12)
    assert np.all(r.lower >= [0, 0]) and np.all(r.upper <= [2.0, 1.5])
    assert np.all(np.max(r.upper - r.lower, axis=1)[r.status == 0] <= 0.02)


# --- random robots against an independent LP ----------------------------------------------------

def random_robot(rng, motion, m, external=False):
    d = 2 if motion in ("2T", "1R2T") else 3
    outlets = rng.uniform(-2, 2, (m, d))
    outlets[:, d - 1] = rng.uniform(0.3, 2.0, m)  # mostly above: gravity pulls down the last axis
    attach = rng.uniform(-0.15, 0.15, (m, d)) if motion in ("1R2T", "3R3T") else np.zeros((m, d))
    if motion == "3R3T":  # random ones hold almost nowhere: a perturbed IPAnema-like layout instead
        corners = np.array(list(itertools.product((-1, 1), (-1, 1), (-1, 1))), float)[rng.permutation(8)[:m]]
        outlets = corners * [2.0, 2.0, 1.0] + [0, 0, 1.0] + rng.normal(0, 0.2, (m, 3))
        attach = corners[:, [1, 0, 2]] * 0.15 + rng.normal(0, 0.03, (m, 3))
    cables = [{"name": f"c{i}", "outlet": outlets[i].tolist(), "attachment": attach[i].tolist()}
              for i in range(m)]
    n = {"2T": 2, "1R2T": 3, "3T": 3, "3R3T": 6}[motion]
    ws = {"grid": {"lower": [-1.0] * (d - 1) + [-0.6], "upper": [1.0] * (d - 1) + [1.4], "step": 0.1}}
    if motion == "3R3T":
        ws = {"grid": {"lower": [-0.6, -0.6, 0.2], "upper": [0.6, 0.6, 1.4], "step": 0.1}}
    if external:
        ws["external_wrench"] = {"lower": [-2.0] + [0.0] * (n - 1), "upper": [2.0] + [1.0] + [0.0] * (n - 2)}
    return spec.from_dict({
        "name": "r", "motion": motion, "frame": {"lower": [-2.0] * d, "upper": [2.0] * d},
        "effector": {"mass": float(rng.uniform(0.5, 3.0)), "size": [0.2] * d,
                     "center_of_mass": (rng.uniform(-0.03, 0.03, d) if n > d else np.zeros(d)).tolist()},
        "tension": [float(rng.choice([0.0, 1.0])), float(rng.uniform(40, 120) * (3 if n == 6 else 1))],
        "cables": cables,
        "workspace": ws})


def lp_feasible(design, position, wrenches, R=np.eye(3)) -> bool:
    """W t = w for every w, t in the bounds (scipy HiGHS), W built here from the spec's points at
    the orientation ``R`` (3, 3) (default zero)."""
    d = design.motion.dim
    p = np.zeros(3)
    p[:d] = position
    A, B = design.outlets, design.attachments @ R.T
    cols = []
    for a, b in zip(A, B):
        v = a - p - b
        u = v / np.linalg.norm(v)
        cols.append(np.concatenate([u, np.cross(b, u)])[list(design.motion.wrench_rows)])
    W = np.array(cols).T
    for w in wrenches:
        r = linprog(np.zeros(design.m), A_eq=W, b_eq=w,
                    bounds=list(zip(design.tension_min, design.tension_max)), method="highs",
                    options={"primal_feasibility_tolerance": 1e-9})
        assert r.status in (0, 2), r.message
        if r.status != 0:
            return False
    return True


def required_wrenches(design, kind, R=np.eye(3)):
    rows = list(design.motion.wrench_rows)
    f = design.effector.mass * np.asarray(design.gravity)
    c = R[:len(design.effector.center_of_mass), :len(design.effector.center_of_mass)] @ np.asarray(
        design.effector.center_of_mass)
    g = np.concatenate([f, np.cross(c, f)])[rows]
    out = [-g]
    box = design.workspace.external_wrench
    if kind == "wrench-feasible" and box is not None:
        out = [-(g + np.asarray(v)) for v in itertools.product(*zip(box.lower, box.upper))]
    return out


CASES = ([("2T", m, "static") for m in range(2, 9)] + [("3T", m, "static") for m in range(3, 9)]
         + [("1R2T", 4, "static"), ("1R2T", 5, "static"), ("3R3T", 7, "static"), ("3R3T", 8, "static"),
            ("2T", 3, "wrench-feasible"), ("3T", 4, "wrench-feasible")])


@pytest.mark.slow
@pytest.mark.parametrize("motion,m,kind", CASES)
def test_random_robots_never_contradict_an_lp(motion, m, kind):
    seed = zlib.crc32(f"{motion} {m} {kind}".encode())
    robots, rng = np.random.default_rng(seed), np.random.default_rng(seed + 1)
    seen = {1: 0, -1: 0}
    for _ in range(4):
        d = random_robot(robots, motion, m, external=kind == "wrench-feasible")
        res = 0.05 if d.motion.planar else 0.1
        r = certify(d, kind=kind, resolution=res, max_boxes=20_000)
        wrenches = required_wrenches(d, kind)
        for code, expect in ((1, True), (-1, False)):
            idx = np.flatnonzero(r.status == code)
            for k in rng.choice(idx, min(idx.size, 60), replace=False) if idx.size else []:
                for _ in range(2):
                    x = rng.uniform(r.lower[k], r.upper[k])
                    assert lp_feasible(d, x, wrenches) == expect, (code, x, r.lower[k], r.upper[k])
                    seen[code] += 1
    if motion == "3R3T":  # random 6-DOF robots hold in thin regions: some boxes decided, of either kind
        assert seen[1] + seen[-1] > 0
    else:  # every other case proves some boxes outside and some inside
        assert seen[-1] > 0 and seen[1] > 0


def test_min_margin_is_proven_against_the_pose_margin():
    import cdpr_design as cd

    rng = np.random.default_rng(11)
    d = random_robot(rng, "2T", 4)
    mu = 3.0
    r = certify(d, resolution=0.05, min_margin=mu)
    plain = certify(d, resolution=0.05)
    assert 0 < r.measure(1) < plain.measure(1)
    for code in (1, -1):
        for k in np.flatnonzero(r.status == code)[:80]:
            x = rng.uniform(r.lower[k], r.upper[k])
            margin = cd.pose(d, x).margin
            assert (margin >= mu) if code == 1 else not (margin >= mu), (code, x, margin)


def test_unsupported_models_are_refused_with_the_reason():
    import cdpr_design as cd

    d = two_outlet_point_mass()
    with pytest.raises(InputError, match="sagging"):
        certify(cd.load("designs/sagging40.yaml"))
    with pytest.raises(InputError, match="--kind"):
        certify(d, kind="wrench-closure")
    with pytest.raises(InputError, match="--resolution"):
        certify(d, resolution=0.0)


# --- the command ----------------------------------------------------------------------------------

def _cli(*args, cwd=None):
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ, PYTHONPATH=str(root), CDPR_DESIGN_PICTURE_WORKER="0")
    return subprocess.run([sys.executable, "-m", "cdpr_design", *args], capture_output=True, text=True,
                          cwd=cwd or root, env=env, timeout=600)


def test_command_writes_boxes_picture_and_summary(tmp_path):
    import json

    import pyarrow.parquet as pq

    r = _cli("certify", "designs/planar2.yaml", "--resolution", "0.01", "--out", str(tmp_path), "--json",
             "--format", "parquet")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s == json.loads((tmp_path / "summary.json").read_text())
    assert s["outer_measure"] == pytest.approx(s["inner_measure"] + s["boundary_measure"])
    assert s["unit"] == "m^2" and set(s["counts"]) == {"inside", "outside", "boundary"}
    t = pq.read_table(tmp_path / "boxes.parquet")
    assert t.column_names == ["lower_x", "upper_x", "lower_y", "upper_y", "status"]
    assert t.num_rows == sum(s["counts"].values())
    assert (tmp_path / "certify.png").stat().st_size > 10_000
    import cdpr_design as cd

    api = cd.certify(cd.load("designs/planar2.yaml"), resolution=0.01).summary()
    assert api["inner_measure"] == s["inner_measure"] and api["counts"] == s["counts"]


def test_command_refuses_unsupported_models_with_exit_2(tmp_path):
    r = _cli("certify", "designs/sagging40.yaml", "--out", str(tmp_path))
    assert r.returncode == 2 and "sagging" in r.stderr and "Traceback" not in r.stderr
    r = _cli("certify", "designs/crane4.yaml", "--out", str(tmp_path))
    assert r.returncode == 2 and "free" in r.stderr
    r = _cli("certify", "designs/planar2.yaml", "--resolution", "-1", "--out", str(tmp_path))
    assert r.returncode == 2 and "--resolution" in r.stderr


def test_check_certifies_the_task_box_and_names_what_it_could_not_prove(tmp_path):
    import json

    import yaml

    raw = yaml.safe_load(open("designs/planar2.yaml"))
    raw["requirements"] = {"task_box": {"lower": [0.45, 0.6], "upper": [1.05, 1.1]}, "certified": True}
    good = tmp_path / "good.yaml"
    good.write_text(yaml.safe_dump(raw))
    r = _cli("check", str(good), "--json")  # (planar2's motors fail their torque check: exit 1 either way)
    row = [c for c in json.loads(r.stdout)["checks"] if c["requirement"] == "certified"][0]
    assert row["passed"]
    raw.pop("winch")
    raw.pop("cable")
    good.write_text(yaml.safe_dump(raw))
    r = _cli("check", str(good))
    assert r.returncode == 0, r.stdout + r.stderr
    raw["requirements"] = {"task_box": {"lower": [0.45, 0.6], "upper": [1.05, 1.4]}}  # above the 20 N limit
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(raw))
    assert "certified" not in _cli("check", str(bad)).stdout  # without --certify nothing is proven
    r = _cli("check", str(bad), "--certify")
    assert r.returncode == 1
    assert "could not prove the box" in r.stderr and "infeasible" in r.stderr
    r = _cli("check", str(bad), "--certify", "--json")
    row = [c for c in json.loads(r.stdout)["checks"] if c["requirement"] == "certified"][0]
    assert not row["passed"] and row["unproven_box"]["status"] == "outside"
    assert row["witness"]["feasible"] is False and row["unproven_box"]["lower"][1] > 1.2


def test_tolerances_shrink_the_inner_measure_and_hold_for_every_geometry_within_them():
    rng = np.random.default_rng(5)
    d = random_robot(rng, "2T", 4)
    inner = [certify(d, resolution=0.05, tolerance_outlets=tol, tolerance_attachments=tol).measure(1)
             for tol in (0.0, 0.01, 0.03, 0.06)]
    assert all(b < a for a, b in zip(inner, inner[1:])) and inner[-1] > 0, inner
    tol = 0.03
    r = certify(d, resolution=0.05, tolerance_outlets=tol, tolerance_attachments=tol)
    idx = np.flatnonzero(r.status == 1)
    for k in rng.choice(idx, 150, replace=False):
        raw = {**d.raw, "cables": [dict(c) for c in d.raw["cables"]]}
        for c in raw["cables"]:  # a geometry within the tolerance (in the plane)
            c["outlet"] = (np.asarray(c["outlet"]) + rng.uniform(-tol, tol, 2)).tolist()
            c["attachment"] = (np.asarray(c["attachment"]) + rng.uniform(-tol, tol, 2)).tolist()
        built = spec.from_dict(raw)
        x = rng.uniform(r.lower[k], r.upper[k])
        assert lp_feasible(built, x, required_wrenches(built, "static")), (x, raw["cables"])


@pytest.mark.slow
@pytest.mark.parametrize("motion,m", [("1R2T", 4), ("3R3T", 8)])
def test_tolerances_of_rotational_robots_hold_for_every_geometry_within_them(motion, m):
    """Robots whose attachments carry moments: at random points of the boxes proven inside (outside)
    with tolerances, random geometries within them are feasible (infeasible) by the LP."""
    import cdpr_design as cd
    from cdpr_design.statics.kinematics import rotation_matrix

    seed = zlib.crc32(f"tolerance {motion} {m}".encode())
    robots, rng = np.random.default_rng(seed), np.random.default_rng(seed + 1)
    if motion == "3R3T":  # random 6-DOF robots hold in thin regions: IPAnema 2, at its orientation
        designs, tol, res = [cd.load("designs/ipanema2.yaml")], 0.001, 0.2
    else:
        designs, tol, res = [random_robot(robots, motion, m) for _ in range(3)], 0.003, 0.05
    seen = {1: 0, -1: 0}
    for d in designs:
        r = certify(d, resolution=res, tolerance_outlets=tol, tolerance_attachments=tol, max_boxes=100_000)
        dim = d.motion.dim
        for code, expect in ((1, True), (-1, False)):
            idx = np.flatnonzero(r.status == code)
            for k in rng.choice(idx, min(idx.size, 40), replace=False) if idx.size else []:
                raw = {**d.raw, "cables": [dict(c) for c in d.raw["cables"]]}
                for c in raw["cables"]:  # a geometry within the tolerance (orientation zero: R = I)
                    c["outlet"] = (np.asarray(c["outlet"]) + rng.uniform(-tol, tol, dim)).tolist()
                    c["attachment"] = (np.asarray(c["attachment"]) + rng.uniform(-tol, tol, dim)).tolist()
                built = spec.from_dict(raw)
                x = rng.uniform(r.lower[k], r.upper[k])
                R = rotation_matrix(*d.default_orientation_full())
                assert lp_feasible(built, x, required_wrenches(built, "static", R), R) == expect, (code, x)
                seen[code] += 1
    assert seen[1] > 0 and seen[-1] > 0, seen


@pytest.mark.slow
def test_millimetre_tolerances_keep_most_of_ipanema2s_proven_interior():
    """A millimetre of manufacturing error on a robot with a 4 m frame keeps most of what is
    proven inside without it: the enclosure in the tolerance variables is centred, not taken
    over whole tolerance boxes (an enclosure of the structure matrix over the boxes lost three
    quarters of the inner volume at 1 mm and all of it at 2 mm, at a 0.2 m resolution)."""
    import cdpr_design as cd

    d = cd.load("designs/ipanema2.yaml")
    inner = {tol: certify(d, resolution=0.2, tolerance_outlets=tol, tolerance_attachments=tol).measure(1)
             for tol in (0.0, 0.001, 0.002)}
    assert inner[0.0] > 0.0
    assert inner[0.001] >= 0.5 * inner[0.0], inner
    assert inner[0.002] >= 0.25 * inner[0.0], inner
    assert inner[0.0] >= inner[0.001] >= inner[0.002], inner


def test_spec_tolerance_is_taken_and_checked(tmp_path):
    from cdpr_design.errors import SpecError

    rng = np.random.default_rng(5)
    d = random_robot(rng, "2T", 4)
    api = certify(d, resolution=0.05, tolerance_outlets=0.01, tolerance_attachments=[0.0, 0.01, 0.0, 0.01])
    tol = spec.from_dict({**d.raw, "tolerance": {"outlets": 0.01, "attachments": [0.0, 0.01, 0.0, 0.01]}})
    s = certify(tol, resolution=0.05).summary()
    assert s["inner_measure"] == api.summary()["inner_measure"] < certify(d, resolution=0.05).measure(1)
    assert s["tolerance"] == {"outlets": 0.01, "attachments": [0.0, 0.01, 0.0, 0.01]}
    with pytest.raises(SpecError, match="tolerance.outlets"):
        spec.from_dict({**d.raw, "tolerance": {"outlets": [0.01, 0.02]}})
    with pytest.raises(SpecError, match="tolerance"):
        spec.from_dict({**d.raw, "tolerance": -0.01})


def test_the_paving_does_not_depend_on_the_thread_count():
    from cdpr_design.kernels import parallel

    d = random_robot(np.random.default_rng(8), "3T", 5)
    runs = []
    for n in (1, 2, 3):
        with parallel.threads_kept():
            parallel.set_threads(n)
            runs.append(certify(d, resolution=0.1))
    for r in runs[1:]:
        assert np.array_equal(r.lower, runs[0].lower) and np.array_equal(r.upper, runs[0].upper)
        assert np.array_equal(r.status, runs[0].status)


@pytest.mark.parametrize("upper_y", [1.3, None])
def test_command_on_a_flat_or_single_point_box_prints_its_table(tmp_path, upper_y):
    """A grid box flat in y (lower = upper, which the spec allows), or a single point: the table
    gives the boundary's share of the box over the axes it has (was: ZeroDivisionError)."""
    import json

    import yaml

    raw = yaml.safe_load(open("designs/planar2.yaml"))
    raw["workspace"]["grid"] = ({"lower": [0.0, 1.3], "upper": [1.5, 1.3], "step": 0.05} if upper_y else
                                {"lower": [0.75, 0.8], "upper": [0.75, 0.8], "step": 0.05})
    p = tmp_path / "flat.yaml"
    p.write_text(yaml.safe_dump(raw))
    r = _cli("certify", str(p), "--resolution", "0.01", "--out", str(tmp_path / "o"))
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert "% of the box" in r.stdout
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    if upper_y:  # a segment: the shares are of its length
        assert s["box_measure"] == 0 and s["inner_fraction"] + s["boundary_fraction"] <= 1 + 1e-12
        assert 0 < s["inner_fraction"] < 1 and s["counts"]["outside"] > 0
    else:  # the point (0.75, 0.8) is inside planar2's workspace: all of it is proven
        assert s["counts"] == {"inside": 1, "outside": 0, "boundary": 0} and s["inner_fraction"] == 1


def test_check_of_a_single_point_task_box_says_all_of_it_is_proven(tmp_path):
    import json

    import yaml

    raw = yaml.safe_load(open("designs/planar2.yaml"))
    raw["requirements"] = {"task_box": {"lower": [0.75, 0.8], "upper": [0.75, 0.8]}, "certified": True}
    p = tmp_path / "point.yaml"
    p.write_text(yaml.safe_dump(raw))
    r = _cli("check", str(p), "--json")
    row = [c for c in json.loads(r.stdout)["checks"] if c["requirement"] == "certified"][0]
    assert row["passed"] and row["figure"].startswith("100 % proven (1 inside"), row  # was "0 % proven"


def test_a_resolution_below_the_floating_point_spacing_stops_at_boxes_it_cannot_halve():
    """A segment across planar2's workspace at --resolution 1e-300: each end of it is bisected
    down to boxes one or two units in the last place wide, and no further (was: zero-width boxes
    until the box cap)."""
    import cdpr_design as cd

    r = cd.certify(cd.load("designs/planar2.yaml"), resolution=1e-300, box=((0.0, 0.8), (1.5, 0.8)),
                   max_boxes=20_000)
    assert r.truncated is None and r.unsplit >= 2 and r.summary()["unsplit_boxes"] == r.unsplit
    width = (r.upper - r.lower)[:, 0]
    assert np.all(width > 0) and r.status.size < 20_000
    assert np.all(width[r.status == 0] <= 4 * np.spacing(np.maximum(np.abs(r.lower[:, 0]), np.abs(r.upper[:, 0])))[r.status == 0])
