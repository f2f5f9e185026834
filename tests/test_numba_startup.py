"""numba's start-up: cached kernels load without numba's compiler set-up
(:func:`cdpr_design.numba_startup.install_lazy_loading`), and a compile does without
``scipy.linalg`` (:func:`cdpr_design.numba_startup.load_blas_check`).

Each probe runs in a new process: the shortcuts act once, at numba's first cache load
or compile, and only a fresh interpreter shows what that imports.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "cdpr_design"


def _run(code: str, cache_dir: Path | None = None) -> str:
    """Standard output of ``code`` in a new interpreter; with ``cache_dir``, numba's cache is there."""
    env = dict(os.environ, PYTHONPATH=str(PACKAGE.parent))
    env.pop("NUMBA_DISABLE_JIT", None)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = str(cache_dir)
    r = subprocess.run([sys.executable, "-c", code], cwd=PACKAGE.parent, env=env, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    return r.stdout


DET = """
import sys
import numpy as np
from cdpr_design.kernels.linalg import det_small
print(det_small(np.array([[2.0, 1.0], [1.0, 3.0]]), 2), sum(det_small.stats.cache_hits.values()))
print(*(m in sys.modules for m in ('scipy.linalg', 'scipy.linalg.cython_blas', 'numba.np.arraymath',
                                   'numba.typed.typeddict', 'numba.np.random.generator_core')))
"""


def test_a_compiled_kernel_leaves_scipy_linalg_unimported(tmp_path):
    out = _run(DET, tmp_path).split()
    assert out[:2] == ["5.0", "0"]  # compiled: the cache was empty
    # numba's BLAS check was answered, and left nothing behind; its compiler was set up in full
    assert out[2:] == ["False", "False", "True", "True", "True"]


def test_a_cached_kernel_loads_without_numbas_compiler_set_up(tmp_path):
    _run(DET, tmp_path)
    out = _run(DET, tmp_path).split()
    assert out[:2] == ["5.0", "1"]  # loaded from the cache
    # none of the implementation modules numba's set-up imports, and no scipy.linalg
    assert out[2:] == ["False"] * 5


CSV = """
import sys
import numba
import numpy as np
from cdpr_design.io.csvfast import format_rows, numba_rows
from cdpr_design.io.csvtext import numpy_rows
cols = [np.array([1.5, -0.25, np.nan]), np.array([3, 4, 5]), np.array([True, False, True])]
print(numba_rows(cols) == numpy_rows(cols), sum(format_rows.stats.cache_hits.values()))
print(*(m in sys.modules for m in ('scipy.linalg', 'numba.np.arraymath', 'numba.typed.typeddict')))
"""


def test_the_compiled_csv_writer_loads_lazily_too(tmp_path):
    """The background writer's row loop (outside the kernels) loads without numba's set-up."""
    assert _run(CSV, tmp_path).split() == ["True", "0", "False", "True", "True"]  # compiled
    assert _run(CSV, tmp_path).split() == ["True", "1", "False", "False", "False"]  # loaded


def test_only_this_packages_functions_load_lazily(tmp_path):
    """numba code of another package keeps numba's own cache load (with its full set-up)."""
    (tmp_path / "otherpkg.py").write_text("import numba\n\n@numba.njit(cache=True)\ndef twice(x):\n"
                                          "    return 2.0 * x\n")
    code = """
import sys
sys.path.insert(0, %r)
from cdpr_design import kernels as K, numba_startup
from cdpr_design.kernels import _jit  # installs the lazy load, before otherpkg's
assert numba_startup.install_lazy_loading()
import otherpkg
print(otherpkg.twice(2.0), sum(otherpkg.twice.stats.cache_hits.values()), 'numba.typed.typeddict' in sys.modules,
      numba_startup.ours(otherpkg.twice._cache), numba_startup.ours(K.eval_square._cache))
""" % str(tmp_path)
    _run(code, tmp_path)
    # cached and loaded by numba's own method: its set-up ran in full
    assert _run(code, tmp_path).split() == ["4.0", "1", "True", "False", "True"]


def test_a_lazy_load_on_a_thread_then_an_error_then_a_compile_of_ours(tmp_path):
    """The first load on a worker thread (as the sweeps' thread pool and the CSV writer do), an
    error raised inside a lazily loaded kernel, and one of our kernels compiled in the same
    process afterwards (a cache miss after a lazy load)."""
    _run(DET, tmp_path)
    out = _run("""
import sys, threading
import numpy as np
from cdpr_design import kernels as K
from cdpr_design.kernels.linalg import det_small
got = []
thread = threading.Thread(target=lambda: got.append(det_small(np.array([[2.0, 1.0], [1.0, 3.0]]), 2)))
thread.start(); thread.join()
print(got[0], sum(det_small.stats.cache_hits.values()), 'numba.typed.typeddict' in sys.modules)
try:
    det_small(np.eye(2), -1)  # np.empty((-1, -1)) inside the kernel
except ValueError as exc:
    print('ValueError')
t = np.empty(2)
K.eval_square(np.array([[1.0, 0.0], [0.0, 1.0]]), np.array([[3.0, 4.0]]), np.zeros(2), np.full(2, 100.0), 0, t)
print(*t, sum(K.eval_square.stats.cache_misses.values()), 'numba.typed.typeddict' in sys.modules)
""", tmp_path).split()
    assert out[:3] == ["5.0", "1", "False"]  # loaded lazily, on the thread
    assert out[3] == "ValueError"
    assert out[4:] == ["3.0", "4.0", "1", "True"]  # compiled, after numba's full set-up


def test_a_compile_after_a_cached_load_sets_numba_up_in_full(tmp_path):
    """A function of the user's, compiled in a process whose kernels came from the cache,
    finds every numba feature (numba refreshes its context before compiling)."""
    _run(DET, tmp_path)
    out = _run(DET + """
import numba
from numba.typed import Dict

@numba.njit(cache=False)
def f(n):
    d = Dict()
    for i in range(n):
        d[i] = np.random.random() * 0.0 + float(i)
    total = 0.0
    for v in d.values():
        total += v
    return total, np.sort(np.arange(n)[::-1])[0]

print(*f(4))
""", tmp_path).split()
    assert out[:2] == ["5.0", "1"]
    assert out[-2:] == ["6.0", "0"]


def test_blas_and_lapack_work_after_it_and_scipy_linalg_imports_in_full(tmp_path):
    out = _run("""
import numpy as np, numba
from cdpr_design.kernels.linalg import det_small
det_small(np.eye(2), 2)  # compiled (empty cache): the check answered cheaply

@numba.njit(cache=False)
def f(a, b):
    return np.dot(a, b), np.linalg.eigvals(a + a.T), np.linalg.solve(a, b[:, 0])

rng = np.random.default_rng(3)
a, b = rng.normal(size=(5, 5)), rng.normal(size=(5, 2))
d, e, s = f(a, b)
print(np.allclose(d, a @ b), np.allclose(np.sort(e), np.linalg.eigvalsh(a + a.T)),
      np.allclose(a @ s, b[:, 0]))
import scipy.linalg, scipy.linalg.cython_blas, sys
print(scipy.linalg.cython_blas is sys.modules['scipy.linalg.cython_blas'], len(scipy.linalg.cython_blas.__pyx_capi__) > 0,
      np.allclose(scipy.linalg.blas.dgemm(1.0, a, b), a @ b), np.allclose(scipy.linalg.solve(a, b), np.linalg.solve(a, b)))
""", tmp_path).split()
    assert out == ["True"] * 7


def test_it_steps_aside_when_scipy_linalg_is_already_imported():
    out = _run("""
import scipy.linalg
import numpy as np
from cdpr_design import numba_startup
from cdpr_design.kernels.linalg import det_small
print(numba_startup.load_blas_check(), det_small(np.eye(3) * 2.0, 3))
""").split()
    assert out == ["False", "8.0"]
