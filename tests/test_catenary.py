"""Elastic catenary kernels against independent, slow references.

References, none of which evaluates Irvine's closed form:

* a lumped-mass chain (N elastic springs EA/l between point weights w l), both
  ends fixed, solved for its equilibrium by minimising its potential energy
  with scipy (banded Newton, energy line search) from a shape that knows
  nothing of the catenary;
* MoorPy's quasi-static mooring-line solver (a test-only dependency);
* closed forms of the two limits: the straight elastic spring (w -> 0) and
  the inextensible catenary y = a cosh(x/a) (EA -> inf);
* finite differences for the Jacobian; the forward map for the inverse.

Everything here also passes with NUMBA_DISABLE_JIT=1.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.linalg import solveh_banded
from scipy.optimize import brentq

from cdpr_design.kernels import catenary as C
from cdpr_design.kernels import catenary_inv as CS

NAN = math.nan
EPS = np.finfo(float).eps


def forces_from(H, VB, L0, w):
    return np.array([H, VB, VB + w * L0])


def force_scale(H, VB, L0, w):
    return max(H, abs(VB), abs(VB + w * L0))


# ---------------------------------------------------------------------------
# the lumped-mass chain
# ---------------------------------------------------------------------------

def chain_solve(X, Z, L0, w, EA, N, maxit=400):
    """Equilibrium of a chain of N springs (stiffness EA/l, l = L0/N, no
    compression) between B = (0, 0) and A = (X, Z); the N-1 free nodes weigh
    w l each (the half-segment weights at the ends go straight to the supports).

    The potential energy sum_k EA/(2l) max(|p_k+1 - p_k| - l, 0)^2 + sum_j w l z_j
    is convex, so its minimiser is the unique equilibrium; it is found by
    Newton steps on the block-tridiagonal Hessian (scipy.linalg.solveh_banded)
    with an Armijo line search on the energy, in units of L0 and of a force
    scale.  Start: the chord sagged vertically by a parabola and resampled to
    equal arcs 2 % longer than l (or the chord itself if longer), so every
    spring starts taut.  A stiff cable (EA above 1e3 times the force scale) is
    reached by continuation in EA (factors of 100) from that start.

    Returns (H, VB, VA, sag, nodes, info): end forces as in the kernels (VB of
    the cable on B, up positive; VA of the cable on A, down positive), the
    largest distance from the chord (the vertex of the parabola through the
    farthest node and its neighbours), node positions [m] (N+1, 2) from B.
    """
    c = math.hypot(X, Z)
    Fs = w * L0 + (EA * (c / L0 - 1.0) if c > L0 else 0.0)
    lh = 1.0 / N
    kk = (EA / Fs) / lh  # spring stiffness, in units of Fs / L0 (changed by the continuation below)
    mg = (w * L0 / N) / Fs
    A = np.array([X, Z]) / L0
    n = N - 1
    tf = np.linspace(0.0, 1.0, 40 * N + 1)

    def curve(sg):
        return np.column_stack([tf * A[0], tf * A[1] - 4.0 * sg * tf * (1.0 - tf)])

    def clen(sg):
        return np.sum(np.hypot(*np.diff(curve(sg), axis=0).T))

    sg = 0.0 if clen(0.0) >= 1.02 else brentq(lambda s: clen(s) - 1.02, 0.0, 10.0)
    Cf = curve(sg)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(Cf, axis=0).T))])
    sn = np.linspace(0.0, arc[-1], N + 1)
    x = np.column_stack([np.interp(sn, arc, Cf[:, 0]), np.interp(sn, arc, Cf[:, 1])])[1:-1].ravel()

    def segs(x):
        P = np.empty((N + 1, 2))
        P[0] = 0.0
        P[-1] = A
        P[1:-1] = x.reshape(-1, 2)
        D = np.diff(P, axis=0)
        return P, D, np.hypot(D[:, 0], D[:, 1])

    def energy(x):
        P, D, d = segs(x)
        e = np.maximum(d - lh, 0.0)
        return 0.5 * kk * (e @ e) + mg * np.sum(P[1:-1, 1])

    def grad(x):
        P, D, d = segs(x)
        Fv = (kk * np.maximum(d - lh, 0.0) / d)[:, None] * D
        g = Fv[:-1] - Fv[1:]
        g[:, 1] += mg
        return g.ravel()

    def hess_banded(x):
        P, D, d = segs(x)
        e = np.maximum(d - lh, 0.0)
        u = D / d[:, None]
        uu = u[:, :, None] * u[:, None, :]
        axial = np.where(e > 0.0, 1.0, 1e-6)  # a slack spring: small stand-in stiffness
        trans = np.maximum(e / d, 1e-9)
        K = kk * (axial[:, None, None] * uu + trans[:, None, None] * (np.eye(2)[None] - uu))
        Dg = K[:-1] + K[1:]
        O = -K[1:-1]
        ab = np.zeros((4, 2 * n))
        ab[3, 0::2] = Dg[:, 0, 0]
        ab[3, 1::2] = Dg[:, 1, 1]
        ab[2, 1::2] = Dg[:, 0, 1]
        ab[2, 2::2] = O[:, 1, 0]
        ab[1, 2::2] = O[:, 0, 0]
        ab[1, 3::2] = O[:, 1, 1]
        ab[0, 3::2] = O[:, 0, 1]
        return ab

    def newton(x, maxit):
        # round-off floor of the node force balance: the spring forces kk (d - l)
        # carry the rounding of d (~eps/N) times kk
        gfloor = 1e3 * EPS * (kk * lh + 1.0)
        best, stall, it = np.inf, 0, 0
        for it in range(maxit):
            g = grad(x)
            gn = np.max(np.abs(g))
            if gn <= 1e-2 * gfloor:
                break
            if gn < 0.5 * best:
                best, stall = gn, 0
            else:
                stall += 1
                if stall >= 5 and gn <= gfloor:
                    break
            p = solveh_banded(hess_banded(x), -g)
            E0 = energy(x)
            gp = g @ p
            a = 1.0
            if abs(gp) > 1e-13 * (abs(E0) + 1.0):  # otherwise the energy cannot resolve the decrease
                while energy(x + a * p) > E0 + 1e-4 * a * gp and a > 1e-10:
                    a *= 0.5
            x = x + a * p
        return x, it, gfloor

    # continuation in the stiffness for a stiff cable: from a strain ~1e-2 up to
    # EA by factors of 100, each stage started from the last one's equilibrium
    stages = [EA]
    while stages[-1] > 1e3 * Fs:
        stages.append(stages[-1] / 100.0)
    nit = 0
    for EAk in stages[::-1]:
        kk = (EAk / Fs) / lh
        x, it, gfloor = newton(x, maxit)
        nit += it
    it = nit
    g = grad(x)
    P, D, d = segs(x)
    f = kk * np.maximum(d - lh, 0.0)
    u = D / d[:, None]
    H = f[0] * u[0, 0] * Fs
    VB = (f[0] * u[0, 1] - 0.5 * mg) * Fs
    VA = (f[-1] * u[-1, 1] + 0.5 * mg) * Fs
    dist = (P[:, 0] * A[1] - P[:, 1] * A[0]) / np.hypot(*A) * L0
    k = int(np.argmax(dist))
    sag = dist[k]
    if 0 < k < N:
        y0, y1, y2 = dist[k - 1], dist[k], dist[k + 1]
        den = y0 - 2.0 * y1 + y2
        if den < 0.0:
            sag = y1 - 0.125 * (y2 - y0) ** 2 / den
    info = dict(nit=it, gnorm=float(np.max(np.abs(g))), gfloor=gfloor,
                hspread=float(np.ptp(f * u[:, 0]) * Fs / max(abs(H), 1e-300)))
    return H, VB, VA, sag, P * L0, info


def chain_cases():
    """(H, VB, L0, w, EA): random spans, slopes, weights and stretches, then
    hand-picked ones.  d = w L0 / H <= 5 keeps the radius of curvature H/w of
    the cable at least 40 chain segments (N = 200), where the chain is in its
    asymptotic, second-order regime."""
    rng = np.random.default_rng(20240611)
    out = []
    for _ in range(36):
        L0 = 10 ** rng.uniform(-0.5, 1.5)
        w = 10 ** rng.uniform(-2, 1)
        d = 10 ** rng.uniform(-2, math.log10(5.0))
        H = w * L0 / d
        VB = H * math.tan(math.radians(rng.uniform(-87, 87)))
        T = max(math.hypot(H, VB), math.hypot(H, VB + w * L0))
        EA = T / 10 ** rng.uniform(-5, -1.5)
        out.append((H, VB, L0, w, EA))
    out += [
        (0.05, 1.0, 4.0, 1.0, 1e5),      # near vertical, hanging from A (VB > 0)
        (0.05, -6.0, 4.0, 1.0, 1e5),     # near vertical, hanging from B (A below B)
        (1.0, -2.0, 4.0, 1.0, 1e4),      # U: lowest point inside the span
        (1.0, -4.0, 4.0, 1.0, 1e4),      # lowest point at B (VA = 0)
        (200.0, 30.0, 5.0, 2.0, 2e4),    # 1 % stretch, taut
        (20.0, -50.0, 5.0, 2.0, 5e4),    # falling, A below B, stretched
        (3.0, 2.0, 10.0, 1.5, 1e6),      # almost inextensible (strain 1e-5), slack
    ]
    return out


@pytest.mark.parametrize("case", chain_cases(), ids=lambda c: "H%.3g_VB%.3g_L%.3g_w%.3g_EA%.3g" % c)
def test_chain_matches_catenary(case):
    """End forces, sag and shape of the chain converge to the catenary's at second order.

    Node equilibrium makes H the same in every segment and gives segment k (from
    B) the vertical force VB + w l (k + 1/2): the value of V(s) at the segment's
    midpoint.  The chain is therefore exactly the midpoint rule applied to the
    closure integrals X = int (1 + T/EA) H/T ds, Z = int (1 + T/EA) V/T ds, whose
    error has an expansion in even powers of l: for the same (X, Z) the chain's
    end forces are the catenary's plus J^-1 c2 l^2 + O(l^4).  So we check (i)
    the error ratio between N = 200 and N = 400 is 4 (second order) wherever it
    is well above round-off, (ii) Richardson's extrapolation (4 F_400 - F_200)/3
    agrees to 1e-8 of the largest end force, (iii) the raw N = 200 error stays
    below 5e-5 (3x the largest seen over these cases: it grows with (w l / T)^2
    divided by the strain, because a stiff cable turns a closure error into a
    large force error).
    """
    H, VB, L0, w, EA = case
    X, Z = C.catenary_ends(H, VB, L0, w, EA)
    h, v, status, _ = CS.catenary_inverse(X, Z, L0, w, EA, NAN, NAN, 1e-13, 100)
    assert status == CS.CAT_CONVERGED
    F = force_scale(h, v, L0, w)
    ref = forces_from(h, v, L0, w)
    # the forward map was fed the generating forces: the inverse must give them back
    assert np.max(np.abs(ref - forces_from(H, VB, L0, w))) <= 1e-9 * F
    sag_c, _ = C.catenary_sag(h, v, L0, w, EA)
    got = {}
    for N in (200, 400):
        Hc, VBc, VAc, sag, P, info = chain_solve(X, Z, L0, w, EA, N)
        assert info["gnorm"] <= info["gfloor"], info           # equilibrium reached
        assert info["hspread"] <= 1e-7, info                    # H constant along the chain
        got[N] = (np.array([Hc, VBc, VAc]), sag, P)
    e200 = np.max(np.abs(got[200][0] - ref)) / F
    e400 = np.max(np.abs(got[400][0] - ref)) / F
    assert e200 <= 5e-5
    if e400 >= 1e-7:
        assert 3.4 <= e200 / e400 <= 4.6, (e200, e400)
    extrap = (4.0 * got[400][0] - got[200][0]) / 3.0
    assert np.max(np.abs(extrap - ref)) <= 1e-8 * F
    # sag: second order too (node positions and the vertex fit)
    s200 = abs(got[200][1] - sag_c) / sag_c
    s_ex = abs((4.0 * got[400][1] - got[200][1]) / 3.0 - sag_c) / sag_c
    assert s200 <= 1e-4
    assert s_ex <= 1e-6
    # shape: chain nodes against the profile at s = k l
    for N in (200, 400):
        s = np.linspace(0.0, L0, N + 1)
        x, z = C.catenary_profile(h, v, L0, w, EA, s)
        err = np.max(np.hypot(got[N][2][:, 0] - x, got[N][2][:, 1] - z)) / L0
        assert err <= (2e-4 if N == 200 else 5e-5)
    s = np.linspace(0.0, L0, 201)
    x, z = C.catenary_profile(h, v, L0, w, EA, s)
    Pex = (4.0 * got[400][2][::2] - got[200][2]) / 3.0
    assert np.max(np.hypot(Pex[:, 0] - x, Pex[:, 1] - z)) <= 1e-7 * L0


@pytest.mark.parametrize("Z", [5.01, -5.01, 0.3, -2.0, 4.9999])
def test_chain_vertical(Z):
    """X = 0: hanging taut cables agree with the chain exactly (the integrand is
    constant); a folded cable (VB < 0 < VA) only at first order, since the
    chain's fold sits on a node: the error is at most half a node weight."""
    L0, w, EA = 5.0, 2.0, 1e4
    h, v, status, _ = CS.catenary_inverse(0.0, Z, L0, w, EA, NAN, NAN, 1e-13, 100)
    assert status == CS.CAT_CONVERGED and h == 0.0
    for N in (200, 400):
        Hc, VBc, VAc, _, P, info = chain_solve(0.0, Z, L0, w, EA, N)
        assert info["gnorm"] <= info["gfloor"]
        assert Hc == pytest.approx(0.0, abs=1e-12)
        assert np.max(np.abs(P[:, 0])) <= 1e-12
        folded = v < 0.0 < v + w * L0
        tol = 0.5 * w * L0 / N + 1e-9 if folded else 1e-9 * (abs(v) + w * L0)
        assert abs(VBc - v) <= tol
        assert abs(VAc - (v + w * L0)) <= tol


# ---------------------------------------------------------------------------
# MoorPy (test-only dependency)
# ---------------------------------------------------------------------------

def test_moorpy_agreement():
    """MoorPy's catenary (end 1 = our B, end 2 = our A; seabed placed far below)
    returns (H, VB, -H, -VA) for the same span and height.  Its own solver
    stops at a displacement tolerance, so the agreement is limited by it; cases
    where it falls back to its taut-line approximation (ProfileType -1, -2) are
    left out, and must stay rare."""
    moorpy_catenary = pytest.importorskip(
        "moorpy.Catenary", reason="moorpy (test extra) is not installed").catenary
    rng = np.random.default_rng(11)
    worst, compared, skipped = 0.0, 0, 0
    for _ in range(200):
        L0 = 10 ** rng.uniform(-0.5, 1.5)
        w = 10 ** rng.uniform(-2, 1)
        d = 10 ** rng.uniform(-2, 1.5)
        H = w * L0 / d
        VB = H * math.tan(math.radians(rng.uniform(-89, 89)))
        T = max(math.hypot(H, VB), math.hypot(H, VB + w * L0))
        EA = T / 10 ** rng.uniform(-5, -1.5)
        X, Z = C.catenary_ends(H, VB, L0, w, EA)
        h, v, status, _ = CS.catenary_inverse(X, Z, L0, w, EA, NAN, NAN, 1e-13, 100)
        assert status == CS.CAT_CONVERGED
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fAH, fAV, fBH, fBV, info = moorpy_catenary(X, Z, L0, EA, w, CB=-1e3 * (L0 + 1.0),
                                                      Tol=1e-12, MaxIter=500)
        if info["ProfileType"] in (-1, -2):
            skipped += 1
            continue
        F = force_scale(h, v, L0, w)
        err = max(abs(fAH - h), abs(fAV - v), abs(-fBH - h), abs(-fBV - (v + w * L0))) / F
        worst = max(worst, err)
        compared += 1
    assert skipped <= 10
    assert worst <= 1e-7, worst


# ---------------------------------------------------------------------------
# limits
# ---------------------------------------------------------------------------

forces = st.tuples(
    st.floats(0.0, 89.5),                      # |angle| of the force at B [deg]
    st.sampled_from([-1.0, 1.0]),
    st.floats(-1.0, 4.0),                      # log10 tension [N]
    st.floats(-1.0, 2.0),                      # log10 L0 [m]
    st.floats(-6.0, -1.0),                     # log10 strain T/EA
)


@given(forces)
@settings(max_examples=200, deadline=None)
def test_weightless_is_the_straight_elastic_cable(f):
    ang, sgn, lt, ll, ls = f
    T, L0 = 10 ** lt, 10 ** ll
    EA = T / 10 ** ls
    H, VB = T * math.cos(math.radians(ang)), sgn * T * math.sin(math.radians(ang))
    L = L0 * (1.0 + T / EA)
    X0, Z0 = C.catenary_ends(H, VB, L0, 0.0, EA)
    assert X0 == pytest.approx(L * H / T, rel=1e-14, abs=1e-15 * L)
    assert Z0 == pytest.approx(L * VB / T, rel=1e-14, abs=1e-15 * L)
    # w -> 0 converges to it smoothly, at first order in w L0 / T (no 0/0 anywhere)
    for k in range(2, 16):
        w = 10.0 ** -k * T / L0
        X, Z = C.catenary_ends(H, VB, L0, w, EA)
        assert math.hypot(X - X0, Z - Z0) <= 1.0 * (w * L0 / T) * L + 4 * EPS * L
    # and the inverse of a weightless cable is T = EA (L/L0 - 1) along the chord
    h, v, status, _ = CS.catenary_inverse(X0, Z0, L0, 0.0, EA, NAN, NAN, 1e-13, 100)
    assert status == CS.CAT_CONVERGED
    assert h == pytest.approx(H, rel=1e-9, abs=1e-9 * T)
    assert v == pytest.approx(VB, rel=1e-9, abs=1e-9 * T)
    # a light cable on the same chord: end force along the chord, to first order in w
    for w_rel in (1e-6, 1e-9, 1e-12):
        w = w_rel * T / L0
        h, v, status, _ = CS.catenary_inverse(X0, Z0, L0, w, EA, NAN, NAN, 1e-13, 100)
        assert status == CS.CAT_CONVERGED
        tol = 1e-9 * T + 2.0 * w * L0
        assert abs(h - H) <= tol and abs(v - VB) <= tol


def test_light_cable_inverse_converges_linearly_to_the_spring():
    """The end force's departure from the straight cable is ~ w L0 / 2 (half the weight)."""
    L0, EA, X, Z = 3.0, 1e5, 2.0, 2.3
    c = math.hypot(X, Z)
    T = EA * (c / L0 - 1.0)
    prev = None
    for k in range(3, 12):
        w = 10.0 ** -k * T / L0
        h, v, status, _ = CS.catenary_inverse(X, Z, L0, w, EA, NAN, NAN, 1e-13, 100)
        assert status == CS.CAT_CONVERGED
        dev = math.hypot(h - T * X / c, v - T * Z / c)
        assert dev <= w * L0
        if prev is not None and dev > 1e-7 * T:
            assert prev / dev == pytest.approx(10.0, rel=0.05)
        prev = dev


def inextensible_closed_form(H, VB, L0, w):
    """Span and height of y = a cosh(x/a), a = H/w, over an arc of length L0
    starting where the slope is VB/H: x_B = a asinh(VB/H), arc length from x_B
    to x_A is a (sinh(x_A/a) - sinh(x_B/a))."""
    a = H / w
    xB = a * np.arcsinh(VB / H)
    xA = a * np.arcsinh(np.sinh(xB / a) + L0 / a)
    return xA - xB, a * (np.cosh(xA / a) - np.cosh(xB / a))


@given(st.floats(-88.0, 88.0), st.floats(-1.5, 1.5), st.floats(-1.0, 1.5), st.floats(-2.0, 1.0))
@settings(max_examples=200, deadline=None)
def test_inextensible_limit(ang, ld, ll, lw):
    L0, w = 10 ** ll, 10 ** lw
    d = 10 ** ld
    H = w * L0 / d
    VB = H * math.tan(math.radians(ang))
    X, Z = inextensible_closed_form(H, VB, L0, w)
    scale = L0 + math.hypot(X, Z)
    Xi, Zi = C.catenary_ends(H, VB, L0, w, math.inf)
    assert abs(Xi - X) <= 1e-12 * scale and abs(Zi - Z) <= 1e-12 * scale
    # EA -> inf: the elastic catenary converges to it at rate 1/EA
    T = max(C.catenary_end_tensions(H, VB, L0, w))
    for EA in (1e3 * T, 1e6 * T, 1e9 * T):
        Xe, Ze = C.catenary_ends(H, VB, L0, w, EA)
        assert math.hypot(Xe - X, Ze - Z) <= 1.01 * L0 * T / EA + 1e-12 * scale
    # the inverse of the inextensible cable satisfies the textbook identity
    # sqrt(L0^2 - Z^2) = 2 a sinh(X / 2a) and closes the cosh form
    h, v, status, _ = CS.catenary_inverse(X, Z, L0, w, math.inf, NAN, NAN, 1e-13, 100)
    assert status == CS.CAT_CONVERGED
    a = h / w
    assert math.sqrt(L0 * L0 - Z * Z) == pytest.approx(2 * a * math.sinh(X / (2 * a)), rel=1e-9)
    Xc, Zc = inextensible_closed_form(h, v, L0, w)
    assert abs(Xc - X) <= 1e-9 * scale and abs(Zc - Z) <= 1e-9 * scale


def test_vertical_cable():
    """H = 0: hanging from A, hanging from B, folded; and the inverse for X = 0."""
    L0, w, EA = 2.0, 3.0, 1e3
    # hanging from A with VB = 5 N at the effector: T(s) = VB + w s
    X, Z = C.catenary_ends(0.0, 5.0, L0, w, EA)
    assert X == 0.0 and Z == pytest.approx(L0 + (5.0 * L0 + 0.5 * w * L0 ** 2) / EA, rel=1e-15)
    # hanging from B (A below B): V < 0 all along
    X, Z = C.catenary_ends(0.0, -10.0, L0, w, EA)
    assert Z == pytest.approx(-L0 + (-10.0 * L0 + 0.5 * w * L0 ** 2) / EA, rel=1e-15)
    # folded: lowest point at s = -VB/w; two vertical strands
    VB = -2.0
    s0 = -VB / w
    strand = lambda s, t0: s + (t0 * s - 0.5 * w * s * s) / EA  # noqa: E731  length of a strand hanging from tension t0
    zB = -strand(s0, -VB)           # B above the lowest point by the stretched B-strand
    zA = strand(L0 - s0, VB + w * L0)
    X, Z = C.catenary_ends(0.0, VB, L0, w, EA)
    assert X == 0.0 and Z == pytest.approx(zA + zB, rel=1e-14)
    # inverse
    for VB in (5.0, -10.0, -2.0, 0.0, -w * L0):
        X, Z = C.catenary_ends(0.0, VB, L0, w, EA)
        h, v, status, _ = CS.catenary_inverse(X, Z, L0, w, EA, NAN, NAN, 1e-13, 100)
        assert status == CS.CAT_CONVERGED and h == 0.0
        assert v == pytest.approx(VB, abs=1e-9 * (abs(VB) + w * L0))
    # the limit H -> 0 of the general closure
    for VB in (5.0, -10.0, -2.0):
        X0, Z0 = C.catenary_ends(0.0, VB, L0, w, EA)
        X1, Z1 = C.catenary_ends(1e-9, VB, L0, w, EA)
        assert X1 <= 1e-7 and Z1 == pytest.approx(Z0, abs=1e-9)


# ---------------------------------------------------------------------------
# Jacobian
# ---------------------------------------------------------------------------

@given(forces, st.floats(-4.0, 2.0))
@settings(max_examples=300, deadline=None)
def test_jacobian_against_finite_differences(f, ld):
    ang, sgn, lt, ll, ls = f
    T, L0 = 10 ** lt, 10 ** ll
    H, VB = T * math.cos(math.radians(ang)), sgn * T * math.sin(math.radians(ang))
    w = 10 ** ld * H / L0
    EA = T / 10 ** ls
    J = np.array(C.catenary_jacobian(H, VB, L0, w, EA)).reshape(2, 2)
    assert J[0, 1] == J[1, 0]                                       # symmetric
    assert J[0, 0] > 0 and J[1, 1] > 0 and np.linalg.det(J) > 0     # positive definite

    def fd(i, h):  # 5-point stencil in H (i = 0) or VB (i = 1)
        def ev(t):
            return np.array(C.catenary_ends(H + t * (i == 0), VB + t * (i == 1), L0, w, EA))
        return (ev(-2 * h) - 8 * ev(-h) + 8 * ev(h) - ev(2 * h)) / (12 * h)

    hs = 1e-3 * H
    Jfd = np.column_stack([fd(0, hs), fd(1, hs)])
    X, Z = C.catenary_ends(H, VB, L0, w, EA)
    rounding = 3.0 * EPS * (abs(X) + abs(Z) + L0) / hs
    assert np.max(np.abs(Jfd - J)) <= 1e-7 * np.max(np.abs(J)) + rounding


def test_jacobian_across_the_quadrature_switch():
    """dX/dH switches from a 12-point Gauss rule (w L0 <= H) to the closed
    form: both agree at the switch and with finite differences around it."""
    L0, EA = 2.0, 1e6
    for VB in (-3.0, -0.5, 0.0, 0.7, 4.0):
        for H in (1.0 - 1e-9, 1.0, 1.0 + 1e-9):
            w = 1.0 / L0  # w L0 = 1
            J = C.catenary_jacobian(H, VB, L0, w, EA)
            Jn = C.catenary_jacobian(1.0, VB, L0, w, EA)
            assert J[0] == pytest.approx(Jn[0], rel=1e-8)


# ---------------------------------------------------------------------------
# inverse
# ---------------------------------------------------------------------------

def random_forces(rng, n, inextensible=False):
    L0 = 10 ** rng.uniform(-1, 2, n)
    w = 10 ** rng.uniform(-3, 2, n)
    d = 10 ** (rng.uniform(-1.3, 2, n) if inextensible else rng.uniform(-6, 2, n))
    H = w * L0 / d
    VB = H * np.tan(np.radians(rng.uniform(-89.9, 89.9, n)))
    T = np.maximum(np.hypot(H, VB), np.hypot(H, VB + w * L0))
    EA = np.full(n, np.inf) if inextensible else T / 10 ** rng.uniform(-6, -1, n)
    return H, VB, L0, w, EA


def condition_numbers(H, VB, L0, w, EA, X, Z):
    """kappa = |J^-1| (L0 + chord) / F: relative change of the end forces per
    relative change of span and height (J from the kernel: used only to scale
    the tolerance)."""
    kap = np.empty(H.size)
    for i in range(H.size):
        J = np.array(C.catenary_jacobian(H[i], VB[i], L0[i], w[i], EA[i])).reshape(2, 2)
        F = force_scale(H[i], VB[i], L0[i], w[i])
        kap[i] = np.linalg.norm(np.linalg.inv(J), 2) * (L0[i] + math.hypot(X[i], Z[i])) / F
    return kap


@pytest.mark.parametrize("inextensible", [False, True])
def test_inverse_round_trip_batch(inextensible):
    """inverse(forward(H, VB)) = (H, VB) on 5000 random cables: to 1e-9 of the
    largest end force wherever the problem's condition number kappa <= 1e6, and
    to within 10 kappa eps everywhere (backward stable: a taut, near-vertical
    inextensible cable has kappa up to ~1e14, and no method can do better than
    the rounding of X and Z times kappa).  Elastic cables: strain 1e-6..0.1."""
    rng = np.random.default_rng(5 + inextensible)
    n = 5000
    H, VB, L0, w, EA = random_forces(rng, n, inextensible)
    X, Z = C.catenary_ends_batch(H, VB, L0, w, EA)
    nan = np.full(n, np.nan)
    h, v, status, iters = CS.catenary_inverse_batch(X, Z, L0, w, EA, nan, nan, 1e-13, 100)
    assert np.all(status == CS.CAT_CONVERGED)
    F = np.maximum.reduce([H, np.abs(VB), np.abs(VB + w * L0)])
    err = np.maximum(np.abs(h - H), np.abs(v - VB)) / F
    kap = condition_numbers(H, VB, L0, w, EA, X, Z)
    good = kap <= 1e6
    assert np.count_nonzero(good) >= 0.8 * n
    assert np.max(err[good]) <= 1e-9
    assert np.all(err <= 10.0 * kap * EPS + 1e-12)
    assert np.max(iters) <= 60
    # the batch is the scalar kernel, case by case
    for i in range(0, n, 97):
        assert CS.catenary_inverse(X[i], Z[i], L0[i], w[i], EA[i], NAN, NAN, 1e-13, 100) == \
            (h[i], v[i], status[i], iters[i])
        assert C.catenary_ends(H[i], VB[i], L0[i], w[i], EA[i]) == (X[i], Z[i])


@given(forces, st.floats(-6.0, 2.0))
@settings(max_examples=300, deadline=None)
def test_inverse_round_trip(f, ld):
    ang, sgn, lt, ll, ls = f
    T, L0 = 10 ** lt, 10 ** ll
    H, VB = T * math.cos(math.radians(ang)), sgn * T * math.sin(math.radians(ang))
    w = 10 ** ld * H / L0
    EA = T / 10 ** ls
    X, Z = C.catenary_ends(H, VB, L0, w, EA)
    h, v, status, _ = CS.catenary_inverse(X, Z, L0, w, EA, NAN, NAN, 1e-13, 100)
    assert status == CS.CAT_CONVERGED
    F = force_scale(H, VB, L0, w)
    assert abs(h - H) <= 1e-9 * F and abs(v - VB) <= 1e-9 * F
    # warm start from a nearby pose converges to the same forces
    h2, v2, status, _ = CS.catenary_inverse(X, Z, L0, w, EA, 1.1 * H, VB + 0.1 * F, 1e-13, 100)
    assert status == CS.CAT_CONVERGED
    assert abs(h2 - H) <= 1e-9 * F and abs(v2 - VB) <= 1e-9 * F


def random_geometry(rng, n):
    """Spans and heights drawn directly (not from forces): from very slack
    (chord 1e-3 L0) to 12 % stretch, vertical and horizontal included."""
    L0 = 10 ** rng.uniform(-1, 2, n)
    c = L0 * 10 ** rng.uniform(-3, 0.05, n)
    ang = rng.uniform(-np.pi / 2, np.pi / 2, n)
    X = np.abs(c * np.cos(ang))
    Z = c * np.sin(ang)
    X[: n // 20] = 0.0
    Z[n // 20: n // 10] = 0.0
    w = 10 ** rng.uniform(-3, 2, n)
    EA = 10 ** rng.uniform(2, 9, n)
    EA[n // 10: n // 5] = np.inf
    return X, Z, L0, w, EA, c


def test_every_geometry_with_a_solution_is_solved():
    """Any X >= 0, Z for a heavy elastic cable has one solution (the chain's
    energy is convex and coercive); an inextensible one needs chord < L0.  The
    rest must be flagged CAT_NO_SOLUTION with NaN forces."""
    rng = np.random.default_rng(9)
    n = 4000
    X, Z, L0, w, EA, c = random_geometry(rng, n)
    nan = np.full(n, np.nan)
    h, v, status, _ = CS.catenary_inverse_batch(X, Z, L0, w, EA, nan, nan, 1e-13, 100)
    solvable = np.isfinite(EA) | (c < L0)
    assert np.all(status[solvable] == CS.CAT_CONVERGED)
    assert np.all(status[~solvable] == CS.CAT_NO_SOLUTION)
    assert np.all(np.isnan(h[~solvable])) and np.all(np.isnan(v[~solvable]))
    assert np.all(h[solvable] >= 0.0)
    Xc, Zc = C.catenary_ends_batch(h[solvable], v[solvable], L0[solvable], w[solvable], EA[solvable])
    res = np.hypot(Xc - X[solvable], Zc - Z[solvable]) / (c + L0)[solvable]
    assert np.max(res) <= 1e-13


def test_unconverged_is_never_reported_as_converged():
    """With a starved iteration budget, a CAT_CONVERGED result is the right one
    and anything else is NaN with CAT_NOT_CONVERGED."""
    rng = np.random.default_rng(21)
    n = 1500
    X, Z, L0, w, EA, c = random_geometry(rng, n)
    EA[:] = 10 ** rng.uniform(2, 9, n)
    nan = np.full(n, np.nan)
    h_ref, v_ref, st_ref, _ = CS.catenary_inverse_batch(X, Z, L0, w, EA, nan, nan, 1e-13, 100)
    assert np.all(st_ref == CS.CAT_CONVERGED)
    F = np.maximum.reduce([h_ref, np.abs(v_ref), np.abs(v_ref + w * L0)])
    starved = 0
    for maxit in (0, 1, 2, 3, 5):
        h, v, status, _ = CS.catenary_inverse_batch(X, Z, L0, w, EA, nan, nan, 1e-13, maxit)
        ok = status == CS.CAT_CONVERGED
        assert np.all(np.isin(status, [CS.CAT_CONVERGED, CS.CAT_NOT_CONVERGED]))
        assert np.all(np.isnan(h[~ok])) and np.all(np.isnan(v[~ok]))
        err = np.maximum(np.abs(h - h_ref), np.abs(v - v_ref))[ok] / F[ok]
        assert np.all(err <= 1e-8)
        starved += np.count_nonzero(~ok & (X > 0))
    assert starved > 100  # the budget did bite


def test_fallback_alone():
    """The bracketed nested solve, started far away, finds the same forces."""
    rng = np.random.default_rng(3)
    H, VB, L0, w, EA = random_forces(rng, 400)
    for i in range(H.size):
        X, Z = C.catenary_ends(H[i], VB[i], L0[i], w[i], EA[i])
        if X <= 0.0:
            continue
        F = force_scale(H[i], VB[i], L0[i], w[i])
        h0 = H[i] * 10 ** rng.uniform(-3, 3)
        v0 = rng.uniform(-3, 3) * F
        h, v, ok, _ = CS._fallback(X, Z, L0[i], w[i], EA[i], h0, v0, w[i] * L0[i] + h0 + abs(v0),
                                  16 * EPS * (math.hypot(X, Z) + L0[i]), 300)
        assert ok
        assert abs(h - H[i]) <= 1e-8 * F and abs(v - VB[i]) <= 1e-8 * F


@pytest.mark.parametrize("args, expected", [
    ((1.0, 1.0, -1.0, 1.0, 1e3), CS.CAT_NO_SOLUTION),     # L0 <= 0
    ((1.0, 1.0, 0.0, 1.0, 1e3), CS.CAT_NO_SOLUTION),
    ((1.0, 1.0, 2.0, -1.0, 1e3), CS.CAT_NO_SOLUTION),     # w < 0
    ((1.0, 1.0, 2.0, 1.0, 0.0), CS.CAT_NO_SOLUTION),      # EA <= 0
    ((1.0, 1.0, 2.0, 1.0, -5.0), CS.CAT_NO_SOLUTION),
    ((-1.0, 1.0, 2.0, 1.0, 1e3), CS.CAT_NO_SOLUTION),     # X < 0
    ((NAN, 1.0, 2.0, 1.0, 1e3), CS.CAT_NO_SOLUTION),
    ((1.0, NAN, 2.0, 1.0, 1e3), CS.CAT_NO_SOLUTION),
    ((1.0, 1.0, NAN, 1.0, 1e3), CS.CAT_NO_SOLUTION),
    ((1.0, 1.0, 2.0, NAN, 1e3), CS.CAT_NO_SOLUTION),
    ((1.0, 1.0, 2.0, 1.0, NAN), CS.CAT_NO_SOLUTION),
    ((math.inf, 1.0, 2.0, 1.0, 1e3), CS.CAT_NO_SOLUTION),
    ((3.0, 4.0, 5.0, 1.0, math.inf), CS.CAT_NO_SOLUTION),  # inextensible, chord = L0
    ((3.0, 4.0, 4.9, 1.0, math.inf), CS.CAT_NO_SOLUTION),  # inextensible, chord > L0
    ((0.0, 5.0, 5.0, 1.0, math.inf), CS.CAT_NO_SOLUTION),  # taut vertical inextensible: tension indeterminate
    ((3.0, 4.0, 4.0, 0.0, math.inf), CS.CAT_NO_SOLUTION),  # weightless inextensible, too short
    ((3.0, 4.0, 6.0, 0.0, 1e3), CS.CAT_SLACK),             # weightless, slack: zero forces
    ((0.0, 0.0, 1.0, 0.0, 1e3), CS.CAT_SLACK),
])
def test_flags(args, expected):
    h, v, status, _ = CS.catenary_inverse(*args, NAN, NAN, 1e-12, 100)
    assert status == expected
    if expected == CS.CAT_SLACK:
        assert h == 0.0 and v == 0.0
    else:
        assert math.isnan(h) and math.isnan(v)


def test_very_slack_and_very_taut():
    """L0 much longer than the chord is an ordinary (deep) catenary; L0 much
    shorter means a large tension; both converge and close."""
    for X, Z, L0, w, EA in [(0.6, 0.8, 1e4, 1.0, math.inf), (0.6, 0.8, 1e4, 1.0, 1e3),
                            (0.6, -0.8, 1.0 + 1e-12, 1.0, math.inf), (3.0, 4.0, 2.5, 1.0, 1e6),
                            (1e-9, 0.8, 100.0, 1.0, 1e6), (1e-300, 0.3, 1.0, 1.0, 1e6)]:
        h, v, status, _ = CS.catenary_inverse(X, Z, L0, w, EA, NAN, NAN, 1e-13, 100)
        assert status == CS.CAT_CONVERGED
        Xc, Zc = C.catenary_ends(h, v, L0, w, EA)
        assert math.hypot(Xc - X, Zc - Z) <= 1e-13 * (L0 + math.hypot(X, Z))
    # L0 half the chord: T = EA (c/L0 - 1) = EA, the weight barely matters
    h, v, status, _ = CS.catenary_inverse(3.0, 4.0, 2.5, 1.0, 1e6, NAN, NAN, 1e-13, 100)
    assert math.hypot(h, v) == pytest.approx(1e6, rel=1e-5)


# ---------------------------------------------------------------------------
# profile, sag, tensions, plane
# ---------------------------------------------------------------------------

@given(forces, st.floats(-3.0, 1.5))
@settings(max_examples=150, deadline=None)
def test_profile_and_sag(f, ld):
    ang, sgn, lt, ll, ls = f
    T, L0 = 10 ** lt, 10 ** ll
    H, VB = T * math.cos(math.radians(ang)), sgn * T * math.sin(math.radians(ang))
    assume(H > 0.0)
    w = 10 ** ld * H / L0
    EA = T / 10 ** ls
    X, Z = C.catenary_ends(H, VB, L0, w, EA)
    s = np.linspace(0.0, L0, 1001)
    x, z = C.catenary_profile(H, VB, L0, w, EA, s)
    assert x[0] == 0.0 and z[0] == 0.0
    assert x[-1] == X and z[-1] == Z
    assert np.all(np.diff(x) > 0.0)                       # H > 0: x increases along the cable
    # the stretched length: segment lengths (1 + T/EA) ds
    seg = np.hypot(np.diff(x), np.diff(z))
    Tm = np.hypot(H, VB + w * 0.5 * (s[1:] + s[:-1]))
    assert np.allclose(seg, (1.0 + Tm / EA) * np.diff(s), rtol=2e-4)  # chord vs arc: (curvature ds)^2/24
    # sag: brute-force maximum of the distance to the chord, on the coarse grid
    # then on a fine one around the best sample
    c = math.hypot(X, Z)
    dist = (x * Z - z * X) / c
    k = int(np.argmax(dist))
    sf = np.linspace(s[max(k - 1, 0)], s[min(k + 1, s.size - 1)], 2001)
    xf, zf = C.catenary_profile(H, VB, L0, w, EA, sf)
    distf = (xf * Z - zf * X) / c
    kf = int(np.argmax(distf))
    sag, sstar = C.catenary_sag(H, VB, L0, w, EA)
    assert sag >= distf[kf] - 1e-12 * c                   # the kernel's max is not below any sample
    assert sag - distf[kf] <= 1e-9 * sag + 1e-14 * c      # nor above the fine sampling's by more than its spacing allows
    # where the sampled distances cannot tell sstar from the sampled maximum (a light cable's flat
    # maximum: they differ by less than their rounding), the samples do not locate it any closer
    xs, zs = C.catenary_profile(H, VB, L0, w, EA, np.array([sstar]))
    unresolved = abs((xs[0] * Z - zs[0] * X) / c - distf[kf]) <= 1e-14 * c
    assert abs(sstar - sf[kf]) <= 2 * (sf[1] - sf[0]) + 1e-6 * L0 or sag <= 1e-9 * c or unresolved


def test_sag_limits():
    assert C.catenary_sag(10.0, 1.0, 2.0, 0.0, 1e4) == (0.0, 0.0)      # weightless: straight
    assert C.catenary_sag(0.0, 1.0, 2.0, 1.0, 1e4) == (0.0, 0.0)       # vertical
    # shallow cable: sag ~ w L^2 cos / (8 T) (parabola)
    H, L0, w = 1e4, 10.0, 1.0
    sag, sstar = C.catenary_sag(H, -0.5 * w * L0, L0, w, math.inf)
    assert sag == pytest.approx(w * L0 ** 2 / (8 * H), rel=1e-3)
    assert sstar == pytest.approx(0.5 * L0, rel=1e-9)


def test_end_tensions_and_plane():
    TA, TB = C.catenary_end_tensions(3.0, -1.0, 2.0, 4.0)
    assert TA == pytest.approx(math.hypot(3.0, 7.0)) and TB == pytest.approx(math.hypot(3.0, 1.0))
    X, Z, ux, uy = C.span_height(4.0, 5.0, 6.0, 1.0, 1.0, 2.0)
    assert (X, Z) == pytest.approx((5.0, 4.0)) and (ux, uy) == pytest.approx((0.6, 0.8))
    assert C.span_height(1.0, 1.0, 3.0, 1.0, 1.0, 2.0) == (0.0, 1.0, 0.0, 0.0)


def test_effector_force_is_not_along_the_chord():
    """The point of the model: at B the cable pulls along its tangent (H, VB),
    which is below the chord by an angle ~ w L0 / (2 T) for a light cable."""
    L0, w, EA = 5.0, 2.0, 1e6
    X, Z = 3.0, 4.01  # chord 1.2 per mille longer than L0: taut, T ~ 1.2 kN >> w L0 = 10 N
    h, v, status, _ = CS.catenary_inverse(X, Z, L0, w, EA, NAN, NAN, 1e-13, 100)
    assert status == CS.CAT_CONVERGED
    chord = math.atan2(Z, X)
    tangent_B = math.atan2(v, h)
    tangent_A = math.atan2(v + w * L0, h)
    assert tangent_B < chord < tangent_A
    T = math.hypot(h, v)
    assert chord - tangent_B == pytest.approx(w * L0 * math.cos(chord) / (2 * T), rel=0.05)


@settings(max_examples=300, deadline=None)
@given(st.floats(-1e300, 1e300, allow_nan=False, allow_infinity=False),
       st.floats(-1e300, 1e300, allow_nan=False, allow_infinity=False))
def test_fast_hypot_within_one_ulp_of_math_hypot(x, y):
    # the catenary kernels' hypot (sum of squares in its safe range) against the correctly rounded one
    from cdpr_design.kernels.scalar import hypot

    want = math.hypot(x, y)
    got = hypot(x, y)
    assert abs(got - want) <= math.ulp(want), (x, y, got, want)


@pytest.mark.parametrize("x, y", [(0.0, 0.0), (3e-200, 4e-200), (3e200, 4e200), (-5.0, 12.0), (1e-320, 0.0),
                                  (math.inf, 1.0), (1.0, -math.inf), (math.nan, 1.0), (math.inf, math.nan)])
def test_fast_hypot_edges(x, y):
    from cdpr_design.kernels.scalar import hypot

    got, want = hypot(x, y), math.hypot(x, y)
    assert (math.isnan(got) and math.isnan(want)) or got == want, (x, y, got, want)
