"""Benchmark of ``cdpr-design optimize``: trials per second on planar2 and IPAnema 3, and the 2-worker speed-up.

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

With ``--samplers``, also the choice of the multi-objective sampler: on
planar2 (the two outlets; maximise the task minimum margin, minimise the peak
tension; the spec's requirements as constraints) multi-objective TPE and
NSGA-II (optuna's defaults otherwise) run the same number of trials for
several seeds, and the hypervolume of each run's front of complete trials
is compared (the reference point: the worst complete values of all runs).

    python scripts/bench_optimize.py            # about 4 minutes on 2 cores
    python scripts/bench_optimize.py --quick    # fewer trials, no cold cache
    python scripts/bench_optimize.py --samplers # the sampler comparison only (about 5 minutes)
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cdpr_design import batch  # noqa: E402
from cdpr_design import optimize as opt  # noqa: E402
from cdpr_design.model import spec  # noqa: E402

LOWER_OUTLETS = [f"cables.c{k}.outlet.2=-0.6:1.5" for k in (5, 6, 7, 8)]


def planar2_light():
    raw = spec.load(ROOT / "designs" / "planar2.yaml").raw
    raw = {**raw, "winch": {k: v for k, v in raw["winch"].items() if k != "motor"},
           "requirements": {k: v for k, v in raw["requirements"].items() if k not in ("max_speed", "max_acceleration")}}
    return spec.from_dict(raw)


def ipanema3(task_box: bool):
    raw = dict(spec.load(ROOT / "designs" / "ipanema3.yaml").raw)
    if task_box:
        raw["requirements"] = {"task_box": {"lower": [-1.5, -1.0, 0.75], "upper": [1.5, 1.0, 1.75]}}
        raw["workspace"] = {**raw["workspace"], "grid": {**raw["workspace"]["grid"], "step": 0.25}}
    return spec.from_dict(raw, source="designs/ipanema3.yaml")


def problems(quick: bool):
    cat = spec.load_catalogue()
    n = 40 if quick else 120
    return [
        ("planar2, 2 outlets, task box", planar2_light(),
         ["cables.0.outlet.0=-0.5:0.5", "cables.1.outlet.0=1:2"], ["task_min_margin"], [], None, 3 * n // 2),
        ("IPAnema 3 with a task box, 4 heights", ipanema3(True), LOWER_OUTLETS, ["task_min_margin"], [], None,
         n // 2),
        ("IPAnema 3 workspace at 1 m, 5 keys, 2 objectives", ipanema3(False), LOWER_OUTLETS + ["tension.1=1000:4000"],
         ["fraction"], ["peak_motor_torque"], 1.0, n // 3),
    ], cat


def cpu_s() -> float:
    """CPU time of this process and its ended children (the worker processes, once joined) [s]."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def run(pb, trials: int, workers: int) -> tuple[float, float, list, dict]:
    """Wall time [s], CPU time [s], the trials, and where a worker's time went (:func:`timing`)."""
    with tempfile.TemporaryDirectory() as tmp:
        c0, w0 = cpu_s(), time.time()
        st = opt.run(pb, Path(tmp), trials, workers=workers, seed=1)
        cpu = cpu_s() - c0
        done = opt.finished(opt.study.load(tmp))
        rows = opt.results.trials(done)
    assert len(rows) == trials, (len(rows), trials)
    return st.elapsed_s, cpu, rows, timing(done, w0, st.elapsed_s)


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


def baseline(pb, rows) -> float:
    """The same variants evaluated without optuna, in this process [s]."""
    job = pb.job()
    t = time.perf_counter()
    for r in rows:
        opt.problem.evaluate(pb, job, r.number, r.params)
    return time.perf_counter() - t


FIRST = """
import time, sys; t0 = time.perf_counter()
sys.path.insert(0, {root!r}); sys.argv = ["x", "--quick"]
import runpy; m = runpy.run_path({script!r}, run_name="bench")
from cdpr_design import optimize as opt, batch
from cdpr_design.model import spec
pb = opt.make_problem(m["ipanema3"](True), m["LOWER_OUTLETS"], ["task_min_margin"], None, None,
                      batch.Options(catalogue=spec.load_catalogue()))
t1 = time.perf_counter()
opt.problem.evaluate(pb, pb.job(), 0, {{p.key: (p.low + p.high) / 2 for p in pb.space.params}})
t2 = time.perf_counter()
opt.problem.evaluate(pb, pb.job(), 1, {{p.key: p.low for p in pb.space.params}})
print(f"{{t1 - t0:.2f}} {{t2 - t1:.2f}} {{time.perf_counter() - t2:.3f}}")
"""


def first_trial(cache_dir: str | None) -> list[float]:
    env = dict(os.environ)
    if cache_dir:
        env["NUMBA_CACHE_DIR"] = cache_dir
    code = FIRST.format(root=str(ROOT), script=str(Path(__file__).resolve()))
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout.split()
    return [float(x) for x in out]


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

    design = spec.load(ROOT / "designs" / "planar2.yaml")
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer trials, no cold-cache start-up")
    ap.add_argument("--samplers", action="store_true", help="only the multi-objective sampler comparison")
    args = ap.parse_args()
    if args.samplers:
        compare_samplers(100, range(5))
        return
    print(f"cores: {batch.default_workers()}, load average before: {os.getloadavg()[0]:.2f}")
    print("first IPAnema 3 trial in a fresh process (imports, first evaluation, second) [s]:")
    imp, first, second = first_trial(None)
    print(f"  warm numba cache: {imp:.2f} + {first:.2f}, then {second:.3f}")
    if not args.quick:
        with tempfile.TemporaryDirectory() as d:
            imp, first, second = first_trial(d)
        print(f"  cold numba cache: {imp:.2f} + {first:.2f} (compiles), then {second:.3f}")
    cases, cat = problems(args.quick)
    for name, design, vary, maxi, mini, step, trials in cases:
        pb = opt.make_problem(design, vary, maxi, mini, None, batch.Options(step=step, catalogue=cat))
        run(pb, 3, 1)  # warm this process (kernels, optuna, SQLite)
        t1, c1, rows, _ = run(pb, trials, 1)
        t2, c2, _, tm2 = run(pb, trials, 2)
        base = baseline(pb, rows)
        print(f"\n{name} ({pb.describe()['evaluates']}), {trials} trials:")
        print(f"  1 worker : {t1:6.1f} s  {trials / t1:6.2f} trials/s  CPU {c1:6.1f} s")
        print(f"  2 workers: {t2:6.1f} s  {trials / t2:6.2f} trials/s  CPU {c2:6.1f} s  (speed-up {t1 / t2:.2f}x)")
        print(f"  per trial, 1 worker: {1e3 * t1 / trials:.0f} ms = evaluation {1e3 * base / trials:.0f} ms "
              f"(the same variants without optuna) + optuna and SQLite {1e3 * (t1 - base) / trials:.0f} ms")
        print("  2 workers, where the time went:")
        print_timing(tm2)
    print(f"\nload average after: {os.getloadavg()[0]:.2f} (other work on the machine skews the ratios)")


if __name__ == "__main__":
    main()
