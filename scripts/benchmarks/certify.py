"""The certified paving (``certify``) against a grid sweep at the same resolution.

For each resolution h: the certified paving of the design's grid box (CPU seconds, inner, boundary
and outer measure) and the grid sweep at step h (``workspaces.run``: CPU seconds and the feasible
volume, feasible fraction x box measure), in the same rounds.  The rows give the inner measure as a
fraction of the grid's feasible measure, the boundary as a fraction of the box, and the CPU ratio
certify / grid, so the growth of time with 1/h can be read off.
"""

from __future__ import annotations

from benchmarks import harness as h

OPTIONS = {"design": "planar2", "resolutions": (0.01, 0.005, 0.002), "max_boxes": 2_000_000}
QUICK = {"resolutions": (0.02, 0.01)}


def run(b: h.Bench) -> None:
    import cdpr_design as cd
    from cdpr_design import workspaces as ws
    from cdpr_design.model.design import Grid
    from cdpr_design.workspaces.certify import certify, check_certifiable, warm_up

    d = cd.load(h.ROOT / "designs" / f"{b.opt['design']}.yaml")
    robot = check_certifiable(d)
    warm_up(robot)
    g0 = d.workspace.grid
    ws.run(d, ws.Analysis(engine="numba"), grid=Grid(g0.lower, g0.lower, g0.step), force=True, keep_maps=False,
           tilt=False)
    for res in b.opt["resolutions"]:
        g = Grid(g0.lower, g0.upper, (res,) * len(g0.lower))
        out = {}
        t = h.rounds({"certify": lambda: out.__setitem__("c", certify(robot, resolution=res, max_boxes=b.opt["max_boxes"])),
                      "grid": lambda: out.__setitem__("g", ws.run(d, ws.Analysis(engine="numba"), grid=g, force=True,
                                                                  keep_maps=False, tilt=False))}, b.rounds)
        s, w = out["c"].summary(), out["g"]
        feas = w.feasible / w.poses * s["box_measure"]
        b.row(f"{b.opt['design']} certify at h = {res} m", f"{h.spread(x.cpu for x in t['certify']).text()} CPU-s, "
              f"{s['boxes_classified']:,} boxes, inner / grid's feasible {s['inner_measure'] / feas:.4f}, boundary "
              f"{100 * s['boundary_measure'] / s['box_measure']:.3g} % of the box"
              + (f", stopped: {s['truncated']}" if s["truncated"] else ""),
              h.ratios(t["grid"], t["certify"], "cpu"), "grid sweep at step h (CPU; below 1: certify slower)")
