#!/usr/bin/env python3
"""Benchmark: CPU time of building and saving the ``workspace`` command's pictures.

For each design the spec is loaded and swept
(``workspaces.run`` on ``make_grid(design, step)``), then ``workspace.png``
and ``tension_map.png`` are drawn with :func:`cdpr_design.plots.worker.draw`
(the function the picture worker runs): one warm-up draw of both, then
``--repeat`` draws of each, timed in process CPU time (best and median).
``--build-only`` also times building the figure without saving it.
``--profile NAME`` prints a cProfile of drawing that design's pictures.
``--png DIR`` writes the PNGs for looking at them.

    python3 scripts/bench_pictures.py [--repeat 5] [--designs ipanema3,cogiro,planar2,planar4]

The designs and grid steps: IPAnema 3 0.14 m (154,440 poses), CoGiRo 0.5 m,
planar2 0.01 m, planar4 0.02 m (spatial and planar, several cable counts).

Figures (2-core development machine, shared), CPU per picture [s], best of 5:

=========  ==================  ===========  ==================  ===========
design     workspace before    after        tension_map before  after
=========  ==================  ===========  ==================  ===========
(filled in below the table by the commit that measured them)
=========  ==================  ===========  ==================  ===========
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

STEPS = {"ipanema3": 0.14, "cogiro": 0.5, "planar2": 0.01, "planar4": 0.02}


def _cpu() -> float:
    return time.process_time()


def child(path: str, repeat: int, profile: bool, build_only: bool) -> None:
    """Time the jobs pickled in ``path`` the way the picture worker draws them: matplotlib
    warmed up as the worker does, the jobs unpickled, one warm-up draw, then ``repeat`` draws."""
    import pickle

    from cdpr_design.plots._style import pyplot
    from cdpr_design.plots.worker import _warm_up, draw

    _warm_up()
    with open(path, "rb") as fh:
        name, jobs = pickle.load(fh)
    draw(jobs)  # warm-up: fonts, colour maps, caches
    for job in jobs:
        times, png = [], b""
        for _ in range(repeat):
            t = _cpu()
            png = draw([job])[0][1]
            times.append(_cpu() - t)
        build = float("nan")
        if build_only:
            bt = []
            for _ in range(repeat):
                t = _cpu()
                fig = job[1](*job[2])
                bt.append(_cpu() - t)
                pyplot().close(fig)
            build = min(bt)
        print(f"{name:10s} {job[0]:16s} {job[2][0].poses:8d} {min(times):10.3f} "
              f"{statistics.median(times):8.3f} {build:8.3f} {len(png) / 1024:7.0f}", flush=True)
        if os.environ.get("BENCH_PNG_DIR"):
            out = Path(os.environ["BENCH_PNG_DIR"])
            out.mkdir(parents=True, exist_ok=True)
            (out / f"{name}_{job[0]}").write_bytes(png)
    if profile:
        import cProfile
        import pstats

        prof = cProfile.Profile()
        prof.enable()
        draw(jobs)
        prof.disable()
        pstats.Stats(prof).sort_stats("cumulative").print_stats(45)
        pstats.Stats(prof).sort_stats("tottime").print_stats(30)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--designs", default="ipanema3,cogiro,planar2,planar4")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--profile", default="", help="design whose drawing is profiled")
    ap.add_argument("--png", default="", help="folder to write the PNGs to")
    ap.add_argument("--build-only", action="store_true", help="also time building the figures alone")
    ap.add_argument("--child", default="", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        return child(args.child, args.repeat, bool(args.profile), args.build_only)

    import pickle
    import subprocess
    import tempfile

    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec
    from cdpr_design.plots import workspace as wsplots
    from cdpr_design.plots._style import DPI

    figs = (("workspace.png", wsplots.workspace_figure), ("tension_map.png", wsplots.tension_figure))
    print(f"{'design':10s} {'picture':16s} {'poses':>8s} {'best CPU s':>10s} {'median':>8s} "
          f"{'build s':>8s} {'PNG kB':>7s}", flush=True)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    if args.png:
        env["BENCH_PNG_DIR"] = args.png
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.designs.split(","):
            d = spec.load(ROOT / "designs" / f"{name}.yaml")
            r = ws.run(d, grid=ws.make_grid(d, STEPS[name], False))
            path = Path(tmp) / f"{name}.pkl"
            with open(path, "wb") as fh:
                pickle.dump((name, [(n, f, (r,), DPI) for n, f in figs]), fh)
            cmd = [sys.executable, __file__, "--child", str(path), "--repeat", str(args.repeat)]
            cmd += ["--profile", "1"] if args.profile == name else []
            cmd += ["--build-only"] if args.build_only else []
            subprocess.run(cmd, check=True, env=env)


if __name__ == "__main__":
    main()
