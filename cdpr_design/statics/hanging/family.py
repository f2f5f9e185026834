"""The march along the family of balanced orientations of a spatial body on four cables.

With four taut cables the balanced orientations of a spatial body at one
position form a curve (the lengths can still choose among them).  Its members
with every tension >= 0 end where one tension reaches zero: there the body
hangs from the other three.  :func:`march_family` follows the curve from a
balanced pulling point by predictor-corrector continuation to its least
tilted pulling member and to where a cable goes slack; :func:`with_marches`
adds what the marches find to a search's candidates.

Units: SI (m, N, rad); conventions of :mod:`cdpr_design.statics.hanging.geometry`.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from cdpr_design.statics.hanging import geometry as hg
from cdpr_design.statics.hanging.balance import Balance, newton_many, on_cables, solve_sym


#: Arc-length step of the march along a four-cable family (rotation [rad] and tension / weight
#: together), its largest number of steps, and the refinements of its least tilted member.
MARCH_STEP = 0.1
MARCH_STEPS = 40
MARCH_REFINE = 16
#: The least move of a refinement of the least tilted member [arc length] where the tilt is flat
#: and the nominal rotation decides (:func:`_v_vertex`); elsewhere 1e-7 (a smaller step moves the
#: tilt by ~1e-14 rad).
TIE_STEP = 1e-10


def _null_vector(J, prev):
    """Unit null vectors (N, c) of J (N, r, c), c = r + 1 (by SVD), signed along ``prev``."""
    v = np.linalg.svd(J)[2][:, -1, :]
    return v * np.where(np.einsum("nc,nc->n", v, prev) < 0.0, -1.0, 1.0)[:, None]


def _tangent(J, prev):
    """The tangents (N, c) of the family where J (N, r, c) is its balance Jacobian: ``prev``
    (a tangent one step back) projected onto the null space of J, made unit."""
    JT = J.transpose(0, 2, 1)
    v = prev - np.einsum("ncr,nr->nc", JT, solve_sym(J @ JT, np.einsum("nrc,nc->nr", J, prev)))
    return v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-300)


def _correct(bal, P, R, t, tol, iterations: int = 4):
    """Minimum-norm Newton steps back onto the family, each row until its scaled residual is
    at most ``tol``: (R, t, scaled residual (N,), J (N, r, c) at each row's last iterate)."""
    R, t = R.copy(), t.copy()
    w0 = np.zeros((len(P), 3))
    F = np.nan_to_num(bal.residual(P, R, t), nan=1e300)
    J = np.zeros((len(P), len(bal.rows), 3 + bal.geo.m))
    todo = np.arange(len(P))
    for it in range(iterations):
        if it:
            todo = todo[np.abs(F[todo]).max(axis=1) > tol]
        if not todo.size:
            break
        Jt = np.nan_to_num(bal.jacobian(P[todo], R[todo], t[todo], w0[todo]))
        JT = Jt.transpose(0, 2, 1)
        dz = -np.einsum("ncr,nr->nc", JT, solve_sym(Jt @ JT, F[todo]))
        R[todo] = hg.rotvec(dz[:, :3]) @ R[todo]
        t[todo] += dz[:, 3:] * bal.geo.weight
        F[todo] = np.nan_to_num(bal.residual(P[todo], R[todo], t[todo]), nan=1e300)
        J[todo] = Jt
    return R, t, np.abs(F).max(axis=1), J


def _advance(bal, P, R, t, tau, h, tol):
    """The family point h [scaled arc length] along the tangent tau from (R, t), corrected
    (:func:`_correct`)."""
    R1 = hg.rotvec(h[:, None] * tau[:, :3]) @ R
    return _correct(bal, P, R1, t + h[:, None] * tau[:, 3:] * bal.geo.weight, tol)


def march_family(geo: hg.Geometry, P, R, t, direction, R0):
    """The least tilted member with every tension >= 0 of the one-parameter family of
    balanced orientations of a spatial body on four taut cables (ranked by
    :func:`~cdpr_design.statics.hanging.geometry.tilt_rank`: of equally tilted members the
    nearest the nominal rotation R0 (3, 3)), along the family from balanced pulling points
    (R (N, 3, 3), t (N, 4) [N]) at positions P (N, 3) [m], in ``direction`` (N, 7)
    (rotation, tension / weight; only its sign along the tangent counts).
    Predictor-corrector continuation in steps of :data:`MARCH_STEP` until a tension
    turns negative (the pulling members end where one cable goes slack) or
    :data:`MARCH_STEPS`, then :data:`MARCH_REFINE` parabolas through the least tilted
    step and its neighbours (where the tilt is flat along the family and the distance to R0
    decides, a V with its vertex at the nearest member: :func:`_v_vertex`).  Returns candidates (R (N, 2, 3, 3), t (N, 2, 4) [N],
    balanced (N, 2)): the least tilted member found (the start where no step improved on
    it), and where a cable went slack the orientation with it just slack
    (:func:`_slack_ends`; unbalanced where the march did not end so)."""
    bal = Balance(geo, False)
    up = -geo.g / np.linalg.norm(geo.g)
    N = len(P)
    R, t = np.array(R, float), np.array(t, float)  # the march's current points (copies)
    tol = 1e-10
    w0 = np.zeros((N, 3))
    tau = _null_vector(np.nan_to_num(bal.jacobian(P, R, t, w0)), direction)
    f = hg.tilt_rank(R, up, R0)
    tl = hg.tilt_many(R, up)
    best = [R.copy(), t.copy(), f.copy(), tau.copy()]
    # the bracket of the least tilted step: arc lengths, ranks and tilts of (previous, best, next)
    x = np.stack([np.full(N, -1.0), np.zeros(N), np.full(N, 1.0)], axis=1) * MARCH_STEP
    fx = np.stack([np.full(N, np.inf), f, np.full(N, np.inf)], axis=1)
    tx = np.stack([np.full(N, np.inf), tl, np.full(N, np.inf)], axis=1)
    s = np.zeros(N)
    f_prev, tl_prev = f.copy(), tl.copy()
    after = np.ones(N, bool)  # the step after the best is still to be recorded
    last, cable = np.zeros(N, bool), np.zeros(N, int)  # marches ended by a cable going slack
    active = np.ones(N, bool)
    for _ in range(MARCH_STEPS):
        idx = np.flatnonzero(active)
        if not idx.size:
            break
        h = np.full(idx.size, MARCH_STEP)
        R1, t1, res, J1 = _advance(bal, P[idx], R[idx], t[idx], tau[idx], h, tol)
        f1 = hg.tilt_rank(R1, up, R0)
        ok_t = np.all(t1 >= -1e-9 * geo.weight, axis=1)
        ok = (res <= tol) & ok_t
        f1 = np.where(ok, f1, np.inf)
        tl1 = np.where(ok, hg.tilt_many(R1, up), np.inf)
        s1 = s[idx] + MARCH_STEP
        rec = after[idx]
        j = idx[rec]
        x[j, 2], fx[j, 2], tx[j, 2] = s1[rec], f1[rec], tl1[rec]
        after[j] = False
        better = ok & (f1 < best[2][idx])
        g = idx[better]
        x[g] = np.stack([s[g], s1[better], np.full(g.size, np.inf)], axis=1)
        fx[g] = np.stack([f_prev[g], f1[better], np.full(g.size, np.inf)], axis=1)
        tx[g] = np.stack([tl_prev[g], tl1[better], np.full(g.size, np.inf)], axis=1)
        after[g] = True
        live = idx[ok]
        tau_new = _tangent(J1[ok], tau[live])
        best[0][g], best[1][g], best[2][g] = R1[better], t1[better], f1[better]
        R[live], t[live], tau[live], s[live], f_prev[live] = R1[ok], t1[ok], tau_new, s1[ok], f1[ok]
        tl_prev[live] = tl1[ok]
        best[3][g] = tau[g]
        # a tension turned negative: the pulling members end between the last step and this one
        end = (res <= tol) & ~ok_t
        e = idx[end]
        last[e], cable[e] = True, np.argmin(t1[end], axis=1)
        active[idx[~ok]] = False
    # successive parabolas (or Vs) about the least tilted step (from it, along its tangent)
    x[:, 2] = np.where(np.isfinite(x[:, 2]), x[:, 2], x[:, 1] + MARCH_STEP)
    todo = np.flatnonzero(np.isfinite(fx[:, 0]) | np.isfinite(fx[:, 2]))
    xb = x[:, 1].copy()
    for _ in range(MARCH_REFINE):
        if not todo.size:
            break
        tie = _tie_decides(fx[todo], tx[todo])
        xn = np.where(tie, _v_vertex(x[todo], fx[todo]), _parabola_vertex(x[todo], fx[todo]))
        least = np.where(tie, TIE_STEP, 1e-7)  # 1e-7: a smaller step moves the tilt by ~1e-14 rad
        moved = np.abs(xn - x[todo, 1]) > least
        Rn, tn, res, _ = _advance(bal, P[todo], best[0][todo], best[1][todo], best[3][todo], xn - xb[todo], tol)
        ok = (res <= tol) & np.all(tn >= -1e-9 * geo.weight, axis=1)
        fn = np.where(ok, hg.tilt_rank(Rn, up, R0), np.inf)
        tln = np.where(ok, hg.tilt_many(Rn, up), np.inf)
        x[todo], fx[todo], tx[todo] = _bracket(x[todo], fx[todo], tx[todo], xn, fn, tln)
        better = fn < best[2][todo]
        g = todo[better]
        best[0][g], best[1][g], best[2][g] = Rn[better], tn[better], fn[better]
        xb[g] = xn[better]
        todo = todo[moved & ((x[todo, 2] - x[todo, 0]) > least)]
    res = np.abs(np.nan_to_num(bal.residual(P, best[0], best[1]), nan=np.inf) * bal.scale).max(axis=1)
    Re, te, oke = _slack_ends(geo, P, R, last, cable)
    return (np.stack([best[0], Re], axis=1), np.stack([best[1], te], axis=1),
            np.stack([res <= 1e-8 * max(1.0, geo.weight), oke], axis=1))


def _slack_ends(geo, P, R, last, cable):
    """Where a march ended with cable ``cable`` going slack (rows ``last``): the balanced
    orientation with that cable just slack, by Newton's method on the other three from the
    march's last orientation ``R``.  (R (N, 3, 3), t (N, m) [N], balanced (N,))."""
    N, m = len(P), geo.m
    Re, te, oke = np.full((N, 3, 3), np.nan), np.zeros((N, m)), np.zeros(N, bool)
    for j in range(m):
        rows = np.flatnonzero(last & (cable == j))
        if not rows.size:
            continue
        keep = [i for i in range(m) if i != j]
        Rn, tn, okn = newton_many(on_cables(geo, keep), P[rows], False, R[rows][:, None], [(0.0, 0.0, 0.0)])
        Re[rows], oke[rows] = Rn[:, 0], okn[:, 0]
        te[rows[:, None], keep] = tn[:, 0]
    return Re, te, oke


def _parabola_vertex(x, f):
    """The vertex of the parabola through (x, f) (k, 3), x ascending, f[:, 1] the least; the
    midpoint of the wider side where the parabola is not convex or f is infinite (x's units)."""
    a, b, c = x.T
    fa, fb, fc = f.T
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        num = (b - a) ** 2 * (fb - fc) - (b - c) ** 2 * (fb - fa)
        den = (b - a) * (fb - fc) - (b - c) * (fb - fa)
        v = b - 0.5 * num / den
    wide = np.where(b - a > c - b, 0.5 * (a + b), 0.5 * (b + c))
    good = np.isfinite(v) & (v > a) & (v < c) & (np.abs(v - b) > 1e-9)
    return np.where(good, v, wide)


def _v_vertex(x, f):
    """The vertex of the symmetric V through (x, f) (k, 3), x ascending, f[:, 1] the least: both
    sides take the steeper side's slope s, the one whose two points lie on the same side of the
    vertex (exact for f = s |x - x*| + f0: the rank where the tilt is flat and the angle to the
    nominal rotation decides, :func:`~cdpr_design.statics.hanging.geometry.tilt_rank`); the
    midpoint of the wider side where that is not inside the bracket (x's units)."""
    a, b, c = x.T
    fa, fb, fc = f.T
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        sl, sr = (fa - fb) / (b - a), (fc - fb) / (c - b)
        s = np.maximum(sl, sr)
        v = np.where(sr >= sl, 0.5 * (a + b) + 0.5 * (fa - fb) / s, 0.5 * (b + c) - 0.5 * (fc - fb) / s)
    wide = np.where(b - a > c - b, 0.5 * (a + b), 0.5 * (b + c))
    return np.where(np.isfinite(v) & (v > a) & (v < c), v, wide)


def _tie_decides(f, tilt):
    """Rows (k,) of brackets (k, 3) whose ranks ``f`` vary by the tie term (the angle to the
    nominal rotation) at least a hundred times as much as by their ``tilt`` [deg]: there the rank
    is a V about the nearest member, which parabolas approach only slowly."""
    with np.errstate(invalid="ignore"):
        return (np.all(np.isfinite(f), axis=1)
                & (np.ptp(tilt, axis=1) <= 0.01 * np.ptp(f - tilt, axis=1)))


def _bracket(x, f, tilt, xn, fn, tn):
    """The new bracket (a, b, c) around the least value after evaluating fn (its tilt tn) at xn:
    (x, f, tilt) (k, 3) each."""
    left = xn < x[:, 1]
    win = fn < f[:, 1]
    out = []
    for v, vn in ((x, xn), (f, fn), (tilt, tn)):
        a, b, c = v.T
        # xn better: it becomes the middle, b the side it came from; else xn replaces that side
        out.append(np.stack([np.where(win, np.where(left, a, b), np.where(left, vn, a)),
                             np.where(win, vn, b),
                             np.where(win, np.where(left, b, c), np.where(left, c, vn))], axis=1))
    return tuple(out)


def with_marches(geo, P, Rs, ts, balanced, R0):
    """The candidates (k, S) of a spatial body on four or five cables with, appended, what
    :func:`march_family` finds from them: on four cables along their family
    (:func:`_marches`), on five along the edges of the pulling region of their family
    (:func:`_walks`).  Candidates (R, t [N], balanced) with the marches' columns after the S
    given (unbalanced where a position has fewer)."""
    Rm, tm, bm = (_marches if geo.m == 4 else _walks)(geo, P, Rs, ts, balanced, R0)
    return (np.concatenate([Rs, Rm], axis=1), np.concatenate([ts, tm], axis=1),
            np.concatenate([balanced, bm], axis=1))


def _columns(k, m, found):
    """The candidates of marches at positions 0..k-1 as columns (k, M, ...), M the most at
    one position (unbalanced where a position has fewer).  ``found``: a list of (positions
    (N,), R (N, E, 3, 3), t (N, E, m) [N], balanced (N, E)), E candidates a march
    (:func:`march_family`)."""
    n_ = np.concatenate([np.repeat(f[0], f[3].shape[1]) for f in found]) if found else np.zeros(0, int)
    cols = int(np.bincount(n_, minlength=k).max()) if n_.size else 0
    Rm, tm, bm = np.full((k, cols, 3, 3), np.nan), np.zeros((k, cols, m)), np.zeros((k, cols), bool)
    if n_.size:
        order = np.argsort(n_, kind="stable")
        slot = np.empty(n_.size, int)
        slot[order] = np.arange(n_.size) - np.searchsorted(n_[order], n_[order])
        Rm[n_, slot] = np.concatenate([f[1].reshape(-1, 3, 3) for f in found])
        tm[n_, slot] = np.maximum(np.concatenate([f[2].reshape(-1, m) for f in found]), 0.0)
        bm[n_, slot] = np.concatenate([f[3].reshape(-1) for f in found])
    return Rm, tm, bm


def _marches(geo, P, Rs, ts, balanced, R0):
    """The least tilted pulling member of a four-cable body's family reached by
    :func:`march_family` from each balanced pulling candidate (k, S) (R, t [N], balanced):
    from one on three cables (the fourth just slack) in the direction that tightens the
    fourth, from one on all four in both directions; and where a march ended with a cable
    going slack, the orientation with it just slack.  (R, t [N], balanced) (k, M)."""
    pull = balanced & np.all(ts >= -1e-9 * geo.weight, axis=2)
    slack = ts <= 0.0
    n_, s_ = np.nonzero(pull & (slack.sum(axis=2) <= 1))
    one = slack[n_, s_].any(axis=1)
    d = np.zeros((n_.size, 7))
    d[one, 3 + np.argmax(slack[n_[one], s_[one]], axis=1)] = 1.0
    four = np.flatnonzero(~one)
    if four.size:  # both ways along the family from a member on all four
        bal = Balance(geo, False)
        J = bal.jacobian(P[n_[four]], Rs[n_[four], s_[four]], ts[n_[four], s_[four]], np.zeros((four.size, 3)))
        d[four] = _null_vector(np.nan_to_num(J), np.ones((four.size, 7)))
        n_, s_, d = np.concatenate([n_, n_[four]]), np.concatenate([s_, s_[four]]), np.concatenate([d, -d[four]])
    found = [(n_, *march_family(geo, P[n_], Rs[n_, s_], ts[n_, s_], d, R0))] if n_.size else []
    return _columns(len(P), geo.m, found)


def _walks(geo, P, Rs, ts, balanced, R0):
    """What marches find along the edges of the pulling region of a five-cable body's
    two-parameter family, from each balanced pulling candidate (k, S) (R, t [N], balanced)
    on three cables.

    The region's edges are arcs of four-cable families (the fifth cable slack), its
    corners three-cable answers.  From a corner with taut cables T and slack x, y a walk
    marches along the family T + x tightening x (:func:`march_family`), another along
    T + y.  Where a march ends with a cable z going slack, at a corner, the walk goes on
    along the family of that corner and the cable that was slack, tightening it; until
    it is back at the corner it started from, or after as many corners as there are (10).
    A family is marched once from each corner a walk enters it at.  Every march adds its
    least tilted member and its end.  (R, t [N], balanced) (k, M).  The interior (all
    five cables pulling) is not searched."""
    m, k = geo.m, len(P)
    bit = 1 << np.arange(m)
    pull = balanced & np.all(ts >= -1e-9 * geo.weight, axis=2)
    n_, s_ = np.nonzero(pull & ((ts > 0.0).sum(axis=2) == 3))
    slack = ts[n_, s_] <= 0.0
    x, y = np.argmax(slack, axis=1), m - 1 - np.argmax(slack[:, ::-1], axis=1)
    # the walks: position, orientation, tensions, the cable to tighten, the one outside the
    # family (left slack)
    wn, wR, wt = np.concatenate([n_, n_]), np.concatenate([Rs[n_, s_]] * 2), np.concatenate([ts[n_, s_]] * 2)
    wa, wo = np.concatenate([x, y]), np.concatenate([y, x])
    # each family is marched once from each corner a walk enters it at: (position, family (by
    # the cable outside it), the corner's taut cables); a walk back at its first corner enters
    # a family already marched from there, and ends
    seen = np.zeros((k, m, 1 << m), bool)
    found = []
    for _ in range(math.comb(m, 3)):
        key = (wn, wo, (wt > 0.0) @ bit)
        first = np.zeros(wn.size, bool)
        first[np.unique(np.ravel_multi_index(key, seen.shape), return_index=True)[1]] = True
        new = first & ~seen[key]
        seen[key] = True
        wn, wR, wt, wa, wo = wn[new], wR[new], wt[new], wa[new], wo[new]
        if not wn.size:
            break
        nxt = []
        for Q in itertools.combinations(range(m), 4):
            out = (set(range(m)) - set(Q)).pop()
            r = np.flatnonzero(wo == out)
            if not r.size:
                continue
            Qs = list(Q)
            d = np.zeros((r.size, 7))
            d[np.arange(r.size), 3 + np.searchsorted(Qs, wa[r])] = 1.0
            Rb, tb, ok = march_family(on_cables(geo, Q), P[wn[r]], wR[r], wt[r][:, Qs], d, R0)
            tf = np.zeros(tb.shape[:2] + (m,))
            tf[:, :, Qs] = tb
            found.append((wn[r], Rb, tf, ok))
            # on from the march's end where a cable went slack (a corner): that cable stays
            # slack, the walk tightens the fifth
            e = np.flatnonzero(ok[:, 1] & np.all(tb[:, 1] >= -1e-9 * geo.weight, axis=1))
            z = np.array(Qs)[np.argmin(tb[e, 1], axis=1)]
            nxt.append((wn[r[e]], Rb[e, 1], tf[e, 1], np.full(e.size, out), z))
        if not nxt:
            break
        wn, wR, wt, wa, wo = (np.concatenate([q[j] for q in nxt]) for j in range(5))
    return _columns(k, m, found)
