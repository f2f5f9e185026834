"""A hanging effector under an external force (``--kind wrench-feasible`` with
``effector.orientation: free``) against slow, obvious references.

The reference is the total potential energy of the effector on stiff elastic cables whose
unstretched lengths hold the answer's pose with the answer's tensions (L0 = L / (1 + t / EA)): its
weight, the external force's potential -F . p (F at the platform origin) and the cables' elastic
energy.  At the answer that energy is stationary exactly when the answer balances weight, force and
moment, and BFGS (scipy) from several starts about it comes back to it when it is a minimum.  The
same energy without the force's potential is not stationary there (the check sees the force).  A
hand case: a planar point mass on two cables, attached above its platform origin, swings under a
horizontal force by atan(F / (2 W)) (module of the test).  On sagging cables, the energy of
tests/test_hanging_sagging.py plus the force's potential.  On designs: crane4 under a box of forces
is feasible only where it is feasible under gravity alone, its rows agree with ``pose``, and the
vertices are the box's.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml
from scipy.optimize import minimize, root

from cdpr_design.statics.hanging import geometry as hg
from cdpr_design.statics.hanging.at_positions import hanging_orientations

from .helpers import ROOT, invoke, read_csv
from .test_hanging_stiffness import energy, pose_of, random_robot, unstretched


def random_force(rng, weight, planar):
    """A force [N] of 10 to 40 % of the weight in a random direction (in the plane for planar bodies)."""
    d = rng.normal(size=3)
    if planar:
        d[2] = 0.0
    return d / np.linalg.norm(d) * weight * rng.uniform(0.1, 0.4)


def loaded_energy(x, robot, L0, EA, p0, R0, F):
    """:func:`tests.test_hanging_stiffness.energy` plus the external force's potential -F . p [J]."""
    p, _ = pose_of(x, p0, R0, robot[5])
    return energy(x, robot, L0, EA, p0, R0) - float(F @ p)


def gradient(fun, x, h=1e-7):
    """Central differences of ``fun`` at ``x``."""
    return np.array([(fun(x + h * e) - fun(x - h * e)) / (2 * h) for e in np.eye(x.size)])


def loaded_cases(seed, kinds=("planar2", "three", "four")):
    """(robot, force, p, R, t) where random robots hang under random forces at random positions."""
    rng = np.random.default_rng(seed)
    out = []
    for kind in kinds:
        for _ in range(3):
            A, B, c, mass, g, planar, P = random_robot(rng, kind)
            weight = mass * np.linalg.norm(g)
            F = random_force(rng, weight, planar)
            h = hanging_orientations(hg.Geometry(A, B, c, mass, g, F), P, planar)
            for k in np.flatnonzero(h.feasible)[:2]:
                out.append(((A, B, c, mass, g, planar), F, P[k], h.rotation[k], h.tensions[k]))
    return out


def test_loaded_hanging_pose_is_the_energy_minimum_scipy_finds():
    """The hanging pose under weight and an external force is a minimum of the total potential
    energy including the force's: the energy's gradient there is zero (1e-6 of the weight), BFGS
    from four starts about it (1 cm, 2 degrees) comes back to it (1e-5 m, rad); without the force's
    potential the gradient there is the force (the reference sees the force)."""
    cases = loaded_cases(61)
    kinds = {(r[5], len(r[0])) for r, *_ in cases}
    assert len(cases) >= 10 and len(kinds) == 3, kinds
    rng = np.random.default_rng(5)
    for robot, F, p, R, t in cases:
        planar, weight = robot[5], robot[3] * np.linalg.norm(robot[4])
        EA = weight * 1e4 * np.ones(len(robot[0]))
        L0 = unstretched(robot, p, R, t, EA)
        n = 3 if planar else 6
        fun = lambda x: loaded_energy(x, robot, L0, EA, p, R, F)  # noqa: E731
        assert np.abs(gradient(fun, np.zeros(n))).max() < 1e-6 * weight, (p, F)
        plain = gradient(lambda x: energy(x, robot, L0, EA, p, R), np.zeros(n))
        np.testing.assert_allclose(plain[:2 if planar else 3], F[:2 if planar else 3], atol=1e-6 * weight)
        for _ in range(4):
            x0 = np.concatenate([rng.normal(0, 0.01, 2 if planar else 3), rng.normal(0, 0.035, 1 if planar else 3)])
            sol = minimize(fun, x0, method="BFGS", jac=lambda x: gradient(fun, x),
                           options={"gtol": 1e-10 * weight, "maxiter": 3000})
            x = root(lambda x: gradient(fun, x), sol.x, method="hybr", options={"xtol": 1e-13}).x
            assert np.abs(x).max() < 1e-5, (p, F, sol.x, x)


def test_loaded_answer_moves_with_the_force():
    """The force turns the effector: the loaded orientation differs from gravity alone's by more
    than 1e-3 rad somewhere (a solver that ignored the force would pass the balance test of gravity
    alone, not the one above)."""
    moved = 0
    for robot, F, p, R, t in loaded_cases(62, ("planar2", "four")):
        A, B, c, mass, g, planar = robot
        h = hanging_orientations(hg.Geometry(A, B, c, mass, g), p[None], planar)
        if h.feasible[0]:
            moved += hg.angle_from(R, h.rotation[0]) > 1e-3
    assert moved >= 2


def test_hand_case_planar_point_mass_swings_by_atan_f_over_2w():
    """A planar point mass attached at b = (0, 0.1) m above its platform origin, its centre of mass
    at c = (0, -0.1) m, weight W, a horizontal force F at the origin: the moments about the
    attachment, -0.2 W sin(phi) + 0.1 F cos(phi) = 0, give phi = atan(F / (2 W)); the cables
    balance (-F, W) from the attachment p + R b."""
    W, F = 10.0 * 9.81, 20.0
    A = np.array([[-1.0, 2.0, 0.0], [1.5, 2.5, 0.0]])
    B = np.array([[0.0, 0.1, 0.0], [0.0, 0.1, 0.0]])
    geo = hg.Geometry(A, B, [0.0, -0.1, 0.0], 10.0, [0.0, -9.81, 0.0], [F, 0.0, 0.0])
    h = hanging_orientations(geo, np.zeros((1, 3)), True)
    phi = math.atan(F / (2 * W))
    assert h.status[0] == 0
    assert math.atan2(h.rotation[0, 1, 0], h.rotation[0, 0, 0]) == pytest.approx(phi, abs=1e-12)
    assert h.tilt_deg[0] == pytest.approx(math.degrees(phi), abs=1e-9)
    att = np.array([-0.1 * math.sin(phi), 0.1 * math.cos(phi)])
    u = (A[:, :2] - att) / np.linalg.norm(A[:, :2] - att, axis=1)[:, None]
    t = np.linalg.solve(u.T, [-F, W])
    np.testing.assert_allclose(h.tensions[0], t, rtol=1e-12)


def test_a_force_that_cancels_the_weight_leaves_nothing_to_hang_from():
    """A planar body whose external force cancels its weight has no balanced orientation (flagged)."""
    A = np.array([[-1.0, 2.0, 0.0], [1.0, 2.0, 0.0]])
    B = np.array([[-0.1, 0.0, 0.0], [0.1, 0.0, 0.0]])
    geo = hg.Geometry(A, B, [0.0, -0.1, 0.0], 1.0, [0.0, -9.81, 0.0], [0.0, 9.81, 0.0])
    h = hanging_orientations(geo, np.zeros((1, 3)), True)
    assert not h.feasible[0] and np.isnan(h.tensions[0]).all()


@pytest.mark.slow
def test_sagging_loaded_pose_is_the_energy_minimum():
    """On sagging cables under an external force: the energy of tests/test_hanging_sagging.py plus
    -F . p is stationary at the answer (1e-6 of the weight) and BFGS from two starts comes back."""
    from cdpr_design.statics.hanging.sagging import hang_on_sagging_cables

    from .test_hanging_sagging import Reference

    rng = np.random.default_rng(63)
    seen = 0
    for kind in ("planar2", "four"):
        A, B, c, mass, g, planar, P = random_robot(rng, kind)
        weight = mass * np.linalg.norm(g)
        F = random_force(rng, weight, planar)
        geo = hg.Geometry(A, B, c, mass, g, F)
        ideal = hanging_orientations(geo, P, planar)
        L = np.linalg.norm(A - P[0] - B, axis=1)
        w, EA = weight * 0.1 / L, weight * 1e3 * np.ones(len(A))
        dofs = hg.DOFS_PLANAR if planar else hg.DOFS_SPATIAL
        h, cab, _ = hang_on_sagging_cables(geo, P, planar, ideal, w, EA, dofs)
        for k in np.flatnonzero(h.status == 0)[:1]:
            ref = Reference((A, B, c, mass, g, planar), cab.unstretched[k], w, EA, P[k], h.rotation[k],
                            zip(cab.H[k], cab.VB[k]))
            n = 3 if planar else 6
            fun = lambda x: ref.energy(x) - float(F @ pose_of(x, P[k], h.rotation[k], planar)[0])  # noqa: E731
            jac = lambda x: ref.gradient(x) - np.concatenate([F[:2], [0.0]] if planar else [F, np.zeros(3)])  # noqa: E731
            assert np.abs(jac(np.zeros(n))).max() < 1e-6 * weight
            for _ in range(2):
                x0 = np.concatenate([rng.normal(0, 0.01, 2 if planar else 3), rng.normal(0, 0.035, 1 if planar else 3)])
                sol = minimize(fun, x0, method="BFGS", jac=jac, options={"gtol": 1e-9 * weight, "maxiter": 3000})
                x = root(jac, sol.x, method="hybr", options={"xtol": 1e-13}).x
                assert np.abs(x).max() < 1e-6, (P[k], x)
            seen += 1
    assert seen == 2


# ----------------------------------------------------------------------------
# designs: crane4 under a box of forces
# ----------------------------------------------------------------------------

BOX = {"lower": [-40.0, -40.0, -100.0], "upper": [40.0, 40.0, 0.0]}


def crane_spec(tmp_path, box=BOX):
    raw = yaml.safe_load((ROOT / "designs" / "crane4.yaml").read_text())
    raw["workspace"]["external_wrench"] = box
    raw["workspace"]["grid"]["step"] = 1.0
    path = tmp_path / "crane4-loaded.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path


def _rows(folder):
    header, rows = read_csv(folder / "workspace.csv")
    return [{h: (float(v) if v != "" else None) for h, v in zip(header, r)} for r in rows], header


@pytest.mark.parametrize("model", ["ideal", "elastic"])
def test_crane4_wrench_feasible_is_static_under_every_vertex(tmp_path, model):
    """crane4 under a box of forces: every wrench-feasible row is feasible under gravity alone with
    the same tensions and tilt, ``tilt_loaded`` >= ``tilt``, some static rows fail a vertex, and
    sampled rows agree with ``pose --kind wrench-feasible`` (feasible, margin, tensions, tilt_loaded)."""
    spec = crane_spec(tmp_path)
    out = {}
    for kind in ("static", "wrench-feasible"):
        r = invoke("workspace", spec, "--kind", kind, "--cable-model", model, "--out", tmp_path / kind, "--quiet")
        assert r.exit_code == 0, r.output
        out[kind] = _rows(tmp_path / kind)
    (st, _), (wf, header) = out["static"], out["wrench-feasible"]
    assert "tilt_loaded" in header and len(st) == len(wf)
    n_static = sum(r["feasible"] == 1 for r in st)
    n_wf = sum(r["feasible"] == 1 for r in wf)
    assert 0 < n_wf < n_static
    for a, b in zip(st, wf):
        if b["feasible"] == 1:
            assert a["feasible"] == 1 and a["tension_c1"] == b["tension_c1"] and a["tilt"] == b["tilt"]
            assert b["tilt_loaded"] >= b["tilt"] and b["margin"] <= a["margin"] + 1e-9
    lost = next(i for i, (a, b) in enumerate(zip(st, wf)) if a["feasible"] == 1 and b["feasible"] == 0)
    for i in (lost, next(i for i, b in enumerate(wf) if b["feasible"] == 1)):
        row = wf[i]
        r = invoke("pose", spec, "--at", f"{row['x']!r},{row['y']!r},{row['z']!r}", "--kind", "wrench-feasible",
                   "--cable-model", model, "--json", "--quiet")
        assert r.exit_code == 0, r.output
        p = json.loads(r.stdout)
        assert p["feasible"] == (row["feasible"] == 1)
        assert p["tilt_loaded"] == pytest.approx(row["tilt_loaded"], rel=1e-6, abs=1e-9)
        if p["feasible"]:
            assert p["margin"] == pytest.approx(row["margin"], rel=1e-6)
            assert p["tensions"]["c2"] == pytest.approx(row["tension_c2"], rel=1e-6)
        else:
            assert "workspace.external_wrench" in p["reason"]


def test_a_moment_on_a_hanging_effector_is_refused_naming_the_box(tmp_path):
    """A planar hanging body (1R2T) under an external moment: refused, naming workspace.external_wrench."""
    from .helpers import random_planar_data, write_spec

    data = random_planar_data(np.random.default_rng(3), m=2, motion="1R2T")
    data["effector"]["orientation"] = "free"
    data.setdefault("workspace", {})["external_wrench"] = {"lower": [0.0, 0.0, -1.0], "upper": [0.0, 0.0, 1.0]}
    r = invoke("workspace", write_spec(tmp_path, data), "--kind", "wrench-feasible", "--out", tmp_path / "o",
               "--quiet")
    assert r.exit_code == 2 and "workspace.external_wrench" in r.stderr and "moment" in r.stderr
