"""``fk`` with elastic and sagging cables against independent solves.

- An effector that hangs freely (``effector.orientation: free``) comes to rest where its
  force AND moment balance: elastic cables are checked against the minimum of the potential
  energy (gravity + the cables' elastic energy) found by scipy over the six (planar: three)
  pose coordinates; sagging cables against Irvine's closure solved by scipy for each cable
  at the reported pose, whose end forces must balance the weight in force and moment.
- A cable reported slack carries no force, so it can never span more than its length; an
  ideal (inextensible) taut cable spans exactly its length.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.optimize import minimize

from cdpr_design.model import spec
from cdpr_design.model.spec import with_cable_model
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.cable_fk import forward

from .helpers import DESIGNS, invoke, write_spec, resolved
from .test_sagging import G, cable_inverse

CRANE4 = DESIGNS / "crane4.yaml"


def rest_pose(design, res) -> np.ndarray:
    """The full pose [x, y, z, rx, ry, rz] of an fk result (its orientation when it hangs)."""
    full = design.full_pose(res.pose)
    if res.orientation is not None:
        if design.motion.planar:
            full[5] = res.orientation
        else:
            full[3:] = res.orientation
    return full


def elastic_energy(design, L0):
    """(energy(q) [J], coordinate indices): gravity's potential plus sum EA/(2 L0) (l - L0)^2 over
    the stretched cables, over q = the full pose's x, y, rz (planar) or all six coordinates."""
    g = np.asarray(design.gravity, float)
    m_eff = design.effector.mass
    c = np.asarray(design.effector.center_of_mass, float)
    EA = np.array([float(cb.props.axial_stiffness) for cb in design.cables])
    idx = [0, 1, 5] if design.motion.planar else list(range(6))

    def energy(q):
        full = np.zeros(6)
        full[idx] = q
        R = kin.rotation_matrix(*full[3:])
        ell = np.linalg.norm(design.outlets - full[:3] - design.attachments @ R.T, axis=1)
        stretch = np.maximum(ell - L0, 0.0)
        return -m_eff * g @ (full[:3] + R @ c) + np.sum(EA / (2 * L0) * stretch ** 2)

    return energy, idx


def _grad(f, q, h=1e-7):
    e = np.eye(q.size)
    return np.array([(f(q + h * e[k]) - f(q - h * e[k])) / (2 * h) for k in range(q.size)])


def check_energy_minimum(design, L0, full, rng) -> None:
    """The pose ``full`` (6,) is a minimum of the elastic energy: its gradient (central
    differences) vanishes, its Hessian is positive definite, and scipy's trust-region Newton
    (finite-difference derivatives) from a perturbed start returns to it."""
    energy, idx = elastic_energy(design, L0)
    q = np.asarray(full, float)[idx]
    weight = design.effector.mass * G
    grad = _grad(energy, q)
    assert np.max(np.abs(grad)) < 1e-5 * weight, grad

    def hess(x):
        Hm = np.array([(_grad(energy, x + 1e-5 * e) - _grad(energy, x - 1e-5 * e)) / 2e-5 for e in np.eye(x.size)])
        return 0.5 * (Hm + Hm.T)

    assert np.linalg.eigvalsh(hess(q)).min() > 0  # stable
    r = minimize(energy, q + rng.uniform(-1e-3, 1e-3, q.size), jac=lambda x: _grad(energy, x), hess=hess,
                 method="trust-exact", options={"gtol": 1e-6 * weight})
    np.testing.assert_allclose(r.x, q, atol=1e-7)


def sagging_wrench(design, full, L0, start_tensions) -> tuple:
    """The net wrench [N, N m] on the effector at a full pose whose cables have unstretched
    lengths L0: gravity plus each cable's end force from Irvine's closure solved by scipy
    (tests/test_sagging.cable_inverse); and the effector-end tensions [N]."""
    g = np.asarray(design.gravity, float)
    up = -g / np.linalg.norm(g)
    R = kin.rotation_matrix(*full[3:])
    Rb = design.attachments @ R.T
    f = design.effector.mass * g
    wrench = np.concatenate([f, np.cross(R @ np.asarray(design.effector.center_of_mass, float), f)])
    t = np.zeros(design.m)
    for i, cb in enumerate(design.cables):
        d = design.outlets[i] - full[:3] - Rb[i]
        Z = d @ up
        h = d - Z * up
        X = np.linalg.norm(h)
        w, EA = cb.props.mass_per_length * G, float(cb.props.axial_stiffness)
        T0 = max(start_tensions[i], 1e-3)
        H, VB = cable_inverse(X, Z, L0[i], w, EA, (T0 * X / np.linalg.norm(d), T0 * Z / np.linalg.norm(d)))
        F = H * h / X + VB * up
        wrench += np.concatenate([F, np.cross(Rb[i], F)])
        t[i] = math.hypot(H, VB)
    return wrench, t


def test_crane4_elastic_fk_balances_the_moment():
    """Issue 40, finding 2: the load was held level on two cables with 48.4 N m unbalanced; it
    hangs tilted about 6 degrees on three, as the ideal fk and the energy minimum say."""
    r = invoke("fk", CRANE4, "--lengths", "2.5,3,3.5,3.2", "--cable-model", "elastic", "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert out["slack"] == ["c4"] and 5.5 < out["tilt"] < 6.5, out
    design = with_cable_model(spec.load(CRANE4), "elastic")
    res = forward(resolved(design, "fk"), [2.5, 3, 3.5, 3.2])
    check_energy_minimum(design, np.array([2.5, 3, 3.5, 3.2]), rest_pose(design, res), np.random.default_rng(4))
    ideal = json.loads(invoke("fk", CRANE4, "--lengths", "2.5,3,3.5,3.2", "--json").output)
    assert abs(out["tilt"] - ideal["tilt"]) < 0.1  # steel cables stretch by about a millimetre


def test_crane4_sagging_fk_balances_force_and_moment():
    design = with_cable_model(spec.load(CRANE4), "sagging")
    L0 = np.array([2.5, 3, 3.5, 3.2])
    res = forward(resolved(design, "fk"), L0)
    full = rest_pose(design, res)
    assert res.tilt is not None and 5.5 < res.tilt < 6.5
    wrench, t = sagging_wrench(design, full, L0, res.tensions)
    weight = design.effector.mass * G
    assert np.max(np.abs(wrench)) < 1e-8 * weight, wrench
    np.testing.assert_allclose(res.tensions, t, rtol=1e-7, atol=1e-9 * weight)


def free_planar(rng, model: str) -> tuple:
    """A planar body on two cables that hangs freely (2T, effector.orientation: free), its
    centre of mass below the attachments, and unstretched lengths that reach."""
    w_, h_ = rng.uniform(1.0, 4.0), rng.uniform(1.0, 3.0)
    half = rng.uniform(0.03, 0.15)
    mass = float(rng.uniform(0.5, 5.0))
    cable = {"model": model, "axial_stiffness": float(mass * G * 10 ** rng.uniform(2, 4))}
    if model == "sagging":
        cable["mass_per_length"] = float(mass * 10 ** rng.uniform(-3, -1) / w_)
    d = {"name": "freeplanar", "motion": "2T", "gravity": [0.0, -G],
         "frame": {"lower": [0.0, 0.0], "upper": [w_, h_]},
         "effector": {"mass": mass, "size": [2 * half, 2 * half], "orientation": "free",
                      "center_of_mass": [float(rng.uniform(-0.3, 0.3) * half), float(-rng.uniform(0.2, 1.0) * half)]},
         "tension": [0.0, 1e6], "cable": cable,
         "cables": [{"name": "a", "outlet": [0.0, h_], "attachment": [-half, half]},
                    {"name": "b", "outlet": [w_, h_], "attachment": [half, half]}]}
    design = spec.from_dict(d)
    p = np.array([rng.uniform(0.3, 0.7) * w_, rng.uniform(0.2, 0.6) * h_, 0.0])
    L = np.linalg.norm(design.outlets - p - design.attachments, axis=1)
    return design, L * rng.uniform(0.98, 1.02, 2)


def free_spatial(rng, model: str) -> tuple:
    """A crane-like body on four cables from the top corners of a box (3T, free)."""
    size = np.array([rng.uniform(3, 8), rng.uniform(3, 8), rng.uniform(3, 6)])
    a, b = rng.uniform(0.2, 0.5), rng.uniform(0.2, 0.5)
    mass = float(rng.uniform(5, 100))
    cable = {"model": model, "axial_stiffness": float(mass * G * 10 ** rng.uniform(2, 4))}
    if model == "sagging":
        cable["mass_per_length"] = float(mass * 10 ** rng.uniform(-3, -1.5) / size.max())
    corners = [(0, 0), (1, 0), (1, 1), (0, 1)]
    d = {"name": "freecrane", "motion": "3T", "gravity": [0.0, 0.0, -G],
         "frame": {"lower": [0.0, 0.0, 0.0], "upper": size.tolist()},
         "effector": {"mass": mass, "size": [2 * a, 2 * b, 0.3], "orientation": "free", "inertia": [1.0, 1.0, 1.0],
                      "center_of_mass": [float(rng.uniform(-0.05, 0.05)), float(rng.uniform(-0.05, 0.05)),
                                         float(-rng.uniform(0.1, 0.4))]},
         "tension": [0.0, 1e6], "cable": cable,
         "cables": [{"name": f"c{k}", "outlet": [i * size[0], j * size[1], size[2]],
                     "attachment": [(2 * i - 1) * a, (2 * j - 1) * b, 0.0]} for k, (i, j) in enumerate(corners)]}
    design = spec.from_dict(d)
    p = rng.uniform([0.3, 0.3, 0.3], [0.7, 0.7, 0.6]) * size
    L = np.linalg.norm(design.outlets - p - design.attachments, axis=1)
    return design, L * rng.uniform(0.97, 1.03, 4)


@pytest.mark.parametrize("build", [free_planar, free_spatial])
def test_random_free_elastic_fk_is_the_energy_minimum(build):
    rng = np.random.default_rng(400 + (build is free_spatial))
    solved = 0
    for _ in range(8):
        design, L0 = build(rng, "elastic")
        try:
            res = forward(resolved(design, "fk"), L0)
        except Exception as exc:  # lengths that do not reach are refused, never answered
            assert "--lengths" in str(exc)
            continue
        solved += 1
        full = rest_pose(design, res)
        check_energy_minimum(design, L0, full, rng)
        # every slack cable spans at most its length
        ell = np.linalg.norm(design.outlets - full[:3] - design.attachments @ kin.rotation_matrix(*full[3:]).T, axis=1)
        for name in res.slack:
            i = design.cable_names.index(name)
            assert ell[i] <= L0[i] * (1 + 1e-12)
    assert solved >= 6


@pytest.mark.parametrize("build", [free_planar, free_spatial])
def test_random_free_sagging_fk_balances_force_and_moment(build):
    rng = np.random.default_rng(410 + (build is free_spatial))
    solved = 0
    for _ in range(6):
        design, L0 = build(rng, "sagging")
        try:
            res = forward(resolved(design, "fk"), L0)
        except Exception as exc:
            assert "--lengths" in str(exc)
            continue
        solved += 1
        full = rest_pose(design, res)
        wrench, t = sagging_wrench(design, full, L0, res.tensions)
        weight = design.effector.mass * G
        assert np.max(np.abs(wrench)) < 1e-7 * weight, (wrench, design.raw)
        np.testing.assert_allclose(res.tensions, t, rtol=1e-6)
    assert solved >= 4


def mixed(ideal_cable: str = "left") -> dict:
    raw = spec.read_yaml(DESIGNS / "sagging40.yaml")
    for c in raw["cables"]:
        if c["name"] == ideal_cable:
            c["model"] = "ideal"
    return raw


@pytest.mark.parametrize("lengths", [[22.0, 22.5], [25.0, 20.0], [10.0, 31.0], [7.07, 35.0], [30.0, 12.0]])
def test_an_ideal_cable_never_spans_more_than_its_length(tmp_path, lengths):
    """Issue 40, finding 3: with an ideal and a sagging cable, fk reported the ideal cable slack
    while it spanned twice its length.  A taut ideal cable spans exactly its length; a slack one
    at most its length; and the effector is balanced (Irvine's closure by scipy)."""
    r = invoke("fk", write_spec(tmp_path, mixed()), "--lengths", ",".join(map(str, lengths)), "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    design = spec.from_dict(mixed())
    full = design.full_pose(out["pose"])
    ell = np.linalg.norm(design.outlets - full[:3] - design.attachments, axis=1)
    if "left" in out["slack"]:
        assert ell[0] <= lengths[0] * (1 + 1e-12)
    else:
        assert abs(ell[0] - lengths[0]) < 1e-9
    # the right (sagging) cable's end force by scipy, the left's along its chord
    g = np.array([0.0, -G, 0.0])
    d = design.outlets[1] - full[:3] - design.attachments[1]
    w = design.cables[1].props.mass_per_length * G
    T = out["tensions"]["right"]
    H, VB = cable_inverse(abs(d[0]), d[1], lengths[1], w, 1e6, (T * abs(d[0]) / np.linalg.norm(d), T * d[1] / np.linalg.norm(d)))
    F = np.array([H * np.sign(d[0]), VB, 0.0]) + out["tensions"]["left"] * (design.outlets[0] - full[:3] - design.attachments[0]) / ell[0]
    np.testing.assert_allclose(F + design.effector.mass * g, 0.0, atol=1e-7 * design.effector.mass * G)
