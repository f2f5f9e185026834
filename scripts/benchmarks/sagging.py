"""Sagging-cable workspaces of CoGiRo and IPAnema 3 against scipy and the ideal model.

For each design (designs/cogiro.yaml, designs/ipanema3.yaml) the static
workspace on the design's own grid (39,729 and 55,936 poses) is swept with
sagging cables through :func:`cdpr_design.workspaces.run`, the library call
behind ``cdpr-design workspace`` (the batched numba kernel
:func:`cdpr_design.kernels.sagging.sweep_grid_sagging`, parallel over poses):

* cold: the first sweep in a fresh process (numba's on-disk cache loaded, or compiled with the
  option ``fresh_cache``), one child process per design and model;
* warm: sweeps in this process, in rounds interleaved with the ideal model's;
* ideal: the same grid with ideal (straight, massless) cables, cold and warm:
  the cost of the sagging model relative to the ideal one;
* scipy: the robot-level problem solved pose by pose with ``scipy.optimize.fsolve``
  (``least_squares`` as a fallback) by the independent reference of
  tests/test_sagging.py (Irvine's closure as printed, force and moment balance,
  the minimum-norm conditions with the active bounds of the straight solution
  found by scipy's SLSQP, updated until the KKT conditions hold) on a random
  sample of the grid's poses (those with a straight solution within the
  bounds), timed per pose, in the same process: the ratio
  scipy / kernel per pose (conservative: the kernel's whole sweep time divided
  by its converged poses only, though the infeasible ones cost it time too),
  and how well the two agree.

poses/s are wall-clock with numba's threads (2 on the reference machine); as
the machine may be shared, the CPU time of the sweep is printed too, and
``2 / CPU s per pose`` is the rate two idle cores would reach.

Cable properties: a design with its own sagging properties keeps them;
otherwise every cable gets a 4 mm steel rope (0.6 N/m, EA = 1e6 N),
given through the raw spec (``cable.model: sagging``).
"""

from __future__ import annotations

import copy
import sys
import time

import numpy as np

from benchmarks import harness as h

OPTIONS = {"designs": ("cogiro", "ipanema3"), "n_scipy": 150, "fresh_cache": False}
QUICK = {"designs": ("cogiro",), "n_scipy": 40}
#: 4 mm steel rope: 0.6 N/m, EA = 1e6 N
STEEL_4MM = {"mass_per_length": 0.6 / 9.81, "axial_stiffness": 1e6}


def load(name: str, model: str):
    """designs/<name>.yaml with ``model`` cables (sagging: the design's properties, else STEEL_4MM)."""
    from cdpr_design.model import spec

    design = spec.load(h.ROOT / "designs" / f"{name}.yaml")
    if model == "ideal":
        return spec.with_cable_model(design, "ideal")
    cable = design.cables[0].props
    if cable.model == "sagging" and all(c.props == cable for c in design.cables):
        return design
    raw = copy.deepcopy(design.raw)
    raw["cable"] = dict(raw.get("cable") or {}, model="sagging", **STEEL_4MM)
    for c in raw["cables"]:
        for k in ("model", "mass_per_length", "axial_stiffness"):
            c.pop(k, None)
    return spec.from_dict(raw)


def sweep(name: str, model: str) -> dict:
    """The first static workspace sweep of this process: wall and CPU seconds, the poses."""
    from cdpr_design import workspaces

    t, res = h.timed(workspaces.run, load(name, model))
    return {"wall": t.wall, "cpu": t.cpu, "poses": res.summary()["poses"]}


def scipy_sample(design, rng, n: int):
    """The scipy reference on up to n random grid poses where it applies: (poses, seconds, refs)."""
    from cdpr_design.workspaces import make_grid
    from cdpr_design.workspaces.grid import grid_positions

    sys.path.insert(0, str(h.ROOT))
    from tests.test_sagging import reference

    g, ori = make_grid(design), design.default_orientation_full()
    pos = grid_positions(g, 0, g.size)
    poses, refs, spent = [], [], 0.0
    for k in rng.permutation(g.size):
        pose = [*pos[k], *ori][: len(design.motion.coords)]
        t0 = time.perf_counter()
        ref = reference(design, pose, bounds=True)
        dt = time.perf_counter() - t0
        if ref is None:
            continue  # no straight solution within the bounds: the kernel stops at once there too
        spent += dt
        poses.append(pose)
        refs.append(ref)
        if len(poses) == n:
            break
    return poses, spent, refs


def agreement(design, poses, refs):
    """Kernel against scipy where both converged: (compared, with an active bound, agreeing to
    1e-9 of the largest tension, the largest such difference, other fixed points and how
    many of those have a kernel norm |t| no larger than the reference's).

    Near a flat direction of the minimum-norm problem (a cable at a bound, the others nearly
    free to trade tension) the sagging problem may have several self-consistent minimum-norm
    solutions (fixed points; tests/test_sagging.py checks the kernel's KKT conditions)."""
    from cdpr_design import api

    compared = active = agreed = other = smaller = 0
    worst = 0.0
    for pose, ref in zip(poses, refs):
        res = api.pose(design, pose)
        if not (ref.ok and res.feasible):
            continue
        compared += 1
        active += int(np.any(ref.active))
        d = float(np.max(np.abs(res.tensions - ref.t)) / np.max(ref.t))
        if d <= 1e-9:
            agreed += 1
            worst = max(worst, d)
        else:
            other += 1
            smaller += int(np.linalg.norm(res.tensions) <= np.linalg.norm(ref.t))
    return compared, active, agreed, worst, other, smaller


def run(b: h.Bench) -> None:
    from cdpr_design import workspaces
    from cdpr_design.kernels import parallel

    for name in b.opt["designs"]:
        designs = {m: load(name, m) for m in ("sagging", "ideal")}
        cold = {m: h.call_in_child("benchmarks.sagging.sweep", name, m,
                                   cache=b.fresh_cache() if b.opt["fresh_cache"] else None) for m in designs}
        out = {}
        t = h.rounds({m: (lambda m=m, d=d: out.__setitem__(m, workspaces.run(d)))
                      for m, d in designs.items()}, b.rounds)
        sag = out["sagging"]
        n = sag.summary()["poses"]
        status = sag.summary().get("cable_status", {})
        props = designs["sagging"].cables[0].props
        b.say(f"{name}: {n:,} poses, sagging cables w = {props.mass_per_length * 9.81:.3g} N/m, EA = "
              f"{props.axial_stiffness:.3g} N; status {status}")
        label = f"{name} sagging workspace, {n:,} poses"
        b.row(f"{label}, warm", f"{n / h.best(t['sagging']):,.0f} poses/s, {h.per_pose(h.best(t['sagging'], 'cpu'), n)} "
              f"CPU", h.ratios(t["sagging"], t["ideal"]), "time ÷ the ideal model's (the sagging model's cost)")
        b.row(f"{label}, cold (first sweep of a new process{', empty numba cache' if b.opt['fresh_cache'] else ''})",
              f"{cold['sagging']['wall']:.2f} s", h.ratios([cold["sagging"]["wall"]], [cold["ideal"]["wall"]]),
              "time ÷ the ideal model's, cold")
        poses, spent, refs = scipy_sample(designs["sagging"], b.rng, b.opt["n_scipy"])
        per_scipy = spent / max(len(poses), 1)
        compared, active, agreed, worst, other, smaller = agreement(designs["sagging"], poses, refs)
        b.say(f"scipy fsolve reference: {len(poses)} poses ({sum(r.ok for r in refs)} converged), "
              f"{per_scipy * 1e3:.2f} ms a pose; of {compared} compared ({active} with a bound active) {agreed} agree "
              f"with the kernel to {worst:.1e} of the largest tension; {other} are another fixed point ({smaller} "
              f"with the kernel's norm the smaller)")
        # conservative: all of the kernel's time charged to the poses that converged (status ok)
        n_ok = max(int(status.get("ok", n)), 1)
        b.row(f"{label}: kernel per converged pose", f"scipy {per_scipy * 1e3:.2f} ms a pose",
              h.ratios([per_scipy * n_ok] * len(t["sagging"]), t["sagging"]),
              f"per-pose scipy fsolve (wall, {parallel.threads()} threads)")
        b.row(f"{label}: kernel per converged pose, CPU", "",
              h.ratios([per_scipy * n_ok] * len(t["sagging"]), t["sagging"], "cpu"), "per-pose scipy fsolve (CPU)")
