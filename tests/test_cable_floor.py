"""The lower tension bound of ``requirements.min_cable_frequency`` in the sweeps and in ``pose``.

A cable of free length L and mass per length mu keeps its first string mode at or above f while
its tension T >= 4 f^2 L^2 mu (docs/algorithms.md, "The cables' own vibration").  With the
requirement, every evaluation bounds cable i from below by max(tension_min_i, 4 f^2 L_i^2 mu_i)
at each pose.  Checked here against what a user reads: the workspace's rows (every base
evaluator: the closed form of two cables, also against the general kernel, the kernels, swivel
pulleys, a hanging effector, an orientation set) against ``pose`` at sampled rows, and the floor against the free lengths computed
independently (statics.kinematics.cable_geometry); the sweep without the requirement as the
baseline the floor must shrink.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from cdpr_design import workspaces as ws
from cdpr_design.model import spec
from cdpr_design.statics import kinematics as kin
from cdpr_design import api

from .helpers import collect_chunks, invoke, ipanema3_data, planar2_raw, write_spec, resolved
from .reference.general_sweep import general_kernel_rows

TOL = 1e-9  # [N], relative to tensions of tens to thousands of newtons


def _with_frequency(data: dict, f: float | None) -> dict:
    data = json.loads(json.dumps(data))
    if f is not None:
        data.setdefault("requirements", {})["min_cable_frequency"] = f
    return data


def _floor(design, pose) -> np.ndarray:
    """4 f^2 L^2 mu at a pose, L the free lengths from the kinematics (tangent point to attachment)."""
    free = np.linalg.norm(kin.cable_geometry(design, pose).vectors, axis=1)
    mu = np.array([c.props.mass_per_length for c in design.cables])
    return 4.0 * design.requirements.min_cable_frequency ** 2 * free ** 2 * mu


def _rows(design, grid, kind="static"):
    """(poses, feasible bool, margin, tensions) of a whole workspace sweep of ``grid``."""
    result, chunks = collect_chunks(ws.run, design, ws.Analysis(kind=kind), grid=grid)
    cat = lambda name: np.concatenate([getattr(c, name) for c in chunks])  # noqa: E731
    return result, cat("poses"), cat("feasible").astype(bool), cat("margin"), cat("tensions")


def _check(design, plain, floored, rng, samples=25, pose_kind="static"):
    """The floor shrinks the feasible set, every feasible row's tensions are at or above the floor
    there, and ``pose`` agrees with sampled rows (feasible and infeasible alike)."""
    _, P, f0, _, _ = plain
    res, P1, f1, marg, ten = floored
    np.testing.assert_array_equal(P, P1)
    assert f1.sum() < f0.sum() and not np.any(f1 & ~f0), (f0.sum(), f1.sum())
    assert res.feasible == int(f1.sum())
    for k in np.flatnonzero(f1)[:: max(1, f1.sum() // 200)]:
        assert np.all(ten[k] >= _floor(design, P1[k]) - TOL), (P1[k], ten[k], _floor(design, P1[k]))
    lost = np.flatnonzero(f0 & ~f1)
    picks = np.concatenate([rng.choice(np.flatnonzero(f1), samples // 2),
                            rng.choice(lost, samples - samples // 2)])
    for k in picks:
        r = api.pose(design, P1[k], pose_kind)
        assert r.feasible == bool(f1[k]), P1[k]
        np.testing.assert_allclose(r.margin, marg[k], rtol=1e-9, atol=1e-9)
        if r.feasible:
            np.testing.assert_allclose(r.tensions, ten[k], rtol=1e-9, atol=1e-9)


def test_planar2_closed_form():
    """planar2 (mu = 4 g/m, 0..20 N) held at 20 Hz: the floor reaches 14.4 N at L = 1.5 m."""
    rng = np.random.default_rng(1)
    base = spec.from_dict(planar2_raw())
    d = spec.from_dict(_with_frequency(planar2_raw(), 20.0))
    grid = ws.make_grid(d, 0.03)
    _check(d, _rows(base, grid=grid), _rows(d, grid=grid), rng)


def test_planar2_closed_form_floor_is_the_general_kernels():
    """The closed form raises the lower bounds by the floor as the general kernel does (its
    reference): the same flags away from a zero margin, margins and tensions to rounding."""
    d = spec.from_dict(_with_frequency(planar2_raw(), 20.0))
    g = ws.make_grid(d, 0.02)
    _, _, feas, marg, ten = _rows(d, grid=g)
    f_ref, m_ref, t_ref, _ = general_kernel_rows(d, grid=g)
    edge = np.abs(m_ref) <= TOL
    assert edge.sum() <= 2 and 0 < feas.sum() < feas.size
    np.testing.assert_array_equal(feas[~edge], f_ref[~edge].astype(bool))
    np.testing.assert_allclose(marg, m_ref, rtol=1e-9, atol=TOL, equal_nan=True)
    np.testing.assert_allclose(ten, t_ref, rtol=1e-9, atol=TOL, equal_nan=True)


@pytest.mark.parametrize("kind", ["static", "wrench-feasible"])
def test_redundant_kernels(kind):
    """IPAnema 3 geometry (8 cables, 3R3T) with a 5 mm steel rope's mass: the redundant kernels."""
    rng = np.random.default_rng(2)
    raw = ipanema3_data("ip3", cable={"diameter": 0.005, "mass_per_length": 0.1},
                        workspace={"external_wrench": {"lower": [-100, 0, 0, 0, 0, 0],
                                                      "upper": [100, 0, 0, 0, 0, 0]}})
    base = spec.from_dict(raw)
    d = spec.from_dict(_with_frequency(raw, 6.0))  # 4 f^2 mu = 14.4 N/m^2: 1,440 N at 10 m
    grid = ws.make_grid(d, 1.2)
    _check(d, _rows(base, grid=grid, kind=kind), _rows(d, grid=grid, kind=kind), rng, pose_kind=kind)


def test_swivel_pulleys_use_the_free_length():
    """Over swivel pulleys the string runs from the tangent point: the floor uses that free length
    (the kinematics' vectors), not the total length with the arc."""
    rng = np.random.default_rng(3)
    raw = ipanema3_data("ip3p", radius=0.4, cable={"diameter": 0.005, "mass_per_length": 0.1})
    base = spec.from_dict(raw)
    d = spec.from_dict(_with_frequency(raw, 6.0))
    grid = ws.make_grid(d, 1.2)
    _check(d, _rows(base, grid=grid), _rows(d, grid=grid), rng)


def test_orientation_set():
    """The total orientation workspace (every orientation of the set through the pulley-aware kernel)."""
    raw = ipanema3_data("ip3o", cable={"diameter": 0.005, "mass_per_length": 0.1},
                        workspace={"orientation_set": {"lower": [-0.1, 0, 0], "upper": [0.1, 0, 0.2],
                                                     "count": [2, 1, 2]}})
    base = spec.from_dict(raw)
    d = spec.from_dict(_with_frequency(raw, 6.0))
    grid = ws.make_grid(d, 1.2)
    r0, c0 = collect_chunks(ws.run, base, ws.Analysis(orientations="total"), grid=grid)
    r1, c1 = collect_chunks(ws.run, d, ws.Analysis(orientations="total"), grid=grid)
    a = np.concatenate([c.feasible for c in c0]).astype(bool)
    b = np.concatenate([c.feasible for c in c1]).astype(bool)
    assert b.sum() < a.sum() and not np.any(b & ~a)
    assert r1.feasible == int(b.sum())


def test_hanging_effector():
    """planar2 hanging freely (effector.orientation: free): its unique tensions meet the floor."""
    raw = planar2_raw()
    raw["effector"]["orientation"] = "free"
    base = spec.from_dict(raw)
    d = spec.from_dict(_with_frequency(raw, 20.0))
    grid = ws.make_grid(d, 0.05)
    f0 = _rows(base, grid=grid)[2]
    _, chunks = collect_chunks(ws.run, d, grid=grid)
    L = np.concatenate([c.lengths for c in chunks])  # at the hanging pose (point outlets: the free lengths)
    T = np.concatenate([c.tensions for c in chunks])
    f1 = np.concatenate([c.feasible for c in chunks]).astype(bool)
    assert f1.sum() < f0.sum() and not np.any(f1 & ~f0)
    assert np.all(T[f1] >= 4 * 20.0 ** 2 * 0.004 * L[f1] ** 2 - TOL)


def test_commands(tmp_path):
    """Through the command line: workspace and pose agree; sagging cables and certify refuse the
    requirement with the reason (exit 2, no traceback)."""
    spec_path = write_spec(tmp_path, _with_frequency(planar2_raw(), 20.0))
    out = tmp_path / "o"
    res = invoke("workspace", spec_path, "--step", "0.05", "--out", out, "--json")
    assert res.exit_code == 0, res.output
    plain = invoke("workspace", write_spec(tmp_path, planar2_raw(), "p.yaml"), "--step", "0.05",
                   "--out", tmp_path / "p", "--json")
    assert json.loads(res.stdout)["feasible"] < json.loads(plain.stdout)["feasible"]
    # a pose the plain robot holds with cable tensions under the floor
    pose = invoke("pose", spec_path, "--at", "0.75,0.2", "--json")
    data = json.loads(pose.stdout)
    floor = data["cable_frequency_tensions"]
    held = json.loads(invoke("pose", write_spec(tmp_path, planar2_raw(), "p.yaml"), "--at", "0.75,0.2",
                             "--json").stdout)
    assert held["feasible"] and any(held["tensions"][c] < floor[c] for c in floor)
    assert not data["feasible"]
    for args in (("--cable-model", "sagging"),):
        r = invoke("workspace", spec_path, *args, "--out", tmp_path / "s")
        assert r.exit_code == 2 and "requirements.min_cable_frequency" in r.output and "Traceback" not in r.output
    r = invoke("certify", spec_path, "--out", tmp_path / "c")
    assert r.exit_code == 2 and "requirements.min_cable_frequency" in r.output


def _four_cables(f: float | None) -> dict:
    """A point mass on four cables from the corners of a 2 m frame (2T, m = 4 > n = 2), cables of 50 g/m."""
    return _with_frequency({
        "name": "p4", "motion": "2T", "gravity": [0, -9.81], "frame": {"lower": [0, 0], "upper": [2, 2]},
        "effector": {"mass": 2.0, "size": [0.1, 0.1]}, "tension": [1.0, 200.0],
        "cable": {"diameter": 0.004, "mass_per_length": 0.05},
        "cables": [{"name": n, "outlet": o, "attachment": [0, 0]} for n, o in
                   (("a", [0, 2]), ("b", [2, 2]), ("c", [0, 0]), ("d", [2, 0]))]}, f)


def _qp(W, w, lower, upper):
    """The minimum 2-norm tensions within [lower, upper] by cvxpy (None: infeasible)."""
    import cvxpy as cp

    t = cp.Variable(W.shape[1])
    prob = cp.Problem(cp.Minimize(cp.sum_squares(t)), [W @ t == w, t >= lower, t <= upper])
    prob.solve()
    return t.value if prob.status == "optimal" else None


def test_trajectory_tensions_and_sizing_take_the_floor():
    """Along a path (motion.trajectory.states) and in the sizing envelope (design.envelope), a
    redundant robot's minimum-norm tensions are those of a cvxpy QP with max(t_min, 4 f^2 L^2 mu)
    as lower bounds, and the floor raises them above the plain ones."""
    from cdpr_design.design import envelope as ev
    from cdpr_design.motion import trajectory as tr

    plain, d = spec.from_dict(_four_cables(None)), spec.from_dict(_four_cables(8.0))  # 4 f^2 mu = 12.8 N/m^2
    P = np.array([[0.5, 0.6], [1.0, 1.0], [1.4, 1.5], [0.3, 1.7]])
    zero = np.zeros_like(P)
    s, s0 = tr.states(resolved(d, "motion"), P, zero, zero), tr.states(resolved(plain, "motion"), P, zero, zero)
    e = ev.envelope_chunk(resolved(d, "size-motors"), P, np.zeros(3), 0.0, 0.0)
    for k, p in enumerate(P):
        W = kin.structure_matrix(d, p)
        w = -kin.gravity_wrench(d, p)
        lower = np.maximum(1.0, _floor(d, p))
        ref = _qp(W, w, lower, 200.0)
        assert ref is not None
        np.testing.assert_allclose(s["tensions"][k], ref, rtol=1e-5, atol=1e-5)
        np.testing.assert_allclose(e["static"][k], ref, rtol=1e-5, atol=1e-5)
        assert s["feasible"][k] and np.all(s["tensions"][k] >= lower - TOL)
    assert np.all(s["tensions"] >= s0["tensions"] - 1e-9) and np.any(s["tensions"] > s0["tensions"] + 1.0)
    # a floor above the upper bound at the far corner: infeasible there, as in the workspace
    far = spec.from_dict({**_four_cables(30.0), "tension": [1.0, 200.0]})  # 180 N/m^2: 200 N at 1.05 m
    f = tr.states(resolved(far, "motion"), P, zero, zero)["feasible"]
    assert not f.all()


def test_the_readmes_planar2_figures(tmp_path):
    """README 'Stiffness and vibration': planar2's feasible poses without the requirement, at 10 Hz
    and at 20 Hz, as the README states them."""
    import re

    from .helpers import ROOT

    text = (ROOT / "README.md").read_text()
    m = re.search(r"(\d+) of its (\d+) poses are feasible without it,\n(\d+) at (\d+) Hz and (\d+) at (\d+) Hz", text)
    plain, poses, n1, f1, n2, f2 = (int(v) for v in m.groups())
    for f, want in ((None, plain), (f1, n1), (f2, n2)):
        path = write_spec(tmp_path, _with_frequency(planar2_raw(), f), f"p{f}.yaml")
        s = json.loads(invoke("workspace", path, "--out", tmp_path / f"o{f}", "--json", "--quiet").stdout)
        assert (s["feasible"], s["poses"]) == (want, poses)
