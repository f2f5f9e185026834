"""``cdpr-design sweep`` backends on planar2's variants, against one process.

The same sweep (effector mass x upper tension limit x outlet position of cable c2, n x n x n
variants, the spec's own 0.01 m grid) on this process (``workers=1``, the baseline), a process
pool of 1 and of 2 spawned workers, and a Dask LocalCluster of 2 worker processes (1 thread each)
started for the sweep, in interleaved rounds; every backend must give the same table.  Pools pay
a fixed start-up (spawned processes import numpy / numba / scipy and load the kernels from numba's
on-disk cache): a second, smaller sweep separates that fixed cost from the per-variant throughput.
Also a worker's start-up with a warm and with a cold (empty) numba cache.
"""

from __future__ import annotations

import time

from benchmarks import harness as h

OPTIONS = {"sides": (10, 6), "cold": True}
QUICK = {"sides": (6,), "cold": False}

RUNS = {"this process (1)": dict(workers=1), "process pool, 1 worker": dict(workers=1, pool=True),
        "process pool, 2 workers": dict(workers=2), "Dask LocalCluster, 2 workers": dict(workers=2, scheduler="local")}


def worker_startup() -> list[float]:
    """Seconds of a fresh process's imports and kernel load (as a big sweep's worker does first), its
    first evaluation of planar2, and a second one."""
    t0 = time.perf_counter()
    import importlib

    from cdpr_design import workspaces as ws
    from cdpr_design.kernels import parallel
    from cdpr_design.model import spec

    ev = importlib.import_module("cdpr_design.design.evaluate")
    d, cat = spec.load(h.ROOT / "designs" / "planar2.yaml"), spec.load_catalogue()
    import cdpr_design.kernels.sweep  # noqa: F401 - numba and the sweep kernels loaded before the clock
    parallel.set_threads(1)
    t1 = time.perf_counter()
    ev.evaluate(d, catalogue=cat)
    t2 = time.perf_counter()
    ev.evaluate(d, catalogue=cat)
    return [t1 - t0, t2 - t1, time.perf_counter() - t2]


def plan_of(n_side: int):
    from cdpr_design import batch as sw
    from cdpr_design.model import spec

    design = spec.load(h.ROOT / "designs" / "planar2.yaml")
    return sw.make_plan(design, [
        ("effector.mass", sw.parse_values(f"0.5:2:{n_side}")),
        ("tension.1", sw.parse_values(f"10:30:{n_side}")),
        ("cables.c2.outlet.0", sw.parse_values(f"1.3:1.5:{n_side}")),
    ])


def sweep(plan, tables: list, **kw) -> float:
    """Wall time until every row is in the caller's hands (what a sweep's caller waits for); the
    workers' exit, which overlaps the caller's next steps, is waited for afterwards so that it does
    not disturb the next run."""
    from cdpr_design import batch as sw

    recs = []
    t = time.perf_counter()
    sw.run(plan, sw.Options(), on_record=recs.append, **kw)
    wall = time.perf_counter() - t
    sw.wait_closed()
    tables.append(sw.table(plan, recs))
    return wall


def run(b: h.Bench) -> None:
    for what, cache in {"warm": None, **({"cold": b.fresh_cache()} if b.opt["cold"] else {})}.items():
        imp, first, steady = h.call_in_child("benchmarks.sweep.worker_startup", cache=cache)
        b.row(f"a sweep worker's start-up, {what} numba cache", f"import and kernels {imp:.2f} s + first evaluation "
              f"{first:.2f} s, then {steady * 1e3:.1f} ms")
    walls = {}
    for n_side in b.opt["sides"]:
        plan = plan_of(n_side)
        n = len(plan)
        tables = []
        t = h.rounds({name: (lambda kw=kw: sweep(plan, tables, **kw)) for name, kw in RUNS.items()}, b.rounds)
        if any(tab != tables[0] for tab in tables):
            raise SystemExit("sweep backends: the rows differ between backends")
        walls[n] = t
        base = t["this process (1)"]
        for name in RUNS:
            if name != "this process (1)":
                b.row(f"planar2 sweep, {n:,} variants: {name}", f"{h.best(t[name]) / n * 1e3:.2f} ms a variant",
                      h.ratios(base, t[name]), "this process, one worker (same rows)")
        b.row(f"planar2 sweep, {n:,} variants: process pool, 2 workers", "",
              h.ratios(t["process pool, 1 worker"], t["process pool, 2 workers"]), "process pool, 1 worker")
        b.row(f"planar2 sweep, {n:,} variants: process pool, 2 workers", "",
              h.ratios(t["Dask LocalCluster, 2 workers"], t["process pool, 2 workers"]), "Dask LocalCluster, 2 workers")
    if len(walls) == 2:
        (big, tb), (small, ts) = walls.items()

        def per(name):  # wall = fixed + n x per-variant, from the best runs
            return (h.best(tb[name]) - h.best(ts[name])) / (big - small)

        for name in RUNS:
            b.say(f"{name}: fixed {h.best(tb[name]) - per(name) * big:.2f} s, {per(name) * 1e3:.2f} ms a variant")
        b.row(f"planar2 sweep throughput ({big:,} and {small:,} variants): process pool, 2 workers",
              f"{per('process pool, 2 workers') * 1e3:.2f} ms a variant",
              h.spread([per("process pool, 1 worker") / per("process pool, 2 workers")]), "process pool, 1 worker")
