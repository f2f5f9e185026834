"""Robot-level statics with sagging cables (:mod:`cdpr_design.kernels.sagging`)
against an independent, slow reference.

The reference (:func:`reference`) never calls the kernels: per cable the
unknowns are the end forces H_i, VB_i and the unstretched length L0_i, plus n
multipliers lambda; the equations are Irvine's closure as printed in the
textbook (with 1/w; docs/cable-models.md), the effector's force and moment
equilibrium, and the minimum-norm condition of the fixed point (t = W(shapes)^T
lambda, the stationarity of min |t|^2 subject to W t = w_req when no bound is
active).  scipy's ``fsolve`` (``least_squares`` as a fallback) solves them from
the straight-cable solution.  The kernel is also checked by residuals computed
here from what it reports (re-integrated shapes, force and moment balance),
in the limits w -> 0 and EA -> inf, on the 10 m planar robot of issue 15, and
through the command line.

Everything here also passes with NUMBA_DISABLE_JIT=1 (``.ci/run`` runs it so).
"""

from __future__ import annotations

import dataclasses
import json
import math
import warnings

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import fsolve, least_squares

from cdpr_design.kernels import catenary as C
from cdpr_design.model import spec
from cdpr_design.statics import kinematics as kin
from cdpr_design import api

from .helpers import invoke, random_planar_data, read_csv, write_spec

G = 9.81


# ---------------------------------------------------------------------------
# the reference: the robot-level problem written plainly, solved with scipy
# ---------------------------------------------------------------------------

def irvine(H, VB, L0, w, EA):
    """Irvine's elastic catenary as printed (Irvine 1981): span X and height Z [m] of A above B."""
    VA = VB + w * L0
    X = H / w * (math.asinh(VA / H) - math.asinh(VB / H)) + H * L0 / EA
    Z = H / w * (math.sqrt(1 + (VA / H) ** 2) - math.sqrt(1 + (VB / H) ** 2)) + (VA * L0 - 0.5 * w * L0 ** 2) / EA
    return X, Z


def geometry(design, pose) -> dict:
    """Per cable: span X, height Z, horizontal unit u, chord; the required wrench; w, EA."""
    full = design.full_pose(pose)
    R = kin.rotation_matrix(*full[3:])
    g = np.asarray(design.gravity, float)
    up = -g / np.linalg.norm(g)
    Rb = design.attachments @ R.T
    chord = design.outlets - (full[:3] + Rb)
    Z = chord @ up
    hvec = chord - np.outer(Z, up)
    X = np.linalg.norm(hvec, axis=1)
    f = design.effector.mass * g
    wreq = -np.concatenate([f, np.cross(R @ np.asarray(design.effector.center_of_mass), f)])[design.rows]
    return dict(Rb=Rb, X=X, Z=Z, u=hvec / X[:, None], up=up, chord=chord, c=np.linalg.norm(chord, axis=1),
                wreq=wreq, rows=design.rows, w=np.array([cb.props.mass_per_length * G for cb in design.cables]),
                EA=np.array([float(cb.props.axial_stiffness) for cb in design.cables]))


def columns(P: dict, F: np.ndarray) -> np.ndarray:
    """The wrench rows of end forces F (m, 3) [N] applied at the attachments: (n, m)."""
    return np.hstack([F, np.cross(P["Rb"], F)])[:, P["rows"]].T


@dataclasses.dataclass
class Ref:
    ok: bool
    t: np.ndarray  # effector-end tensions [N]
    TA: np.ndarray  # outlet tensions [N]
    L0: np.ndarray  # unstretched lengths [m]
    H: np.ndarray
    VB: np.ndarray
    active: np.ndarray  # per cable: -1 at its lower bound, +1 at its upper bound, 0 free


def along(H, VB, L0, w):
    """(smallest, largest) tension [N] along each cable: V runs from VB to VA = VB + w L0."""
    VA = VB + w * L0
    TA, TB = np.hypot(H, VA), np.hypot(H, VB)
    return np.where((VB < 0) & (VA > 0), H, np.minimum(TA, TB)), np.maximum(TA, TB)


def straight_qp(W, wreq, lo, hi):
    """min |t|^2, W t = wreq, lo <= t <= hi with scipy's SLSQP (None: no solution)."""
    from scipy.optimize import minimize

    t0 = np.clip(np.linalg.pinv(W) @ wreq, lo, hi)
    r = minimize(lambda t: 0.5 * t @ t, t0, jac=lambda t: t, method="SLSQP", bounds=list(zip(lo, hi)),
                 constraints=[{"type": "eq", "fun": lambda t: W @ t - wreq, "jac": lambda t: W}],
                 options={"ftol": 1e-12, "maxiter": 500})
    ok = np.max(np.abs(W @ r.x - wreq)) < 1e-8 * np.max(np.abs(r.x)) and np.all((r.x >= lo - 1e-9) & (r.x <= hi + 1e-9))
    return r.x if ok else None


def _solve(P, x0, active, lo, hi, Fs, Ls):
    """fsolve on the robot-level equations with the given active set; (x, max residual, split)."""
    m = P["X"].size

    def split(x):
        return x[:m] * Fs, x[m:2 * m] * Fs, x[2 * m:3 * m] * Ls, x[3 * m:] * Fs

    def residual(x):
        H, VB, L0, lam = split(x)
        r = []
        for i in range(m):
            Xc, Zc = irvine(H[i], VB[i], L0[i], P["w"][i], P["EA"][i])
            r += [(Xc - P["X"][i]) / Ls, (Zc - P["Z"][i]) / Ls]
        F = H[:, None] * P["u"] + VB[:, None] * P["up"]
        t = np.linalg.norm(F, axis=1)
        r += list((columns(P, F) @ np.ones(m) - P["wreq"]) / Fs)  # force and moment balance
        # free cables: t in the row space of W(shapes) (min-norm stationarity); cables at a
        # bound: the smallest (largest) tension along the cable equals it
        tlo, thi = along(H, VB, L0, P["w"])
        mn = t - columns(P, F / t[:, None]).T @ lam
        r += list(np.where(active < 0, tlo - lo, np.where(active > 0, thi - hi, mn)) / Fs)
        return np.array(r)

    with warnings.catch_warnings():  # the residual is checked by the caller
        warnings.simplefilter("ignore", RuntimeWarning)
        x, _, ier, _ = fsolve(residual, x0, full_output=True, xtol=1e-14)
    if ier != 1 or np.max(np.abs(residual(x))) > 1e-13:
        x = least_squares(residual, x0, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    return x, np.max(np.abs(residual(x))), split


def reference(design, pose, bounds: bool = False) -> Ref | None:
    """The sagging min-norm statics by fsolve, from the straight solution.

    Without ``bounds``: no bound active (tension limits ignored); None when the straight
    min-norm solution has a cable at or below 5 % of the largest tension.  With ``bounds``:
    the active set of the straight bounded solution (scipy's SLSQP), then updated until the
    KKT conditions hold (free cables within their bounds along the whole cable, multipliers
    t - W^T lambda of the right sign at the bounds); None when the straight problem has no
    solution.
    """
    P = geometry(design, pose)
    m = P["X"].size
    W0 = columns(P, P["chord"] / P["c"][:, None])
    lo, hi = (design.tension_min, design.tension_max) if bounds else (np.zeros(m), np.full(m, np.inf))
    if bounds:
        t0 = straight_qp(W0, P["wreq"], lo, hi)
        if t0 is None:
            return None
    else:
        t0 = np.linalg.pinv(W0) @ P["wreq"]
        if t0.min() <= 0.05 * t0.max():
            return None
    Fs, Ls = t0.max(), P["c"].max()
    tol = 1e-7 * Fs
    active = np.where(t0 <= lo + tol, -1, np.where(t0 >= hi - tol, 1, 0))
    x = np.concatenate([t0 * P["X"] / P["c"], t0 * P["Z"] / P["c"], P["c"] / (1 + t0 / P["EA"]) * Fs / Ls,
                        np.linalg.lstsq(W0.T, t0, rcond=None)[0]]) / Fs
    for _ in range(6):
        x, res, split = _solve(P, x, active, lo, hi, Fs, Ls)
        H, VB, L0, lam = split(x)
        tlo, thi = along(H, VB, L0, P["w"])
        F = H[:, None] * P["u"] + VB[:, None] * P["up"]
        t = np.hypot(H, VB)
        mu = t - columns(P, F / t[:, None]).T @ lam
        new = np.where((active == 0) & (tlo < lo - tol), -1, np.where((active == 0) & (thi > hi + tol), 1, active))
        new = np.where(((active < 0) & (mu < -tol)) | ((active > 0) & (mu > tol)), 0, new)
        if np.array_equal(new, active):
            break
        active = new
    ok = bool(res <= 1e-12 and H.min() > 0 and L0.min() > 0 and np.array_equal(new, active))
    return Ref(ok, t, np.hypot(H, VB + P["w"] * L0), L0, H, VB, active)


# ---------------------------------------------------------------------------
# random robots
# ---------------------------------------------------------------------------

def _sagging_cable(rng, weight: float, span: float) -> dict:
    """Cable properties for a load ``weight`` [N] and spans ~``span`` [m]: w span / weight
    from 0.003 to 0.2, strain weight / EA from 1e-4 to 1e-2."""
    w = weight / span * 10 ** rng.uniform(-2.5, -1.0)
    return {"model": "sagging", "mass_per_length": float(w / G), "axial_stiffness": float(weight * 10 ** rng.uniform(2, 4))}


def random_planar(rng, m: int, motion: str):
    """A planar robot (helpers.random_planar_data) with sagging cables and a pose in its middle."""
    d = random_planar_data(rng, m, motion)
    d["tension"] = [0.0, 1e6]
    for c in d["cables"]:
        c.pop("tension")
    fw, fh = d["frame"]["upper"]
    d["effector"]["center_of_mass"] = [float(v) for v in rng.uniform(-0.03, 0.03, 2)]
    d["cable"] = _sagging_cable(rng, d["effector"]["mass"] * G, max(fw, fh))
    pose = [rng.uniform(0.3, 0.7) * fw, rng.uniform(0.2, 0.5) * fh]
    return spec.from_dict(d), pose + ([float(rng.uniform(-0.2, 0.2))] if motion == "1R2T" else [])


def random_spatial(rng, m: int, motion: str):
    """A spatial robot of m cables in a box frame: four outlets near the upper corners, the
    others near lower corners or high on the sides; 3T: a point effector, 3R3T: attachments
    near the corners of a box platform, matched to their outlets."""
    size = np.array([rng.uniform(3, 15), rng.uniform(3, 12), rng.uniform(2, 6)])
    corners = np.array([[i, j, k] for k in (1, 0) for i, j in ((0, 0), (1, 0), (1, 1), (0, 1))], float)
    outlets = (corners[:m] + rng.uniform(-0.05, 0.05, (m, 3))) * size
    outlets[4:, 2] = np.where(rng.random(m - 4) < 0.5, outlets[4:, 2], rng.uniform(0.6, 0.9, m - 4) * size[2])
    plat = rng.uniform(0.2, 0.6, 3)
    attach = (corners[:m] - 0.5 + rng.uniform(-0.05, 0.05, (m, 3))) * plat if motion == "3R3T" else np.zeros((m, 3))
    mass = float(rng.uniform(5, 100))
    d = {"name": "r", "motion": motion, "gravity": [0.0, 0.0, -G],
         "frame": {"lower": [0.0, 0.0, 0.0], "upper": size.tolist()},
         "effector": {"mass": mass, "size": (plat if motion == "3R3T" else np.zeros(3)).tolist(),
                      "center_of_mass": rng.uniform(-0.05, 0.05, 3).tolist() if motion == "3R3T" else [0, 0, 0],
                      "inertia": [1.0, 1.0, 1.0]},
         "tension": [0.0, 1e6], "cable": _sagging_cable(rng, mass * G, float(size.max())),
         "cables": [{"name": f"c{i}", "outlet": outlets[i].tolist(), "attachment": attach[i].tolist()}
                    for i in range(m)]}
    pose = (rng.uniform([0.35, 0.35, 0.2], [0.65, 0.65, 0.6]) * size).tolist()
    return spec.from_dict(d), pose + (rng.uniform(-0.1, 0.1, 3).tolist() if motion == "3R3T" else [])


FAMILIES = {  # (motion, cable counts, builder)
    "2T": ("2T", (2, 3), random_planar), "1R2T": ("1R2T", (3, 4), random_planar),
    "3T": ("3T", (6, 7, 8), random_spatial), "3R3T": ("3R3T", (6, 7, 8), random_spatial),
}


def random_cases(family: str, count: int, seed: int):
    """``count`` (design, pose, reference) whose reference solution exists (at most 40 count tries)."""
    motion, ms, build = FAMILIES[family]
    rng = np.random.default_rng(seed)
    out = []
    for k in range(40 * count):
        design, pose = build(rng, ms[k % len(ms)], motion)
        ref = reference(design, pose)
        if ref is not None and ref.ok:
            out.append((design, pose, ref))
            if len(out) == count:
                break
    assert len(out) == count, f"{family}: only {len(out)} references solved"
    return out


# ---------------------------------------------------------------------------
# the kernel's answers against the reference
# ---------------------------------------------------------------------------

def end_forces(design, pose, res):
    """(geometry, H, VB) of every cable from a pose result: the end-force direction is read from
    the force rows of the reported structure matrix, the tension is the reported one."""
    P = geometry(design, pose)
    d = np.zeros((design.m, 3))
    for k, r in enumerate(design.rows):
        if r < 3:
            d[:, r] = res.W[k]
    H, VB = res.tensions * np.einsum("ij,ij->i", d, P["u"]), res.tensions * (d @ P["up"])
    # the direction is a unit vector in the cable's vertical plane
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(np.hypot(H, VB), res.tensions, rtol=1e-14)
    return P, H, VB


def integrate_ends(H, VB, L0, w, EA):
    """(X, Z) [m] by quadrature of dx/ds = (1 + T/EA) H/T, dz/ds = (1 + T/EA) V/T, V = VB + w s."""
    def T(s):
        return math.hypot(H, VB + w * s)
    X = quad(lambda s: (1 + T(s) / EA) * H / T(s), 0.0, L0, epsabs=1e-12, epsrel=1e-12, limit=200)[0]
    Z = quad(lambda s: (1 + T(s) / EA) * (VB + w * s) / T(s), 0.0, L0, epsabs=1e-12, epsrel=1e-12, limit=200)[0]
    return X, Z


def bounded(design, pose, rng):
    """``design`` with tension bounds around its unbounded sagging tensions at ``pose``: with
    redundant cables t_min from 1 to 1.5 times the smallest (active), else half of it."""
    free = api.pose(design, pose)
    lo = (float(rng.uniform(1.0, 1.5)) if design.m > design.n else 0.5) * np.min(free.tensions)
    return spec.from_dict(dict(design.raw, tension=[lo, 2.0 * np.max(free.cable_state.outlet_tensions)]))


def cable_inverse(X, Z, L0, w, EA, start):
    """(H, VB) [N] of one cable of length L0 spanning X, Z: Irvine's closure by fsolve (on ln H)."""
    def f(p):
        Xc, Zc = irvine(math.exp(p[0]), p[1], L0, w, EA)
        return [Xc - X, Zc - Z]
    with warnings.catch_warnings():  # the residual is checked below
        warnings.simplefilter("ignore", RuntimeWarning)
        p = fsolve(f, [math.log(start[0]), start[1]], xtol=1e-14)
    if max(map(abs, f(p))) > 1e-12 * L0:
        p = least_squares(f, [math.log(start[0]), start[1]], method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    assert max(map(abs, f(p))) < 1e-12 * L0
    return math.exp(p[0]), p[1]


def least_tension_reference(X, Z, w, EA):
    """min over L0 of the effector-end tension of a heavy cable spanning X, Z [m], by scipy's
    bounded Brent on ln L0 (each L0 solved by :func:`cable_inverse` from the previous one)."""
    from scipy.optimize import minimize_scalar

    c = math.hypot(X, Z)
    start = [w * c, 0.0]

    def tb(x):
        H, VB = cable_inverse(X, Z, math.exp(x), w, EA, start)
        start[:] = [H, VB]
        return math.hypot(H, VB)
    # the tension falls from the taut cable (L0 ~ chord) to a minimum within 1.3 chords
    x = np.linspace(math.log(c * 1.0005), math.log(3 * c), 60)
    k = int(np.argmin([tb(v) for v in x]))
    r = minimize_scalar(tb, bounds=(x[max(k - 1, 0)], x[min(k + 1, x.size - 1)]), method="bounded",
                        options={"xatol": 1e-11})
    return r.fun, math.exp(r.x)


def row_space_residual(W, t, free):
    """|t_F - W_F^T lambda| / max t for lambda fitted on the cables ``free`` (boolean), and t - W^T lambda."""
    lam = np.linalg.lstsq(W[:, free].T, t[free], rcond=None)[0]
    mu = t - W.T @ lam
    return np.max(np.abs(mu[free])) / np.max(t), mu


def check_kkt(design, pose, res) -> np.ndarray:
    """The kernel's answer is the minimum-norm distribution for its own shapes: free cables'
    tensions in the row space of W, multipliers t - W^T lambda >= 0 at a lower bound (the
    smallest tension along the cable at t_min, or a heavy cable at its least tension, checked
    against :func:`least_tension_reference`) and <= 0 at an upper bound (the largest at t_max).
    Returns the cables at their least tension."""
    P, H, VB = end_forces(design, pose, res)
    t = res.tensions
    tlo, thi = along(H, VB, res.cable_state.unstretched_lengths, P["w"])
    tol = 1e-9 * t.max()
    at_lo = np.abs(tlo - design.tension_min) <= tol
    at_hi = np.abs(thi - design.tension_max) <= tol
    free = ~(at_lo | at_hi)
    least = np.zeros(design.m, bool)
    if row_space_residual(res.W, t, free)[0] > 1e-9:
        for i in np.flatnonzero(free & (t < 0.3 * np.median(t))):
            least[i] = abs(least_tension_reference(P["X"][i], P["Z"][i], P["w"][i], P["EA"][i])[0] - t[i]) <= tol
        free &= ~least
    resid, mu = row_space_residual(res.W, t, free)
    assert resid < 1e-9, (resid, t, at_lo, at_hi, least)
    assert np.all(mu[at_lo | least] >= -tol) and np.all(mu[at_hi] <= tol), (mu, at_lo, at_hi, least)
    return least


@pytest.mark.slow
@pytest.mark.parametrize("family,seed", [("2T", 1), ("1R2T", 2), ("3T", 3), ("3R3T", 4)])
def test_sagging_statics_matches_the_reference(family, seed):
    """Each random robot twice: with bounds that no cable reaches, and with bounds around its
    tensions (often active).  Wherever the reference converges the kernel finds a feasible
    answer that is the minimum-norm one for its own shapes (:func:`check_kkt`) and, unless a
    heavy cable sits at its least tension (a second fixed point of the problem, which the
    reference does not model), the reference's: tensions, outlet tensions, unstretched lengths."""
    rng = np.random.default_rng(seed)
    sags, compared, active = [], 0, 0
    for design, pose, ref in random_cases(family, 10, seed):
        capped = bounded(design, pose, rng)
        for d, r in ((design, ref), (capped, reference(capped, pose, bounds=True))):
            if r is None or not r.ok:
                continue
            res = api.pose(d, pose)
            st = res.cable_state
            assert st.status == "ok" and res.feasible, (d.raw, pose)
            if check_kkt(d, pose, res).any():
                continue
            compared += 1
            active += int(np.any(r.active))
            scale = r.t.max()
            np.testing.assert_allclose(res.tensions, r.t, rtol=0, atol=1e-9 * scale)
            np.testing.assert_allclose(st.outlet_tensions, r.TA, rtol=0, atol=1e-9 * scale)
            np.testing.assert_allclose(st.unstretched_lengths, r.L0, rtol=0, atol=1e-10 * res.lengths.max())
            sags.append(np.max((r.TA - r.t) / r.t))
    print(family, "compared", compared, "with active bounds", active, "max sag", max(sags))
    assert compared >= 12 and active >= 2, (compared, active)
    # the cases are not all nearly straight: the outlets carry visibly more than the effector ends
    assert max(sags) > 0.02, sags


@pytest.mark.slow
@pytest.mark.parametrize("family,seed", [("2T", 11), ("1R2T", 12), ("3T", 13), ("3R3T", 14)])
def test_sagging_solutions_balance_and_close(family, seed):
    """Every feasible pose, bounds active or not: the reported shapes close on the outlets
    within 1e-9 m and their end forces balance the load within 1e-9 N; the bounds hold
    along the whole cable; the tensions are the minimum-norm ones (:func:`check_kkt`)."""
    rng = np.random.default_rng(seed)
    active = checked = 0
    for design, pose, _ in random_cases(family, 8, seed):
        for d in (design, bounded(design, pose, rng)):
            res = api.pose(d, pose)
            if not res.feasible:
                continue
            checked += 1
            P, H, VB = end_forces(d, pose, res)
            L0 = res.cable_state.unstretched_lengths
            for i in range(d.m):
                for X, Z in (integrate_ends(H[i], VB[i], L0[i], P["w"][i], P["EA"][i]),
                             C.catenary_ends(H[i], VB[i], L0[i], P["w"][i], P["EA"][i])):
                    assert abs(X - P["X"][i]) < 1e-9 and abs(Z - P["Z"][i]) < 1e-9, (i, X - P["X"][i], Z - P["Z"][i])
            F = H[:, None] * P["u"] + VB[:, None] * P["up"]
            assert np.max(np.abs(columns(P, F).sum(axis=1) - P["wreq"])) < 1e-9
            VA = VB + P["w"] * L0
            TA = np.hypot(H, VA)
            np.testing.assert_allclose(res.cable_state.outlet_tensions, TA, rtol=1e-12)
            top = np.maximum(TA, res.tensions)
            low = np.where((VB < 0) & (VA > 0), H, np.minimum(TA, res.tensions))
            tol = 1e-9 * top.max()
            assert np.all(top <= d.tension_max + tol) and np.all(low >= d.tension_min - tol)
            active += int(np.any(low <= d.tension_min + tol) or np.any(top >= d.tension_max - tol))
            check_kkt(d, pose, res)
    assert checked >= 10 and active >= 2, (checked, active)


# ---------------------------------------------------------------------------
# limits
# ---------------------------------------------------------------------------

def with_cable(design, **props):
    """``design`` with every cable's physical properties replaced (e.g. mass_per_length=0)."""
    cables = tuple(dataclasses.replace(c, props=dataclasses.replace(c.props, **props)) for c in design.cables)
    return dataclasses.replace(design, cables=cables)


LIMIT_CASES = [("2T", 21), ("1R2T", 22), ("3R3T", 23)]


@pytest.mark.parametrize("family,seed", LIMIT_CASES)
def test_weightless_cables_are_the_elastic_ones(family, seed):
    """w -> 0: the ideal tensions (the straight cable's do not depend on EA) and L0 = L / (1 + T/EA);
    w = 0 exactly: the same to round-off; EA -> inf as well: the ideal cable (L0 = chord)."""
    for design, pose, _ in random_cases(family, 3, seed):
        ideal = api.pose(spec.with_cable_model(design, "ideal"), pose)
        EA = design.cables[0].props.axial_stiffness
        for mass, tol in ((0.0, 1e-12), (1e-12, 1e-9)):
            for ea in (EA, 1e300):
                res = api.pose(with_cable(design, mass_per_length=mass, axial_stiffness=ea), pose)
                st = res.cable_state
                assert res.feasible and st.status == "ok"
                scale = ideal.tensions.max()
                np.testing.assert_allclose(res.tensions, ideal.tensions, rtol=0, atol=tol * scale)
                np.testing.assert_allclose(st.outlet_tensions, ideal.tensions, rtol=0, atol=tol * scale)
                np.testing.assert_allclose(st.unstretched_lengths, ideal.lengths / (1 + ideal.tensions / ea),
                                           rtol=tol, atol=0)
                np.testing.assert_allclose(st.sag, 0.0, atol=tol * ideal.lengths.max())
        elastic = api.pose(spec.with_cable_model(design, "elastic"), pose)
        np.testing.assert_allclose(elastic.cable_state.unstretched_lengths, ideal.lengths / (1 + ideal.tensions / EA))


@pytest.mark.slow
@pytest.mark.parametrize("family,seed", LIMIT_CASES)
def test_sagging_tensions_converge_linearly_to_the_ideal_ones(family, seed):
    """|t(w) - t_ideal| shrinks in proportion to w: over w / 10^k (k = 0..4) the error falls
    by 10 per decade (order 1, within 5 %) and err / w tends to a constant."""
    for design, pose, _ in random_cases(family, 2, seed):
        ideal = api.pose(spec.with_cable_model(design, "ideal"), pose).tensions
        mpl = design.cables[0].props.mass_per_length
        errs = []
        for k in range(5):
            res = api.pose(with_cable(design, mass_per_length=mpl / 10 ** k), pose)
            assert res.feasible
            errs.append(np.max(np.abs(res.tensions - ideal)) / ideal.max())
        orders = np.log10(np.array(errs[:-1]) / np.array(errs[1:]))
        assert errs[0] > 1e-4, errs  # the heaviest cables are visibly not straight
        assert np.all(np.abs(orders[1:] - 1.0) < 0.05), (errs, orders)


# ---------------------------------------------------------------------------
# the 10 m planar robot of issue 15
# ---------------------------------------------------------------------------

def planar10(tension_max: float = 5000.0, model: str = "sagging"):
    """10 m square frame, outlets at the two top corners, a 20 kg point effector, 4 mm steel
    cables: 0.6 N/m (mass_per_length 0.6/9.81 kg/m), EA = 1e6 N (issue 15)."""
    return spec.from_dict({
        "name": "planar10", "motion": "2T", "gravity": [0.0, -G],
        "frame": {"lower": [0.0, 0.0], "upper": [10.0, 10.0]},
        "effector": {"mass": 20.0, "size": [0.0, 0.0]}, "tension": [0.0, tension_max],
        "cable": {"model": model, "mass_per_length": 0.6 / G, "axial_stiffness": 1e6},
        "cables": [{"name": "left", "outlet": [0.0, 10.0], "attachment": [0.0, 0.0]},
                   {"name": "right", "outlet": [10.0, 10.0], "attachment": [0.0, 0.0]}],
    })


#: the working region of planar10 where the issue's figures are read: the middle 40 % in x,
#: above 3 m (towards the frame's sides and bottom the effects grow without bound)
REGION = [(x, y) for x in np.arange(3.0, 7.01, 0.5) for y in np.arange(3.0, 9.01, 0.5)]


@pytest.mark.slow
def test_planar10_reproduces_the_issue_figures():
    """The issue's measurements: the winch sees up to ~5 % more than the effector end and
    ~4 % more than the ideal model; commanded lengths off by millimetres.  The geometry is not
    in the issue; on this one (REGION) the largest effects are asserted within 1.5 points of
    the issue's figures, and each pose obeys the physics: T_A - T_B = w int dz / (1 + T/EA),
    between w Z / (1 + T_A/EA) and w Z / (1 + T_B/EA), and below the cable's weight w L0."""
    design, ideal = planar10(), planar10(model="ideal")
    w, EA = 0.6, 1e6
    over_effector, over_ideal, length_error = [], [], []
    for pose in REGION:
        res, ref = api.pose(design, pose), api.pose(ideal, pose)
        assert res.feasible and ref.feasible
        P, H, VB = end_forces(design, pose, res)
        TB, TA, L0 = res.tensions, res.cable_state.outlet_tensions, res.cable_state.unstretched_lengths
        assert np.all(VB > 0)  # both cables rise from the effector: T grows monotonically to the outlet
        d = TA - TB
        assert np.all(d > 0) and np.all(d < w * L0)
        assert np.all(d >= w * P["Z"] / (1 + TA / EA) * (1 - 1e-12))
        assert np.all(d <= w * P["Z"] / (1 + TB / EA) * (1 + 1e-12))
        over_effector.append(np.max(TA / TB - 1))
        over_ideal.append(np.max(TA / ref.tensions - 1))
        length_error.append(np.max(np.abs(ref.lengths - L0)))
    print(f"planar10: outlet over effector {max(over_effector):.2%}, over ideal {max(over_ideal):.2%}, "
          f"length error {1e3 * max(length_error):.2f} mm")
    assert abs(max(over_effector) - 0.05) < 0.015
    assert abs(max(over_ideal) - 0.04) < 0.015
    assert 0.5e-3 < max(length_error) < 5e-3  # millimetres


def test_planar10_outlet_bound_flips_feasibility():
    """A t_max between the effector-end and the outlet tension of the most loaded cable: the
    ideal model (which is below both) says feasible, the sagging one infeasible, though every
    effector-end tension is below t_max; with t_max just above the outlet tension it is feasible
    again, just below it is not: the bound is applied at the outlet."""
    pose = [4.0, 5.0]
    free = api.pose(planar10(), pose)
    TB, TA = free.tensions, free.cable_state.outlet_tensions
    i = int(np.argmax(TA))
    tmax = 0.5 * (TB[i] + TA[i])
    assert TB.max() < tmax < TA[i] and np.all(api.pose(planar10(model="ideal"), pose).tensions < tmax)
    assert api.pose(planar10(tmax, "ideal"), pose).feasible
    capped = api.pose(planar10(tmax), pose)
    assert not capped.feasible and capped.cable_state.status == "ok"
    assert np.all(np.isnan(capped.tensions))
    assert api.pose(planar10(TA[i] * (1 + 1e-9)), pose).feasible
    assert not api.pose(planar10(TA[i] * (1 - 1e-9)), pose).feasible


# ---------------------------------------------------------------------------
# a heavy cable cannot be slack: its least tension
# ---------------------------------------------------------------------------

def test_least_tension_matches_scipy():
    """The kernel's least tension and its length against a bounded Brent search with scipy, on
    random cables: spans 0.5-20 m, slopes -80..80 degrees, strains of the least-tension
    shape from 1e-6 to 1e-2, inextensible ones; and the kernel's shape closes."""
    from cdpr_design.kernels.cable_shape import least_tension

    rng = np.random.default_rng(5)
    for k in range(12):
        X = 10 ** rng.uniform(-0.3, 1.3)
        Z = X * math.tan(math.radians(rng.uniform(-80, 80)))
        w = 10 ** rng.uniform(-1.5, 1)
        EA = math.inf if k % 4 == 3 else w * X * 10 ** rng.uniform(2, 6)
        tau, H, VB, L0 = least_tension(X, Z, w, EA)
        ref, L0_ref = least_tension_reference(X, Z, w, EA)
        assert tau == pytest.approx(ref, rel=1e-10)
        assert L0 == pytest.approx(L0_ref, rel=1e-5)  # the minimum is flat: L0 is known to sqrt(eps)
        assert tau == pytest.approx(math.hypot(H, VB), rel=1e-15)
        np.testing.assert_allclose(C.catenary_ends(H, VB, L0, w, EA), (X, Z), rtol=0, atol=1e-12 * (X + abs(Z)))
    # a cable hanging straight down from its outlet may be slack; one hanging below the effector
    # carries its own weight
    assert least_tension(0.0, 3.0, 1.0, 1e6)[0] == 0.0
    assert least_tension(0.0, -3.0, 2.0, math.inf)[0] == pytest.approx(6.0, rel=1e-15)


def planar3(tension_min: float, model: str = "sagging"):
    """planar10 with a third cable from the effector down to the lower right corner."""
    raw = dict(planar10(model=model).raw, tension=[tension_min, 5000.0])
    raw["cables"] = raw["cables"] + [{"name": "down", "outlet": [10.0, 0.0], "attachment": [0.0, 0.0]}]
    return spec.from_dict(raw)


@pytest.mark.parametrize("tension_min", [0.0, 1.0])
def test_a_heavy_cable_holds_at_least_its_least_tension(tension_min):
    """With straight cables the lower cable of planar3 is at its lower bound (slack at 0 N, or
    1 N).  A heavy cable spanning X, Z cannot pull with less than its least tension (reached
    at one unstretched length; longer or shorter, it pulls harder): the sagging answer holds
    the lower cable there, with its shape, and balances the load; it is neither slack with
    zero force nor refused as having no catenary."""
    pose = [5.0, 5.0]
    ideal = api.pose(planar3(tension_min, "ideal"), pose)
    assert ideal.tensions[2] == pytest.approx(tension_min, abs=1e-9)
    design = planar3(tension_min)
    res = api.pose(design, pose)
    assert res.feasible and res.cable_state.status == "ok", res.cable_state
    P = geometry(design, pose)
    tau_min, L0_min = least_tension_reference(P["X"][2], P["Z"][2], P["w"][2], P["EA"][2])
    assert tau_min > 2.0 * tension_min  # the least tension binds, not the bound
    assert res.tensions[2] == pytest.approx(tau_min, rel=1e-9)
    assert res.cable_state.unstretched_lengths[2] == pytest.approx(L0_min, rel=1e-6)
    assert np.all(np.isfinite(res.cable_state.outlet_tensions)) and np.all(res.cable_state.sag > 0)
    _, H, VB = end_forces(design, pose, res)
    F = H[:, None] * P["u"] + VB[:, None] * P["up"]
    assert np.max(np.abs(columns(P, F).sum(axis=1) - P["wreq"])) < 1e-9


# ---------------------------------------------------------------------------
# the command line: bad input, and poses without a catenary
# ---------------------------------------------------------------------------

def _planar10_data(**cable) -> dict:
    raw = json.loads(json.dumps(planar10().raw))
    raw["cable"].update(cable)
    return {k: v for k, v in raw.items() if v is not None}


def _drop(data: dict, *keys) -> dict:
    for k in keys:
        data["cable"].pop(k)
    return data


@pytest.mark.parametrize("data,extra,key", [
    (_planar10_data(axial_stiffness=-1e6), [], "cable.axial_stiffness"),
    (_planar10_data(axial_stiffness=0.0), [], "cable.axial_stiffness"),
    (_planar10_data(mass_per_length=0.0), [], "cable.mass_per_length"),
    (_planar10_data(mass_per_length=-0.06), [], "cable.mass_per_length"),
    (_drop(_planar10_data(), "mass_per_length"), [], "cable.mass_per_length"),
    (_drop(_planar10_data(), "axial_stiffness", "mass_per_length"), [], "cable.axial_stiffness"),
    (_drop(_planar10_data(model="ideal"), "mass_per_length"), ["--cable-model", "sagging"], "cable.mass_per_length"),
    (_drop(_planar10_data(model="ideal"), "axial_stiffness"), ["--cable-model", "elastic"], "cable.axial_stiffness"),
    (_planar10_data(), ["--cable-model", "bogus"], "--cable-model"),
])
@pytest.mark.parametrize("command", ["pose", "workspace"])
def test_bad_cable_input_exits_2_naming_the_key(tmp_path, data, extra, key, command):
    path = write_spec(tmp_path, data)
    args = ["--at", "5,5", "--json"] if command == "pose" else ["--out", tmp_path / "out", "--step", "2"]
    res = invoke(command, path, *args, *extra)
    assert res.exit_code == 2, res.output
    assert key in res.output and "Traceback" not in res.output


def test_a_cable_override_names_its_cable(tmp_path):
    data = _planar10_data()
    data["cables"][1]["axial_stiffness"] = -5.0
    res = invoke("pose", write_spec(tmp_path, data), "--at", "5,5")
    assert res.exit_code == 2 and "cables[1].axial_stiffness" in res.output, res.output


def nocat_data(mass_per_length: float = 5.0, effector_mass: float = 1.0) -> dict:
    """A 10 m planar robot whose second cable runs down from the effector to (10, 3).  With 5 kg/m
    cables and a 1 kg effector, at (3, 2) the load asks a cable for less than its least tension
    on the taut branch: the only equilibrium scipy finds on Irvine's equations has a cable on the
    deep branch (tests/test_sagging_light.py).  (At (5, 6), once given as an example, the two
    cables hold it taut at about 1,885 N: issue 40.)"""
    raw = _planar10_data(mass_per_length=mass_per_length)
    raw["effector"]["mass"] = effector_mass
    raw["cables"][1]["outlet"] = [10.0, 3.0]
    return raw


@pytest.mark.parametrize("data,pose,status", [
    (nocat_data(), "3,2", "no-catenary"),
    # a weightless effector on heavy cables: no tensions >= their least ones balance nothing
    (_planar10_data(model="sagging") | {"effector": {"mass": 0.0, "size": [0.0, 0.0]}}, "5,5", "no-catenary"),
])
def test_a_pose_without_catenary_has_a_status_and_no_numbers(tmp_path, data, pose, status):
    res = invoke("pose", write_spec(tmp_path, data), "--at", pose, "--json")
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["feasible"] is False and out["cable_status"] == status
    for key in ("tensions", "outlet_tensions", "unstretched_lengths", "sag"):
        assert all(v is None for v in out[key].values()), (key, out[key])
    assert out["margin"] is None


def test_workspace_rows_carry_the_cable_status(tmp_path):
    """workspace.csv: every row has a cable_status; rows that did not converge to a shape have no
    tensions, outlet tensions, unstretched lengths or sag, only their status; the summary counts them."""
    out = tmp_path / "out"
    res = invoke("workspace", write_spec(tmp_path, nocat_data(0.2, 5.0)), "--out", out, "--step", "1", "--json")
    assert res.exit_code == 0, res.output
    header, rows = read_csv(out / "workspace.csv")
    col = {h: i for i, h in enumerate(header)}
    status = np.array([int(r[col["cable_status"]]) for r in rows])
    assert np.any(status == 0) and np.any(status == 2), np.bincount(status)
    values = [c for c in header if c.split("_")[0] in ("tension", "outlet", "unstretched", "sag")]
    assert len(values) == 8, header
    for r, st in zip(rows, status):
        if st != 0:
            assert r[col["feasible"]] == "0" and all(r[col[c]] == "" for c in values), r
    summary = json.loads(res.output)
    assert summary["cable_status"]["no-catenary"] == int(np.sum(status == 2))


def test_sagging_rows_do_not_depend_on_the_chunking():
    """Every pose starts from its own straight solution: the same rows, bit for bit, whatever
    the chunk size (the relaxation and the Newton starts keep no state from pose to pose)."""
    from cdpr_design import workspaces

    from .helpers import collect_chunks

    design = spec.from_dict(nocat_data(0.2, 5.0))
    rows = []
    for chunk in (7, 10_000):
        _, chunks = collect_chunks(workspaces.run, design, step=0.5, chunk=chunk)
        rows.append({k: np.concatenate([c.extra[k] if k in c.extra else getattr(c, k) for c in chunks])
                     for k in ("tensions", "margin", "outlet_tension_right", "unstretched_length_left", "cable_status")})
    assert np.any(rows[0]["cable_status"] == 0) and np.any(rows[0]["cable_status"] != 0)
    for k in rows[0]:
        np.testing.assert_array_equal(rows[0][k], rows[1][k], err_msg=k)
