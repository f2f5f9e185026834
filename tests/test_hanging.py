"""The hanging effector (statics.hanging) against slow, independent references.

References, none of which shares code with the implementation:

* the planar two-cable body's one-degree-of-freedom curve with both cables
  taut, scanned by brute force (the angle of cable 1 at its outlet, 20,000
  samples, two assembly branches), plus the two single-cable modes;
* multi-start constrained energy minimisation with scipy SLSQP in Euler
  angles (its own kinematics, random starts);
* cvxpy (second-order cone program) for the point mass;
* for the hanging orientation at a position: a dense scan of the
  instantaneous-centre condition (cable lines and the vertical through the
  centre of mass concurrent) with brentq, tensions from the 2 x 2 force
  balance and stability from finite differences of the energy along the
  constant-length curve.

Everything here also passes with NUMBA_DISABLE_JIT=1.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq, linprog, minimize, minimize_scalar

from cdpr_design.model import spec
from cdpr_design.statics.robot import underconstrained
from cdpr_design.statics import hanging as H
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.hanging import planar2, results
from tests.conftest import DESIGNS
from tests.helpers import NO_KERNELS
from tests.reference import hanging_kernel as K
from tests.reference.tilt_map import tilt_map

G2 = np.array([0.0, -9.81, 0.0])
G3 = np.array([0.0, 0.0, -9.81])


def cr(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def rot2(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s], [s, c]])


def euler(a, b, c):
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    Rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    Rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
    return Rx @ Ry @ Rz


def random_planar2(rng):
    """Outlets near the top corners of a W x Hh frame, a small body, COM anywhere near it."""
    W, Hh = rng.uniform(1.0, 3.0), rng.uniform(1.0, 3.0)
    A = np.array([[rng.uniform(0, 0.1 * W), Hh - rng.uniform(0, 0.2), 0.0],
                  [W - rng.uniform(0, 0.1 * W), Hh - rng.uniform(0, 0.2), 0.0]])
    B = np.array([[rng.uniform(-0.15, -0.03), rng.uniform(-0.05, 0.1), 0.0],
                  [rng.uniform(0.03, 0.15), rng.uniform(-0.05, 0.1), 0.0]])
    c = np.array([rng.uniform(-0.05, 0.05), rng.uniform(-0.15, 0.08), 0.0])
    return A, B, c, rng.uniform(0.2, 5.0), W, Hh


# ---------------------------------------------------------------------------
# reference: hanging orientation at a position (instantaneous centre)
# ---------------------------------------------------------------------------

def ref_tilt(A, B, c, mass, p, n=4000):
    """All balanced orientations at position p with tensions and stability; the
    chosen one (stable, tensions >= 0, closest to level)."""
    A2, B2, c2, gd = A[:, :2], B[:, :2], c[:2], np.array([0.0, -1.0])

    def parts(phi):
        co, si = np.cos(phi)[..., None], np.sin(phi)[..., None]
        P = [p + np.concatenate([co * b[0] - si * b[1], si * b[0] + co * b[1]], -1) for b in B2]
        C = p + np.concatenate([co * c2[0] - si * c2[1], si * c2[0] + co * c2[1]], -1)
        return P, C

    def resid(phi):
        # I = A1 + s d1 on both cable lines; cross(gd, I - C) * cross(d1, d2), a smooth form
        P, C = parts(np.asarray(phi, float))
        d1, d2 = P[0] - A2[0], P[1] - A2[1]
        return cr(gd, A2[0] - C) * cr(d1, d2) + cr(A2[1] - A2[0], d2) * cr(gd, d1)

    phis = np.linspace(-np.pi, np.pi, n + 1)
    r = resid(phis)
    roots = []
    for k in range(n):
        if r[k] == 0:
            roots.append(phis[k])
        elif r[k] * r[k + 1] < 0:
            roots.append(brentq(lambda x: float(resid(x)), phis[k], phis[k + 1], xtol=1e-15, rtol=1e-15))
    rho_of = lambda phi: np.linalg.norm(A2 - np.array(parts(np.asarray(phi))[0]), axis=1)
    out = []
    for x in roots:
        P = np.array(parts(np.asarray(x))[0])
        v = A2 - P
        L = np.linalg.norm(v, axis=1)
        u = v / L[:, None]
        if abs(cr(u[0], u[1])) < 1e-9:
            continue
        t = np.linalg.solve(u.T, np.array([0.0, 9.81 * mass]))
        # stability: energy along the constant-length curve, by finite differences
        rho = rho_of(x)
        E = []
        for dx in (-1e-3, 0.0, 1e-3):
            R = rot2(x + dx)
            Cc = A2 - B2 @ R.T  # circles |Cc_i - q| = rho_i for the origin q
            e = Cc[1] - Cc[0]
            D = np.linalg.norm(e)
            a = (rho[0] ** 2 - rho[1] ** 2 + D ** 2) / (2 * D)
            h = math.sqrt(max(rho[0] ** 2 - a ** 2, 0.0))
            nrm = np.array([-e[1], e[0]]) / D
            qs = [Cc[0] + a * e / D + s * h * nrm for s in (1, -1)]
            q = min(qs, key=lambda q: np.linalg.norm(q - p))
            E.append(9.81 * mass * (q + R @ c2)[1])
        d2E = (E[0] + E[2] - 2 * E[1]) / 1e-6
        out.append((x, t, d2E))
    ok = [o for o in out if o[1].min() >= -1e-9 * 9.81 * mass and o[2] > 0]
    best = min(ok, key=lambda o: abs(o[0])) if ok else None
    return best, out


def closed_form(A, B, c, mass, g, P):
    """The product's closed form (:mod:`cdpr_design.statics.hanging.planar2`) at positions P (k, 2)
    [m]: (phi (k,) [rad], tensions (k, 2) [N], h (k,), status (k,), balanced orientations (k,)) of
    the root it chooses (NaN where none)."""
    phis, ts, hs, ok, degenerate = planar2.planar_two_cable(A, B, c, mass, g, P)
    j, status, _, _ = planar2.choose(phis, ts, hs, ok, degenerate, mass * np.linalg.norm(g))
    rows, good = np.arange(len(P)), status == results.OK
    phi = np.where(good, phis[rows, j], np.nan)
    t = np.where(good[:, None], np.maximum(ts[rows, j], 0.0), np.nan)
    return phi, t, np.where(good, hs[rows, j], np.nan), status, ok.sum(axis=1)


@pytest.mark.slow
def test_closed_form_against_instantaneous_centre_reference():
    """The closed form = slow reference on random designs and positions (ambiguous
    poses - near-zero tension, near-neutral stability, ties - are skipped and counted)."""
    rng = np.random.default_rng(11)
    compared = skipped = 0
    for _ in range(12):
        A, B, c, mass, W, Hh = random_planar2(rng)
        P = np.column_stack([rng.uniform(-0.1 * W, 1.1 * W, 60), rng.uniform(0.0, Hh - 0.1, 60)])
        phi, t, h, status, nbal = closed_form(A, B, c, mass, G2, P)
        for k in range(len(P)):
            best, allb = ref_tilt(A, B, c, mass, P[k])
            wt = 9.81 * mass
            amb = any(abs(o[1].min()) < 1e-4 * wt or abs(o[2]) < 1e-4 * wt for o in allb)
            if best is not None:
                amb |= sum(abs(abs(o[0]) - abs(best[0])) < 1e-6 for o in allb) > 1
            if amb:
                skipped += 1
                continue
            compared += 1
            assert nbal[k] == len(allb)
            if best is None:
                assert status[k] != results.OK
                continue
            assert status[k] == results.OK
            assert phi[k] == pytest.approx(best[0], abs=1e-9)
            assert t[k] == pytest.approx(best[1], rel=1e-8, abs=1e-9 * wt)
            assert h[k] > 0
    assert compared >= 0.9 * (compared + skipped)
    print(f"closed form vs reference: {compared} positions compared, {skipped} ambiguous skipped")


def test_closed_form_status_reasons():
    d = spec.load(DESIGNS / "planar2.yaml")
    A, B, c, g = d.outlets, d.attachments, np.asarray(d.effector.center_of_mass), np.asarray(d.gravity)
    P = np.array([[0.75, 0.8], [0.75, 2.5], [3.0, 1.0], [0.2, 1.45]])
    phi, _, _, st, _ = closed_form(A, B, c, 1.0, g, P)
    assert st[0] == results.OK and abs(phi[0]) < 1e-12
    assert st[1] != results.OK and st[2] == results.PUSHING  # above the outlets / beyond them
    for s in st:
        assert isinstance(results.REASONS[s], str)
    res = [H.hanging_pose(d, p) for p in P]
    assert [r.feasible for r in res] == [s == results.OK for s in st]
    assert "pushing" in res[2].reason


def test_hanging_pose_matches_the_reference_kernel():
    rng = np.random.default_rng(5)
    for _ in range(4):
        A, B, c, mass, W, Hh = random_planar2(rng)
        P = np.column_stack([rng.uniform(0, W, 30), rng.uniform(0, Hh - 0.1, 30)])
        phi, t, _, st, _ = K.hanging_tilt_batch(A, B, c, mass, G2, P)
        for k in range(len(P)):
            r = H.hanging_pose_arrays(A, B, c, mass, G2, P[k], True)
            assert r.feasible == (st[k] == K.TILT_OK)
            if r.feasible:
                assert r.orientation == pytest.approx(phi[k], abs=1e-9)
                np.testing.assert_allclose(r.tensions, t[k], rtol=1e-8, atol=1e-9)


def instant_centre_offset(A, B, c, p, phi):
    """Horizontal distance between the cable lines' intersection and the COM [m]."""
    R = rot2(phi)
    P = p[:2] + B[:, :2] @ R.T
    C = p[:2] + R @ c[:2]
    d1, d2 = P[0] - A[0, :2], P[1] - A[1, :2]
    s = cr(A[1, :2] - A[0, :2], d2) / cr(d1, d2)
    I = A[0, :2] + s * d1
    return abs(I[0] - C[0])


def test_instantaneous_centre():
    """Both cables taut: the cable lines meet on the vertical through the COM."""
    rng = np.random.default_rng(2)
    n = 0
    for _ in range(6):
        A, B, c, mass, W, Hh = random_planar2(rng)
        P = np.column_stack([rng.uniform(0.1 * W, 0.9 * W, 50), rng.uniform(0, Hh - 0.3, 50)])
        phi, _, _, st, _ = closed_form(A, B, c, mass, G2, P)
        for k in np.flatnonzero(st == results.OK):
            assert instant_centre_offset(A, B, c, P[k], phi[k]) < 1e-9
            n += 1
        for k in np.flatnonzero(st == results.OK)[:5]:
            rho = np.linalg.norm(A[:, :2] - P[k] - B[:, :2] @ rot2(phi[k]).T, axis=1)
            r = H.fk_arrays(A, B, c, mass, G2, rho, True)
            if not r.slack:
                assert instant_centre_offset(A, B, c, r.position, r.orientation) < 1e-9
    assert n > 100


# ---------------------------------------------------------------------------
# reference: the planar two-cable body's one-DoF curve, brute force
# ---------------------------------------------------------------------------

def curve_minima(A2, B2, c2, mass, rho, n):
    """Local minima of the energy on the both-taut curve, parametrised by the angle of
    cable 0 at its outlet (two assembly branches), with tensions >= 0."""
    dB = B2[1] - B2[0]
    lb = np.linalg.norm(dB)

    def branch(th, s):
        P1 = A2[0] + rho[0] * np.stack([np.cos(th), np.sin(th)], -1)
        e = A2[1] - P1
        D = np.linalg.norm(e, axis=-1)
        a = (lb ** 2 - rho[1] ** 2 + D ** 2) / (2 * D)
        with np.errstate(invalid="ignore"):
            h = np.sqrt(lb ** 2 - a ** 2)
        nrm = np.stack([-e[..., 1], e[..., 0]], -1) / D[..., None]
        P2 = P1 + a[..., None] * e / D[..., None] + s * h[..., None] * nrm
        phi = np.arctan2((P2 - P1)[..., 1], (P2 - P1)[..., 0]) - math.atan2(dB[1], dB[0])
        co, si = np.cos(phi), np.sin(phi)
        Rb1 = np.stack([co * B2[0, 0] - si * B2[0, 1], si * B2[0, 0] + co * B2[0, 1]], -1)
        p = P1 - Rb1
        C = p + np.stack([co * c2[0] - si * c2[1], si * c2[0] + co * c2[1]], -1)
        return 9.81 * mass * C[..., 1], p, phi, P1, P2

    th = np.linspace(-np.pi, np.pi, n, endpoint=False)
    step = 2 * np.pi / n
    out = []
    for s in (1.0, -1.0):
        E = branch(th, s)[0]
        for k in range(n):
            e0, em, ep = E[k], E[k - 1], E[(k + 1) % n]
            if np.isfinite(e0) and np.isfinite(em) and np.isfinite(ep) and e0 <= em and e0 <= ep:
                r = minimize_scalar(lambda x, s=s: branch(np.array(x), s)[0], bounds=(th[k] - step, th[k] + step),
                                    method="bounded", options={"xatol": 1e-13})
                Ex, p, phi, P1, P2 = branch(np.array(r.x), s)
                u = np.array([A2[0] - P1, A2[1] - P2])
                u /= np.linalg.norm(u, axis=1)[:, None]
                t = np.linalg.solve(u.T, [0.0, 9.81 * mass])
                if t.min() >= -1e-6 * mass:
                    out.append((float(Ex), p, math.atan2(math.sin(phi), math.cos(phi)), t, ()))
    return out


def ref_fk_planar2(A, B, c, mass, rho, n=20000):
    """Global minimum first, then the other stable equilibria, of a planar body on two
    cables.  The curve is scanned twice, by the angle of either cable at its outlet, so
    that a minimum near a turning point of one parametrisation is not missed."""
    A2, B2, c2 = A[:, :2], B[:, :2], c[:2]
    cands = curve_minima(A2, B2, c2, mass, rho, n)
    for E, p, phi, t, sl in curve_minima(A2[::-1], B2[::-1], c2, mass, rho[::-1], n):
        if not any(abs(E - o[0]) < 1e-9 * mass and np.allclose(p, o[1], atol=1e-7) for o in cands):
            cands.append((E, p, phi, t[::-1], sl))
    # single-cable modes: hanging from cable i, COM straight below its attachment
    for i in (0, 1):
        j = 1 - i
        Pi = A2[i] + rho[i] * np.array([0.0, -1.0])
        arm = c2 - B2[i]
        phi = -math.pi / 2 - math.atan2(arm[1], arm[0]) if np.linalg.norm(arm) > 0 else 0.0
        R = rot2(phi)
        p = Pi - R @ B2[i]
        if np.linalg.norm(A2[j] - p - R @ B2[j]) <= rho[j] - 1e-9:
            t = np.zeros(2)
            t[i] = 9.81 * mass
            cands.append((9.81 * mass * (p + R @ c2)[1], p, math.atan2(math.sin(phi), math.cos(phi)), t, (j,)))
    cands.sort(key=lambda x: x[0])
    return cands


def random_lengths(rng, A, B, c, W, Hh, slack_bias=0.3):
    """Lengths of a random pose, or (with probability ``slack_bias``) of the body hanging
    from one cable with the other one longer than needed."""
    if rng.uniform() < slack_bias:
        i = rng.integers(2)
        arm = c[:2] - B[i, :2]
        R = rot2(-math.pi / 2 - math.atan2(arm[1], arm[0]))
        rho = np.empty(2)
        rho[i] = rng.uniform(0.3, 0.8) * Hh
        p = A[i, :2] + [0.0, -rho[i]] - R @ B[i, :2]
        rho[1 - i] = np.linalg.norm(A[1 - i, :2] - p - R @ B[1 - i, :2]) + rng.uniform(0.01, 0.3)
        return rho
    p = np.array([rng.uniform(0.1 * W, 0.9 * W), rng.uniform(0.1 * Hh, 0.8 * Hh)])
    phi = rng.uniform(-0.6, 0.6)
    rho = np.linalg.norm(A[:, :2] - p - B[:, :2] @ rot2(phi).T, axis=1)
    if rng.uniform() < 0.3:
        rho[rng.integers(2)] += rng.uniform(0.05, 0.5)
    return rho


@pytest.mark.slow
@NO_KERNELS
def test_fk_planar2_against_curve_scan():
    """Random designs and lengths: the global minimum and every stable equilibrium of the
    brute-force scan, including single-cable (slack) modes."""
    rng = np.random.default_rng(7)
    slack_modes = 0
    for trial in range(24):
        A, B, c, mass, W, Hh = random_planar2(rng)
        rho = random_lengths(rng, A, B, c, W, Hh)
        ref = ref_fk_planar2(A, B, c, mass, rho)
        r = H.fk_arrays(A, B, c, mass, G2, rho, True)
        E, p, phi, t, slack = ref[0]
        scale = 9.81 * mass
        assert r.energy == pytest.approx(E, abs=1e-8 * scale)
        # the scan's minimiser is only as sharp as the energy's flat bottom allows (~1e-7)
        np.testing.assert_allclose(r.position, p, atol=1e-6)
        assert math.remainder(r.orientation - phi, 2 * math.pi) == pytest.approx(0, abs=1e-6)
        np.testing.assert_allclose(r.tensions, t, rtol=1e-6, atol=1e-6 * scale)
        assert r.slack == slack and r.stable
        assert r.residual <= 1e-10 * max(1, scale)
        slack_modes += bool(slack)
        found = [r] + list(r.equilibria)
        for Ei, pi, phii, ti, _ in ref[1:]:
            if ti.min() > 1e-3 * scale:  # a robust stable equilibrium of the scan: found too
                assert any(abs(f.energy - Ei) < 1e-7 * scale and np.allclose(f.position, pi, atol=1e-6)
                           for f in found)
    assert slack_modes >= 3


def test_slack_mode_planar2():
    """planar2, cable 2 much too long: the body hangs from cable 1, COM under its attachment."""
    d = spec.load(DESIGNS / "planar2.yaml")
    r = H.fk(d, [0.5, 1.6])
    assert r.slack == (1,) and r.tensions[0] == pytest.approx(9.81) and r.tensions[1] == 0
    assert r.tilt_deg == pytest.approx(45.0, abs=1e-9)
    P1 = r.position + r.rotation[:2, :2] @ d.attachments[0, :2]
    np.testing.assert_allclose(P1, [0.0, 1.0], atol=1e-12)


# ---------------------------------------------------------------------------
# reference: multi-start SLSQP
# ---------------------------------------------------------------------------

def ref_slsqp(A, B, c, mass, g, rho, planar, rng, starts=30):
    """Lowest energy over SLSQP runs from random starts (x, y[, z], angles)."""
    d = 2 if planar else 3

    def conf(x):
        R = rot2(x[2]) if planar else euler(*x[3:6])
        p = x[:d]
        return p, R

    Ad, Bd, cd, gd = A[:, :d], B[:, :d], c[:d], g[:d]

    def energy(x):
        p, R = conf(x)
        return -mass * gd @ (p + R @ cd)

    def cons(x):
        p, R = conf(x)
        return rho ** 2 - np.sum((Ad - p - Bd @ R.T) ** 2, axis=1)

    best = None
    lo, hi = Ad.min(0) - rho.max(), Ad.max(0)
    for _ in range(starts):
        x0 = np.concatenate([rng.uniform(lo, hi), rng.uniform(-np.pi, np.pi, 1 if planar else 3)])
        s = minimize(energy, x0, method="SLSQP", constraints=[{"type": "ineq", "fun": cons}],
                     options={"ftol": 1e-13, "maxiter": 500})
        if cons(s.x).min() < -1e-8:
            continue
        if best is None or s.fun < best[0]:
            best = (s.fun, s.x)
    return best


def check_equilibrium(A, B, c, mass, g, rho, e, planar):
    """An Equilibrium is a KKT point: balance, lengths, complementarity, t >= 0."""
    d = 2 if planar else 3
    p = np.zeros(3)
    p[:d] = e.position
    R = e.rotation
    l = A - p - B @ R.T
    L = np.linalg.norm(l, axis=1)
    u = l / L[:, None]
    scale = mass * np.linalg.norm(g)
    f = u.T @ e.tensions + mass * g
    mo = np.cross(B @ R.T, u).T @ e.tensions + np.cross(R @ c, mass * g)
    assert np.all(e.tensions >= 0)
    assert np.all(L <= rho + 1e-9)
    taut = e.tensions > 1e-9 * scale
    np.testing.assert_allclose(L[taut], rho[taut], atol=1e-9)
    assert np.max(np.abs(f)) <= 1e-9 * scale + 1e-12
    if not np.allclose(B, B[0]):
        assert np.max(np.abs(mo if not planar else mo[2:])) <= 1e-9 * scale + 1e-12
    assert e.stable or abs(e.hessian_min) <= 1e-8 * scale  # stable, or neutral (a zero mode)


@pytest.mark.slow
@NO_KERNELS
@pytest.mark.parametrize("planar,m,trials", [(True, 1, 3), (True, 2, 4), (True, 3, 4), (True, 4, 3),
                                             (False, 2, 2), (False, 3, 3), (False, 4, 2)])
def test_fk_against_multistart_slsqp(planar, m, trials):
    rng = np.random.default_rng(100 + m + 10 * planar)
    for _ in range(trials):
        d = 2 if planar else 3
        g = G2 if planar else G3
        ang = np.sort(rng.uniform(0, 2 * np.pi, m)) if not planar else None
        if planar:
            A = np.column_stack([np.sort(rng.uniform(0, 2, m)), rng.uniform(1.5, 2.0, m), np.zeros(m)])
            B = np.column_stack([rng.uniform(-0.15, 0.15, m), rng.uniform(-0.1, 0.1, m), np.zeros(m)])
            c = np.array([rng.uniform(-0.05, 0.05), rng.uniform(-0.1, 0.05), 0.0])
            p0 = np.array([rng.uniform(0.3, 1.7), rng.uniform(0.2, 1.2), 0.0])
            R0 = np.eye(3)
            R0[:2, :2] = rot2(rng.uniform(-0.5, 0.5))
        else:
            A = np.column_stack([2 * np.cos(ang), 2 * np.sin(ang), rng.uniform(2.5, 3.0, m)])
            B = np.column_stack([0.2 * np.cos(ang + rng.uniform(-0.5, 0.5, m)),
                                 0.2 * np.sin(ang + rng.uniform(-0.5, 0.5, m)), rng.uniform(-0.05, 0.05, m)])
            c = np.array([rng.uniform(-0.03, 0.03), rng.uniform(-0.03, 0.03), rng.uniform(-0.15, 0.0)])
            p0 = np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(0.5, 1.5)])
            R0 = euler(*rng.uniform(-0.4, 0.4, 3))
        rho = np.linalg.norm(A - p0 - B @ R0.T, axis=1) + rng.uniform(0, 0.05, m)
        mass = rng.uniform(0.5, 3.0)
        r = H.fk_arrays(A, B, c, mass, g, rho, planar)
        ref = ref_slsqp(A, B, c, mass, g, rho, planar, rng, starts=30 if planar else 16)
        assert ref is not None
        scale = mass * 9.81
        assert r.energy <= ref[0] + 1e-7 * scale  # never worse than the reference
        assert r.energy == pytest.approx(ref[0], abs=1e-5 * scale)
        for e in (r, *r.equilibria):
            check_equilibrium(A, B, c, mass, g, rho, e, planar)
        assert [e.energy for e in r.equilibria] == sorted(e.energy for e in r.equilibria)
        assert all(e.energy >= r.energy for e in r.equilibria)
        assert r.underconstrained == (m < (3 if planar else 6))
        del d


# ---------------------------------------------------------------------------
# point mass: the convex problem
# ---------------------------------------------------------------------------

@pytest.mark.slow
@NO_KERNELS
def test_point_mass_against_cvxpy():
    cp = pytest.importorskip("cvxpy")
    rng = np.random.default_rng(4)
    for d, m in [(2, 1), (2, 2), (2, 3), (3, 1), (3, 2), (3, 3), (3, 4), (3, 5)]:
        for _ in range(3):
            A = np.zeros((m, 3))
            A[:, :d] = rng.uniform(-2, 2, (m, d))
            A[:, d - 1] = rng.uniform(2, 3, m)
            g = G2 if d == 2 else G3
            q0 = np.zeros(d)
            q0[:d - 1] = rng.uniform(-1, 1, d - 1)
            q0[d - 1] = rng.uniform(0, 1)
            rho = np.linalg.norm(A[:, :d] - q0, axis=1) + rng.uniform(0, 0.3, m)
            x = cp.Variable(d)
            prob = cp.Problem(cp.Minimize(-g[:d] @ x), [cp.norm(x - A[i, :d]) <= rho[i] for i in range(m)])
            prob.solve(solver=cp.CLARABEL)
            r = H.fk_arrays(A, np.zeros((m, 3)), np.zeros(3), 1.5, g, rho, d == 2)
            assert r.model == "point"
            # the height is flat (quadratic) across a ball's lowest point: an interior-point
            # solution's position is good to ~sqrt(its tolerance); compare heights sharply
            np.testing.assert_allclose(r.position, x.value, atol=1e-4)
            assert -g[:d] @ r.position == pytest.approx(prob.value, abs=1e-6)
            check_equilibrium(A, np.zeros((m, 3)), np.zeros(3), 1.5, g, rho, r, d == 2)
            assert r.equilibria == ()


def test_point_mass_lowest_trilateration_point_needs_a_pushing_cable():
    """Three outlets; the lengths put the lower trilateration point outside the
    prism over the outlet triangle, where cable 2 would have to push.  The mass
    hangs lower, from cables 0 and 1, with cable 2 slack."""
    A = np.array([[0.0, 0.0, 3.0], [2.0, 0.0, 3.0], [1.0, 1.5, 3.0]])
    P = np.array([1.0, -1.0, 1.0])  # below and outside the triangle (y < 0)
    rho = np.linalg.norm(A - P, axis=1)
    u = (A - P) / rho[:, None]
    t_tri = np.linalg.solve(u.T, [0, 0, 9.81])
    assert t_tri[2] < 0  # the trilateration point needs cable 2 to push
    r = H.fk_arrays(A, np.zeros((3, 3)), np.zeros(3), 1.0, G3, rho, False)
    assert r.slack == (2,)
    assert r.position[2] < P[2] - 1e-3
    assert np.linalg.norm(A[2] - r.position) < rho[2] - 1e-3
    np.testing.assert_allclose(np.linalg.norm(A[:2] - r.position, axis=1), rho[:2], atol=1e-12)
    check_equilibrium(A, np.zeros((3, 3)), np.zeros(3), 1.0, G3, rho, r, False)
    # the old answer (kinematics.forward_kinematics on a 3T design) is the trilateration point
    d = spec.from_dict({"name": "pm3", "motion": "3T", "gravity": [0, 0, -9.81],
                        "frame": {"lower": [-1, -2, 0], "upper": [3, 2, 3]},
                        "effector": {"mass": 1.0, "size": [0.01, 0.01, 0.01]}, "tension": [0, 100],
                        "cables": [{"name": f"c{i}", "outlet": A[i].tolist(), "attachment": [0, 0, 0]}
                                   for i in range(3)],
                        "workspace": {"grid": {"step": 0.5}}})
    old = kin.forward_kinematics(d, rho, guess=[1.0, -0.5, 1.2])
    np.testing.assert_allclose(old.pose, P, atol=1e-6)
    new = H.fk(d, rho)
    np.testing.assert_allclose(new.position, r.position, atol=1e-12)


# ---------------------------------------------------------------------------
# planar2: the figures
# ---------------------------------------------------------------------------

def planar2_with_com(cy):
    d = spec.load(DESIGNS / "planar2.yaml")
    return d, np.array([0.0, cy, 0.0])


def test_planar2_equal_lengths_keep_it_level():
    d, _ = planar2_with_com(0.0)
    for L in np.linspace(0.8, 2.0, 7):
        for cy in (0.0, 0.03):
            r = H.fk_arrays(d.outlets, d.attachments, [0, cy, 0], 1.0, d.gravity, [L, L], True)
            assert abs(r.orientation) < 1e-12 and r.position[0] == pytest.approx(0.75, abs=1e-12)
            assert r.slack == () and r.stable


def planar2_level_scan(cy, margin=0.12, step=0.02):
    """The tool's level lengths (inverse kinematics with R = I) for commanded positions
    at least ``margin`` from every frame edge, and where planar2 really rests for them:
    (max tilt [deg], its commanded position, max position error [m]).  The region's
    boundary is scanned every ``step`` (its left half: the design is mirror-symmetric)
    and its interior every 0.1 m."""
    d = spec.load(DESIGNS / "planar2.yaml")
    A, B, c = d.outlets, d.attachments, np.array([0.0, cy, 0.0])
    edge = np.round(np.arange(margin, 1.5 - margin + 1e-9, step), 9)
    inner = np.round(np.arange(margin + 0.05, 1.5 - margin, 0.1), 9)
    pts = ([(margin, y) for y in edge] + [(1.5 - margin, y) for y in edge[:1]]
           + [(x, y) for x in edge if x <= 0.75 for y in (margin, 1.5 - margin)]
           + [(x, y) for x in inner for y in inner])
    worst, where, err = 0.0, None, 0.0
    for p in pts:
        L = np.linalg.norm(A[:, :2] - np.array(p) - B[:, :2], axis=1)
        r = H.fk_arrays(A, B, c, 1.0, d.gravity, L, True)
        err = max(err, float(np.linalg.norm(r.position - p)))
        if r.tilt_deg > worst:
            worst, where = r.tilt_deg, p
    return worst, where, err


@pytest.mark.slow
@NO_KERNELS
@pytest.mark.parametrize("cy,tilt,pos_err", [(0.0, 33.4, 0.043), (0.03, 45.3, 0.057)])
def test_planar2_level_lengths_tilt(cy, tilt, pos_err):
    """The issue's figures (~33 and ~44 deg), reproduced by this scan: the current tool
    commands the level inverse kinematics; for commanded positions one effector width
    (0.12 m) or more inside the frame, planar2 really rests tilted by up to 33.4 deg
    (COM 0.06 m below the attachment line) and 45.3 deg (COM 0.03 m below), near the
    lower corners (commanded (0.12, 0.16) and (0.12, 0.12)), and up to 4.3 and 5.7 cm away
    from the commanded position."""
    worst, where, err = planar2_level_scan(cy)
    assert worst == pytest.approx(tilt, abs=0.3)
    assert where[0] == pytest.approx(0.12) and where[1] < 0.3
    assert err == pytest.approx(pos_err, abs=0.003)


@pytest.fixture(scope="module")
def planar2_maps():
    """The tilt map of planar2 over its frame, every 0.01 m (151 x 151 positions), for the
    COM 0.06 m below the attachment line (the spec's) and 0.03 m below."""
    d = spec.load(DESIGNS / "planar2.yaml")
    out = {}
    for cy in (0.0, 0.03):
        dd = d.replace(effector=d.effector.__class__(**{**vars(d.effector), "center_of_mass": (0.0, cy, 0.0)}))
        out[cy] = (dd, tilt_map(dd))
    return out


def box_inside(tm, half=0.06, lo=0.0, hi=1.5):
    X, Y = np.meshgrid(*tm.axes, indexing="ij")
    co, si = np.cos(tm.phi), np.sin(tm.phi)
    ok = tm.feasible.copy()
    for sx in (-half, half):
        for sy in (-half, half):
            qx, qy = X + co * sx - si * sy, Y + si * sx + co * sy
            ok &= (qx >= lo) & (qx <= hi) & (qy >= lo) & (qy <= hi)
    return ok


@pytest.mark.parametrize("cy,origin_max,box_max", [(0.0, 45.0, 38.3), (0.03, 61.1, 52.9)])
def test_planar2_tilt_figures(planar2_maps, cy, origin_max, box_max):
    """The hanging orientation at commanded positions (the tilt map; the issue's figures
    come from the level-lengths scan above).

    Scan: every position of the 151 x 151 grid over the 1.5 m frame; at each,
    the stable hanging orientation with both cables taut (the lengths that put
    the effector there are one length pair).  Maximum tilt (a) over the
    positions where the platform origin is in the frame: 45.0 / 61.1 deg, at the
    lower corners, where the body tends to hang from one cable (its limit is
    atan(0.06/0.06) = 45 and atan(0.06/0.03) = 63.4 deg); (b) where the whole
    tilted 0.12 m effector is inside the frame: 38.3 / 52.9 deg, at (0.09, 0.09)
    and its mirror image.  Only ~4-5 % of the frame cannot be hung at (along the
    top edge, where the balanced orientations are unstable or need a pushing cable).
    """
    d, tm = planar2_maps[cy]
    assert tm.phi.shape == (151, 151)
    assert np.nanmax(tm.tilt_deg[tm.feasible]) == pytest.approx(origin_max, abs=0.1)
    inside = box_inside(tm)
    k = np.nanargmax(np.where(inside, tm.tilt_deg, np.nan))
    assert tm.tilt_deg.ravel()[k] == pytest.approx(box_max, abs=0.1)
    assert 0.94 < tm.feasible.mean() < 0.97
    assert np.all(tm.feasible[tm.within_limits]) and 0.5 < tm.within_limits.mean() < tm.feasible.mean()
    # symmetric design: the map is mirror-symmetric, level on the centre line
    np.testing.assert_allclose(tm.phi[75][tm.feasible[75]], 0.0, atol=1e-12)
    np.testing.assert_allclose(tm.phi, -tm.phi[::-1], atol=1e-9, equal_nan=True)
    # the worst pose is where the robot really rests for its lengths (global minimum)
    i, j = np.unravel_index(k, tm.phi.shape)
    p = np.array([tm.axes[0][i], tm.axes[1][j]])
    at = H.hanging_pose(d, p)
    r = H.fk(d, at.lengths)
    np.testing.assert_allclose(r.position, p, atol=1e-9)
    assert r.orientation == pytest.approx(tm.phi[i, j], abs=1e-9)


def test_planar2_tilt_is_larger_with_com_closer_to_the_line(planar2_maps):
    t0, t3 = planar2_maps[0.0][1], planar2_maps[0.03][1]
    both = t0.feasible & t3.feasible
    assert np.all(t3.tilt_deg[both] >= t0.tilt_deg[both] - 1e-9)


# ---------------------------------------------------------------------------
# fully constrained designs, unreachable lengths, hanging_pose
# ---------------------------------------------------------------------------

def wrench_closure(d, pose):
    W = kin.structure_matrix(d, pose)
    res = linprog(np.zeros(W.shape[1]), A_eq=W, b_eq=np.zeros(W.shape[0]), bounds=[(1, None)] * W.shape[1])
    return res.status == 0


@pytest.mark.slow
@NO_KERNELS
@pytest.mark.parametrize("name,poses", [
    ("planar4.yaml", [[1.0, 0.75, 0.0], [1.3, 1.0, -0.2], [0.8, 0.6, 0.05]]),
    ("ipanema1.yaml", [[0, 0, 1, 0, 0, 0], [0.3, -0.2, 0.9, 0.05, -0.03, 0.1]]),
])
def test_fully_constrained_gives_the_ik_pose_back(name, poses):
    d = spec.load(DESIGNS / name)
    assert not underconstrained(d)
    for pose in poses:
        assert wrench_closure(d, pose)
        r = H.fk(d, kin.inverse_kinematics(d, pose))
        np.testing.assert_allclose(r.pose, pose, atol=1e-8)
        assert r.stable and not r.underconstrained
        W = kin.structure_matrix(d, pose)
        np.testing.assert_allclose(W @ r.tensions, kin.required_wrench(d, pose), atol=1e-8)


def test_unreachable_lengths_raise():
    d = spec.load(DESIGNS / "planar2.yaml")
    with pytest.raises(H.UnreachableLengths, match="cannot both reach"):
        H.fk(d, [0.6, 0.7])
    assert issubclass(H.UnreachableLengths, ValueError)
    # three discs that meet pairwise but have no common point (point mass, plane)
    A = np.array([[0.0, 2.0, 0], [2.0, 2.0, 0], [1.0, 2.0 + math.sqrt(3), 0]])
    with pytest.raises(H.UnreachableLengths, match="no common point"):
        H.fk_arrays(A, np.zeros((3, 3)), np.zeros(3), 1.0, G2, [1.05] * 3, True)
    # fully constrained planar4: lengths 1 cm shorter than its IK lengths
    d4 = spec.load(DESIGNS / "planar4.yaml")
    with pytest.raises(H.UnreachableLengths, match="no configuration"):
        H.fk(d4, kin.inverse_kinematics(d4, [1.0, 0.75, 0.0]) - 0.01)
    with pytest.raises(ValueError):
        H.fk(d, [1.0, -1.0])
    with pytest.raises(ValueError, match="pinned"):
        H.fk(d, [0.0, 1.38])


@NO_KERNELS
def test_hanging_pose():
    d = spec.load(DESIGNS / "planar2.yaml")
    r = H.hanging_pose(d, [0.75, 0.8])
    assert r.feasible and abs(r.orientation) < 1e-12 and r.tilt_deg < 1e-12 and r.stable
    r = H.hanging_pose(d, [0.3, 0.5])
    assert r.feasible and r.tilt_deg == pytest.approx(math.degrees(abs(r.orientation)))
    back = H.fk(d, r.lengths)  # the lengths it reports put it there
    np.testing.assert_allclose(back.pose, r.pose, atol=1e-9)
    np.testing.assert_allclose(r.pose[:2], [0.3, 0.5])
    assert r.within_limits  # planar2: 0 <= t <= 20 N
    high = H.hanging_pose(d, [0.75, 1.4])
    assert high.feasible and high.tensions.max() > 20 and high.within_limits is False
    assert H.fk(d, high.lengths).within_limits is False
    bad = H.hanging_pose(d, [3.0, 1.0])
    assert not bad.feasible and "pushing" in bad.reason and math.isnan(bad.tilt_deg)
    with pytest.raises(H.NotUnderconstrained):
        H.hanging_pose(spec.load(DESIGNS / "planar4.yaml"), [1.0, 0.75])
    # a spatial rigid body on three cables: the balanced orientation is where fk puts it
    ang = np.array([0.0, 2.1, 4.2])
    A = np.column_stack([2 * np.cos(ang), 2 * np.sin(ang), np.full(3, 3.0)])
    B = np.column_stack([0.2 * np.cos(ang + 0.3), 0.2 * np.sin(ang + 0.3), np.full(3, 0.05)])
    c = np.array([0.02, -0.01, -0.1])
    for p in ([0.2, -0.1, 1.0], [1.2, 0.3, 1.5]):
        a = H.hanging_pose_arrays(A, B, c, 2.0, G3, p, False)
        assert a.feasible and a.stable
        f = H.fk_arrays(A, B, c, 2.0, G3, a.lengths, False)
        np.testing.assert_allclose(f.position, p, atol=1e-8)
        np.testing.assert_allclose(f.rotation, a.rotation, atol=1e-8)
    # a point mass on one cable hangs only straight below its outlet
    pm = H.hanging_pose_arrays(A[:1], np.zeros((1, 3)), np.zeros(3), 1.0, G3, [0.5, 0.0, 1.0], False)
    assert not pm.feasible
    pm = H.hanging_pose_arrays(A[:1], np.zeros((1, 3)), np.zeros(3), 1.0, G3, [2.0, 0.0, 1.0], False)
    assert pm.feasible and pm.tensions[0] == pytest.approx(9.81)


def test_results_convert_to_plain_data():
    d = spec.load(DESIGNS / "planar2.yaml")
    r = H.fk(d, [0.9, 1.2]).to_dict()
    assert set(r) >= {"position", "orientation", "tilt_deg", "tensions", "slack", "stable", "equilibria"}
    assert isinstance(r["orientation"], float)
    a = H.hanging_pose(d, [0.4, 0.4]).to_dict()
    assert a["feasible"] and isinstance(a["tilt_deg"], float)
