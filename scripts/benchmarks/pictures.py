"""CPU of drawing the ``workspace`` command's pictures, as the picture worker draws them.

For each design the spec is loaded and swept (``workspaces.run`` on ``make_grid(design, step)``),
then ``workspace.png`` and ``tension_map.png`` are drawn in a child process set up as the picture
worker is (:mod:`cdpr_design.plots.worker`: matplotlib warmed up, the request unpickled, one
warm-up draw), one picture per request, in the child's CPU time; ``gc`` is the garbage collection
the worker runs after answering (off the parent's path, counted in the figure).  With
``--baseline DIR`` the same pictures are drawn by the other checkout in a second child,
alternately with this one, so both see the same load; the ratio is baseline / this checkout.
``png`` (a folder) keeps the PNGs to look at.
"""

from __future__ import annotations

import pickle
import subprocess
import sys
from pathlib import Path

from benchmarks import harness as h

OPTIONS = {"designs": ("ipanema3", "cogiro", "planar2", "planar4"), "repeat": 7, "png": ""}
QUICK = {"designs": ("ipanema3", "planar2"), "repeat": 3}

#: Each design's grid step [m].
STEPS = {"ipanema3": 0.14, "cogiro": 0.5, "planar2": 0.01, "planar4": 0.02}

#: The child: draws the jobs pickled in its argument the way the picture worker does, one job per
#: line read (``draw K``: CPU of the answer, of the collection after it, PNG bytes; ``png K FILE``).
CHILD = r"""
import gc, pickle, sys, time
from pathlib import Path
from cdpr_design.plots import worker
from cdpr_design.plots.worker import _warm_up, draw
_warm_up()
jobs = pickle.load(open(sys.argv[1], "rb"))
draw(jobs)  # warm-up: fonts, colour maps, caches
print("ready", flush=True)
for line in sys.stdin:
    cmd = line.split()
    if cmd[0] == "draw":  # as the worker answers a request, then collects its garbage
        t = time.process_time()
        res = worker.answer([jobs[int(cmd[1])]])
        t1 = time.process_time()
        gc.collect()
        print(f"{t1 - t} {time.process_time() - t1} {len(res[1][0][1])}", flush=True)
    elif cmd[0] == "png":
        Path(cmd[2]).write_bytes(draw([jobs[int(cmd[1])]])[0][1])
        print("done", flush=True)
"""


class Side:
    """A child drawing one checkout's pictures."""

    def __init__(self, root: Path, path: Path):
        self.proc = subprocess.Popen([sys.executable, "-c", CHILD, str(path)], env=h.env_for(root), text=True,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, cwd=root)
        assert self.proc.stdout.readline().strip() == "ready"

    def ask(self, line: str) -> str:
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        return self.proc.stdout.readline().strip()

    def draw(self, k: int) -> tuple[h.Timing, int]:
        t, gc_t, n = self.ask(f"draw {k}").split()
        return h.Timing(float(t) + float(gc_t), float(t) + float(gc_t)), int(n)

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait()


def run(b: h.Bench) -> None:
    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec
    from cdpr_design.plots import workspace as wsplots
    from cdpr_design.plots._style import DPI

    figs = (("workspace.png", wsplots.workspace_figure), ("tension_map.png", wsplots.tension_figure))
    roots = {"this": h.ROOT} | ({"baseline": b.baseline} if b.baseline else {})
    for name in b.opt["designs"]:
        d = spec.load(h.ROOT / "designs" / f"{name}.yaml")
        r = ws.run(d, grid=ws.make_grid(d, STEPS[name], False))
        path = b.tmp / f"{name}.pkl"
        with open(path, "wb") as fh:  # the figure functions by name: each side imports its own
            pickle.dump([(n, f, (r,), DPI) for n, f in figs], fh)
        sides = {k: Side(root, path) for k, root in roots.items()}
        for k, (pic, _) in enumerate(figs):
            size = {}

            def draw(s):
                t, size[s] = sides[s].draw(k)
                return t

            t = h.rounds({s: (lambda s=s: draw(s)) for s in sides}, b.opt["repeat"])
            kb = " / ".join(f"{size[s] / 1024:.0f}" for s in sides)
            b.row(f"{name} {pic} ({r.poses:,} poses), CPU with its gc", f"{h.seconds(h.spread(x.cpu for x in t['this']))}"
                  f", PNG {kb} kB", h.ratios(t["baseline"], t["this"], "cpu") if b.baseline else None,
                  "the baseline checkout's drawing" if b.baseline else "")
            if b.opt["png"]:
                for s, side in sides.items():
                    out = Path(b.opt["png"]) / s
                    out.mkdir(parents=True, exist_ok=True)
                    side.ask(f"png {k} {out / (name + '_' + pic)}")
        for side in sides.values():
            side.close()
