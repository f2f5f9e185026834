"""numba's on-disk cache of the kernels: a change to *any* kernel module gives new results.

numba alone keys a cached function on its own file; a kernel calling into an edited module would
load stale machine code.  The command line caches the kernels in a folder per version of their
sources (:mod:`cdpr_design.kernels.cache`); these tests run what it runs, in new processes.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "cdpr_design"

# what ``python -m cdpr_design`` does first (cdpr_design/__main__.py), then a kernel
START = """
from cdpr_design.cli import env
print(env.use_kernel_cache())
"""

# eval_square (pose.py) calls square_eval_into (hsm.py): print the tensions of one square pose
PROBE = START + """
import numpy as np
from cdpr_design import kernels as K
W = np.array([[1.0, 0.0], [0.0, 1.0]])
t = np.empty(2)
K.eval_square(W, np.array([[3.0, 4.0]]), np.zeros(2), np.full(2, 100.0), 0, t)
print(repr(t.tolist()))
"""


# det_small (linalg.py), a small kernel outside hsm.py: print its answer
PROBE_ALONE = START + """
import numpy as np
from cdpr_design import kernels as K
print(repr([K.det_small(np.array([[2.0, 1.0], [1.0, 3.0]]), 2)]))
"""


def _probe(root: Path, code: str = PROBE) -> tuple[list[float], Path]:
    """The probe's printed values and the cache folder it used, in a new process on the package in ``root``."""
    env = dict(os.environ, PYTHONPATH=str(root), NUMBA_CACHE_DIR=str(root / "numba-cache"))
    env.pop("NUMBA_DISABLE_JIT", None)
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=root, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr
    folder, values = out.stdout.strip().splitlines()
    return eval(values), Path(folder)


def _cached(folder: Path) -> set[str]:
    """The names of numba's cache files in ``folder`` (index and data files)."""
    return {p.name for p in folder.rglob("*") if p.suffix in (".nbi", ".nbc")}


def _copy_package(root: Path) -> Path:
    shutil.copytree(PACKAGE, root / "cdpr_design", ignore=shutil.ignore_patterns("__pycache__"))
    return root / "cdpr_design" / "kernels"


def test_an_edit_to_any_kernel_module_starts_a_new_cache_folder(tmp_path):
    """The same sources reuse their cache folder (a second run adds no file to it); an edit to a
    kernel module, even one the kernel run does not call, gives a new, empty folder, under the
    user's NUMBA_CACHE_DIR."""
    kernels = _copy_package(tmp_path)
    got, first = _probe(tmp_path, PROBE_ALONE)
    assert got == [5.0]
    assert first.parent == tmp_path / "numba-cache" and first.name.startswith("cdpr-design-kernels-")
    files = _cached(first)
    assert any(name.startswith("linalg.det_small") for name in files), files
    assert _probe(tmp_path, PROBE_ALONE) == ([5.0], first)
    assert _cached(first) == files  # loaded, nothing written
    hsm = kernels / "hsm.py"
    hsm.write_text(hsm.read_text() + "\n# edited by the test\n")
    got, second = _probe(tmp_path, PROBE_ALONE)
    assert got == [5.0] and second.parent == first.parent and second != first
    assert _cached(second) and _cached(first) == files


@pytest.mark.slow
def test_an_edit_to_a_called_module_changes_its_callers_results(tmp_path):
    """The kernel in pose.py gives the new result after an edit to hsm.py alone, not its cached
    old one; a file only touched (its time changed, as a checkout does) is not an edit: the
    same folder, loaded from the cache."""
    hsm = _copy_package(tmp_path) / "hsm.py"
    got, first = _probe(tmp_path)
    assert got == [3.0, 4.0]
    files = _cached(first)
    os.utime(hsm, (1, 1))
    assert _probe(tmp_path) == ([3.0, 4.0], first)
    assert _cached(first) == files
    text = hsm.read_text()
    head = "        det = W[0, 0] * W[1, 1] - W[0, 1] * W[1, 0]\n"  # square_eval_into, n = 2
    assert text.count(head) == 1
    hsm.write_text(text.replace(head, head + "        det = det * 2.0  # edited by the test\n", 1))
    got, second = _probe(tmp_path)
    assert got == [1.5, 2.0] and second != first  # det doubled: halved tensions


def test_a_command_started_by_a_command_keeps_its_cache_folder(tmp_path):
    """The folder chosen under a NUMBA_CACHE_DIR that is already one (set by the command that
    started this one) is that folder, not a folder inside it; without NUMBA_CACHE_DIR, the user's
    cache folder."""
    from cdpr_design.cli import env as cli_env

    environ = {"NUMBA_CACHE_DIR": str(tmp_path)}
    chosen = cli_env.use_kernel_cache(environ)
    assert Path(chosen).parent == tmp_path and environ["NUMBA_CACHE_DIR"] == chosen
    assert cli_env.use_kernel_cache(environ) == chosen
    environ = {"XDG_CACHE_HOME": str(tmp_path / "xdg")}
    assert Path(cli_env.use_kernel_cache(environ)).parent == tmp_path / "xdg" / "cdpr-design"


LEAK_PROBE = """
from numba.core.runtime import rtsys
from cdpr_design import workspaces as ws
from cdpr_design.model import spec
for name, step, collisions in (("ipanema3", 0.5, False), ("pointmass3", 0.2, False), ("planar4", 0.1, True),
                               ("crane4", 0.5, False)):
    d = spec.load(f"designs/{name}.yaml")
    g = ws.make_grid(d, step, True)
    run = lambda: ws.run(d, ws.Analysis(engine="numba", collisions=collisions), grid=g, force=True)
    run()
    a = rtsys.get_allocation_stats()
    run()
    b = rtsys.get_allocation_stats()
    print(name, g.size, b.alloc - a.alloc, b.free - a.free, b.mi_alloc - a.mi_alloc, b.mi_free - a.mi_free)
"""


@pytest.mark.slow
def test_sweeps_free_every_array_they_allocate():
    """numba's allocation counts over a second sweep (grid m = n and m > n, explicit positions with
    interference, hanging orientations): every array allocated is freed, and the loops allocate
    nothing per pose (a few buffers a block)."""
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
    # the counts are numba's (the sweeps' buffers are numpy's: none there); the hanging tilt
    # allocates its work arrays in a compiled block, so a count of 0 everywhere means no counting
    assert any(int(line.split()[2]) > 0 for line in lines), lines
