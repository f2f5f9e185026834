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
if "--child" not in sys.argv:  # a child draws with the checkout on its PYTHONPATH
    sys.path.insert(0, str(ROOT))

STEPS = {"ipanema3": 0.14, "cogiro": 0.5, "planar2": 0.01, "planar4": 0.02}


def _cpu() -> float:
    return time.process_time()


def child(path: str) -> None:
    """Draw the jobs pickled in ``path`` the way the picture worker does (matplotlib warmed up
    as the worker does, the jobs unpickled, one warm-up draw), one job per command read from
    stdin (``draw K``: the CPU time and PNG size printed; ``png K FILE``: the PNG written;
    ``profile``: a cProfile of all jobs printed on stderr)."""
    import gc
    import pickle

    from cdpr_design.plots import worker
    from cdpr_design.plots.worker import _warm_up, draw

    _warm_up()
    with open(path, "rb") as fh:
        jobs = pickle.load(fh)
    draw(jobs)  # warm-up: fonts, colour maps, caches
    print("ready", flush=True)
    for line in sys.stdin:
        cmd = line.split()
        if cmd[0] == "draw":  # as the worker answers a request, then collects its garbage
            t = _cpu()
            job = [jobs[int(cmd[1])]]
            res = worker.answer(job) if hasattr(worker, "answer") else ("ok", draw(job))  # (before: draw)
            t1 = _cpu()
            if hasattr(worker, "answer"):  # the worker collects after answering (before: never)
                gc.collect()
            print(f"{t1 - t} {_cpu() - t1} {len(res[1][0][1])}", flush=True)
        elif cmd[0] == "png":
            Path(cmd[2]).write_bytes(draw([jobs[int(cmd[1])]])[0][1])
            print("done", flush=True)
        elif cmd[0] == "profile":
            import cProfile
            import pstats

            prof = cProfile.Profile()
            prof.enable()
            draw(jobs)
            prof.disable()
            for key, n in (("cumulative", 45), ("tottime", 30)):
                pstats.Stats(prof, stream=sys.stderr).sort_stats(key).print_stats(n)
            print("done", flush=True)


class Side:
    """A child drawing one checkout's pictures (``root``: the checkout's folder)."""

    def __init__(self, root: Path, path: Path):
        import subprocess

        env = {**os.environ, "PYTHONPATH": str(root)}
        self.proc = subprocess.Popen([sys.executable, __file__, "--child", str(path)], env=env, text=True,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        assert self.proc.stdout.readline().strip() == "ready"

    def ask(self, line: str) -> str:
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        return self.proc.stdout.readline().strip()

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait()


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--designs", default="ipanema3,cogiro,planar2,planar4")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--baseline", default="", help="a checkout of the previous version, drawn alternately")
    ap.add_argument("--profile", default="", help="design whose drawing is profiled (on stderr)")
    ap.add_argument("--png", default="", help="folder to write the PNGs to")
    ap.add_argument("--child", default="", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        return child(args.child)

    import pickle
    import tempfile

    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec
    from cdpr_design.plots import workspace as wsplots
    from cdpr_design.plots._style import DPI

    figs = (("workspace.png", wsplots.workspace_figure), ("tension_map.png", wsplots.tension_figure))
    roots = {"this": ROOT} | ({"baseline": Path(args.baseline).resolve()} if args.baseline else {})
    head = "".join(f" {k[:4] + ' best':>10s} {'median':>7s} {'gc':>6s} {'kB':>5s}" for k in roots)
    print(f"{'design':9s} {'picture':16s} {'poses':>7s}{head}" + ("  this/baseline" if args.baseline else ""),
          flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.designs.split(","):
            d = spec.load(ROOT / "designs" / f"{name}.yaml")
            r = ws.run(d, grid=ws.make_grid(d, STEPS[name], False))
            path = Path(tmp) / f"{name}.pkl"
            with open(path, "wb") as fh:  # the figure functions by name: each side imports its own
                pickle.dump([(n, f, (r,), DPI) for n, f in figs], fh)
            sides = {k: Side(root, path) for k, root in roots.items()}
            for k, (pic, _) in enumerate(figs):
                times = {s: [] for s in sides}
                size = {}
                for _ in range(args.repeat):  # interleaved: both sides see the same load
                    for s, side in sides.items():
                        t, gc_t, n = side.ask(f"draw {k}").split()
                        times[s].append((float(t), float(gc_t)))
                        size[s] = int(n)
                total = {s: statistics.median(a + b for a, b in times[s]) for s in sides}
                cols = "".join(f" {min(a for a, _ in times[s]):10.3f} {statistics.median(a for a, _ in times[s]):7.3f} "
                               f"{statistics.median(b for _, b in times[s]):6.3f} {size[s] / 1024:5.0f}"
                               for s in sides)
                ratio = f"  {total['this'] / total['baseline']:.2f}" if args.baseline else ""
                print(f"{name:9s} {pic:16s} {r.poses:7d}{cols}{ratio}", flush=True)
                if args.png:
                    for s, side in sides.items():
                        out = Path(args.png) / s
                        out.mkdir(parents=True, exist_ok=True)
                        side.ask(f"png {k} {out / (name + '_' + pic)}")
            if args.profile == name:
                sides["this"].ask("profile")
            for side in sides.values():
                side.close()


if __name__ == "__main__":
    main()
