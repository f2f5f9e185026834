"""Stiffness of sagging cables (Irvine's elastic catenary) against references that never use the
kernels' formulas (tests/reference/sagging_stiffness.py):

- the reference catenary (scipy on Irvine's equations) against a chain of many point masses;
- K = -dw/dx against central differences of the net cable force at fixed unstretched lengths,
  each cable's end force solved on its own by that reference, on random planar and spatial
  robots at random poses: 1e-5 relative;
- as the mass per length goes to zero, the elastic cables' stiffness and frequencies;
- the sweep kernel's least stiffness and lowest frequency (lumped cable masses) against numpy/scipy;
- through the commands: ``workspace --stiffness`` with sagging cables agrees with ``pose --json``,
  ``check`` reads the task box's figures, and the README's sagging40 pendulum.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.linalg import eigh

from cdpr_design.model import spec
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics import stiffness as st
from tests.helpers import DESIGNS, invoke
from tests.reference import sagging_stiffness as sref
from tests.reference import stiffness as ref

MOTIONS = ("2T", "1R2T", "3T", "3R3T")


def test_reference_catenary_matches_a_chain_of_point_masses():
    """scipy's end forces on Irvine's equations, fed to chains of 400 and 800 point masses: the
    chain's span and height converge to the cable's at second order (error ratio about 4) and
    Richardson's extrapolation agrees to 1e-9 of the chord, on 40 random cables (spans 1-40 m,
    slopes both ways, taut to sagging by 5 %)."""
    rng = np.random.default_rng(1)
    for _ in range(40):
        X, Z = rng.uniform(1, 40), rng.uniform(-30, 30)
        c = np.hypot(X, Z)
        w, EA = rng.uniform(0.1, 50), 10 ** rng.uniform(4, 7)
        L0 = c * (1 + rng.uniform(-0.003, 0.05))
        H, VB = sref.solve_ends(X, Z, L0, w, EA)
        a = np.array(sref.chain_ends(H, VB, L0, w, EA, 400))
        b = np.array(sref.chain_ends(H, VB, L0, w, EA, 800))
        e400, e800 = np.abs(a - (X, Z)), np.abs(b - (X, Z))
        big = np.argmax(e400)
        if e400[big] > 1e-10 * c:
            assert 3.9 < e400[big] / e800[big] < 4.1, (e400, e800)
        np.testing.assert_allclose((4 * b - a) / 3, [X, Z], rtol=0, atol=1e-9 * c)


def random_sagging_robot(rng, motion, mu=None):
    """A random robot of ``motion`` on sagging cables: 1-8 cables from outlets up to 15 m away,
    mass per length 0.01-2 kg/m (or ``mu``), EA 1e4-1e7 N, random COM, inertia and gravity."""
    d = 2 if motion in ("2T", "1R2T") else 3
    m = int(rng.integers(1, 9))
    cables = [{"name": f"c{i}", "outlet": rng.uniform(-15, 15, d).tolist(),
               "attachment": rng.uniform(-0.5, 0.5, d).tolist(),
               "axial_stiffness": float(10 ** rng.uniform(4, 7)),
               "mass_per_length": float(10 ** rng.uniform(-2, 0.3)) if mu is None else mu} for i in range(m)]
    a = rng.normal(size=(3, 3))
    inertia = float(rng.uniform(0.01, 2)) if d == 2 else (a @ a.T + 0.1 * np.eye(3)).tolist()
    g = rng.normal(size=d)
    g *= rng.uniform(1, 12) / np.linalg.norm(g)
    return spec.from_dict({
        "name": "r", "motion": motion, "gravity": g.tolist(), "frame": {"lower": [-15.0] * d, "upper": [15.0] * d},
        "effector": {"mass": float(rng.uniform(0.1, 50)), "size": [0.2] * d,
                     "center_of_mass": rng.uniform(-0.3, 0.3, d).tolist(), "inertia": inertia},
        "tension": [0.0, 1e7], "cable": {"model": "sagging"}, "cables": cables})


def random_pose(rng, design):
    mot = design.motion
    return np.concatenate([rng.uniform(-1, 1, mot.dim), rng.uniform(-0.6, 0.6, len(mot.rotation_coords))])


def random_lengths(rng, design, p, low=-0.002, high=0.02):
    """Unstretched lengths around the chords: from stretched taut cables to cables 2 % longer."""
    return kin.inverse_kinematics(design, p) * (1 + rng.uniform(low, high, design.m))


def relative_error(K, K_ref):
    return float(np.max(np.abs(K - K_ref)) / np.max(np.abs(K_ref)))


@pytest.mark.slow
@pytest.mark.parametrize("motion", MOTIONS)
def test_sagging_stiffness_is_minus_wrench_derivative(motion):
    """20 random robots of each motion type at random poses and random unstretched lengths (the
    wrench not balanced: the matrix is -dw/dx anywhere): the kernel's K against central
    differences of the net wrench, each cable's end force solved by scipy, to 1e-5 relative."""
    rng = np.random.default_rng(MOTIONS.index(motion) + 200)
    worst = 0.0
    for _ in range(20):
        design = random_sagging_robot(rng, motion)
        p = random_pose(rng, design)
        L0 = random_lengths(rng, design, p)
        s = st.pose_stiffness(design, p, np.full(design.m, np.nan), L0)
        assert s.reason is None or "unstable" in s.reason or "singular" in s.reason, s.reason
        K_fd = sref.fd_stiffness(design, design.full_pose(p), L0)
        worst = max(worst, relative_error(s.matrix, K_fd))
    assert worst < 1e-5, worst


@pytest.mark.parametrize("motion", MOTIONS)
def test_light_cables_tend_to_the_elastic_stiffness(motion):
    """As the mass per length goes to zero the sagging K tends to the straight elastic cables' K
    at the same unstretched lengths (tensions EA (L - L0) / L0), at least linearly in the mass, and the
    natural frequencies to those of the elastic K with the cables' lumped mass (a third of each,
    itself going to zero with the mass per length)."""
    rng = np.random.default_rng(MOTIONS.index(motion) + 300)
    for _ in range(10):
        seed = int(rng.integers(1 << 30))
        errors = []
        for mu in (1e-3, 1e-5, 1e-7):
            design = random_sagging_robot(np.random.default_rng(seed), motion, mu=mu)
            p = random_pose(np.random.default_rng(seed + 1), design)
            L = kin.inverse_kinematics(design, p)
            L0 = L / (1 + np.random.default_rng(seed + 2).uniform(1e-4, 0.01, design.m))
            s = st.pose_stiffness(design, p, np.full(design.m, np.nan), L0)
            EA = np.array([c.props.axial_stiffness for c in design.cables])
            g = kin.cable_geometry(design, p)
            R = kin.pose_rotation(design, p)
            K_el = st.restrict(design, ref.stiffness_matrix(
                g.vectors, g.attachments, EA * (L - L0) / L0, EA, design.effector.mass * np.asarray(design.gravity),
                R @ np.asarray(design.effector.center_of_mass)))
            errors.append(relative_error(s.matrix, K_el))
            if mu == 1e-7 and s.frequencies is not None:
                # the elastic cables' K with the cables' lumped mass (mu sum L0 / 3, which goes with mu)
                f_el = st.vibration(K_el, st.restrict(design, sref.mass_matrix(design, R, L0)))[0]
                np.testing.assert_allclose(s.frequencies, f_el, rtol=1e-6)
        assert errors[2] < 1e-7, errors
        # at least linearly in the mass per length (100 times lighter: 50 times closer), down to round-off
        assert errors[1] <= max(errors[0] / 50, 1e-12) and errors[2] <= max(errors[1] / 50, 1e-12), errors


@pytest.mark.slow
@pytest.mark.parametrize("motion", MOTIONS)
def test_sweep_kernel_matches_numpy(motion):
    """The sweep kernel's least stiffness and lowest frequency (per-pose mass matrices with a
    third of each cable's mass at its attachment) against numpy/scipy (K assembled from scipy's
    end forces and Irvine's textbook flexibility, Schur complement, generalised eigenproblem)
    on 15 random robots x 6 positions (one of them infeasible) at a random orientation."""
    rng = np.random.default_rng(MOTIONS.index(motion) + 400)
    compared = 0
    for _ in range(15):
        design = random_sagging_robot(rng, motion)
        p0 = random_pose(rng, design)
        full0 = design.full_pose(p0)
        P = np.zeros((6, 3))
        P[:, : design.motion.dim] = full0[: design.motion.dim] + rng.uniform(-0.5, 0.5, (6, design.motion.dim))
        L0 = np.array([random_lengths(rng, design, np.concatenate([P[k, :design.motion.dim], p0[design.motion.dim:]]))
                       for k in range(6)])
        L0[2] = np.nan  # an infeasible pose: no shapes
        T = np.full(L0.shape, np.nan)
        kmin, flow = st.sweep_figures(st.sweep_arrays(design, full0[3:]), P, T, L0)
        assert np.isnan(kmin[2]) and np.isnan(flow[2])
        R = kin.rotation_matrix(*full0[3:])
        d = design.motion.dim
        for k in (0, 1, 3, 4, 5):
            full = np.concatenate([P[k], full0[3:]])
            K = st.restrict(design, sref.stiffness_matrix(design, full, L0[k]))
            M = st.restrict(design, sref.mass_matrix(design, R, L0[k]))
            scale = np.max(np.abs(K))
            assert abs(kmin[k] - ref.min_stiffness(K, d)) <= 1e-6 * scale, (kmin[k], ref.min_stiffness(K, d))
            w2 = eigh(0.5 * (K + K.T), M, eigvals_only=True)[0]
            if w2 < -1e-6 * scale / np.max(np.diag(M)):
                assert np.isnan(flow[k])
            elif w2 > 1e-6 * scale / np.max(np.diag(M)):
                assert flow[k] == pytest.approx(np.sqrt(w2) / (2 * np.pi), rel=1e-5)
            compared += 1
    assert compared == 15 * 5


@pytest.mark.slow
def test_workspace_stiffness_with_sagging_cables_is_the_pose_commands(tmp_path):
    """sagging40 (5 kg on 40 m spans of 4 mm steel rope): ``workspace --stiffness`` computes
    the sagging cables' stiffness (no refusal); at feasible rows the columns are ``pose --json``'s
    min_stiffness and lowest natural frequency; the summary holds the least of each; the map is
    drawn."""
    path = DESIGNS / "sagging40.yaml"
    r = invoke("workspace", path, "--step", 4.0, "--stiffness", "--out", tmp_path / "s", "--json", "--quiet")
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    from tests.test_stiffness_sweep import columns

    cols = columns(tmp_path / "s" / "workspace.csv")
    feas = cols["feasible"].astype(bool)
    k, f = cols["min_stiffness"], cols["lowest_frequency"]
    assert feas.sum() > 10 and np.isfinite(k[feas]).all() and np.isnan(k[~feas]).all()
    assert s["min_stiffness"] == pytest.approx(np.nanmin(k[feas]), rel=1e-9)
    assert s["lowest_frequency"] == pytest.approx(np.nanmin(f[feas]), rel=1e-9)
    assert (tmp_path / "s" / "stiffness_map.png").stat().st_size > 0
    rows = np.flatnonzero(feas)
    for i in rows[:: max(1, len(rows) // 3)][:3]:
        at = f"{cols['x'][i]:.12g},{cols['y'][i]:.12g}"
        p = json.loads(invoke("pose", path, "--at", at, "--json").stdout)
        assert p["stiffness_reason"] is None
        assert p["min_stiffness"] == pytest.approx(k[i], rel=1e-7)
        assert p["natural_frequencies"][0] == pytest.approx(f[i], rel=1e-7)


@pytest.mark.slow
def test_check_reads_the_sagging_cables_stiffness_over_the_task_box(tmp_path):
    """``check`` with ``requirements.min_stiffness`` / ``min_frequency`` on sagging cables: the
    figures are the least over the task box's feasible poses of the sagging sweep with the
    stiffness (no refusal); a limit above the figure fails, one below passes."""
    import copy

    import yaml

    from cdpr_design import workspaces as ws
    from cdpr_design.design.envelope import task_grid

    raw = copy.deepcopy(spec.load(DESIGNS / "sagging40.yaml").raw)
    raw["requirements"] = {"task_box": {"lower": [18.0, 8.0], "upper": [22.0, 12.0]}}
    raw["workspace"]["grid"]["step"] = 1.0
    design = spec.from_dict(raw)
    task = ws.run(design, ws.Analysis(stiffness=True), grid=task_grid(design), tilt=False).summary()
    kmin, fmin = task["min_stiffness"], task["lowest_frequency"]
    assert kmin > 0 and fmin > 0

    def check(**req):
        path = tmp_path / "s.yaml"
        path.write_text(yaml.safe_dump({**raw, "requirements": {**raw["requirements"], **req}}))
        r = invoke("check", path, "--json")
        assert r.exit_code in (0, 1), r.output
        return {c["requirement"]: c for c in json.loads(r.stdout)["checks"]}

    checks = check(min_stiffness=0.99 * kmin, min_frequency=0.99 * fmin)
    assert checks["min_stiffness"]["passed"] and checks["min_frequency"]["passed"]
    checks = check(min_stiffness=1.01 * kmin, min_frequency=1.01 * fmin)
    assert checks["min_stiffness"]["passed"] is False and checks["min_frequency"]["passed"] is False


def test_the_readmes_sagging40_pendulum():
    """README 'Stiffness and vibration': sagging40 at (4, 0.5) swings on its short, nearly vertical
    left cable while the long right one hangs 8.4 m below its chord: 4.9 N/m and 0.14 Hz, against
    21 kN/m with straight elastic cables.  The pendulum bounds it: above the left cable's lateral
    string term T/L, and the frequency near a pendulum's sqrt(g/L)/2 pi."""
    import re

    from tests.helpers import ROOT

    text = " ".join((ROOT / "README.md").read_text().split())
    k, f, x, y, sag, k_el = re.search(r"and ([\d.]+) N/m and ([\d.]+) Hz at \(([\d.]+), ([\d.]+)\), where it swings "
                                      r".* hangs ([\d.]+) m below .* gives (\d+) kN/m there", text).groups()
    at = f"{x},{y}"
    p = json.loads(invoke("pose", DESIGNS / "sagging40.yaml", "--at", at, "--json").stdout)
    assert round(p["min_stiffness"], 1) == float(k) and round(p["natural_frequencies"][0], 2) == float(f)
    assert round(p["sag"]["right"], 1) == float(sag)
    el = json.loads(invoke("pose", DESIGNS / "sagging40.yaml", "--at", at, "--json", "--cable-model", "elastic").stdout)
    assert round(el["min_stiffness"] / 1e3) == float(k_el)
    L = np.hypot(0.0 - (float(x) - 0.15), 20.0 - (float(y) + 0.15))
    assert p["tensions"]["left"] / L < p["min_stiffness"] < 2 * p["tensions"]["left"] / L
    assert p["natural_frequencies"][0] == pytest.approx(np.sqrt(9.81 / L) / (2 * np.pi), rel=0.3)
