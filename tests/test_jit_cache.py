"""numba's on-disk cache of the kernels is invalidated by a change to *any* kernel module.

numba alone keys a cached function on its own file; a kernel calling into an
edited module would load stale machine code (:mod:`cdpr_design.kernels._jit`).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numba as nb
import numpy as np
import pytest

from cdpr_design.kernels import _jit

PACKAGE = Path(__file__).resolve().parents[1] / "cdpr_design"

# eval_square (pose.py) calls square_eval (hsm.py): print the tensions of one square pose
PROBE = """
import numpy as np
from cdpr_design import kernels as K
W = np.array([[1.0, 0.0], [0.0, 1.0]])
t = np.empty(2)
K.eval_square(W, np.array([[3.0, 4.0]]), np.zeros(2), np.full(2, 100.0), 0, t)
print(repr(t.tolist()), sum(K.eval_square.stats.cache_hits.values()))
"""


# chunk_stats (sweep.py) calls no other kernel: print its answer and whether it came from the cache
PROBE_ALONE = """
import numpy as np
from cdpr_design import kernels as K
got = K.chunk_stats(np.ones(2, np.uint8), np.array([1.0, 2.0]), np.ones((2, 1)), 2, np.zeros(1))
print(repr(list(got)), sum(K.chunk_stats.stats.cache_hits.values()))
"""


def _probe(root: Path, code: str = PROBE) -> tuple[list[float], int]:
    env = dict(os.environ, PYTHONPATH=str(root), NUMBA_CACHE_DIR=str(root / "numba-cache"))
    env.pop("NUMBA_DISABLE_JIT", None)
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=root, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr
    values, _, hits = out.stdout.strip().rpartition(" ")
    return eval(values), int(hits)


def _copy_package(root: Path) -> Path:
    shutil.copytree(PACKAGE, root / "cdpr_design", ignore=shutil.ignore_patterns("__pycache__"))
    return root / "cdpr_design" / "kernels"


def test_an_edit_to_any_kernel_module_recompiles_every_kernel(tmp_path):
    """A kernel's cached code is kept while no kernel module changes (a copy of the same sources
    reuses it) and recompiled after an edit to a module it does not even call: the cache is
    keyed on every kernel module's contents (the package digest), not on the kernel's own file."""
    kernels = _copy_package(tmp_path)
    assert _probe(tmp_path, PROBE_ALONE) == ([2, 1.0, 2.0], 0)  # compiled and cached
    assert _probe(tmp_path, PROBE_ALONE) == ([2, 1.0, 2.0], 1)  # loaded from the cache
    hsm = kernels / "hsm.py"
    hsm.write_text(hsm.read_text() + "\n# edited by the test\n")
    assert _probe(tmp_path, PROBE_ALONE) == ([2, 1.0, 2.0], 0)  # compiled again


@pytest.mark.slow
def test_an_edit_to_a_called_module_recompiles_its_callers(tmp_path):
    """The kernel in pose.py is recompiled after an edit to hsm.py alone, not loaded stale; a
    file only touched (its time changed, as a checkout does) is not an edit: loaded from the cache."""
    hsm = _copy_package(tmp_path) / "hsm.py"
    assert _probe(tmp_path) == ([3.0, 4.0], 0)  # compiled and cached
    assert _probe(tmp_path) == ([3.0, 4.0], 1)  # loaded from the cache
    os.utime(hsm, (1, 1))
    assert _probe(tmp_path) == ([3.0, 4.0], 1)  # touched only: still loaded from the cache
    text = hsm.read_text()
    head = "        det = W[0, 0] * W[1, 1] - W[0, 1] * W[1, 0]\n"  # square_eval_into, n = 2
    assert text.count(head) == 1
    hsm.write_text(text.replace(head, head + "        det = det * 2.0  # edited by the test\n", 1))
    assert _probe(tmp_path) == ([1.5, 2.0], 0)  # det doubled: halved tensions, compiled again


def _scaled_py(a, scr, k):
    return a[k] * scr[0][0] + scr[1][0]


_scaled = nb.njit(inline="always")(_scaled_py)


def _pass_on(a, out, scr):
    for k in range(a.shape[0]):
        out[k] = _scaled(a, scr, k)


def test_noref_loops_are_compiled_without_reference_counting():
    """numba honours the option behind ``njit_noref``: the same loop, passing a tuple of arrays on to
    an inlined helper, counts references with the kernels' usual options and not with NOREF."""
    usual = nb.njit(**dict(_jit.JIT, cache=False))(_pass_on)
    noref = nb.njit(**dict(_jit.NOREF, cache=False))(_pass_on)
    a, scr = np.arange(5.0), (np.full(2, 2.0), np.full(3, 1.0))
    for f in (usual, noref):
        out = np.empty(5)
        f(a, out, scr)
        assert out.tolist() == [1.0, 3.0, 5.0, 7.0, 9.0]
    ir = {f: "".join(f.inspect_llvm().values()) for f in (usual, noref)}
    assert "NRT_decref" in ir[usual]
    assert "NRT_incref" not in ir[noref] and "NRT_decref" not in ir[noref]


def test_a_noref_loop_cannot_allocate():
    """An allocation in a loop without reference counting is refused when it compiles, not leaked."""
    def allocates(n):
        return np.empty(n).sum()

    with pytest.raises(nb.errors.TypingError):
        nb.njit(**dict(_jit.NOREF, cache=False))(allocates)(3)


# Each loop compiled without reference counting, called in a new process before anything else calls
# what it calls: whatever it calls is then compiled without reference counting too, and would fail
# there if it allocated.
_ROBOT = """
import numpy as np
from cdpr_design import kernels as K
from cdpr_design.statics.robot import combinations
rng = np.random.default_rng(5)
m = {m}
A = rng.uniform(-2.0, 2.0, (m, 3)); Bp = rng.uniform(-0.3, 0.3, (m, 3)); rows = np.arange({n})
tmin, tmax = np.zeros(m), np.full(m, 100.0)
wreq = np.array([[0.0, 0.0, -9.81, 0.0, 0.0, 0.0][:{n}]])
feas, marg, ten, L = np.empty(64, np.uint8), np.empty(64), np.empty((64, m)), np.empty((64, m))
"""
#: The grid loop of each redundancy m - n = 0, 1 and 2, and more (sweep._grid_loop_0/_small/_any) on a
#: robot of n = 3 and m cables, in turn in one process: each loop is compiled by its own first
#: call, and each callee by the first loop that calls it -- a loop without reference counting
#: either way, so one process checks what a process a loop would (at a quarter of the compiling:
#: the loops share most of their callees).
_GRID_LOOPS = """
def grid_loop(m):
    A = rng.uniform(-2.0, 2.0, (m, 3)); Bp = rng.uniform(-0.3, 0.3, (m, 3))
    tmin, tmax = np.zeros(m), np.full(m, 100.0)
    feas, marg, ten, L = np.empty(64, np.uint8), np.empty(64), np.empty((64, m)), np.empty((64, m))
    K.sweep_grid(0, 64, np.full(3, -0.5), np.full(3, 0.3), np.array([4, 4, 4]), Bp, A, rows, wreq, tmin, tmax,
                 np.zeros(m), combinations(m, 3), KIND, feas, marg, ten, L)
"""
NOREF_PROBES = {
    "grid loops": _ROBOT.format(m=3, n=3) + "KIND = K.KIND_WRENCH_FEASIBLE" + _GRID_LOOPS + """
for m in (3, 4, 5, 7):
    grid_loop(m)
""",
    "planar2": _ROBOT.format(m=2, n=2) + """
K.sweep_grid_planar2(0, 64, np.full(3, -0.5), np.full(3, 0.3), np.array([8, 8, 1]), Bp, A, wreq, tmin, tmax,
                     np.zeros(m), feas, marg, ten, L)
K.chunk_stats(feas, marg, ten, 64, np.zeros(m))
""",
    "rotated": _ROBOT.format(m=8, n=6) + """
from cdpr_design.kernels.hanging import eval_rotated
P = rng.uniform(-0.5, 0.5, (64, 3)); R = np.tile(np.eye(3), (64, 1, 1))
eval_rotated(P, R, A, Bp, rows, np.tile(wreq, (64, 1, 1)), tmin, tmax, np.zeros(m), combinations(m, 6),
               K.KIND_STATIC, feas, marg, ten, L)
""",
    "points": """
import numpy as np
from cdpr_design.model import spec
from cdpr_design.statics.robot import Analysis, resolve
from cdpr_design.workspaces.hardware import Evaluator
d = spec.load("designs/planar4.yaml")
Evaluator(resolve(d, Analysis(collisions=True)))(np.zeros((16, 3)), [0.0, 0.0, 0.0])
""",
    "sagging": """
import numpy as np
from cdpr_design import workspaces
from cdpr_design.model import spec
from cdpr_design.statics import cables
from cdpr_design.statics.robot import Analysis, resolve
d = spec.load("designs/sagging40.yaml")
workspaces.run(d, step=4.0)
at = np.array([[20.0, 10.0, 0.0]])
cables.sagging_structures(resolve(d, Analysis(command="size-motors")), at, np.zeros(3))
cables.sagging_samples(resolve(d, Analysis(command="motion")), at, d.attachments[None], np.array([[0.0, 5.0 * 9.81]]))
""",
    "catenary": """
import numpy as np
from cdpr_design.kernels import catenary as c
one = np.ones(16)
X, Z = c.catenary_ends_batch(100.0 * one, 20.0 * one, 5.0 * one, one, 1e5 * one)
c.catenary_inverse_batch(X, Z, 5.0 * one, one, 1e5 * one, np.full(16, np.nan), np.full(16, np.nan), 1e-10, 50)
""",
}


@pytest.mark.slow
def test_the_noref_loops_compile_in_a_new_process_with_an_empty_cache(tmp_path):
    """Every probe of NOREF_PROBES in turn, in one new process: each loop is compiled by its own first
    call, and each callee by the first loop that calls it -- a loop without reference counting
    whichever it is, as in _GRID_LOOPS -- so one process checks what a process a probe would (about
    130 s of compiling instead of 240: the loops share most of their callees).  The order the other
    way round, a kernel with reference counting first, is test_the_loops_run_without_reference_counting_..."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("NUMBA_DISABLE_JIT", None)
    probe = "".join(f"{NOREF_PROBES[name]}\nprint('compiled', {name!r}, flush=True)\n"
                    for name in sorted(NOREF_PROBES)) + NO_ARRAY_RETURNS
    r = subprocess.run([sys.executable, "-c", probe], cwd=PACKAGE.parent, env=env, capture_output=True, text=True)
    assert r.returncode == 0, f"after {r.stdout.splitlines()[-1:]}: {r.stderr[-3000:]}"
    assert r.stdout.splitlines() == [f"compiled {name}" for name in sorted(NOREF_PROBES)] + ["done"], r.stdout


PARALLEL_PROBE = """
import sys
import numpy as np
from cdpr_design import workspaces as ws
from cdpr_design.kernels import geometry, hsm_small, sweep, tension_qp, warm
from cdpr_design.model import spec
for name, facets in (("ipanema3", hsm_small.facets_two), ("planar4", hsm_small.facets_one)):
    d = spec.load(f"designs/{name}.yaml")
    g = ws.make_grid(d, 0.5 if name == "ipanema3" else 0.1, True)
    p = ws.plan(ws.robot_for(d, g, engine="numba"), g)
    print(name, warm.compile_pose(p.robot.n, p.robot.m))  # True: the other process was kept
    ws.warm_up(p)
    r = p.run()
    np.save(f"{sys.argv[1]}/{name}.npy", np.concatenate([r.feasible_map.ravel(), r.margin_map.ravel(),
                                                         r.tension_maps.ravel()]))
    # what this process compiled of the other's share, and loaded (loaded once in a process: the
    # counts of the functions planar4 shares with ipanema3 stay as they were)
    for f in (tension_qp.null_space, hsm_small.facet_setup, facets, geometry.structure_matrix, sweep.chunk_stats):
        print(name, sum(f.stats.cache_misses.values()), sum(f.stats.cache_hits.values()))
"""


@pytest.mark.slow
def test_a_first_run_compiles_the_margins_in_another_process(tmp_path):
    """With an empty cache, ``warm_up`` of a straight-cable sweep has another process compile its
    share of the pose's functions (m - n = 2 and 1: the null basis, the margins' setup and facets
    and the structure matrix, which the sweep's loop is given pointers to) and the chunk
    statistics: this one loads them from the cache, compiles nothing of them (the types
    :func:`~cdpr_design.kernels.pointers.pose_functions` gives are the sweep's), and sweeps exactly
    what a process that compiled everything itself sweeps.  planar4 after IPAnema 3 in the same
    process is a first run of m - n = 1 and has its own other process; a process that loads them
    all from the cache keeps none."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=str(PACKAGE.parent))
    env.pop("NUMBA_DISABLE_JIT", None)
    r = subprocess.run([sys.executable, "-c", PARALLEL_PROBE, str(tmp_path)], cwd=PACKAGE.parent, env=env,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-3000:]
    assert r.stdout.split() == (["ipanema3", "True"] + ["ipanema3", "0", "1"] * 5
                                + ["planar4", "True"] + ["planar4", "0", "1"] * 5), r.stdout
    # a run that loads them (the cache is full now) keeps no other process, nor does a second call
    again = "from cdpr_design.kernels import warm; print(warm.compile_pose(6, 8), warm.compile_pose(6, 8))"
    r = subprocess.run([sys.executable, "-c", again], cwd=PACKAGE.parent, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-3000:]
    assert r.stdout.split() == ["False", "False"], r.stdout
    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec

    for name, step in (("ipanema3", 0.5), ("planar4", 0.1)):
        d = spec.load(PACKAGE.parent / "designs" / f"{name}.yaml")
        g = ws.make_grid(d, step, True)
        res = ws.plan(ws.robot_for(d, g, engine="numba"), g).run()
        mine = np.concatenate([res.feasible_map.ravel(), res.margin_map.ravel(), res.tension_maps.ravel()])
        np.testing.assert_array_equal(np.load(tmp_path / f"{name}.npy"), mine)


def test_a_square_design_starts_no_other_process():
    """m = n: the pose calls one small function (``eval_square_into``), so there is nothing for another
    process to compile (``compile_pose`` once took the QP of an empty list: an IndexError)."""
    from cdpr_design.kernels import warm

    assert warm.compile_pose(3, 3) is False
    assert warm.compile_pose(6, 6) is False


LEAK_PROBE = """
from numba.core.runtime import rtsys
from cdpr_design import workspaces as ws
from cdpr_design.model import spec
for name, step, collisions in (("ipanema3", 0.5, False), ("pointmass3", 0.2, False), ("planar4", 0.1, True),
                               ("crane4", 0.5, False)):
    d = spec.load(f"designs/{name}.yaml")
    g = ws.make_grid(d, step, True)
    run = lambda: ws.run(d, kind="static", grid=g, force=True, engine="numba", interference=collisions)
    run()
    a = rtsys.get_allocation_stats()
    run()
    b = rtsys.get_allocation_stats()
    print(name, g.size, b.alloc - a.alloc, b.free - a.free, b.mi_alloc - a.mi_alloc, b.mi_free - a.mi_free)
"""


@pytest.mark.slow
def test_sweeps_free_every_array_they_allocate():
    """numba's allocation counts over a second sweep (grid m = n and m > n, explicit positions with
    interference, hanging orientations): every array allocated is freed, and the loops without
    reference counting allocate nothing per pose (a few buffers a block)."""
    env = dict(os.environ, NUMBA_NRT_STATS="1")
    env.pop("NUMBA_DISABLE_JIT", None)
    r = subprocess.run([sys.executable, "-c", LEAK_PROBE], cwd=PACKAGE.parent, env=env, capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr[-3000:]
    lines = r.stdout.strip().splitlines()
    for line in lines:
        name, poses, alloc, free, mi_alloc, mi_free = line.split()
        assert alloc == free and mi_alloc == mi_free, line
        assert int(alloc) < int(poses), line  # per block, not per pose
    # the counts are numba's (the grid sweeps' buffers are numpy's: none there); the point and
    # hanging sweeps allocate theirs in compiled blocks, so a count of 0 everywhere means no counting
    assert any(int(line.split()[2]) > 0 for line in lines), lines


#: No compiled function declared without reference counting returns an array (its caller would
#: release a reference it was never given): every such function of the kernels this process compiled.
NO_ARRAY_RETURNS = """
import numba as nb
from numba.core import types
from cdpr_design.kernels import catenary, geometry, hanging, hsm, hsm_small, interference, linalg, pose, sag_path
from cdpr_design.kernels import sagging, sweep, tension_qp

def arrays_in(ty):
    return isinstance(ty, types.Array) or any(arrays_in(x) for x in getattr(ty, "types", ()))

for mod in (catenary, geometry, hanging, hsm, hsm_small, interference, linalg, pose, sag_path, sagging, sweep,
            tension_qp):
    for name, f in vars(mod).items():
        if isinstance(f, nb.core.registry.CPUDispatcher) and f.targetoptions.get("_nrt") is False:
            for sig in f.nopython_signatures:
                assert not arrays_in(sig.return_type), (mod.__name__, name, sig)
print("done")
"""

ORDER_PROBE = """
from cdpr_design.kernels import sweep
t = np.empty(m)
K.eval_pose(rng.normal(size=(3, m)), wreq, tmin, tmax, combinations(m, 3), K.KIND_STATIC, t)  # its callees first
loops = {3: sweep._grid_loop_0, 4: sweep._grid_loop_small, 5: sweep._grid_loop_small, 7: sweep._grid_loop_any}
for m, loop in loops.items():  # then each grid loop (one of each redundancy)
    grid_loop(m)
    ir = "".join(loop.inspect_llvm().values())
    print("counting calls in the loop", m, ir.count("NRT_incref") + ir.count("NRT_decref"))
""" + NO_ARRAY_RETURNS


@pytest.mark.slow
def test_the_loops_run_without_reference_counting_whatever_compiled_first(tmp_path):
    """The per-pose kernel compiled first (its callees with it), then the grid loop of each
    redundancy, in a new process with an empty cache: every loop and every callee linked into it
    still count no references (they are declared without it, not left to inherit the first
    caller's choice), and no function declared so returns an array (its caller would release a
    reference it was never given).  One process for the four loops: the per-pose kernel's types,
    and so what it compiles first, do not depend on the number of cables."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("NUMBA_DISABLE_JIT", None)
    probe = _ROBOT.format(m=3, n=3) + "KIND = K.KIND_STATIC" + _GRID_LOOPS + ORDER_PROBE
    r = subprocess.run([sys.executable, "-c", probe], cwd=PACKAGE.parent, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-3000:]
    assert r.stdout.split()[-1] == "done", r.stdout
    for m in (3, 4, 5, 7):
        assert f"counting calls in the loop {m} 0" in r.stdout, r.stdout
