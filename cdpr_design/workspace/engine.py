"""Workspace grids and chunked sweeps.

:func:`run` sweeps a grid of platform positions at the workspace's fixed
orientation in chunks (bounded memory: one chunk of rows at a time, however
large the grid), hands each chunk to an optional callback (the CLI streams it
to ``workspace.csv``), and returns a :class:`WorkspaceResult` with the summary
figures and maps for the pictures (subsampled for very large grids).
"""

from __future__ import annotations

import itertools
import os
import sys
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from cdpr_design.statics import kinematics as kin
from cdpr_design.errors import InputError, SpecError
from cdpr_design.model.design import Design, Grid

#: workspace kinds and their kernel codes (= ``_kernels.KIND_*``; a test checks)
KINDS = {"static": 0, "wrench-feasible": 1, "wrench-closure": 2}

#: Largest grid swept without ``force=True`` (poses).
MAX_POSES = 20_000_000
#: Rows evaluated per chunk (bounded memory: ~ CHUNK * (2 m + 2) * 8 bytes).
CHUNK = 1 << 18
#: Largest number of cells kept for the maps behind the pictures.
MAP_CELLS = 4_000_000
#: Engines: ``numba`` (the kernels of :mod:`cdpr_design.kernels`) or ``numpy``
#: (the closed form of two cables and two wrench rows, vectorised).  ``auto``
#: takes numpy for closed-form grids up to :data:`NUMPY_MAX_POSES` poses while
#: the kernels are not loaded in this process: numba's start-up (import and
#: first-call set-up, about 1 s) would cost more than the sweep itself.
ENGINES = ("auto", "numba", "numpy")
NUMPY_MAX_POSES = 2_000_000


def _K():
    """The numba kernels, imported on first use (importing numba takes ~0.4 s)."""
    from cdpr_design import kernels as _kernels

    return _kernels


def load_kernels() -> None:
    """Load the numba kernels now: for a process that will sweep many grids (a sweep
    worker), where numba's start-up is repaid and ``auto`` should then choose them."""
    _K()


@dataclass
class Chunk:
    """One chunk of a sweep: rows ``start .. start + len`` of the grid (C order x, y, z).

    ``poses`` are in the motion's coordinates (orientation columns hold the
    sweep's fixed orientation).
    """

    start: int
    poses: np.ndarray
    feasible: np.ndarray
    margin: np.ndarray
    tensions: np.ndarray
    lengths: np.ndarray
    #: uint8 (count,), 1 where no interference (only when the sweep checks it)
    collision_free: np.ndarray | None = None
    #: further CSV columns after the contract's (name -> (count,) array)
    extra: dict = field(default_factory=dict)


@dataclass
class WorkspaceResult:
    """Result of a workspace sweep. Infeasible poses are flags and NaNs, never errors.

    Attributes
    ----------
    poses, feasible : int
        Grid poses evaluated and how many are feasible.
    fraction : float
        feasible / poses.
    measure : float
        Feasible area [m^2] (planar) or volume [m^3]: feasible count x cell size.
    min_margin, max_margin : float or None
        Extremes of the capacity margin [N] over the feasible poses.
    max_tension : (m,) array
        Largest tension [N] of each cable over the feasible poses (NaN if none).
    feasible_map, margin_map : arrays of the grid's shape (nx, ny[, nz])
        For the pictures; subsampled with ``map_stride`` when the grid is huge.
    tension_maps : (m, nx, ny[, nz]) float32
    map_axes : list of arrays, the coordinates of the map cells per axis.
    """

    design: Design
    kind: str
    grid: Grid
    orientation: np.ndarray
    poses: int
    feasible: int
    min_margin: float | None
    max_margin: float | None
    max_tension: np.ndarray
    elapsed_s: float
    feasible_map: np.ndarray
    margin_map: np.ndarray
    tension_maps: np.ndarray
    map_axes: list
    map_stride: tuple
    extra: dict = field(default_factory=dict)
    #: orientation sweeps only (:func:`run_orientations`): a hardware.OrientationMaps
    orientation_maps: object = None

    @property
    def fraction(self) -> float:
        return self.feasible / self.poses if self.poses else 0.0

    @property
    def measure(self) -> float:
        return self.feasible * self.grid.cell

    def summary(self) -> dict:
        """The contract's ``summary.json`` / ``--json`` keys (cli.md), plus extras."""
        mt = self.max_tension
        finite = mt[np.isfinite(mt)]
        out = {
            "name": self.design.name,
            "kind": self.kind,
            "poses": int(self.poses),
            "feasible": int(self.feasible),
            "fraction": float(self.fraction),
            "measure": float(self.measure),
            "min_margin": _num(self.min_margin),
            "max_margin": _num(self.max_margin),
            "max_tension": float(finite.max()) if finite.size else None,
            "elapsed_s": round(float(self.elapsed_s), 4),
            "max_tension_per_cable": {c: _num(v) for c, v in zip(self.design.cable_names, mt)},
            "grid": {"lower": list(self.grid.lower), "upper": list(self.grid.upper),
                     "step": list(self.grid.step), "shape": list(self.grid.shape)},
            "orientation": [float(x) for x in self.orientation_coords()],
            "measure_unit": "m^2" if self.design.motion.planar else "m^3",
        }
        out.update(self.extra)
        return out

    def orientation_coords(self) -> list[float]:
        """The fixed orientation in the motion's rotation coordinates."""
        mot = self.design.motion
        if mot.name == "1R2T":
            return [float(self.orientation[2])]
        if mot.name == "3R3T":
            return [float(x) for x in self.orientation]
        return []


def _num(x):
    if x is None:
        return None
    x = float(x) + 0.0  # + 0.0 turns -0.0 into 0.0
    return x if np.isfinite(x) else None


def make_grid(design: Design, step: float | None = None, force: bool = False) -> Grid:
    """The design's workspace grid, with ``step`` [m] overriding ``workspace.grid.step``.

    Raises
    ------
    SpecError
        When the step is not positive, or the grid exceeds :data:`MAX_POSES`
        poses without ``force`` (the message says how many it would be).
    """
    g = design.workspace.grid
    if step is not None:
        if not np.isfinite(step) or step <= 0:
            raise SpecError([("--step", f"expected a positive number of metres, got {step}")])
        g = Grid(g.lower, g.upper, (float(step),) * len(g.lower))
    check_grid_size(g, force, path="--step" if step is not None else "workspace.grid.step")
    return g


def check_grid_size(g: Grid, force: bool, path: str = "workspace.grid.step") -> None:
    if not force and g.size > MAX_POSES:
        dims = " x ".join(str(s) for s in g.shape)
        raise SpecError([(path, f"the grid would have {g.size:,} poses ({dims}), more than the "
                                f"{MAX_POSES:,} swept without --force; raise the step or pass --force")])


def wrench_vertices(design: Design, kind: str, orientation=None) -> np.ndarray:
    """Required-wrench vertices (nv, n) for a sweep at a fixed orientation.

    Row 0 is the nominal wrench -gravity (the one whose tensions are
    reported).  For ``wrench-feasible`` every vertex of the external wrench
    box is added to gravity (dimensions where lower = upper contribute one value).
    """
    ori = design.default_orientation_full() if orientation is None else np.asarray(orientation, float)
    pose = _pose_at(design, np.zeros(3), ori)
    g = kin.gravity_wrench(design, pose)
    rows = [-g]
    box = design.workspace.external_wrench
    if kind == "wrench-feasible" and box is not None:
        lo, hi = np.asarray(box.lower), np.asarray(box.upper)
        choices = [(lo[i],) if lo[i] == hi[i] else (lo[i], hi[i]) for i in range(lo.size)]
        for v in itertools.product(*choices):
            rows.append(-(g + np.asarray(v)))
    return np.ascontiguousarray(np.array(rows, dtype=float))


def combinations(m: int, n: int) -> np.ndarray:
    """All subsets of n-1 of the m cables, as a (C(m, n-1), n-1) int64 array."""
    c = list(itertools.combinations(range(m), n - 1))
    return np.array(c, dtype=np.int64).reshape(len(c), n - 1)


def _pose_at(design: Design, position3, ori3) -> np.ndarray:
    full = np.concatenate([np.asarray(position3, float), np.asarray(ori3, float)])
    return full[list(design.motion.pose_index)]


def _grid3(g: Grid):
    d = len(g.lower)
    lower = np.zeros(3)
    step = np.ones(3)
    shape = np.ones(3, dtype=np.int64)
    lower[:d] = g.lower
    step[:d] = g.step
    shape[:d] = g.shape
    return lower, step, shape


def grid_positions(g: Grid, start: int, count: int) -> np.ndarray:
    """Positions (count, dim) of flat grid indices start .. start+count (C order)."""
    lower, step, shape = _grid3(g)
    idx = np.arange(start, start + count, dtype=np.int64)
    iz = idx % shape[2]
    r = idx // shape[2]
    iy = r % shape[1]
    ix = r // shape[1]
    pos = np.stack([lower[0] + ix * step[0], lower[1] + iy * step[1], lower[2] + iz * step[2]], axis=1)
    return pos[:, : len(g.lower)]


def run(design: Design, kind: str = "static", step: float | None = None, grid: Grid | None = None,
        orientation=None, on_chunk: Callable[[Chunk], None] | None = None,
        progress: Callable[[int, int], None] | None = None, force: bool = False,
        chunk: int = CHUNK, keep_maps: bool = True, interference: bool = False,
        engine: str | None = None) -> WorkspaceResult:
    """Sweep the workspace grid and return the summary and maps.

    Parameters
    ----------
    design : Design
    kind : {'static', 'wrench-feasible', 'wrench-closure'}
        ``static``: gravity only; ``wrench-feasible``: gravity plus every vertex
        of ``workspace.external_wrench``; ``wrench-closure``: tension bounds
        ignored, the cables positively span the wrench space.
    step : float, optional
        Grid step [m] overriding ``workspace.grid.step``.
    grid : Grid, optional
        Sweep this grid instead of the design's (e.g. the task box).
    orientation : (3,) array, optional
        Fixed (rx, ry, rz) [rad]; default ``workspace.orientation``.
    on_chunk : callable, optional
        Called with each :class:`Chunk` in grid order (stream rows to a file).
    progress : callable, optional
        Called as ``progress(done, total)`` after each chunk.
    interference : bool
        Also check cable-cable, cable-effector, effector-frame and cable-frame
        interference (:mod:`cdpr_design.statics.interference`): ``feasible`` becomes
        statics-feasible *and* collision free, chunks carry ``collision_free``,
        and the summary gains ``collision_free``, ``feasible_statics`` and
        ``collisions_by_kind``.
    engine : {'auto', 'numba', 'numpy'}, optional
        Default: the ``CDPR_DESIGN_ENGINE`` environment variable, else ``auto``
        (see :data:`ENGINES`).  Both engines give the same results (tested).

    Swivel pulleys (``cables[i].pulley``) are honoured whenever present; a
    design without pulleys and without ``interference`` takes the point-outlet
    kernels unchanged.
    """
    if kind not in KINDS:
        raise SpecError([("--kind", f"expected one of {', '.join(KINDS)}, got {kind!r}")])
    if interference or kin.has_pulleys(design):
        from cdpr_design.workspace.hardware import run_hardware  # pulleys and interference (real hardware geometry)

        return run_hardware(design, kind, step, grid, orientation, on_chunk, progress, force,
                            chunk, keep_maps, interference)
    t0 = time.perf_counter()
    g = grid if grid is not None else make_grid(design, step, force)
    if grid is not None:
        check_grid_size(g, force)
    ori = design.default_orientation_full() if orientation is None else np.asarray(orientation, float)
    R = kin.rotation_matrix(*ori)
    Rb = np.ascontiguousarray(design.attachments @ R.T)
    A = np.ascontiguousarray(design.outlets)
    rows = design.rows
    tmin, tmax = design.tension_min, design.tension_max
    wreq = wrench_vertices(design, kind, ori)
    combos = combinations(design.m, design.n)
    kcode = KINDS[kind]
    # the paper's case (two cables, two wrench rows) has an inlined closed-form kernel
    planar2 = design.m == 2 and design.n == 2 and kind != "wrench-closure"
    use_numpy = _use_numpy(engine, planar2, g.size)
    K = None if use_numpy else _K()
    wreq_used = wreq if kind == "wrench-feasible" else wreq[:1].copy()
    lower, stp, shape = _grid3(g)
    total = g.size
    m = design.m
    ncoords = len(design.motion.coords)
    ori_coords = _pose_at(design, np.zeros(3), ori)[design.motion.dim:]

    # maps for the pictures (subsampled so they never exceed MAP_CELLS)
    gshape = np.array(g.shape, dtype=np.int64)
    stride = np.ones_like(gshape)
    if keep_maps:
        while np.prod((gshape + stride - 1) // stride) > MAP_CELLS:
            stride[np.argmax((gshape + stride - 1) // stride)] += 1
    mshape = tuple(int(x) for x in (gshape + stride - 1) // stride) if keep_maps else (0,) * len(gshape)
    fmap = np.zeros(mshape, dtype=np.uint8)
    mmap = np.full(mshape, np.nan, dtype=np.float32)
    tmaps = np.full((m,) + mshape, np.nan, dtype=np.float32)

    nfeas = 0
    mmin, mmax = np.inf, -np.inf
    tpeak = np.full(m, -np.inf)
    chunk = max(1, min(chunk, total))
    feas_b = np.empty(chunk, dtype=np.uint8)
    marg_b = np.empty(chunk)
    ten_b = np.empty((chunk, m))
    len_b = np.empty((chunk, m))
    done = 0
    while done < total:
        cnt = min(chunk, total - done)
        if use_numpy:
            _planar2_numpy(g, done, cnt, Rb, A, wreq_used, tmin, tmax, feas_b, marg_b, ten_b, len_b)
            nf, cmin, cmax = _chunk_stats_numpy(feas_b, marg_b, ten_b, cnt, tpeak)
        elif planar2:
            K.sweep_grid_planar2(done, cnt, lower, stp, shape, Rb, A, wreq_used, tmin, tmax,
                                 feas_b, marg_b, ten_b, len_b)
        else:
            K.sweep_grid(done, cnt, lower, stp, shape, Rb, A, rows, wreq, tmin, tmax, combos, kcode,
                         feas_b, marg_b, ten_b, len_b)
        if not use_numpy:
            nf, cmin, cmax = K.chunk_stats(feas_b, marg_b, ten_b, cnt, tpeak)
        nfeas += nf
        if nf:
            mmin, mmax = min(mmin, cmin), max(mmax, cmax)
        if keep_maps and not (stride > 1).any():
            # full-resolution maps: the chunk is a contiguous run of the flat grid
            fmap.reshape(-1)[done:done + cnt] = feas_b[:cnt]
            mmap.reshape(-1)[done:done + cnt] = marg_b[:cnt]
            tmaps.reshape(m, -1)[:, done:done + cnt] = ten_b[:cnt].T
        elif keep_maps:
            idx = np.arange(done, done + cnt, dtype=np.int64)
            sub = np.unravel_index(idx, g.shape)
            keep = np.ones(cnt, dtype=bool)
            for ax, s in zip(sub, stride):
                if s > 1:
                    keep &= ax % s == 0
            msub = tuple(ax[keep] // s for ax, s in zip(sub, stride))
            fmap[msub] = feas_b[:cnt][keep]
            mmap[msub] = marg_b[:cnt][keep]
            for i in range(m):
                tmaps[(i,) + msub] = ten_b[:cnt, i][keep]
        if on_chunk is not None:
            pos = grid_positions(g, done, cnt)
            poses = np.empty((cnt, ncoords))
            poses[:, : design.motion.dim] = pos
            poses[:, design.motion.dim:] = ori_coords
            on_chunk(Chunk(done, poses, feas_b[:cnt].copy(), marg_b[:cnt].copy(),
                           ten_b[:cnt].copy(), len_b[:cnt].copy()))
        done += cnt
        if progress is not None:
            progress(done, total)
    tpeak[~np.isfinite(tpeak)] = np.nan
    axes = [ax[::s] for ax, s in zip(g.axes(), stride)]
    return WorkspaceResult(
        design=design, kind=kind, grid=g, orientation=ori, poses=total, feasible=nfeas,
        min_margin=mmin if nfeas else None, max_margin=mmax if nfeas else None,
        max_tension=tpeak, elapsed_s=time.perf_counter() - t0, feasible_map=fmap,
        margin_map=mmap, tension_maps=tmaps, map_axes=axes, map_stride=tuple(int(s) for s in stride),
    )


def _use_numpy(engine: str | None, planar2: bool, poses: int) -> bool:
    """Whether a point-outlet sweep takes the numpy closed form (see :data:`ENGINES`)."""
    source = "engine"
    if engine is None:
        engine = os.environ.get("CDPR_DESIGN_ENGINE", "").strip().lower() or "auto"
        source = "CDPR_DESIGN_ENGINE"
    if engine not in ENGINES:
        raise InputError(f"{source}: expected one of {', '.join(ENGINES)}, got {engine!r}")
    if engine == "numpy":
        if not planar2:
            raise InputError(f"{source}=numpy: the numpy engine covers two cables with two wrench rows "
                             "(static or wrench-feasible); use auto or numba for this design")
        return True
    if engine == "numba":
        return False
    return planar2 and poses <= NUMPY_MAX_POSES and "cdpr_design.kernels" not in sys.modules


def _planar2_numpy(g: Grid, start, count, Rb, A, wreq, tmin, tmax, feasible, margin, tensions, lengths):
    """``_kernels.sweep_grid_planar2`` vectorised with numpy: same formulas, same order.

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


#: = ``_kernels.RANK_TOL`` (a test checks): |det W| at or below it is rank deficient
_RANK_TOL = 1e-10


def _chunk_stats_numpy(feasible, margin, tensions, count, tpeak):
    """``_kernels.chunk_stats`` with numpy: (feasible count, min margin, max margin); raises ``tpeak``."""
    f = feasible[:count].astype(bool)
    nf = int(np.count_nonzero(f))
    if not nf:
        return 0, np.inf, -np.inf
    mm = margin[:count][f]
    np.maximum(tpeak, tensions[:count][f].max(axis=0), out=tpeak)
    return nf, float(mm.min()) + 0.0, float(mm.max()) + 0.0


def extra_columns(design: Design, interference: bool, mode: str | None) -> list[str]:
    """Names of the extra ``workspace.csv`` columns, in the order :func:`chunk_extra` gives them."""
    cols = ["collision_free"] if interference else []
    if mode == "total":
        cols.append("orientations_feasible")
    elif mode == "range":
        cols += [f"range_{c}" for c in design.motion.rotation_coords]
    return cols


def chunk_extra(chunk) -> dict:
    """The extra columns of a :class:`Chunk` (name -> array)."""
    out = {}
    cf = getattr(chunk, "collision_free", None)
    if cf is not None:
        out["collision_free"] = cf
    out.update(getattr(chunk, "extra", None) or {})
    return out


def representative_pose(result: WorkspaceResult) -> np.ndarray | None:
    """A feasible pose with the largest capacity margin (for drawing), or None."""
    mm = np.where(result.feasible_map.astype(bool), result.margin_map, np.nan)
    if not np.isfinite(mm).any():
        return None
    idx = np.unravel_index(int(np.nanargmax(mm)), mm.shape)
    pos = np.array([ax[i] for ax, i in zip(result.map_axes, idx)])
    return _pose_at(result.design, np.pad(pos, (0, 3 - pos.size)), result.orientation)


@dataclass
class PoseResult:
    """One pose evaluated exactly as a grid sweep would (same kernel).

    Attributes: pose (motion coords), lengths (m,) [m], tensions (m,) [N] (NaN
    where infeasible), feasible, margin [N] (NaN where W is rank deficient),
    W (n, m) structure matrix, wrench (n,) the nominal required wrench.
    """

    pose: np.ndarray
    lengths: np.ndarray
    tensions: np.ndarray
    feasible: bool
    margin: float
    W: np.ndarray
    wrench: np.ndarray
    #: colliding pairs (cli.md names; :func:`cdpr_design.statics.interference.check_pose`)
    collisions: list = field(default_factory=list)


def evaluate_pose(design: Design, pose, kind: str = "static") -> PoseResult:
    """Feasibility, capacity margin and minimum 2-norm tensions at one pose.

    Swivel pulleys are honoured (true outlet points in W, arc + free lengths);
    ``collisions`` lists the interfering pairs (``feasible`` is the statics
    result, as in a sweep without interference).
    """
    if kind not in KINDS:
        raise SpecError([("--kind", f"expected one of {', '.join(KINDS)}, got {kind!r}")])
    full = design.full_pose(pose)
    R = kin.rotation_matrix(*full[3:])
    Rb = np.ascontiguousarray(design.attachments @ R.T)
    W = np.empty((design.n, design.m))
    L = np.empty(design.m)
    K = _K()
    if kin.has_pulleys(design):
        from cdpr_design.statics.interference import hardware_arrays

        hw = hardware_arrays(design)
        ok = K.structure_matrix_pulley(full[0], full[1], full[2], Rb,
                                       np.ascontiguousarray(design.outlets), hw.axes, hw.eref,
                                       hw.radii, design.rows, W, L, np.empty((design.m, 3)))
    else:
        ok = K.structure_matrix(full[0], full[1], full[2], Rb, np.ascontiguousarray(design.outlets),
                                design.rows, W, L)
    wreq = wrench_vertices(design, kind, full[3:])
    t = np.full(design.m, np.nan)
    if ok:
        feasible, margin = K.eval_pose(W, wreq, design.tension_min, design.tension_max,
                                       combinations(design.m, design.n), KINDS[kind], t)
    else:
        feasible, margin = False, np.nan
    from cdpr_design.statics.interference import collisions

    return PoseResult(np.asarray(pose, float), L, t, bool(feasible), float(margin), W, wreq[0],
                      collisions(design, pose))


def run_orientations(design: Design, mode: str = "total", **kwargs) -> WorkspaceResult:
    """Total orientation workspace or orientation range per position (1R2T, 3R3T).

    See :func:`cdpr_design.workspace.hardware.run_orientations` for the parameters
    (``kind``, ``step``, ``grid``, ``orientation``, ``orientations``,
    ``on_chunk``, ``progress``, ``force``, ``interference``).
    """
    from cdpr_design.workspace.hardware import run_orientations as _run

    return _run(design, mode, **kwargs)
