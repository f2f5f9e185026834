#!/usr/bin/env python3
"""Benchmark: CPU time of building and saving the ``workspace`` command's pictures.

For each design the spec is loaded and swept (``workspaces.run`` on
``make_grid(design, step)``), then ``workspace.png`` and ``tension_map.png``
are drawn in a child process set up as the picture worker is
(:mod:`cdpr_design.plots.worker`: matplotlib warmed up, the request
unpickled, one warm-up draw), one picture per request, ``--repeat`` times,
timed in the child's CPU time; ``gc`` is the garbage collection the worker
runs after answering (off the parent's path, counted in the ratio).
``--baseline DIR`` draws the same pictures with another checkout (e.g. ``git
archive`` of the previous commit) in a second child, alternately with this
one, so both see the same load on a shared machine; the ratio is of the
medians.  ``--profile NAME`` prints a cProfile of that design's drawing
(stderr), ``--png DIR`` writes the PNGs to look at.

    python3 scripts/bench_pictures.py [--repeat 7] [--baseline DIR] [--designs ipanema3,cogiro,planar2,planar4]

Grid steps: IPAnema 3 0.14 m (154,440 poses), CoGiRo 0.5 m, planar2 0.01 m,
planar4 0.02 m.  Measured on the 2-core development machine (shared, load
about 1-2), CPU per picture [s], median of 9, against 946fb56's pictures:

=========  ===============  =======  =============  =====  ====================
design     picture          before   after + gc     ratio  PNG before/after kB
=========  ===============  =======  =============  =====  ====================
ipanema3   workspace.png    0.600    0.329 + 0.010  0.61  114 / 139
ipanema3   tension_map.png  0.556    0.281 + 0.012  0.53  98 / 125
cogiro     workspace.png    0.571    0.343 + 0.011  0.62  78 / 91
cogiro     tension_map.png  0.680    0.334 + 0.022  0.52  74 / 97
planar2    workspace.png    0.203    0.173 + 0.003  0.87  91 / 103
planar2    tension_map.png  0.218    0.163 + 0.004  0.76  65 / 78
planar4    workspace.png    0.236    0.212 + 0.005  0.92  92 / 97
planar4    tension_map.png  0.339    0.222 + 0.009  0.68  57 / 76
=========  ===============  =======  =============  =====  ====================

Where the time went before (cProfile, IPAnema 3): matplotlib's ticks (each
two lines, a grid line and two texts; 271 made for the two pictures, at
1-2 ms each to make, lay out and draw), the automatic placement of every
panel title (a tight bounding box of each axis), full garbage collections
walking the worker's ~100,000 long-lived objects (a fifth of the time), and
the PNG's zlib.  What changed: the panels' tick labels only on the outer
side (the inner panels' tick marks as one line of markers), no ticks beyond
the limits, titles placed at a fixed height, :func:`gc.freeze` after the
worker's warm-up and no collection while it draws, zlib level 3.  What is
left is each panel's axes (about 6 ms to make), the outer ticks and the
text; a single-panel planar map has little else to save.
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
