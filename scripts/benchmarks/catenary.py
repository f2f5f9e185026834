"""The batched elastic-catenary inverse against a per-cable scipy solve.

The inverse problem (span X, height Z, unstretched length L0 -> end forces H, VB) for random
cables from slack to taut with :func:`cdpr_design.kernels.catenary_inv.catenary_inverse_batch` (numba,
parallel over cables), cold (a new process with an empty numba cache: compiled) and warm, against
``scipy.optimize.fsolve`` on Irvine's closure equations with their analytic Jacobian (from the
same kind of start as the kernel, ``least_squares`` if fsolve gives up), on a subsample in the
same rounds, per cable; and how well the two agree.
"""

from __future__ import annotations

import math

import numpy as np

from benchmarks import harness as h

OPTIONS = {"n": 100_000, "n_scipy": 2000, "seed": 1}
QUICK = {"n": 20_000, "n_scipy": 300}


def random_cables(rng, n):
    """Heavy elastic cables from slack to taut: L0 0.1-100 m, w 1e-3..100 N/m,
    w L0 / H 1e-3..30, slopes to +-89 deg at B, strain 1e-5..1e-1."""
    L0 = 10 ** rng.uniform(-1, 2, n)
    w = 10 ** rng.uniform(-3, 2, n)
    H = w * L0 / 10 ** rng.uniform(-3, 1.5, n)
    VB = H * np.tan(np.radians(rng.uniform(-89, 89, n)))
    T = np.maximum(np.hypot(H, VB), np.hypot(H, VB + w * L0))
    EA = T / 10 ** rng.uniform(-5, -1, n)
    return H, VB, L0, w, EA


def scipy_inverse(X, Z, L0, w, EA):
    """One cable with scipy.optimize.fsolve: Irvine's equations as printed
    (with 1/w), analytic Jacobian, H kept positive by solving for ln H."""
    from scipy.optimize import brentq, fsolve, least_squares

    def closure(H, VB):
        VA = VB + w * L0
        Xc = H / w * (math.asinh(VA / H) - math.asinh(VB / H)) + H * L0 / EA
        Zc = H / w * (math.sqrt(1 + (VA / H) ** 2) - math.sqrt(1 + (VB / H) ** 2)) + (VA * L0 - 0.5 * w * L0 ** 2) / EA
        return Xc, Zc

    def f(p):
        H = math.exp(p[0])
        Xc, Zc = closure(H, p[1])
        return [Xc - X, Zc - Z]

    def jac(p):
        H = math.exp(p[0])
        VB = p[1]
        VA = VB + w * L0
        TA, TB = math.hypot(H, VA), math.hypot(H, VB)
        dXdH = (math.asinh(VA / H) - math.asinh(VB / H)) / w - (VA / TA - VB / TB) / w + L0 / EA
        dXdV = (H / TA - H / TB) / w
        dZdV = (VA / TA - VB / TB) / w + L0 / EA
        return [[dXdH * H, dXdV], [dXdV * H, dZdV]]

    # start: the better-closing of the straight elastic cable (chord longer than
    # L0) and the inextensible catenary of length L0 (Peyrot-Goulois shape
    # parameter lam = w X / 2H from sinh(lam)/lam = sqrt(L0^2 - Z^2)/X, by brentq)
    starts = []
    c = math.hypot(X, Z)
    if c > L0:
        T = EA * (c / L0 - 1.0)
        starts.append((T * X / c, T * Z / c - 0.5 * w * L0))
    Lc = max(L0, 1.000001 * c)
    rho = math.sqrt(Lc * Lc - Z * Z) / X
    q = math.log(rho) if rho > 1.0 + 1e-15 else 1e-15
    lam = brentq(lambda t: t + math.log1p(-math.exp(-2 * t)) - math.log(2 * t) - q, 1e-7, q + 50.0)  # ln(sinh t / t) = q
    starts.append((w * X / (2.0 * lam), 0.5 * w * (Z / math.tanh(lam) - L0)))
    H0, V0 = min(starts, key=lambda p: np.hypot(*f([math.log(p[0]), p[1]])))
    sol, info, ier, msg = fsolve(f, [math.log(H0), V0], fprime=jac, full_output=True, xtol=1e-13)
    if ier == 1:
        return math.exp(sol[0]), sol[1], True
    # fallback: least_squares (trust region) from the same start
    r = least_squares(f, [math.log(H0), V0], jac=jac, xtol=1e-15, ftol=1e-15, gtol=1e-15, method="lm")
    return math.exp(r.x[0]), r.x[1], bool(r.success and np.max(np.abs(r.fun)) <= 1e-10 * (c + L0))


def problem(n: int, seed: int):
    from cdpr_design.kernels import catenary as C

    H, VB, L0, w, EA = random_cables(np.random.default_rng(seed), n)
    X, Z = C.catenary_ends_batch(H, VB, L0, w, EA)
    return H, VB, L0, w, EA, X, Z


def inverse(X, Z, L0, w, EA):
    from cdpr_design.kernels import catenary_inv as C

    nan = np.full(len(X), np.nan)
    return C.catenary_inverse_batch(X, Z, L0, w, EA, nan, nan, 1e-12, 100)


def cold(n: int, seed: int) -> float:
    """Seconds of the inverse's first call in this process (the forward batch loaded first)."""
    H, VB, L0, w, EA, X, Z = problem(n, seed)
    t, _ = h.timed(inverse, X, Z, L0, w, EA)
    return t.wall


def run(b: h.Bench) -> None:
    from cdpr_design.kernels import catenary_inv as C

    n, seed = b.opt["n"], b.opt["seed"]
    t_cold = h.call_in_child("benchmarks.catenary.cold", n, seed, cache=b.fresh_cache())
    H, VB, L0, w, EA, X, Z = problem(n, seed)
    hh, v, status, iters = inverse(X, Z, L0, w, EA)
    F = np.maximum.reduce([H, np.abs(VB), np.abs(VB + w * L0)])
    err = np.maximum(np.abs(hh - H), np.abs(v - VB)) / F
    idx = b.rng.choice(n, size=min(b.opt["n_scipy"], n), replace=False)
    sp = []
    t = h.rounds({"kernel": lambda: inverse(X, Z, L0, w, EA),
                  "scipy": lambda: sp.__setitem__(slice(None), [scipy_inverse(X[i], Z[i], L0[i], w[i], EA[i])
                                                                for i in idx])}, b.rounds)
    sp_ok = np.array([s[2] for s in sp])
    sp_err = np.array([max(abs(s[0] - H[i]), abs(s[1] - VB[i])) / F[i] for s, i in zip(sp, idx)])
    b.say(f"kernel: {n} cables, converged {np.count_nonzero(status == C.CAT_CONVERGED)}, Newton iterations mean "
          f"{iters.mean():.2f} max {iters.max()}, round-trip error max {err.max():.1e} (median {np.median(err):.1e}); "
          f"scipy: {idx.size} cables, converged {sp_ok.sum()}, error > 1e-6 on "
          f"{np.count_nonzero(~sp_ok | (sp_err > 1e-6))}")
    scale = n / idx.size
    b.row(f"catenary inverse, {n:,} random cables, warm", h.per_pose(h.best(t["kernel"]), n).replace("pose", "cable"),
          h.ratios(t["scipy"], t["kernel"], scale=scale), "per-cable scipy fsolve")
    b.row(f"catenary inverse, {n:,} cables, cold (empty numba cache, new process)", f"{t_cold:.2f} s",
          h.ratios([h.best(t["scipy"])], [t_cold], scale=scale), "per-cable scipy fsolve (best round)")
