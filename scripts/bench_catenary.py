"""Benchmark: batched elastic-catenary inverse against per-cable scipy.

Solves the inverse problem (span X, height Z, unstretched length L0 -> end
forces H, VB) for ~1e5 random cables with
:func:`cdpr_design.kernels.catenary.catenary_inverse_batch` (numba, parallel
over cables), cold (first call in this process: compilation, or loading numba's
on-disk cache) and warm, and with a plain per-cable scipy implementation
(``scipy.optimize.fsolve`` on Irvine's closure equations with their analytic
Jacobian, from the same kind of start as the kernel, ``least_squares`` if
fsolve gives up), run on
a subsample in the same process and scaled per cable.  Prints both per-cable
times and their ratio, and how well the two agree.

Usage:  python scripts/bench_catenary.py [--n 100000] [--n-scipy 2000] [--fresh-cache]

``--fresh-cache`` points numba at an empty cache directory, so "cold" is a
real compilation.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))


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


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=100_000, help="cables for the numba kernel")
    ap.add_argument("--n-scipy", type=int, default=2000, help="cables for the scipy reference (a subsample)")
    ap.add_argument("--repeat", type=int, default=3, help="warm repetitions (best is kept)")
    ap.add_argument("--fresh-cache", action="store_true", help="compile from scratch (empty numba cache)")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    if args.fresh_cache:
        os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="numba-cache-")

    import numba
    from cdpr_design.kernels import parallel

    from cdpr_design.kernels import catenary as C

    rng = np.random.default_rng(args.seed)
    H, VB, L0, w, EA = random_cables(rng, args.n)
    X, Z = C.catenary_ends_batch(H, VB, L0, w, EA)
    nan = np.full(args.n, np.nan)
    # the forward batch above compiled/loaded catenary_ends_batch only; the inverse is cold here
    t0 = time.perf_counter()
    h, v, status, iters = C.catenary_inverse_batch(X, Z, L0, w, EA, nan, nan, 1e-12, 100)
    t_cold = time.perf_counter() - t0
    t_warm = math.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        h, v, status, iters = C.catenary_inverse_batch(X, Z, L0, w, EA, nan, nan, 1e-12, 100)
        t_warm = min(t_warm, time.perf_counter() - t0)
    F = np.maximum.reduce([H, np.abs(VB), np.abs(VB + w * L0)])
    err = np.maximum(np.abs(h - H), np.abs(v - VB)) / F

    idx = rng.choice(args.n, size=min(args.n_scipy, args.n), replace=False)
    t0 = time.perf_counter()
    sp = [scipy_inverse(X[i], Z[i], L0[i], w[i], EA[i]) for i in idx]
    t_scipy = time.perf_counter() - t0
    sp_ok = np.array([s[2] for s in sp])
    sp_err = np.array([max(abs(s[0] - H[i]), abs(s[1] - VB[i])) / F[i] for s, i in zip(sp, idx)])

    n = args.n
    per_cold = t_cold / n
    per_warm = t_warm / n
    per_scipy = t_scipy / idx.size
    print(f"numba {numba.__version__}, {parallel.threads()} threads"
          + ("; fresh cache (cold = compilation)" if args.fresh_cache else ""))
    print(f"kernel: {n} cables, converged {np.count_nonzero(status == C.CAT_CONVERGED)}, "
          f"Newton iterations mean {iters.mean():.2f} max {iters.max()}, "
          f"round-trip error max {err.max():.1e} (median {np.median(err):.1e})")
    print(f"  cold {t_cold:8.3f} s  = {per_cold * 1e6:9.3f} us/cable")
    print(f"  warm {t_warm:8.3f} s  = {per_warm * 1e6:9.3f} us/cable")
    print(f"scipy fsolve: {idx.size} cables, converged {sp_ok.sum()}, "
          f"error max {np.max(sp_err[sp_ok]) if sp_ok.any() else np.nan:.1e} "
          f"(>1e-6 on {np.count_nonzero(~sp_ok | (sp_err > 1e-6))})")
    print(f"  {t_scipy:8.3f} s  = {per_scipy * 1e6:9.3f} us/cable")
    print(f"ratio scipy / kernel per cable: cold {per_scipy / per_cold:8.1f}x   warm {per_scipy / per_warm:8.1f}x")


if __name__ == "__main__":
    main()
