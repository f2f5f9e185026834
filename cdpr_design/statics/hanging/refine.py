"""Local solvers of the forward problem: an equilibrium near a configuration.

Newton's method on force and moment balance and the taut cables' lengths
(:func:`newton`), wrapped in an active set of taut cables (:func:`refine`);
tensions that balance a wrench with every cable pulling
(:func:`nonnegative_tensions`, :func:`min_norm_nonnegative`); and two scipy
fall-backs of :func:`cdpr_design.statics.hanging.forward.fk_arrays`: a feasibility
phase (:func:`feasibility_phase`) and a local constrained minimisation of the
potential energy (:func:`local_minimum`).

Units: SI (m, N, rad); conventions of :mod:`cdpr_design.statics.hanging.geometry`.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.statics.hanging import geometry as hg


def nonnegative_tensions(W, w):
    """Tensions t >= 0 with W t = w: the least-squares min-norm solution when it is
    non-negative, else scipy's NNLS.  Returns (t, residual 2-norm)."""
    t, *_ = np.linalg.lstsq(W, w, rcond=None)
    if np.all(t >= 0):
        return t, float(np.linalg.norm(W @ t - w))
    from scipy.optimize import nnls
    t, r = nnls(W, w)
    return t, float(r)


def min_norm_nonnegative(W, w):
    """The minimum 2-norm t >= 0 with W t = w (a small QP; SLSQP)."""
    t0, r = nonnegative_tensions(W, w)
    from scipy.optimize import minimize
    sol = minimize(lambda t: 0.5 * t @ t, t0, jac=lambda t: t, method="SLSQP",
                   bounds=[(0.0, None)] * W.shape[1],
                   constraints=[{"type": "eq", "fun": lambda t: W @ t - w, "jac": lambda t: W}],
                   options={"ftol": 1e-14, "maxiter": 200})
    t = np.maximum(sol.x, 0.0)
    return (t, float(np.linalg.norm(W @ t - w))) if sol.success else (t0, r)


def newton(geo: hg.Geometry, rho, p, R, t, S, dofs, tol_f, maxit=60):
    """Newton's method on force + moment balance (``dofs`` rows) and the taut
    cables' lengths |l_i| = rho_i (i in S), unknowns the configuration and t_S.

    Steps solve the linearised system in the least-squares sense (a cable set
    that over-determines the pose gives the minimum-norm tension update) and
    are halved until the scaled residual decreases.  Returns (p, R, t,
    balance residual [N, N m], length residual [m]).
    """
    dofs = list(dofs)
    S = list(S)
    t = np.array(t, float)
    ls = geo.size

    def res(p, R, t):
        b = geo.balance(p, R, t)[dofs]
        L = geo.cables(p, R)[2]
        return b, L[S] - rho[S]

    def merit(b, e):
        sc = np.array([1.0 if k < 3 else ls for k in dofs])
        return float(np.linalg.norm(b / sc) / geo.weight + np.linalg.norm(e) / ls)

    b, e = res(p, R, t)
    cur = merit(b, e)
    for _ in range(maxit):
        if np.max(np.abs(b), initial=0.0) <= tol_f and np.max(np.abs(e), initial=0.0) <= 1e-13 * (1 + rho.max()):
            break
        Jz, Jt, G = geo.jacobian(p, R, t, S)
        J = np.block([[Jz[np.ix_(dofs, dofs)], Jt[dofs]], [G[:, dofs], np.zeros((len(S), len(S)))]])
        F = np.concatenate([b, e])
        step, *_ = np.linalg.lstsq(J, -F, rcond=None)
        lam = 1.0
        improved = False
        for _ in range(16):
            dz = np.zeros(6)
            dz[dofs] = lam * step[: len(dofs)]
            p2 = p + dz[:3]
            R2 = hg.rotvec(dz[3:]) @ R
            t2 = t.copy()
            t2[S] += lam * step[len(dofs):]
            b2, e2 = res(p2, R2, t2)
            new = merit(b2, e2)
            if new < cur or (new <= cur * (1 + 1e-12) and lam == 1.0):
                p, R, t, b, e, cur = p2, R2, t2, b2, e2, new
                improved = True
                break
            lam *= 0.5
        if not improved:
            break
    return p, R, t, float(np.max(np.abs(b), initial=0.0)), float(np.max(np.abs(e), initial=0.0))


def refine(geo: hg.Geometry, rho, p, R, dofs, tol_f, ltol, active_tol=1e-7):
    """An equilibrium near (p, R): Newton's method with an active set of taut cables.

    Starts with the cables whose length is within ``active_tol`` [m] of rho;
    drops a cable whose tension turns negative, adds one that the pose
    stretches beyond rho + ``ltol``, and repeats.  When more cables are taut
    than the pose has degrees of freedom and they lock it, the tensions are
    statically indeterminate: the minimum-norm non-negative ones are kept.
    Returns (p, R, t, S, balance residual, indeterminate, length residual), or
    None when Newton's method does not converge (the caller then minimises first).
    """
    dofs = list(dofs)
    n = len(dofs)
    L = geo.cables(p, R)[2]
    S = sorted(int(i) for i in np.flatnonzero(L >= rho - active_tol))
    ttol = 1e-9 * geo.weight
    seen = set()
    for _ in range(3 * geo.m + 3):
        key = tuple(S)
        if key in seen:
            break
        seen.add(key)
        t = np.zeros(geo.m)
        W, wg = geo.wrenches(p, R)
        if S:
            t[S], _ = nonnegative_tensions(W[np.ix_(dofs, S)], -wg[dofs])
        p1, R1, t1, rb, rl = newton(geo, rho, p, R, t, S, dofs, tol_f)
        indeterminate = False
        if len(S) > n:
            _, _, G = geo.jacobian(p1, R1, t1, S)
            if np.linalg.matrix_rank(G[:, dofs], tol=1e-9) == n:
                indeterminate = True
                W, wg = geo.wrenches(p1, R1)
                tS, _ = min_norm_nonnegative(W[np.ix_(dofs, S)], -wg[dofs])
                t1 = np.zeros(geo.m)
                t1[S] = tS
                rb = float(np.max(np.abs(geo.balance(p1, R1, t1)[dofs])))
        L1 = geo.cables(p1, R1)[2]
        neg = [i for i in S if t1[i] < -ttol]
        over = [i for i in range(geo.m) if i not in S and L1[i] > rho[i] + ltol]
        if neg:
            S.remove(min(neg, key=lambda i: t1[i]))
            continue
        if over:
            S.append(max(over, key=lambda i: L1[i] - rho[i]))
            S.sort()
            p, R = p1, R1
            continue
        if rl > ltol or rb > 1e3 * tol_f:
            return None  # Newton did not converge with this cable set (inconsistent lengths)
        t1[t1 < 0] = 0.0
        return p1, R1, t1, S, max(rb, 0.0), indeterminate, rl
    return None


def feasibility_phase(geo: hg.Geometry, rho, p, R, dofs, tol):
    """Least squares on the stretches max(0, |l_i| - rho_i) from (p, R) (scipy).

    Returns a configuration with every |l_i| <= rho_i + tol, or None.
    """
    from scipy.optimize import least_squares

    dofs = list(dofs)

    def unpack(x):
        z = np.zeros(6)
        z[dofs] = x
        return p + z[:3], hg.rotvec(z[3:]) @ R

    def fun(x):
        q, Q = unpack(x)
        return np.maximum(geo.cables(q, Q)[2] - rho, 0.0)

    def jac(x):
        z = np.zeros(6)
        z[dofs] = x
        q, Q = p + z[:3], hg.rotvec(z[3:]) @ R
        Rb, _, L, u = geo.cables(q, Q)
        G = np.hstack([-u, -np.cross(Rb, u)])
        G[:, 3:] = G[:, 3:] @ hg.left_jacobian(z[3:])
        G[L <= rho] = 0.0
        return G[:, dofs]

    sol = least_squares(fun, np.zeros(len(dofs)), jac=jac, xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=500)
    if np.max(sol.fun, initial=0.0) > tol:
        return None
    return unpack(sol.x)


def local_minimum(geo: hg.Geometry, rho, p, R, dofs):
    """Minimise U subject to |l_i|^2 <= rho_i^2 from a feasible (p, R) (scipy SLSQP,
    rotation as exp([w]) R with analytic gradients).  Returns (p, R)."""
    from scipy.optimize import minimize

    dofs = list(dofs)
    scale_u = geo.weight * (1.0 + float(np.max(rho)))

    def unpack(x):
        z = np.zeros(6)
        z[dofs] = x
        return p + z[:3], hg.rotvec(z[3:]) @ R, z[3:]

    def f(x):
        q, Q, _ = unpack(x)
        return geo.energy(q, Q) / scale_u

    def df(x):
        _, Q, w = unpack(x)
        fg = geo.mass * geo.g
        grad = np.concatenate([-fg, hg.left_jacobian(w).T @ -np.cross(Q @ geo.c, fg)])
        return grad[dofs] / scale_u

    def cons(x):
        q, Q, _ = unpack(x)
        L = geo.cables(q, Q)[2]
        return (rho ** 2 - L ** 2) / np.maximum(rho, 1e-9) ** 2

    def dcons(x):
        q, Q, w = unpack(x)
        Rb, l, _, _ = geo.cables(q, Q)
        G = np.hstack([2.0 * l, 2.0 * np.cross(Rb, l) @ hg.left_jacobian(w)])
        return G[:, dofs] / np.maximum(rho, 1e-9)[:, None] ** 2

    sol = minimize(f, np.zeros(len(dofs)), jac=df, method="SLSQP",
                   constraints=[{"type": "ineq", "fun": cons, "jac": dcons}],
                   options={"ftol": 1e-14, "maxiter": 300})
    q, Q, _ = unpack(sol.x)
    return q, Q
