"""The hanging effector end to end: spec keys, workspace, pose and fk on the command line.

- ``effector.orientation: fixed`` (the default) leaves every existing output as it was:
  the same rows as the plain engine, the same ``pose`` keys and values, the paper's closed
  form from ``fk`` wherever both cables pull;
- a fully constrained design gives the same answers under ``fixed`` and ``free``;
- ``free`` judges the workspace at the hanging orientation (the same rows as ``pose --at``
  at each position), ``--max-tilt`` and ``requirements.max_tilt`` cut larger tilts;
- bad input (impossible, negative or miscounted lengths, a tilt limit where none applies,
  analyses the hanging model does not cover) exits 2 naming the option or key.
"""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest

from cdpr_design import workspaces as ws
from cdpr_design.model import spec
from cdpr_design.statics import hanging as H
from cdpr_design.statics import kinematics as kin
from cdpr_design import api
from cdpr_design.statics.robot import Analysis, resolve
from cdpr_design.workspaces.engine import StraightSweep
from cdpr_design.workspaces.plan import Plan
from tests.reference import hanging_kernel as K


def straight_sweep(design, kind, g, ori, on_chunk=None, chunk=1000):
    """The plain straight-cable sweep alone: the plan's base evaluator without any wrapper."""
    robot = resolve(design, Analysis(kind=kind))
    return Plan(robot, g, ori, StraightSweep(robot, ori, g)).run(on_chunk, chunk=chunk)
from tests.helpers import DESIGNS, PLANAR2, collect_chunks, invoke, planar2_raw, planar4_cables, read_csv, write_spec

POINTMASS3 = DESIGNS / "pointmass3.yaml"
CRANE4 = DESIGNS / "crane4.yaml"


def free_planar2(tmp_path, **req):
    data = planar2_raw()
    data["name"] = "planar2free"
    data["effector"]["orientation"] = "free"
    if req:
        data["requirements"] = {**data.get("requirements", {}), **req}
    return write_spec(tmp_path, data, "free.yaml")


def with_orientation(d, mode):
    return d.replace(effector=dataclasses.replace(d.effector, orientation=mode))


def csv_numbers(values) -> str:
    return ",".join(repr(float(v)) for v in values)


def stacked(chunks, name):
    return np.concatenate([getattr(c, name) for c in chunks])


# ---------------------------------------------------------------------------
# fixed: unchanged
# ---------------------------------------------------------------------------

def test_fixed_workspace_rows_are_the_plain_engines(planar2):
    """planar2 (under-constrained, fixed): every contract column bit-identical to the plain
    sweep's, the summary's existing keys unchanged; the tilt columns come on top."""
    res, chunks = collect_chunks(ws.run, planar2, step=0.02, chunk=1000)
    g = ws.make_grid(planar2, 0.02)
    ref, ref_chunks = collect_chunks(straight_sweep, planar2, "static", g, np.zeros(3), chunk=1000)
    for name in ("poses", "feasible", "margin", "tensions", "lengths"):
        np.testing.assert_array_equal(stacked(chunks, name), stacked(ref_chunks, name))
    s, r = res.summary(), ref.summary()
    assert {k: v for k, v in s.items() if k in r and k != "elapsed_s"} == {k: v for k, v in r.items() if k != "elapsed_s"}
    assert set(s) - set(r) == {"effector_orientation", "underconstrained", "hangs", "max_tilt", "max_tilt_hanging"}
    assert list(chunks[0].extra) == ["tilt", "orientation_phi"]
    P = np.concatenate([c.poses for c in chunks])
    phi, _, _, status, _ = K.hanging_tilt_batch(planar2.outlets, planar2.attachments,
                                                np.zeros(3), 1.0, np.asarray(planar2.gravity), P)
    tilt = np.concatenate([c.extra["tilt"] for c in chunks])
    np.testing.assert_allclose(tilt, np.where(status == 0, np.degrees(np.abs(phi)), np.nan), atol=1e-12)


@pytest.mark.slow
def test_an_underconstrained_design_without_a_hanging_solve_is_still_classified(tmp_path):
    """cli.md: an under-constrained design's summary has effector_orientation and
    underconstrained, also where there is no hanging solve (sagging cables, a weightless
    effector): then without the tilt keys.  A fully constrained design has neither."""
    data = planar2_raw()
    data["effector"]["mass"] = 0.0
    for path in (DESIGNS / "sagging40.yaml", write_spec(tmp_path, data, "weightless.yaml")):
        s = json.loads(invoke("workspace", path, "--step", "1.0" if "sagging" in path.name else "0.1",
                              "--out", tmp_path / path.stem, "--json").stdout)
        assert s["effector_orientation"] == "fixed" and s["underconstrained"] is True, path
        assert "hangs" not in s and "max_tilt" not in s, path
        res = invoke("workspace", path, "--step", "1.0" if "sagging" in path.name else "0.1",
                     "--out", tmp_path / path.stem, "--overwrite")
        assert res.exit_code == 0 and "effector orientation" in res.output and "hangs at" not in res.output
    s = json.loads(invoke("workspace", DESIGNS / "ipanema1.yaml", "--step", "0.5", "--out", tmp_path / "i",
                          "--json").stdout)
    assert "underconstrained" not in s and "effector_orientation" not in s


def test_without_tilt_a_held_design_is_the_plain_sweep_and_a_free_one_still_hangs(tmp_path, planar2):
    """``run(tilt=False)`` (what the evaluation and the sizing envelope use): a held design's
    sweep without the hanging solve -- the same rows and summary as the plain engines, no tilt --
    while a ``free`` design is still swept at its hanging orientation (its statics need it)."""
    res, chunks = collect_chunks(ws.run, planar2, step=0.02, chunk=1000, tilt=False)
    g = ws.make_grid(planar2, 0.02)
    ref, ref_chunks = collect_chunks(straight_sweep, planar2, "static", g, np.zeros(3), chunk=1000)
    for name in ("poses", "feasible", "margin", "tensions", "lengths"):
        np.testing.assert_array_equal(stacked(chunks, name), stacked(ref_chunks, name))
    assert res.hanging is None and not chunks[0].extra and "max_tilt" not in res.summary()
    free = spec.load(free_planar2(tmp_path))
    a, b = ws.run(free, step=0.05), ws.run(free, step=0.05, tilt=False)
    assert b.hanging is not None and b.summary()["max_tilt"] == a.summary()["max_tilt"]
    assert (b.feasible, b.min_margin) == (a.feasible, a.min_margin)


def test_fixed_pose_and_fk_unchanged(planar2):
    res = invoke("pose", PLANAR2, "--at", "0.3,0.5", "--json")
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    p = api.pose(planar2, [0.3, 0.5])
    assert data["feasible"] is True and data["margin"] == p.margin
    assert list(data["tensions"].values()) == list(p.tensions) and list(data["lengths"].values()) == list(p.lengths)
    assert data["tilt"] == pytest.approx(22.287, abs=1e-3) and data["hanging"]["feasible"]
    rng = np.random.default_rng(1)
    for _ in range(5):
        q = [rng.uniform(0.2, 1.3), rng.uniform(0.2, 1.2)]
        L = kin.inverse_kinematics(planar2, q)
        f = json.loads(invoke("fk", PLANAR2, "--lengths", csv_numbers(L), "--json").stdout)
        np.testing.assert_allclose(f["pose"], kin.forward_kinematics(planar2, L).pose, atol=1e-12)
        assert f["orientation"] == 0.0 and f["slack"] == [] and f["model"] == "held"


@pytest.mark.slow
def test_fixed_fk_with_pulleys_is_the_kinematic_solve(tmp_path):
    data = planar2_raw()
    for c, ax in zip(data["cables"], ([0.0, 1.0, 0.0], [0.0, 1.0, 0.0])):
        c["pulley"] = {"radius": 0.02, "axis": ax}
    path = write_spec(tmp_path, data)
    d = spec.load(path)
    L = kin.inverse_kinematics(d, [0.6, 0.9])
    f = json.loads(invoke("fk", path, "--lengths", csv_numbers(L), "--json").stdout)
    np.testing.assert_allclose(f["pose"], kin.forward_kinematics(d, L).pose, atol=1e-12)
    assert "kinematic" in f["method"] and f["tensions"] is None
    res = invoke("workspace", path, "--step", "0.1", "--out", tmp_path / "o", "--json")
    assert res.exit_code == 0 and "tilt" not in read_csv(tmp_path / "o" / "workspace.csv")[0]
    data["effector"]["orientation"] = "free"
    res = invoke("workspace", write_spec(tmp_path, data, "f.yaml"), "--step", "0.1", "--out", tmp_path / "f")
    assert res.exit_code == 2 and "swivel pulleys" in res.output


def test_fully_constrained_design_same_under_both(tmp_path):
    base = {"name": "p4", "motion": "1R2T", "gravity": [0, -9.81], "frame": {"lower": [0, 0], "upper": [2, 2]},
            "effector": {"mass": 1.0, "size": [0.2, 0.1]}, "tension": [1, 60], "cables": planar4_cables(),
            "workspace": {"grid": {"step": 0.1}}}
    fixed = spec.from_dict(base)
    free = spec.from_dict({**base, "effector": {**base["effector"], "orientation": "free"}})
    assert resolve(free).orientation.name == "commanded" and not resolve(free).underconstrained
    a, ca = collect_chunks(ws.run, fixed)
    b, cb = collect_chunks(ws.run, free)
    for name in ("poses", "feasible", "margin", "tensions", "lengths"):
        np.testing.assert_array_equal(stacked(ca, name), stacked(cb, name))
    assert {k: v for k, v in a.summary().items() if k != "elapsed_s"} == \
        {k: v for k, v in b.summary().items() if k != "elapsed_s"}
    L = kin.inverse_kinematics(fixed, [1.0, 0.8, 0.05])
    fa, fb = H.equilibrium(fixed, L), H.equilibrium(free, L)
    np.testing.assert_allclose(fa.pose, [1.0, 0.8, 0.05], atol=1e-8)
    np.testing.assert_array_equal(fa.pose, fb.pose)
    pa = json.loads(invoke("pose", write_spec(tmp_path, base, "a.yaml"), "--at", "1,0.8,0.05", "--json").stdout)
    free_path = write_spec(tmp_path, {**base, "effector": {**base["effector"], "orientation": "free"}}, "b.yaml")
    pb = json.loads(invoke("pose", free_path, "--at", "1,0.8,0.05", "--json").stdout)
    assert pa == pb and "tilt" not in pa


# ---------------------------------------------------------------------------
# free: the workspace at the hanging orientation
# ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def free_rows(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("free")
    path = free_planar2(tmp)
    res = invoke("workspace", path, "--step", "0.05", "--out", tmp / "o", "--json")
    assert res.exit_code == 0, res.output
    header, rows = read_csv(tmp / "o" / "workspace.csv")
    return path, tmp / "o", json.loads(res.stdout), header, rows


@pytest.mark.slow
def test_free_workspace_rows_are_the_hanging_pose_at_each_position(free_rows):
    path, out, summary, header, rows = free_rows
    assert header == ["x", "y", "feasible", "margin", "tension_c1", "tension_c2", "length_c1", "length_c2",
                      "tilt", "orientation_phi"]
    assert (out / "tilt_map.png").stat().st_size > 10_000
    assert summary["effector_orientation"] == "free" and summary["tilt_limit"] is None
    assert summary["max_tilt"] <= summary["max_tilt_hanging"] == pytest.approx(45.0)
    num = lambda v: float(v) if v != "" else None  # noqa: E731
    rng = np.random.default_rng(0)
    picked = rng.choice(len(rows), 40, replace=False)
    seen = set()
    for k in picked:
        row = dict(zip(header, rows[k]))
        res = invoke("pose", path, "--at", f"{row['x']},{row['y']}", "--json")
        p = json.loads(res.stdout)
        seen.add((p["feasible"], p["orientation"] is None))
        assert p["feasible"] == (row["feasible"] == "1")
        for c in ("c1", "c2"):
            for key, col in (("tensions", "tension_"), ("lengths", "length_")):
                a, b = p[key][c], num(row[col + c])
                assert (a is None) == (b is None) and (a is None or a == pytest.approx(b, rel=1e-9, abs=1e-12))
        # the CSV holds 10 significant digits
        assert (p["tilt"] is None) == (row["tilt"] == "") and (p["tilt"] is None or
                                                              p["tilt"] == pytest.approx(float(row["tilt"]), rel=1e-9))
        if p["margin"] is not None:
            assert p["margin"] == pytest.approx(float(row["margin"]), rel=1e-9, abs=1e-12)
    assert {(True, False), (False, False), (False, True)} <= seen  # feasible, out of bounds, cannot hang


def test_free_feasibility_is_the_hanging_statics(free_rows):
    """feasible = it hangs (the reference kernel) with both tensions within 0-20 N; tensions are the hanging ones."""
    path, out, summary, header, rows = free_rows
    d = spec.load(path)
    a = np.array([[float(v) if v != "" else np.nan for v in r] for r in rows])
    P = a[:, :2]
    phi, t, _, status, _ = K.hanging_tilt_batch(d.outlets, d.attachments, np.zeros(3), 1.0, np.asarray(d.gravity),
                                                np.ascontiguousarray(P))
    ok = status == 0
    within = ok & np.all((t >= -1e-9) & (t <= 20 + 1e-9), axis=1)
    feasible = a[:, 2] == 1
    assert np.all(feasible <= within)
    assert np.count_nonzero(within & ~feasible) <= np.count_nonzero(np.isclose(t[within], 0, atol=1e-9).any(1)
                                                                   | np.isclose(t[within], 20, atol=1e-9).any(1))
    np.testing.assert_allclose(a[feasible, 4:6], t[feasible], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(a[:, 8], np.where(ok, np.degrees(np.abs(phi)), np.nan), rtol=1e-9, atol=1e-12)
    assert summary["feasible"] == int(feasible.sum()) and summary["hangs"] == int(ok.sum())


@pytest.mark.slow
def test_max_tilt_makes_larger_tilts_infeasible(free_rows, tmp_path):
    path, out, summary, header, rows = free_rows
    res = invoke("workspace", path, "--step", "0.05", "--out", tmp_path / "m", "--json", "--max-tilt", "15")
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    _, rows15 = read_csv(tmp_path / "m" / "workspace.csv")
    f0 = np.array([r[2] == "1" for r in rows])
    f15 = np.array([r[2] == "1" for r in rows15])
    tilt = np.array([float(r[8]) if r[8] else np.nan for r in rows])
    np.testing.assert_array_equal(f15, f0 & (tilt <= 15))
    assert s["tilt_limit"] == 15 and s["tilt_limited"] == int(np.count_nonzero(f0 & ~f15)) > 0
    assert s["max_tilt"] <= 15
    # the same limit as a requirement
    res = invoke("workspace", free_planar2(tmp_path, max_tilt=15.0), "--step", "0.05", "--out", tmp_path / "r",
                 "--json")
    assert json.loads(res.stdout)["feasible"] == s["feasible"]


@pytest.mark.parametrize("args,message", [
    # the option declares its range (issue 19): refused outside it, naming the option and the bound
    # crossed (the wording is typer's or click's, by version: "Input should be greater than or equal
    # to 0" or "is not in the range 0<=x<=180")
    (["--max-tilt", "-1"], r"'--max-tilt'.*(greater than or equal to 0\b|\b0<=x)"),
    (["--max-tilt", "200"], r"'--max-tilt'.*(less than or equal to 180|x<=180)"),
    (["--kind", "wrench-closure"], "--kind wrench-closure"),
    (["--orientations", "total"], "--orientations: an under-constrained design with effector.orientation: free"),
])
def test_free_workspace_bad_options_exit_2(tmp_path, args, message):
    res = invoke("workspace", free_planar2(tmp_path), "--step", "0.1", "--out", tmp_path / "o", *args)
    text = " ".join(res.output.split())  # a long message may be wrapped
    assert res.exit_code == 2 and "Traceback" not in res.output
    assert re.search(message if message.startswith("'") else re.escape(message), text), res.output


def test_tilt_limit_needs_a_free_design(tmp_path):
    res = invoke("workspace", PLANAR2, "--step", "0.1", "--out", tmp_path / "o", "--max-tilt", "10")
    assert res.exit_code == 2 and "--max-tilt" in res.output and "effector.orientation: free" in res.output
    data = planar2_raw()
    data["requirements"]["max_tilt"] = 10
    res = invoke("check", write_spec(tmp_path, data))
    assert res.exit_code == 2 and "requirements.max_tilt" in res.output


@pytest.mark.slow
def test_crane_workspace(tmp_path):
    """crane4 (spatial, free, max_tilt 10): orientation per axis, feasibility at the hanging pose."""
    res = invoke("workspace", CRANE4, "--step", "0.5", "--out", tmp_path, "--json")
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    header, rows = read_csv(tmp_path / "workspace.csv")
    assert header[-4:] == ["tilt", "orientation_rx", "orientation_ry", "orientation_rz"]
    a = np.array([[float(v) if v != "" else np.nan for v in r] for r in rows])
    feas = a[:, 3] == 1
    assert 0 < feas.sum() < len(a) and np.all(a[feas, -4] <= 10) and s["tilt_limit"] == 10
    assert s["max_tilt_hanging"] > 30 and s["tilt_limited"] > 0
    d = spec.load(CRANE4)
    k = int(np.flatnonzero(feas)[0])
    at = H.hanging_pose(d, a[k, :3], nominal=np.eye(3))
    np.testing.assert_allclose(at.orientation, a[k, -3:], atol=1e-9)
    np.testing.assert_allclose(at.tensions, a[k, 5:9], rtol=1e-9)
    assert (tmp_path / "tilt_map.png").is_file()
    assert invoke("check", CRANE4).exit_code == 0


# ---------------------------------------------------------------------------
# fk and pose on the command line
# ---------------------------------------------------------------------------

def test_fk_point_mass_with_a_pushing_cable():
    """pointmass3: lengths whose lower trilateration point would need cable c to push; the pod
    hangs lower from a and b, c slack, and the old kinematic answer is that trilateration point."""
    d = spec.load(POINTMASS3)
    P = np.array([5.0, -1.5, 3.0])  # outside the triangle, beyond its side a-b
    L = np.linalg.norm(d.outlets - P, axis=1)
    u = (d.outlets - P) / L[:, None]
    assert np.linalg.solve(u.T, [0, 0, 5 * 9.81])[2] < 0  # holding P would need c to push
    res = invoke("fk", POINTMASS3, "--lengths", csv_numbers(L), "--json")
    assert res.exit_code == 0, res.output
    f = json.loads(res.stdout)
    assert f["slack"] == ["c"] and f["tensions"]["c"] == 0 and f["stable"] and f["model"] == "held"
    assert f["pose"][2] < P[2] - 0.01 and f["residual"] < 1e-12 and f["balance_residual"] < 1e-9
    assert set(f) >= {"pose", "orientation", "tilt", "tensions", "slack", "stable", "equilibria", "residual",
                      "method"}
    np.testing.assert_allclose(kin.forward_kinematics(d, L, guess=[5, -1, 3.5]).pose, P, atol=1e-6)


def test_fk_free_reports_orientation_and_equilibria(tmp_path):
    path = free_planar2(tmp_path)
    at = H.hanging_pose(spec.load(path), [0.3, 0.5])
    res = invoke("fk", path, "--lengths", csv_numbers(at.lengths), "--json")
    f = json.loads(res.stdout)
    assert f["orientation"] == pytest.approx(at.orientation, abs=1e-9) and f["tilt"] == pytest.approx(at.tilt_deg)
    np.testing.assert_allclose(f["pose"], [0.3, 0.5], atol=1e-9)
    assert f["model"] == "rigid" and f["effector_orientation"] == "free"
    assert all(e["energy"] >= f["energy"] and e["stable"] for e in f["equilibria"])
    d = spec.load(CRANE4)
    L = H.hanging_pose(d, [1.0, 1.0, 2.0]).lengths
    f = json.loads(invoke("fk", CRANE4, "--lengths", csv_numbers(L), "--json").stdout)
    assert len(f["orientation"]) == 3 and len(f["slack"]) == 1 and f["tilt"] == pytest.approx(24.787, abs=1e-3)


@pytest.mark.parametrize("spec_path,lengths,message", [
    (PLANAR2, "0.6,0.7", "--lengths: cables c1 and c2 cannot both reach the effector"),
    (PLANAR2, "0.6,-0.7", "--lengths: cable lengths must be non-negative"),
    (PLANAR2, "0.6,0.7,0.8", "--lengths: expected 2 cable lengths"),
    (PLANAR2, "0,1.38", "--lengths: cable c1 is shorter than 1 micrometre"),
    (POINTMASS3, "5,5,5", "--lengths: the balls |a_i - P| <= rho_i have no common point"),
])
def test_fk_bad_lengths_exit_2(spec_path, lengths, message):
    res = invoke("fk", spec_path, "--lengths", lengths)
    assert res.exit_code == 2, res.output
    assert message in res.output.replace("\n", " ") and "Traceback" not in res.output


def test_fk_unreachable_lengths_give_the_excess():
    res = invoke("fk", PLANAR2, "--lengths", "0.6,0.7")
    assert "short by 0.08 m" in res.output.replace("\n", " ")
    res = invoke("fk", POINTMASS3, "--lengths", "5,5,5")
    assert "smallest excess" in res.output.replace("\n", " ")


def test_pose_free(tmp_path):
    path = free_planar2(tmp_path)
    p = json.loads(invoke("pose", path, "--at", "0.3,0.5", "--json").stdout)
    assert p["feasible"] and p["tilt"] == pytest.approx(22.287, abs=1e-3) and p["stable"]
    assert p["orientation"] < 0 and p["effector_orientation"] == "free"
    W = np.array(p["structure_matrix"])
    t = np.array(list(p["tensions"].values()))
    np.testing.assert_allclose(W @ t, [0, 9.81], atol=1e-9)  # the hanging tensions hold the weight
    bad = json.loads(invoke("pose", path, "--at", "3,1", "--json").stdout)
    assert not bad["feasible"] and "pushing" in bad["reason"] and bad["tilt"] is None
    assert bad["lengths"] == {"c1": None, "c2": None}
    res = invoke("pose", path, "--at", "0.3,0.5,0.1")
    assert res.exit_code == 2 and "--at: expected 2 numbers (x,y)" in res.output
    res = invoke("pose", path, "--at", "0.3,0.5", "--objective", "min-max")
    assert res.exit_code == 2 and "--objective" in res.output
    res = invoke("pose", path, "--at", "0.3,0.5", "--kind", "wrench-closure")
    assert res.exit_code == 2 and "--kind wrench-closure" in res.output


def test_pose_table_shows_the_tensions_an_infeasible_load_hangs_with():
    """crane4 at (1.5, 1.5, 2) hangs tilted 14.4 deg, more than its max_tilt of 10: the
    pose is infeasible (no tensions in the table), yet the load hangs there, and the table's
    text gives the tensions it hangs with (the JSON's hanging_tensions)."""
    data = json.loads(invoke("pose", CRANE4, "--at", "1.5,1.5,2", "--json").stdout)
    assert not data["feasible"] and "max_tilt" in data["reason"]
    assert all(v is None for v in data["tensions"].values())
    text = invoke("pose", CRANE4, "--at", "1.5,1.5,2").output.replace("\n", " ")
    shown = ", ".join(f"{c} {v:.6g}" for c, v in data["hanging_tensions"].items())
    assert f"and tensions [N] {shown}" in text
    feasible = invoke("pose", CRANE4, "--at", "2.5,2,2").output
    assert "and tensions" not in feasible  # the table has them


@pytest.mark.slow
def test_free_on_sagging_cables_checks_interference_along_the_catenaries(tmp_path):
    """A free design hangs on every cable model (tests/test_hanging_cables.py, test_hanging_sagging.py),
    with its interference along the catenaries at the hanging pose: a row is collision free where
    ``pose`` lists no colliding pair; under fixed the other models' outputs come without the tilt."""
    path = free_planar2(tmp_path)
    res = invoke("workspace", path, "--step", "0.1", "--out", tmp_path / "o", "--cable-model", "sagging",
                 "--collisions", "--json")
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["interference"] is True
    header, rows = read_csv(tmp_path / "o" / "workspace.csv")
    col = header.index("collision_free")
    hanging = [r for r in rows if r[header.index("tilt")] != ""]
    assert hanging
    for r in hanging[:: max(1, len(hanging) // 8)]:
        res = invoke("pose", path, "--at", f"{r[0]},{r[1]}", "--cable-model", "sagging", "--json")
        assert res.exit_code == 0, res.output
        assert (json.loads(res.stdout)["collisions"] == []) == (r[col] == "1")
    res = invoke("workspace", PLANAR2, "--step", "0.1", "--out", tmp_path / "e", "--cable-model", "elastic")
    assert res.exit_code == 0 and "tilt" not in read_csv(tmp_path / "e" / "workspace.csv")[0]


# ---------------------------------------------------------------------------
# issue 40, finding 5: an infeasible hanging pose's margin, and the tilt limit's tolerance
# ---------------------------------------------------------------------------

def test_a_pose_rejected_for_its_tilt_does_not_pass_the_margin_check(tmp_path):
    """With max_tilt 2 deg most of crane4's task box hangs too tilted: the task_box check fails,
    and min_margin must fail too (it passed with the margin of the rejected poses, 258.5 N)."""
    raw = spec.read_yaml(CRANE4)
    raw["requirements"].update(max_tilt=2.0, min_margin=1.0)
    path = write_spec(tmp_path, raw)
    res = invoke("check", path, "--json")
    assert res.exit_code == 1, res.output
    flat = json.dumps(json.loads(res.stdout))
    assert '"check_task_box": false' in flat and '"check_min_margin": false' in flat, flat
    # every infeasible row's margin is negative or empty; feasible rows keep theirs
    res = invoke("workspace", path, "--step", "0.5", "--out", tmp_path / "o", "--json")
    assert res.exit_code == 0, res.output
    header, rows = read_csv(tmp_path / "o" / "workspace.csv")
    col = {h: i for i, h in enumerate(header)}
    infeasible = [r for r in rows if r[col["feasible"]] == "0"]
    assert infeasible and all(r[col["margin"]] == "" or float(r[col["margin"]]) < 0 for r in infeasible)
    assert all(r[col["margin"]] != "" for r in rows if r[col["feasible"]] == "1")


def test_max_tilt_zero_accepts_a_level_pose(tmp_path):
    """A pose that hangs level has a computed tilt of about 1e-15 deg: --max-tilt 0 accepts it
    (tolerance 1e-9 rad), and rejects one tilted by more."""
    res = invoke("workspace", CRANE4, "--max-tilt", "0", "--step", "0.5", "--out", tmp_path / "o", "--json")
    assert res.exit_code == 0, res.output
    header, rows = read_csv(tmp_path / "o" / "workspace.csv")
    col = {h: i for i, h in enumerate(header)}
    level = [r for r in rows if r[col["x"]] == "2.5" and r[col["y"]] == "2"]
    assert level and all(abs(float(r[col["tilt"]])) < 1e-12 and r[col["feasible"]] == "1" for r in level)
    assert json.loads(res.stdout)["feasible"] == len(level)
    raw = spec.read_yaml(CRANE4)
    raw["requirements"]["max_tilt"] = 0.0
    path = write_spec(tmp_path, raw)
    level, tilted = (json.loads(invoke("pose", path, "--at", at, "--json").stdout) for at in ("2.5,2,2", "2.6,2,2"))
    assert level["feasible"] is True and level["tilt"] < 1e-12
    assert tilted["feasible"] is False and tilted["margin"] is None and "max_tilt" in tilted["reason"]
