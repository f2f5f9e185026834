"""numba's start-up without ``scipy.linalg`` (:func:`cdpr_design.kernels._jit._load_blas_check`).

Each probe runs in a new process: the shortcut acts once, before numba's first
compile or cache load, and only a fresh interpreter shows what that imports.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "cdpr_design"


def _run(code: str) -> str:
    env = dict(os.environ, PYTHONPATH=str(PACKAGE.parent))
    r = subprocess.run([sys.executable, "-c", code], cwd=PACKAGE.parent, env=env, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    return r.stdout


def test_a_kernel_call_leaves_scipy_linalg_unimported():
    out = _run("""
import sys
import numpy as np
from cdpr_design.kernels.linalg import det_small
print(det_small(np.array([[2.0, 1.0], [1.0, 3.0]]), 2))
print('scipy.linalg' in sys.modules, 'scipy.linalg.cython_blas' in sys.modules, 'numba.np.arraymath' in sys.modules)
""").split()
    assert float(out[0]) == 5.0
    # numba's BLAS check was answered, and left nothing behind; numba's array functions are loaded
    assert out[1:] == ["False", "False", "True"]


def test_blas_and_lapack_work_after_it_and_scipy_linalg_imports_in_full():
    out = _run("""
import numpy as np, numba
from cdpr_design.kernels import _jit

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
""").split()
    assert out == ["True"] * 7


def test_it_steps_aside_when_scipy_linalg_is_already_imported():
    out = _run("""
import scipy.linalg
import numpy as np
from cdpr_design.kernels import _jit
from cdpr_design.kernels.linalg import det_small
print(_jit._load_blas_check(), det_small(np.eye(3) * 2.0, 3))
""").split()
    assert out == ["False", "8.0"]
