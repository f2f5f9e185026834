"""Benchmark: the planar2 tilt map, batched numba kernel against per-pose scipy.

The hanging orientation of planar2's effector (two cables, free orientation)
at every position of a 151 x 151 grid over its 1.5 m frame (22,801 poses),
with :func:`cdpr_design.kernels.hanging.hanging_tilt_batch` cold (first call
in this process: compilation, or loading numba's on-disk cache) and warm
(best of ``--repeat``), and with a plain per-pose scipy solve on a random
subsample in the same process, scaled per pose:

    for each start angle in 8 evenly spaced ones, ``scipy.optimize.least_squares``
    on force + moment balance (unknowns phi, t1, t2; residuals scaled by the
    weight), the distinct converged roots kept; tensions >= 0 and stability
    (second difference of the energy along the constant-length curve) decide;
    the stable one closest to level wins - the kernel's rule.

The same map is also timed through the library's two other paths: the numpy
twin of the kernel (:func:`cdpr_design.statics.hanging.planar2.planar_two_cable`,
what a ``fixed`` design's workspace uses while numba is not loaded) and the
whole ``free`` workspace sweep (:func:`cdpr_design.workspaces.run`: the
hanging orientation, then feasibility, margin and tensions there, streamed
in chunks), cold (first call in this process) and warm.

Prints the per-pose times, their ratios to scipy (cold and warm) and how
well the kernel and scipy agree (orientation and status on the subsample).

Usage:  python scripts/bench_hanging.py [--n-scipy 400] [--com-y 0.0] [--fresh-cache]
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


def scipy_tilt(A, B, c, mass, g, p, starts=8):
    """One position with scipy least_squares from several angles (see module doc)."""
    from scipy.optimize import least_squares

    A2, B2, c2, gv = A[:, :2], B[:, :2], c[:2], g[:2]
    W = mass * float(np.hypot(*gv))

    def rot(phi):
        co, si = math.cos(phi), math.sin(phi)
        return np.array([[co, -si], [si, co]])

    def residual(x):
        phi, t1, t2 = x
        R = rot(phi)
        Rb = B2 @ R.T
        v = A2 - p - Rb
        u = v / np.linalg.norm(v, axis=1)[:, None]
        f = t1 * u[0] + t2 * u[1] + mass * gv
        rc = R @ c2
        mom = sum(t * ((Rb[i, 0] - rc[0]) * u[i, 1] - (Rb[i, 1] - rc[1]) * u[i, 0])
                  for i, t in enumerate((t1, t2)))
        return np.array([f[0], f[1], mom / 0.1]) / W

    def energy_on_curve(phi, rho):
        R = rot(phi)
        C = A2 - B2 @ R.T
        e = C[1] - C[0]
        D = float(np.linalg.norm(e))
        a = (rho[0] ** 2 - rho[1] ** 2 + D ** 2) / (2 * D)
        h = math.sqrt(max(rho[0] ** 2 - a ** 2, 0.0))
        n = np.array([-e[1], e[0]]) / D
        q = min((C[0] + a * e / D + s * h * n for s in (1, -1)), key=lambda q: np.linalg.norm(q - p))
        return -mass * gv @ (q + R @ c2)

    found = []
    for k in range(starts):
        s = least_squares(residual, [-math.pi + 2 * math.pi * k / starts, W / 2, W / 2],
                          xtol=1e-15, ftol=1e-15, gtol=1e-15)
        if np.max(np.abs(s.fun)) > 1e-10:
            continue
        phi = math.atan2(math.sin(s.x[0]), math.cos(s.x[0]))
        if any(abs(phi - f[0]) < 1e-8 for f in found):
            continue
        found.append((phi, s.x[1], s.x[2]))
    best = None
    for phi, t1, t2 in found:
        if min(t1, t2) < -1e-9 * W:
            continue
        rho = np.linalg.norm(A2 - p - B2 @ rot(phi).T, axis=1)
        h = 1e-3
        d2 = energy_on_curve(phi + h, rho) + energy_on_curve(phi - h, rho) - 2 * energy_on_curve(phi, rho)
        if d2 > 0 and (best is None or abs(phi) < abs(best)):
            best = phi
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n-scipy", type=int, default=400, help="positions for the scipy reference (a subsample)")
    ap.add_argument("--repeat", type=int, default=5, help="warm repetitions (best is kept)")
    ap.add_argument("--com-y", type=float, default=None, help="centre of mass height in the platform [m] "
                    "(default: the spec's, 0.06 m below the attachment line)")
    ap.add_argument("--fresh-cache", action="store_true", help="compile from scratch (empty numba cache)")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    if args.fresh_cache:
        os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="numba-cache-")

    import numba
    from cdpr_design.kernels import parallel

    from cdpr_design.model import spec

    root = os.path.join(os.path.dirname(__file__), "..")
    d = spec.load(os.path.join(root, "designs", "planar2.yaml"))
    A, B = d.outlets, d.attachments
    c = np.asarray(d.effector.center_of_mass, float)
    if args.com_y is not None:
        c[1] = args.com_y
    g = np.asarray(d.gravity, float)
    mass = float(d.effector.mass)
    xs = 0.01 * np.arange(151)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    P = np.ascontiguousarray(np.column_stack([X.ravel(), Y.ravel()]))
    n = P.shape[0]

    t0 = time.perf_counter()
    from cdpr_design.kernels import hanging as K
    phi, _, _, status, _ = K.hanging_tilt_batch(A, B, c, mass, g, P)
    t_cold = time.perf_counter() - t0
    t_warm = math.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        phi, _, _, status, _ = K.hanging_tilt_batch(A, B, c, mass, g, P)
        t_warm = min(t_warm, time.perf_counter() - t0)

    import dataclasses

    from cdpr_design import workspaces as ws
    from cdpr_design.statics.hanging.at_positions import hanging_orientations
    from cdpr_design.statics.hanging.geometry import Geometry

    geo = Geometry(A, B, c, mass, g)
    t_numpy = math.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        hanging_orientations(geo, P, True, engine="numpy")
        t_numpy = min(t_numpy, time.perf_counter() - t0)
    free = d.replace(effector=dataclasses.replace(d.effector, orientation="free", center_of_mass=tuple(c)))
    t0 = time.perf_counter()
    res = ws.run(free)
    t_ws_cold = time.perf_counter() - t0
    t_ws = math.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        res = ws.run(free)
        t_ws = min(t_ws, time.perf_counter() - t0)

    rng = np.random.default_rng(args.seed)
    idx = rng.choice(n, size=min(args.n_scipy, n), replace=False)
    t0 = time.perf_counter()
    ref = [scipy_tilt(A, B, c, mass, g, P[i]) for i in idx]
    t_scipy = time.perf_counter() - t0
    ok_k = status[idx] == K.TILT_OK
    ok_s = np.array([r is not None for r in ref])
    both = ok_k & ok_s
    diff = np.abs(phi[idx][both] - np.array([r for r in ref if r is not None])[both[ok_s]])

    per_cold, per_warm, per_scipy = t_cold / n, t_warm / n, t_scipy / idx.size
    tilt = np.degrees(np.abs(phi))
    print(f"numba {numba.__version__}, {parallel.threads()} threads"
          + ("; fresh cache (cold = compilation)" if args.fresh_cache else ""))
    print(f"planar2 tilt map, COM at y = {c[1]:+.3f} m: {n} positions, "
          f"{np.count_nonzero(status == K.TILT_OK)} hang stably, max tilt {np.nanmax(tilt):.2f} deg; "
          f"status counts {np.bincount(status, minlength=5).tolist()}")
    print(f"  kernel cold {t_cold:8.3f} s  = {per_cold * 1e6:9.3f} us/pose")
    print(f"  kernel warm {t_warm:8.3f} s  = {per_warm * 1e6:9.3f} us/pose")
    print(f"scipy least_squares x 8 starts: {idx.size} positions, {t_scipy:.3f} s = {per_scipy * 1e6:9.1f} us/pose; "
          f"status agrees on {np.count_nonzero(ok_k == ok_s)}/{idx.size}, "
          f"max |dphi| {diff.max() if diff.size else float('nan'):.1e} rad")
    print(f"  numpy twin  {t_numpy:8.3f} s  = {t_numpy / n * 1e6:9.3f} us/pose (warm)")
    print(f"  free workspace sweep (tilt + statics at the hanging pose, {res.feasible} feasible): "
          f"cold {t_ws_cold:.3f} s, warm {t_ws:.3f} s = {t_ws / n * 1e6:.3f} us/pose")
    print(f"ratio scipy / kernel per pose: cold {per_scipy / per_cold:8.1f}x   warm {per_scipy / per_warm:8.1f}x")
    print(f"ratio scipy / numpy twin: {per_scipy * n / t_numpy:8.1f}x   scipy / free workspace sweep: "
          f"cold {per_scipy * n / t_ws_cold:8.1f}x   warm {per_scipy * n / t_ws:8.1f}x")
    print(f"estimated full map with scipy: {per_scipy * n:.1f} s")


if __name__ == "__main__":
    main()
