"""Sagging statics where the straight-cable start misleads, and poses without shapes.

- A light effector on heavy cables (sagging40 with a 1 kg effector): at the straight
  tensions the cables' end forces point below the horizontal, so no tensions of those
  shapes hold the load, yet a solution exists at higher tensions.  The kernel must find
  it: it is checked against Irvine's equations solved by scipy from several tension
  levels (the reference of ``tests/test_sagging.py``, which never calls the kernels),
  on sagging40 and on random light-effector robots.
- A zero-length cable (the effector on an outlet) has no direction and no shape: the
  pose reports NaN (JSON null) in the structure matrix, the same on every run, never
  what a scratch buffer held.
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from scipy.optimize import fsolve, least_squares

from cdpr_design.model import spec
from cdpr_design import api

from .helpers import DESIGNS, invoke, write_spec
from .test_sagging import G, columns, geometry, irvine


def sagging40(mass: float, **extra) -> dict:
    raw = spec.read_yaml(DESIGNS / "sagging40.yaml")
    raw["effector"]["mass"] = mass
    raw.update(extra)
    return raw


def taut_branch(X, Z, L0, w, EA, H, VB) -> bool:
    """Whether paying the cable out relaxes its effector end (dT_B/dL0 < 0): the taut branch,
    the one that tends to the straight cable as w -> 0.  By finite differences of Irvine's
    closure solved for (H, VB) at L0 (1 +- 1e-6)."""
    def tb(L):
        def f(p):
            Xc, Zc = irvine(math.exp(p[0]), p[1], L, w, EA)
            return [(Xc - X) / L, (Zc - Z) / L]
        p = fsolve(f, [math.log(H), VB], xtol=1e-14)
        return math.hypot(math.exp(p[0]), p[1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return tb(L0 * (1 + 1e-6)) < tb(L0 * (1 - 1e-6))


def square_solutions(design, pose, scales=(1.0, 1.5, 2.0, 3.0, 5.0, 8.0)) -> list:
    """Every solution of the square (m = n) sagging statics scipy finds from the straight
    tensions times each of ``scales``: per cable (H, VB, L0), from Irvine's closure and
    the force and moment balance.  Returns [(t_B, t_A, L0, taut)] with H > 0, L0 > 0."""
    P = geometry(design, pose)
    m = P["X"].size
    assert m == design.n
    W0 = columns(P, P["chord"] / P["c"][:, None])
    t0 = np.linalg.solve(W0, P["wreq"])
    Fs, Ls = max(np.abs(t0).max(), 1.0), P["c"].max()

    def residual(x):
        H, VB, L0 = x[:m] * Fs, x[m:2 * m] * Fs, x[2 * m:] * Ls
        r = []
        for i in range(m):
            Xc, Zc = irvine(H[i], VB[i], L0[i], P["w"][i], P["EA"][i])
            r += [(Xc - P["X"][i]) / Ls, (Zc - P["Z"][i]) / Ls]
        F = H[:, None] * P["u"] + VB[:, None] * P["up"]
        return np.array(r + list((columns(P, F) @ np.ones(m) - P["wreq"]) / Fs))

    found = []
    for k in scales:
        t = np.maximum(t0, 0.0) * k + 0.5 * P["w"] * P["c"]
        x0 = np.concatenate([t * P["X"] / P["c"] / Fs, t * P["Z"] / P["c"] / Fs, P["c"] / Ls])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            x = least_squares(residual, x0, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15).x
        if not np.max(np.abs(residual(x))) < 1e-11:
            continue
        H, VB, L0 = x[:m] * Fs, x[m:2 * m] * Fs, x[2 * m:] * Ls
        if H.min() <= 0 or L0.min() <= 0:
            continue
        tB, tA = np.hypot(H, VB), np.hypot(H, VB + P["w"] * L0)
        if any(np.allclose(tB, s[0], rtol=1e-8) for s in found):
            continue
        taut = all(taut_branch(P["X"][i], P["Z"][i], L0[i], P["w"][i], P["EA"][i], H[i], VB[i]) for i in range(m))
        found.append((tB, tA, L0, taut))
    return found


def test_a_light_effector_on_heavy_cables_is_held():
    """Issue 40, finding 4: sagging40 with a 1 kg effector at (20, 10) is held by 23.4 N at the
    effector and 29.3 N at the outlets (fk and Irvine's equations agree); it was 'no-tensions'."""
    design = spec.from_dict(sagging40(1.0, tension=[0.0, 400.0]))
    refs = [s for s in square_solutions(design, [20.0, 10.0]) if s[3]]
    assert len(refs) == 1, refs
    tB, tA, L0, _ = refs[0]
    res = api.pose(design, [20.0, 10.0])
    assert res.cable_state.status == "ok" and res.feasible, res.cable_state.status
    np.testing.assert_allclose(res.tensions, tB, rtol=1e-8)
    np.testing.assert_allclose(res.cable_state.outlet_tensions, tA, rtol=1e-8)
    np.testing.assert_allclose(res.cable_state.unstretched_lengths, L0, rtol=1e-9)
    np.testing.assert_allclose(tB, 23.375, atol=0.01)
    np.testing.assert_allclose(tA, 29.27, atol=0.01)


def test_a_light_effector_workspace_is_not_empty(tmp_path):
    """The whole 1 kg workspace was 0 feasible poses, even with bounds [0, 400] N."""
    out = tmp_path / "out"
    res = invoke("workspace", write_spec(tmp_path, sagging40(1.0, tension=[0.0, 400.0])), "--step", "2",
                 "--out", out, "--json")
    assert res.exit_code == 0, res.output
    summary = json.loads(res.output)
    assert summary["feasible"] > 0.3 * summary["poses"], summary


def _light_robot(rng) -> tuple:
    """A planar two-cable robot whose cables weigh 0.5 to 3 times its effector, and a pose below
    the outlets."""
    span = float(rng.uniform(5, 40))
    height = float(rng.uniform(0.4, 0.8)) * span
    mass = float(rng.uniform(0.2, 5.0))
    ratio = 10 ** rng.uniform(math.log10(0.5), math.log10(3.0))  # cable weight / effector weight
    w = ratio * mass * G / span
    half = float(rng.uniform(0.0, 0.02)) * span
    d = {"name": "light", "motion": "2T", "gravity": [0.0, -G],
         "frame": {"lower": [0.0, 0.0], "upper": [span, height]},
         "effector": {"mass": mass, "size": [2 * half, 2 * half]},
         "tension": [0.0, 1e6],
         "cables": [{"name": "a", "outlet": [0.0, height], "attachment": [-half, half]},
                    {"name": "b", "outlet": [span, height], "attachment": [half, half]}],
         "cable": {"model": "sagging", "mass_per_length": w / G,
                   "axial_stiffness": float(mass * G * 10 ** rng.uniform(3, 5))}}
    pose = [float(rng.uniform(0.25, 0.75)) * span, float(rng.uniform(0.2, 0.75)) * height]
    return spec.from_dict(d), pose


def test_light_effectors_match_irvine_solved_independently():
    """On random light-effector robots, wherever scipy finds the taut-branch solution of Irvine's
    equations with the force balance, the kernel reports it (status ok, the same tensions);
    where the kernel reports a solution, it is one of scipy's."""
    rng = np.random.default_rng(40)
    held = 0
    for _ in range(30):
        design, pose = _light_robot(rng)
        refs = [s for s in square_solutions(design, pose) if s[3]]
        res = api.pose(design, pose)
        if refs:
            held += 1
            assert res.cable_state.status == "ok", (design.raw, pose, refs)
            assert any(np.allclose(res.tensions, r[0], rtol=1e-7) for r in refs), (res.tensions, refs)
            assert res.feasible
        elif res.cable_state.status == "ok":
            raise AssertionError(f"the kernel holds {pose} with {res.tensions}; scipy found no taut solution")
    assert held >= 20, held


# ---------------------------------------------------------------------------
# a zero-length cable: no garbage in the outputs
# ---------------------------------------------------------------------------

def test_effector_on_an_outlet_reports_no_structure_matrix(tmp_path):
    """Issue 40, finding 1: the structure matrix of a sagging pose with a zero-length cable came
    from an np.empty buffer (1e+243 ..., different on every run).  It is null, with status
    singular, and the same on every run."""
    path = write_spec(tmp_path, sagging40(5.0))
    outs = []
    for _ in range(3):
        res = invoke("pose", path, "--at", "0.15,19.85", "--json")
        assert res.exit_code == 0, res.output
        outs.append(json.loads(res.output))
    assert outs[0] == outs[1] == outs[2]
    out = outs[0]
    assert out["cable_status"] == "singular" and out["feasible"] is False and out["margin"] is None
    assert out["structure_matrix"] == [[None, None], [None, None]], out["structure_matrix"]


def test_random_singular_poses_are_nan_not_garbage():
    """At random poses with an attachment on its outlet (sagging cables, planar and spatial, with
    every objective): the structure matrix and per-cable outputs are NaN, the lengths finite, the
    status singular; nothing depends on what memory held before."""
    from .test_sagging import random_planar, random_spatial

    rng = np.random.default_rng(7)
    for k in range(12):
        build, motion, m = [(random_planar, "2T", 2), (random_planar, "1R2T", 3),
                            (random_spatial, "3T", 6), (random_spatial, "3R3T", 7)][k % 4]
        design, pose = build(rng, m, motion)
        i = int(rng.integers(m))
        full = design.full_pose(pose)
        from cdpr_design.statics import kinematics as kin

        b = design.attachments[i] @ kin.rotation_matrix(*full[3:]).T
        pos = design.outlets[i] - b
        pose = list(pos[: design.motion.dim]) + list(pose[design.motion.dim:])
        for objective in ("min-norm", "min-max"):
            res = api.pose(design, pose, objective=objective)
            assert res.cable_state.status == "singular"
            assert not res.feasible and math.isnan(res.margin)
            assert np.all(np.isnan(res.W)), res.W
            assert np.all(np.isnan(res.tensions))
            for v in (res.cable_state.outlet_tensions, res.cable_state.unstretched_lengths, res.cable_state.sag):
                assert np.all(np.isnan(v))
            assert np.all(np.isfinite(res.lengths)) and res.lengths[i] < 1e-9


def test_a_taut_rope_solution_is_found():
    """tests/test_sagging.py's 10 m robot with 5 kg/m cables and a 1 kg effector, at (5, 6): once
    reported 'no-catenary' (the straight start asks a cable for less than its least tension), it is
    held by the two cables pulled taut, about 1,885 N (Irvine's equations by scipy agree)."""
    from .test_sagging import nocat_data

    design = spec.from_dict(nocat_data())
    refs = [s for s in square_solutions(design, [5.0, 6.0], scales=(1, 2, 5, 10, 20, 40, 80)) if s[3]]
    assert len(refs) == 1
    res = api.pose(design, [5.0, 6.0])
    assert res.cable_state.status == "ok" and res.feasible
    np.testing.assert_allclose(res.tensions, refs[0][0], rtol=1e-8)
    np.testing.assert_allclose(res.cable_state.outlet_tensions, refs[0][1], rtol=1e-8)


@pytest.mark.parametrize("position", [[-6.5, -1.0, 3.75], [-0.75, 4.5, 3.5], [6.75, 0.75, 3.75]])
def test_cogiro_poses_the_straight_start_missed(position):
    """CoGiRo with sagging cables: poses the fixed point did not converge to from the straight
    start, solved by the continuation in the weight: balanced, and the minimum-norm distribution
    for their own shapes (tests/test_sagging.check_kkt: free cables' tensions in the row space of
    W, multipliers of the right sign at the bounds)."""
    from cdpr_design.model.spec import with_cable_model

    from .helpers import DESIGNS as D
    from .test_sagging import check_kkt, end_forces

    design = with_cable_model(spec.load(D / "cogiro.yaml"), "sagging")
    pose = position + [0.0, 0.0, 0.0]
    res = api.pose(design, pose)
    assert res.cable_state.status == "ok" and res.feasible
    P, H, VB = end_forces(design, pose, res)
    F = H[:, None] * P["u"] + VB[:, None] * P["up"]
    np.testing.assert_allclose(columns(P, F).sum(axis=1), P["wreq"], atol=1e-9 * res.tensions.max())
    check_kkt(design, pose, res)


@pytest.mark.parametrize("objective", ["min-max", "min-sum"])
def test_other_objectives_hold_a_light_effector(objective):
    """The other objectives' fixed point started from the straight cables too: it printed
    'feasible' with no tensions and the structure matrix of shapes it never converged to.
    With two cables every objective has the min-norm tensions."""
    design = spec.from_dict(sagging40(1.0, tension=[0.0, 400.0]))
    ref = api.pose(design, [20.0, 10.0])
    res = api.pose(design, [20.0, 10.0], objective=objective)
    assert res.cable_state.status == "ok" and res.feasible
    np.testing.assert_allclose(res.tensions, ref.tensions, rtol=1e-9)
    np.testing.assert_allclose(res.W, ref.W, rtol=1e-9, atol=1e-12)
