"""The first ``workspace`` run of every shipped design, cold and warm.

For each design, ``cdpr-design workspace DESIGN --json`` in a new process, started as the installed
command starts (:data:`~benchmarks.harness.ENTRY_POINT`, on any checkout); the wall time, and the
CPU of the command's process and of the processes it waits for (the picture process, which it does
not wait for, is not in it):

1. cold: numba's cache a new, empty folder (every kernel the design uses compiled);
2. warm: the same folder again (loaded from numba's cache), in interleaved rounds;
3. the total compile: one new folder for all designs run one after the other, so that each kernel
   is compiled once, by the first design that needs it: the sum over the designs of (that run's
   CPU - the design's warm CPU).

With ``--baseline DIR`` the baseline checkout runs beside this one (its cold run just before this
one's, its warm runs in the same rounds), the rows give the ratios baseline / this checkout, and
the two checkouts' outputs are compared (``workspace.csv`` and ``summary.json`` without its times):
a change to how the kernels compile must not change a number.
"""

from __future__ import annotations

import filecmp
import json
from pathlib import Path

from benchmarks import harness as h

OPTIONS = {"designs": None, "total": True}
QUICK = {"designs": ("ipanema3", "planar2"), "total": False}


def workspace(b: h.Bench, root: Path, design: str, cache: Path, out: Path | None = None) -> h.Timing:
    out = out or b.folder("out")
    t, _ = h.command(["workspace", str(root / "designs" / f"{design}.yaml"), "--out", str(out), "--overwrite"],
                     root=root, cache=cache)
    return t


def same_outputs(a: Path, b: Path) -> bool:
    """``workspace.csv`` byte-identical and ``summary.json`` equal without its times."""
    def summary(folder):
        s = json.loads((folder / "summary.json").read_text())
        for key in ("timings", "elapsed_s"):
            s.pop(key, None)
        return s

    return filecmp.cmp(a / "workspace.csv", b / "workspace.csv", shallow=False) and summary(a) == summary(b)


def run(b: h.Bench) -> None:
    designs = b.opt["designs"]
    if isinstance(designs, str):
        designs = designs.split(",")
    designs = list(designs or sorted(p.stem for p in (h.ROOT / "designs").glob("*.yaml")))
    roots = ({"baseline": b.baseline} if b.baseline else {}) | {"this": h.ROOT}
    warm_cpu = {}
    for name in designs:
        caches = {k: b.fresh_cache() for k in roots}
        outs = {k: b.folder(f"{name}-{k}") for k in roots}
        cold = {k: workspace(b, r, name, caches[k], outs[k]) for k, r in roots.items()}
        warm = h.rounds({k: (lambda k=k: workspace(b, roots[k], name, caches[k])) for k in roots}, b.rounds)
        warm_cpu[name] = h.spread(t.cpu for t in warm["this"]).median
        b.row(f"{name}: first workspace, cold (empty numba cache)", f"{cold['this'].wall:.2f} s, "
              f"{cold['this'].cpu:.1f} CPU-s", h.ratios([cold["baseline"]], [cold["this"]]) if b.baseline else None,
              "the baseline checkout, cold" if b.baseline else "")
        b.row(f"{name}: workspace, warm", f"{h.seconds(h.spread(t.wall for t in warm['this']))}, "
              f"{h.spread(t.cpu for t in warm['this']).text()} CPU-s",
              h.ratios(warm["baseline"], warm["this"]) if b.baseline else None,
              "the baseline checkout, warm" if b.baseline else "")
        if b.baseline:
            b.say(f"{name}: outputs {'identical' if same_outputs(outs['baseline'], outs['this']) else 'DIFFER'}")
    if b.opt["total"]:
        cache = b.fresh_cache()
        total = sum(max(0.0, workspace(b, h.ROOT, n, cache).cpu - warm_cpu[n]) for n in designs)
        b.row("cold compile of every kernel the designs use (one cache, CPU - warm CPU)", f"{total:.1f} CPU-s")
