"""planar2's static workspace: the numba kernel against the numpy engine; the quick start's command.

Both engines compute, for every grid pose, the cable lengths, the structure matrix, the tensions
t = W^-1 w, feasibility under the bounds and the closed-form capacity margin, in this process on the
same grid (default 0.001 m: 2,253,001 poses), and must agree bit for bit: once with the statistics
only, once handing every row back (as the command does for ``workspace.csv``).

Then the README's quick start, ``cdpr-design workspace designs/planar2.yaml`` in a new process:
as shipped (``auto``: the numpy engine for this small grid, pictures drawn by the picture worker),
without the picture worker, and with the numba engine from an empty numba cache (cold) and warm,
the warm variants in interleaved rounds.
"""

from __future__ import annotations

import numpy as np

from benchmarks import harness as h

OPTIONS = {"step": 0.001, "command": True}
QUICK = {"step": 0.004}


def rows_sweep(design, grid, engine):
    """A sweep handing every row back to the caller (as the command does for workspace.csv)."""
    from cdpr_design import workspaces as ws

    out = {"f": [], "m": [], "t": []}

    def keep(c):
        out["f"].append(c.feasible)
        out["m"].append(c.margin)
        out["t"].append(c.tensions)

    ws.run(design, ws.Analysis(engine=engine), grid=grid, on_chunk=keep, keep_maps=False)
    return [np.concatenate(v) for v in out.values()]


def quick_start(b: h.Bench, cache=None, **env) -> h.Timing:
    t, _ = h.command(["workspace", str(h.ROOT / "designs" / "planar2.yaml"), "--out", str(b.folder("qs")),
                      "--quiet"], cache=cache, **env)
    return t


def run(b: h.Bench) -> None:
    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec

    design = spec.load(h.ROOT / "designs" / "planar2.yaml")
    grid = ws.make_grid(design, b.opt["step"], force=True)
    ws.run(design, ws.Analysis(engine="numba"), step=0.1)  # the kernels loaded (or compiled) before timing
    label = f"planar2, {grid.size:,} poses"
    kernel, numpy_ = rows_sweep(design, grid, "numba"), rows_sweep(design, grid, "numpy")
    for a, c, what in zip(kernel, numpy_, ("feasibility", "margins", "tensions")):
        assert np.array_equal(a.view(np.uint8), c.view(np.uint8)), f"{what} differ between the engines"
    t = h.rounds({"numba": lambda: ws.run(design, ws.Analysis(engine="numba"), grid=grid, keep_maps=False),
                  "numpy": lambda: ws.run(design, ws.Analysis(engine="numpy"), grid=grid, keep_maps=False),
                  "numba rows": lambda: rows_sweep(design, grid, "numba"),
                  "numpy rows": lambda: rows_sweep(design, grid, "numpy")}, b.rounds)
    b.row(f"{label}: numba kernel, statistics only", f"{grid.size / h.best(t['numba']) / 1e6:.3g} M poses/s",
          h.ratios(t["numpy"], t["numba"]), "numpy engine", "results bit-identical")
    b.row(f"{label}: numba kernel, every row to the caller", f"{grid.size / h.best(t['numba rows']) / 1e6:.3g} M poses/s",
          h.ratios(t["numpy rows"], t["numba rows"]), "numpy engine, every row")
    if not b.opt["command"]:
        return
    cache = b.fresh_cache()
    cold = quick_start(b, cache, CDPR_DESIGN_ENGINE="numba")
    quick_start(b)  # bytecode and the numpy path warm
    t = h.rounds({"shipped": lambda: quick_start(b),
                  "no worker": lambda: quick_start(b, CDPR_DESIGN_PICTURE_WORKER="0"),
                  "numba": lambda: quick_start(b, cache, CDPR_DESIGN_ENGINE="numba")}, b.rounds)
    b.row("quick start `workspace designs/planar2.yaml`, as shipped, warm",
          f"{h.seconds(h.spread(x.wall for x in t['shipped']))}, {h.spread(x.cpu for x in t['shipped']).text()} CPU-s",
          h.ratios(t["no worker"], t["shipped"]), "without the picture worker")
    b.row("quick start as shipped, against the numba engine", h.seconds(h.spread(x.wall for x in t["numba"])),
          h.ratios(t["numba"], t["shipped"]), "the numba engine, warm (its time is the figure)")
    b.row("quick start with the numba engine, cold (empty numba cache)", f"{cold.wall:.2f} s, {cold.cpu:.1f} CPU-s")
