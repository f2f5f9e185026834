"""``cdpr-design optimize``: trials per second on planar2 and IPAnema 3, and the 2-worker speed-up.

Problems (each a study in a temporary folder):

- planar2, two outlet x coordinates, maximise the task minimum margin (the
  README's example without the motor requirements): trials sweep the task box
  only (3,111 poses, numpy closed form);
- IPAnema 3 with a task box (a 3 x 2 x 1 m box around the centre at 0.25 m,
  585 poses, wrench-feasible under the spec's process load; numba kernels),
  the four lower outlets' heights, maximise the task minimum margin;
- IPAnema 3 without a task box (the README's two-objective example): the
  workspace grid at 1 m and the sizing over its feasible poses.

For each: one worker (this process) and two (this process and a spawned
one), the same number of trials; trials/s, CPU time (this process and its
joined workers: on a shared machine the wall-clock speed-up alone says
little), the speed-up, and the split of a one-worker trial into the
design's evaluation (the baseline: the same variants evaluated without
optuna, in this process) and optuna's share (sampling and the SQLite study);
for the two-worker run, where each worker's time went (start-up, evaluation,
optuna and SQLite, waiting for the claim lock, idle at the end).  Also the
first IPAnema 3 trial in a fresh process with a warm and a cold (empty)
numba cache.

With the option ``samplers``, also the choice of the multi-objective sampler: on
planar2 (the two outlets; maximise the task minimum margin, minimise the peak
tension; the spec's requirements as constraints) multi-objective TPE and
NSGA-II (optuna's defaults otherwise) run the same number of trials for
several seeds, and the hypervolume of each run's front of complete trials
is compared (the reference point: the worst complete values of all runs).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from benchmarks import harness as h

OPTIONS = {"trials": 120, "cold": True, "samplers": False}
QUICK = {"trials": 40, "cold": False}

LOWER_OUTLETS = [f"cables.c{k}.outlet.2=-0.6:1.5" for k in (5, 6, 7, 8)]


def planar2_light():
    from cdpr_design.model import spec

    raw = spec.load(h.ROOT / "designs" / "planar2.yaml").raw
    raw = {**raw, "winch": {k: v for k, v in raw["winch"].items() if k != "motor"},
           "requirements": {k: v for k, v in raw["requirements"].items() if k not in ("max_speed", "max_acceleration")}}
    return spec.from_dict(raw)


def ipanema3(task_box: bool):
    from cdpr_design.model import spec

    raw = dict(spec.load(h.ROOT / "designs" / "ipanema3.yaml").raw)
    if task_box:
        raw["requirements"] = {"task_box": {"lower": [-1.5, -1.0, 0.75], "upper": [1.5, 1.0, 1.75]}}
        raw["workspace"] = {**raw["workspace"], "grid": {**raw["workspace"]["grid"], "step": 0.25}}
    return spec.from_dict(raw, source="designs/ipanema3.yaml")


def problems(n: int):
    return [
        ("planar2, 2 outlets, task box", planar2_light(),
         ["cables.0.outlet.0=-0.5:0.5", "cables.1.outlet.0=1:2"], ["task_min_margin"], [], None, 3 * n // 2),
        ("IPAnema 3 with a task box, 4 heights", ipanema3(True), LOWER_OUTLETS, ["task_min_margin"], [], None,
         n // 2),
        ("IPAnema 3 workspace at 1 m, 5 keys, 2 objectives", ipanema3(False), LOWER_OUTLETS + ["tension.1=1000:4000"],
         ["fraction"], ["peak_motor_torque"], 1.0, n // 3),
    ]


def cpu_s() -> float:
    """CPU time of this process and its ended children (the worker processes, once joined) [s]."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def study(pb, trials: int, workers: int, out: dict | None = None) -> h.Timing:
    """One study of ``trials`` on ``workers``; its trials and where a worker's time went in ``out``."""
    import time

    from cdpr_design import optimize as opt

    with tempfile.TemporaryDirectory() as tmp:
        c0, w0 = cpu_s(), time.time()
        st = opt.run(pb, Path(tmp), trials, workers=workers, seed=1)
        cpu = cpu_s() - c0
        done = opt.finished(opt.study.load(tmp))
        rows = opt.results.trials(done)
    assert len(rows) == trials, (len(rows), trials)
    if out is not None:
        out.update(rows=rows, timing=timing(done, w0, st.elapsed_s))
    return h.Timing(st.elapsed_s, cpu)


def timing(done, start: float, elapsed: float) -> dict:
    """Per worker: seconds from the run's start to its first trial (process start-up), and of its
    trials' wall time the evaluation's share and the rest (sampling, SQLite; from the study's
    timestamps); the mean idle gap between a worker's trials (waiting for the claim lock)."""
    out = {}
    for w in sorted({t.user_attrs["result"]["worker"] for t in done}):
        ts = sorted((t for t in done if t.user_attrs["result"]["worker"] == w), key=lambda t: t.datetime_start)
        walls = [(t.datetime_complete - t.datetime_start).total_seconds() for t in ts]
        evals = [t.user_attrs["result"]["seconds"] for t in ts]
        gaps = [(b.datetime_start - a.datetime_complete).total_seconds() for a, b in zip(ts, ts[1:])]
        out[w] = {"trials": len(ts), "startup": ts[0].datetime_start.timestamp() - start,
                  "eval": sum(evals), "other": sum(walls) - sum(evals), "gap": sum(gaps),
                  "tail": start + elapsed - ts[-1].datetime_complete.timestamp()}
    return out


def print_timing(t: dict) -> None:
    for w, d in t.items():
        n = d["trials"]
        print(f"    worker {w}: {n} trials, first after {d['startup']:.2f} s; per trial: evaluation "
              f"{1e3 * d['eval'] / n:.0f} ms, optuna and SQLite {1e3 * d['other'] / n:.0f} ms, "
              f"waiting between trials {1e3 * d['gap'] / max(1, n - 1):.0f} ms; idle at the end {d['tail']:.2f} s")


def evaluations(pb, rows) -> None:
    """The same variants evaluated without optuna, in this process."""
    from cdpr_design import optimize as opt

    job = pb.job()
    for r in rows:
        opt.problem.evaluate(pb, job, r.number, r.params)


def first_trial() -> list[float]:
    """Seconds of a fresh process's imports and problem, its first IPAnema 3 evaluation, its second."""
    import time

    t0 = time.perf_counter()
    from cdpr_design import batch
    from cdpr_design import optimize as opt
    from cdpr_design.model import spec

    pb = opt.make_problem(ipanema3(True), LOWER_OUTLETS, ["task_min_margin"], None, None,
                          batch.Options(catalogue=spec.load_catalogue()))
    t1 = time.perf_counter()
    opt.problem.evaluate(pb, pb.job(), 0, {p.key: (p.low + p.high) / 2 for p in pb.space.params})
    t2 = time.perf_counter()
    opt.problem.evaluate(pb, pb.job(), 1, {p.key: p.low for p in pb.space.params})
    return [t1 - t0, t2 - t1, time.perf_counter() - t2]


def hypervolume(points, ref) -> float:
    """Area dominated by 2-D points (both minimised) up to ``ref``."""
    pts = sorted(p for p in points if p[0] < ref[0] and p[1] < ref[1])
    area, best_y = 0.0, ref[1]
    for x, y in pts:
        if y < best_y:
            area += (ref[0] - x) * (best_y - y)
            best_y = y
    return area


def compare_samplers(trials: int, seeds: range) -> None:
    import optuna

    from cdpr_design.optimize import study as st

    from cdpr_design import batch
    from cdpr_design import optimize as opt
    from cdpr_design.model import spec

    design = spec.load(h.ROOT / "designs" / "planar2.yaml")
    pb = opt.make_problem(design, ["cables.0.outlet.0=-0.5:0.5", "cables.1.outlet.0=1:2"], ["task_min_margin"],
                          ["peak_tension"], None, batch.Options(catalogue=spec.load_catalogue()))
    samplers = {"multi-objective TPE (ours)": st.make_sampler,
                "NSGA-II": lambda seed: optuna.samplers.NSGAIISampler(seed=seed)}
    fronts: dict[str, list] = {}
    keep = st.make_sampler
    try:
        for name, make in samplers.items():
            st.make_sampler = make
            for seed in seeds:
                with tempfile.TemporaryDirectory() as tmp:
                    opt.run(pb, Path(tmp), trials, seed=seed)
                    rows = opt.results.trials(opt.finished(opt.study.load(tmp)))
                fronts.setdefault(name, []).append([(-r.values[0], r.values[1]) for r in rows
                                                    if r.state == "complete"])
    finally:
        st.make_sampler = keep
    allpts = [p for runs in fronts.values() for run in runs for p in run]
    ref = (max(p[0] for p in allpts), max(p[1] for p in allpts))
    print(f"\nsamplers on planar2 (2 outlets; max task_min_margin, min peak_tension), {trials} trials, "
          f"seeds {seeds.start}-{seeds.stop - 1}: hypervolume of the complete trials' front [N^2]")
    for name, runs in fronts.items():
        hv = [hypervolume(run, ref) for run in runs]
        print(f"  {name:28s} " + "  ".join(f"{h:6.2f}" for h in hv) + f"   mean {sum(hv) / len(hv):6.2f}")


def run(b: h.Bench) -> None:
    from cdpr_design import batch
    from cdpr_design import optimize as opt
    from cdpr_design.model import spec

    if b.opt["samplers"]:
        compare_samplers(100, range(5))
    caches = {"warm": None} | ({"cold": b.fresh_cache()} if b.opt["cold"] else {})
    for what, cache in caches.items():
        imp, first, second = h.call_in_child("benchmarks.optimize.first_trial", cache=cache)
        b.row(f"first IPAnema 3 trial in a fresh process, {what} numba cache", f"imports {imp:.2f} s + first "
              f"evaluation {first:.2f} s, then {second:.3f} s")
    cat = spec.load_catalogue()
    for name, design, vary, maxi, mini, step, trials in problems(b.opt["trials"]):
        pb = opt.make_problem(design, vary, maxi, mini, None, batch.Options(step=step, catalogue=cat))
        study(pb, 3, 1)  # this process warm (kernels, optuna, SQLite)
        one, two = {}, {}
        t = h.rounds({"1": lambda: study(pb, trials, 1, one), "2": lambda: study(pb, trials, 2, two),
                      "evaluations": lambda: evaluations(pb, one["rows"]) if one else None}, b.rounds)
        label = f"optimize {name} ({pb.describe()['evaluates']}), {trials} trials"
        b.row(f"{label}: 2 workers", f"{trials / h.best(t['2']):.2f} trials/s, CPU "
              f"{h.spread(x.cpu for x in t['2']).text()} s", h.ratios(t["1"], t["2"]), "1 worker (wall)")
        b.row(f"{label}: 1 worker", f"{trials / h.best(t['1']):.2f} trials/s, CPU "
              f"{h.spread(x.cpu for x in t['1']).text()} s", h.ratios(t["evaluations"], t["1"]),
              "the same evaluations without optuna (share of the trial's time)")
        for w, d in two["timing"].items():
            n = d["trials"]
            b.say(f"2 workers, worker {w}: {n} trials, first after {d['startup']:.2f} s; per trial: evaluation "
                  f"{1e3 * d['eval'] / n:.0f} ms, optuna and SQLite {1e3 * d['other'] / n:.0f} ms, waiting between "
                  f"trials {1e3 * d['gap'] / max(1, n - 1):.0f} ms; idle at the end {d['tail']:.2f} s")
