"""The straight-cable grid sweep: point outlets, no interference, one fixed orientation.

Two engines compute the same rows:

- ``numba``: the kernels of :mod:`cdpr_design.kernels` (any m, n, kind);
- ``numpy``: the closed form of two cables and two wrench rows, vectorised
  over each chunk with the same formulas in the same order (bit-identical
  results, tested).

``auto`` takes numpy for closed-form grids up to :data:`NUMPY_MAX_POSES` poses
while the kernels are not loaded in this process: numba's start-up (its
import and the cached kernels' load, 0.3-0.5 s) would cost more than the sweep itself.
"""

from __future__ import annotations

import sys
import time
from typing import Callable

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.model.design import Design, Grid
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.pose import KINDS, combinations, pose_at, wrench_vertices
from cdpr_design.workspaces.grid import CHUNK, Chunk, Maps, WorkspaceResult, grid3, grid_positions

#: Engines (see the module docstring).
ENGINES = ("auto", "numba", "numpy")
#: Largest closed-form grid ``auto`` gives to numpy while the kernels are not loaded.  Measured
#: on planar2 (with its hanging tilt), warm, the whole ``workspace`` command in a new process,
#: two runs an engine and size: numpy 13-18 us a pose, numba 5-7 us a pose on two threads plus
#: 0.45-0.5 s of numba start-up (``load_s``), which puts the crossover at 45,000-90,000 poses;
#: the commands measured it there, loosely (the machine's speed drifted between runs): numpy
#: 0.25 s faster at 63,001 poses, numba 0.3-0.5 s faster at 74,529 and 0.6-0.8 s at 90,601.
#: Batch sweeps decide apart (``batch.sweep.KERNELS_FROM_POSES``).
NUMPY_MAX_POSES = 70_000


#: The kernel module whose presence means "the kernels are loaded in this process": the package
#: :mod:`cdpr_design.kernels` itself is lazy (``kernels.parallel`` is imported without numba by
#: the batch and optimize layers), so its presence in ``sys.modules`` says nothing.
LOADED = "cdpr_design.kernels.sweep"


def kernels():
    """The numba kernels, imported on first use (importing numba takes ~0.4 s): :data:`LOADED`
    now, the rest of the (lazy) package as its names are used."""
    import importlib

    from cdpr_design import kernels as K

    importlib.import_module(LOADED)
    return K


def load_kernels() -> None:
    """Load the numba kernels now: for a process that will sweep many grids (a sweep
    worker), where numba's start-up is repaid and ``auto`` should then choose them."""
    kernels()


def check_engine(engine: str) -> None:
    """Raise an :class:`InputError` naming ``engine`` unless it is one of :data:`ENGINES`."""
    if engine not in ENGINES:
        raise InputError(f"engine: expected one of {', '.join(ENGINES)}, got {engine!r}")


def resolve(engine: str, poses: int) -> str:
    """The engine to run a sweep of ``poses`` poses with: ``auto`` becomes ``numba`` where
    :func:`use_numpy` would not take numpy at any design (grids over :data:`NUMPY_MAX_POSES`),
    so that a one-pose run with the result loads the same kernels as the whole sweep."""
    check_engine(engine)
    return "numba" if engine == "auto" and poses > NUMPY_MAX_POSES else engine


def use_numpy(engine: str, planar2: bool, poses: int) -> bool:
    """Whether a point-outlet sweep of ``poses`` poses takes the numpy closed form.

    ``planar2``: the design has two cables and two wrench rows and the kind is
    not wrench closure (the closed form's case).
    """
    check_engine(engine)
    if engine == "numpy":
        if not planar2:
            raise InputError("engine=numpy: the numpy engine covers two cables with two wrench rows "
                             "(static or wrench-feasible); use auto or numba for this design")
        return True
    if engine == "numba":
        return False
    return planar2 and poses <= NUMPY_MAX_POSES and LOADED not in sys.modules


class _Sweep:
    """The arrays a straight-cable sweep hands to its engine, built once per sweep."""

    def __init__(self, design: Design, kind: str, g: Grid, ori: np.ndarray, engine: str):
        R = kin.rotation_matrix(*ori)
        self.Rb = np.ascontiguousarray(design.attachments @ R.T)
        self.A = np.ascontiguousarray(design.outlets)
        self.rows = design.rows
        self.tmin, self.tmax = design.tension_min, design.tension_max
        self.wreq = wrench_vertices(design, kind, ori)
        self.combos = combinations(design.m, design.n)
        self.kcode = KINDS[kind]
        # the paper's case (two cables, two wrench rows) has a closed form
        self.planar2 = design.m == 2 and design.n == 2 and kind != "wrench-closure"
        self.numpy = use_numpy(engine, self.planar2, g.size)
        self.K = None if self.numpy else kernels()
        self.wreq_used = self.wreq if kind == "wrench-feasible" else self.wreq[:1].copy()
        self.g = g
        self.lower, self.step, self.shape = grid3(g)

    def chunk(self, start: int, cnt: int, feas, marg, ten, lens, tpeak):
        """Fill the buffers' first ``cnt`` rows for grid rows start .. start+cnt; return the stats."""
        if self.numpy:
            _planar2_numpy(self.g, start, cnt, self.Rb, self.A, self.wreq_used, self.tmin, self.tmax,
                           feas, marg, ten, lens)
            return _chunk_stats_numpy(feas, marg, ten, cnt, tpeak)
        K = self.K
        if self.planar2:
            K.sweep_grid_planar2(start, cnt, self.lower, self.step, self.shape, self.Rb, self.A,
                                 self.wreq_used, self.tmin, self.tmax, feas, marg, ten, lens)
        else:
            K.sweep_grid(start, cnt, self.lower, self.step, self.shape, self.Rb, self.A, self.rows,
                         self.wreq, self.tmin, self.tmax, self.combos, self.kcode, feas, marg, ten, lens)
        return K.chunk_stats(feas, marg, ten, cnt, tpeak)


def sweep(design: Design, kind: str, g: Grid, ori: np.ndarray, *,
          on_chunk: Callable[[Chunk], None] | None = None,
          progress: Callable[[int, int], None] | None = None,
          chunk: int = CHUNK, keep_maps: bool = True, engine: str = "auto") -> WorkspaceResult:
    """Sweep grid ``g`` at orientation ``ori`` (3,) [rad] with straight cables from point outlets.

    The caller (:func:`cdpr_design.workspaces.run`) has checked ``kind`` and
    the grid's size.  ``on_chunk`` receives each :class:`Chunk` in grid
    order; ``progress(done, total)`` is called after each chunk.
    """
    t0 = time.perf_counter()
    sw = _Sweep(design, kind, g, ori, engine)
    total, m = g.size, design.m
    ncoords = len(design.motion.coords)
    ori_coords = pose_at(design, np.zeros(3), ori)[design.motion.dim:]
    maps = Maps(g, m, keep_maps)
    chunk = max(1, min(chunk, total))
    feas_b = np.empty(chunk, dtype=np.uint8)
    marg_b = np.empty(chunk)
    ten_b = np.empty((chunk, m))
    len_b = np.empty((chunk, m))
    done = 0
    while done < total:
        cnt = min(chunk, total - done)
        stats = sw.chunk(done, cnt, feas_b, marg_b, ten_b, len_b, maps.tpeak)
        maps.add(done, stats, feas_b[:cnt], marg_b[:cnt], ten_b[:cnt])
        if on_chunk is not None:
            poses = np.empty((cnt, ncoords))
            poses[:, : design.motion.dim] = grid_positions(g, done, cnt)
            poses[:, design.motion.dim:] = ori_coords
            on_chunk(Chunk(done, poses, feas_b[:cnt].copy(), marg_b[:cnt].copy(),
                           ten_b[:cnt].copy(), len_b[:cnt].copy()))
        done += cnt
        if progress is not None:
            progress(done, total)
    return maps.result(design, kind, ori, t0)


def _planar2_numpy(g: Grid, start, count, Rb, A, wreq, tmin, tmax, feasible, margin, tensions, lengths):
    """``kernels.sweep_grid_planar2`` vectorised with numpy: same formulas, same order.

    Two cables, two wrench rows: t = W^-1 w in closed form, the capacity margin
    min_i min(t_i - t_min,i, t_max,i - t_i) / ||row_i(W^-1)||, the other rows of
    ``wreq`` (wrench-feasible) lowering the margin.  Fills rows 0 .. count of
    the output buffers exactly as the kernel does.
    """
    pos = grid_positions(g, start, count)
    px, py = pos[:, 0], pos[:, 1]
    lx0 = (A[0, 0] - Rb[0, 0]) - px
    ly0 = (A[0, 1] - Rb[0, 1]) - py
    lx1 = (A[1, 0] - Rb[1, 0]) - px
    ly1 = (A[1, 1] - Rb[1, 1]) - py
    L0 = np.sqrt(lx0 * lx0 + ly0 * ly0)
    L1 = np.sqrt(lx1 * lx1 + ly1 * ly1)
    lengths[:count, 0] = L0
    lengths[:count, 1] = L1
    with np.errstate(divide="ignore", invalid="ignore"):
        u0x, u0y, u1x, u1y = lx0 / L0, ly0 / L0, lx1 / L1, ly1 / L1
        det = u0x * u1y - u1x * u0y
        inv = 1.0 / det
        i00, i01, i10, i11 = u1y * inv, -u1x * inv, -u0y * inv, u0x * inv
        r0 = np.sqrt(i00 * i00 + i01 * i01)
        r1 = np.sqrt(i10 * i10 + i11 * i11)
        w0, w1 = wreq[0, 0], wreq[0, 1]
        t0 = i00 * w0 + i01 * w1
        t1 = i10 * w0 + i11 * w1
        s = np.minimum(np.minimum(t0 - tmin[0], tmax[0] - t0) / r0, np.minimum(t1 - tmin[1], tmax[1] - t1) / r1)
        inb = s >= 0.0
        for v in range(1, wreq.shape[0]):
            q0 = i00 * wreq[v, 0] + i01 * wreq[v, 1]
            q1 = i10 * wreq[v, 0] + i11 * wreq[v, 1]
            s = np.minimum(s, np.minimum(np.minimum(q0 - tmin[0], tmax[0] - q0) / r0,
                                         np.minimum(q1 - tmin[1], tmax[1] - q1) / r1))
    # a zero-length cable or parallel cables: rank deficient, no margin, infeasible
    bad = (L0 <= 1e-12) | (L1 <= 1e-12) | (np.abs(det) <= _RANK_TOL)
    s[bad] = np.nan
    s += 0.0  # -0.0 -> 0.0, as the kernel (np.minimum and min() differ on the sign of equal zeros)
    ok = s >= 0.0
    margin[:count] = s
    feasible[:count] = ok
    tensions[:count, 0] = np.where(inb & ~bad, t0, np.nan)
    tensions[:count, 1] = np.where(inb & ~bad, t1, np.nan)


#: = ``kernels.RANK_TOL`` (a test checks): |det W| at or below it is rank deficient
_RANK_TOL = 1e-10


def _chunk_stats_numpy(feasible, margin, tensions, count, tpeak):
    """``kernels.chunk_stats`` with numpy: (feasible count, min margin, max margin); raises ``tpeak``."""
    f = feasible[:count].astype(bool)
    nf = int(np.count_nonzero(f))
    if not nf:
        return 0, np.inf, -np.inf
    mm = margin[:count][f]
    np.maximum(tpeak, tensions[:count][f].max(axis=0), out=tpeak)
    return nf, float(mm.min()) + 0.0, float(mm.max()) + 0.0
