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

from cdpr_design import kernels as K
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


def test_kernels_are_stamped_with_the_package_digest():
    for fn in (K.eval_square, K.eval_general, K.sweep_grid.__globals__["grid_block"](2), K.min_norm_tensions):
        locator = fn._cache._impl._locator
        assert isinstance(locator, _jit._PackageStamp), type(locator)
        assert locator.get_source_stamp() == ("cdpr-design kernels", _jit.source_digest())


def test_digest_follows_contents_not_times(tmp_path):
    folder = tmp_path / "kernels"
    shutil.copytree(PACKAGE / "kernels", folder, ignore=shutil.ignore_patterns("__pycache__"))
    before = _jit.source_digest.__wrapped__(str(folder))
    os.utime(folder / "hsm.py", (1, 1))  # touched only: same digest
    assert _jit.source_digest.__wrapped__(str(folder)) == before
    with open(folder / "hsm.py", "a") as fh:
        fh.write("\n# edited\n")
    assert _jit.source_digest.__wrapped__(str(folder)) != before


def _probe(root: Path) -> tuple[list[float], int]:
    env = dict(os.environ, PYTHONPATH=str(root), NUMBA_CACHE_DIR=str(root / "numba-cache"))
    env.pop("NUMBA_DISABLE_JIT", None)
    out = subprocess.run([sys.executable, "-c", PROBE], env=env, cwd=root, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr
    values, _, hits = out.stdout.strip().rpartition(" ")
    return eval(values), int(hits)


def test_an_edit_to_a_called_module_recompiles_its_callers(tmp_path):
    """The kernel in pose.py is recompiled after an edit to hsm.py alone, not loaded stale."""
    shutil.copytree(PACKAGE, tmp_path / "cdpr_design", ignore=shutil.ignore_patterns("__pycache__"))
    assert _probe(tmp_path) == ([3.0, 4.0], 0)  # compiled and cached
    assert _probe(tmp_path) == ([3.0, 4.0], 1)  # loaded from the cache
    hsm = tmp_path / "cdpr_design" / "kernels" / "hsm.py"
    text = hsm.read_text()
    head = "def square_eval(W, wreq, tmin, tmax, t):\n"
    assert head in text
    hsm.write_text(text.replace(head, head + "    W = W * 2.0  # edited by the test\n", 1))
    assert _probe(tmp_path) == ([1.5, 2.0], 0)  # W doubled: halved tensions, compiled again


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
