"""Workspace grids: their size, their positions, chunks of rows, and the streamed result.

A sweep visits a grid of platform positions at a fixed orientation in chunks
of :data:`CHUNK` rows (bounded memory however large the grid), hands each
:class:`Chunk` to an optional callback (the command line streams it to
``workspace.csv``), and collects into :class:`Maps` the summary figures and
the maps behind the pictures (subsampled for very large grids), which become
a :class:`WorkspaceResult`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from cdpr_design.errors import SpecError
from cdpr_design.model.design import Design, Grid
from cdpr_design.statics.kinematics import pose_at

#: Largest grid swept without ``force=True`` (poses).
MAX_POSES = 20_000_000
#: Largest grid swept even with ``force=True`` (poses): grid indices and positions stay exact in float64.
HARD_MAX_POSES = 2 ** 53
#: Rows evaluated per chunk (bounded memory: ~ CHUNK * (2 m + 2) * 8 bytes).
CHUNK = 1 << 18
#: Largest number of cells kept for the maps behind the pictures.
MAP_CELLS = 4_000_000


@dataclass
class Chunk:
    """One chunk of a sweep: rows ``start .. start + len`` of the grid (C order x, y, z).

    ``poses`` are in the motion's coordinates (orientation columns hold the
    sweep's fixed orientation, or the hanging one).  ``extra`` holds the
    columns after the contract's, in the order the sweep plan declares them
    (:attr:`cdpr_design.workspaces.plan.Plan.extra_columns`).
    """

    start: int
    poses: np.ndarray
    feasible: np.ndarray
    margin: np.ndarray
    tensions: np.ndarray
    lengths: np.ndarray
    #: further table columns after the contract's (name -> (count,) array)
    extra: dict = field(default_factory=dict)

    @property
    def collision_free(self) -> np.ndarray | None:
        """uint8 (count,), 1 where no interference (only when the sweep checks it)."""
        return self.extra.get("collision_free")


@dataclass
class Rows:
    """What a sweep's base evaluator computes for a chunk of positions, before the wrappers
    add their columns: ``feasible`` uint8 (k,), ``margin`` (k,) [N], ``tensions`` (k, m) [N],
    ``lengths`` (k, m) [m] (None where the rows are not written), ``extra`` the declared
    columns (name -> (k,)), ``maps`` the declared maps' values (name -> (k,)), ``poses`` the
    motion's pose coordinates where they are not the grid's at the sweep's orientation,
    ``nominal`` where rows stand for a set of orientations of sagging cables: the statics at the
    nominal orientation, (effector tensions [N], extra columns ``outlet_tension_<c>`` [N] and
    ``unstretched_length_<c>`` [m]) (the loads on the frame take them); ``loads`` the envelope of
    the loads on the frame of the feasible rows where the base evaluator computed it with them
    (:meth:`~cdpr_design.workspaces.parts.Base.keep_frame_loads`: ``cab`` (m, 13), ``tot`` (5, 3)
    as :func:`cdpr_design.kernels.frame_loads.frame_load_stats` leaves them); ``sets`` where rows
    stand for every orientation of a set (the total orientation workspace): the statics at each, a
    list of (angles (3,) [rad], effector tensions (k, m) [N], extra columns (sagging cables:
    ``outlet_tension_<c>`` [N], ``unstretched_length_<c>`` [m]; else none)) (the loads on the frame
    take them)."""

    feasible: np.ndarray
    margin: np.ndarray
    tensions: np.ndarray
    lengths: np.ndarray | None
    extra: dict = field(default_factory=dict)
    maps: dict = field(default_factory=dict)
    poses: np.ndarray | None = None
    nominal: tuple | None = None
    loads: tuple | None = None
    sets: list | None = None


#: Rows per block of :func:`chunk_stats`'s reduction of the tensions (a block's cells are one
#: contiguous run, reduced element by element against the other blocks').
STATS_BLOCK = 64


def chunk_stats(r: Rows, tpeak: np.ndarray) -> tuple[int, float, float]:
    """(feasible count, least margin [N], largest margin [N]) over the feasible rows of ``r`` (a
    margin of -0.0 reported as 0.0; (0, inf, -inf) when none is feasible); raises ``tpeak`` (m,)
    [N] in place to each cable's largest feasible tension (a largest tension of zero as 0.0).
    NaN margins and tensions (a feasible pose without tensions) are passed over."""
    feas = np.asarray(r.feasible)
    nf = int(np.count_nonzero(feas))
    if not nf:
        return 0, np.inf, -np.inf
    f = feas.astype(bool)
    np.fmax(tpeak, _feasible_peak(np.asarray(r.tensions), f) + 0.0, out=tpeak)
    marg = np.asarray(r.margin)
    return (nf, float(np.fmin.reduce(marg, where=f, initial=np.inf)) + 0.0,
            float(np.fmax.reduce(marg, where=f, initial=-np.inf)) + 0.0)


def _feasible_peak(ten: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Per column, the largest value of the rows of ``ten`` (k, m) where ``f`` (k,) bool, NaN passed
    over (-inf where there is none): the whole blocks of :data:`STATS_BLOCK` rows reduced as one
    (nb, STATS_BLOCK * m) array along its first axis, then the blocks' peaks and the rows left."""
    k, m = ten.shape
    whole = k // STATS_BLOCK * STATS_BLOCK
    peak = np.fmax.reduce(ten[whole:], axis=0, where=f[whole:, None], initial=-np.inf)
    if whole:
        cells = ten[:whole].reshape(-1, STATS_BLOCK * m)
        mask = np.repeat(f[:whole], m).reshape(cells.shape)
        blocks = np.fmax.reduce(cells, axis=0, where=mask, initial=-np.inf)
        np.fmax(peak, np.fmax.reduce(blocks.reshape(STATS_BLOCK, m), axis=0), out=peak)
    return peak


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
    #: orientation sweeps only (``Analysis.orientations``): a hardware.OrientationMaps
    orientation_maps: object = None
    #: under-constrained designs only: the hanging tilt map (a workspaces.hanging.HangingMaps)
    hanging: object = None
    #: the resolved robot the sweep ran (:class:`cdpr_design.statics.robot.Robot`)
    robot: object = None
    #: ``--stiffness`` only: the maps ``min_stiffness`` [N/m] and ``lowest_frequency`` [Hz]
    stiffness: dict | None = None
    #: ``--accelerations`` only: the map of the acceleration radius [m/s^2]
    acceleration: np.ndarray | None = None
    #: the picture files the sweep's plan declared (:attr:`~cdpr_design.workspaces.plan.Plan.pictures`)
    pictures: list = field(default_factory=list)
    #: the boundary between the grid points (a :class:`~cdpr_design.workspaces.boundary.Boundary`;
    #: sweeps planned with ``solid``)
    boundary: object = None
    #: the loads on the frame (a :class:`~cdpr_design.workspaces.frame_loads.FrameLoadTable`;
    #: sweeps planned with ``solid``)
    frame_loads: object = None

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
        check_step(step, "--step")
        g = Grid(g.lower, g.upper, (float(step),) * len(g.lower))
    check_grid_size(g, force, path="--step" if step is not None else "workspace.grid.step")
    return g


def first_pose(g: Grid) -> Grid:
    """The one-pose grid at ``g``'s first pose (its lower corner), with ``g``'s step."""
    return Grid(tuple(g.lower), tuple(g.lower), tuple(g.step))


def check_step(step: float, path: str = "--step") -> None:
    """A grid step [m]: a positive finite number (:class:`SpecError` naming ``path`` otherwise)."""
    if isinstance(step, bool) or not isinstance(step, (int, float, np.floating)) or not (
            math.isfinite(step) and step > 0):
        raise SpecError([(path, f"expected a positive number of metres, got {step}")])


def axis_counts(g: Grid) -> list[float]:
    """Samples per axis of a grid, as floats: never overflows (inf for a zero or tiny step)."""
    out = []
    for lo, hi, st in zip(g.lower, g.upper, g.step):
        c = (hi - lo) / st if st > 0 else math.inf
        out.append(float(math.floor(c + 1e-9) + 1) if math.isfinite(c) else math.inf)
    return out


def grid_count(g: Grid) -> float:
    """Poses of a grid, as a float computed without overflow (before any array or int64 sees it)."""
    return math.prod(axis_counts(g))


def _count_text(n: float) -> str:
    if not math.isfinite(n):
        return "more than 1e308"
    return f"{n:,.0f}" if n < 1e15 else f"{n:.3g}"


def check_grid_size(g: Grid, force: bool, path: str = "workspace.grid.step") -> None:
    """Refuse a grid of more than :data:`MAX_POSES` poses (without ``force``) or of more than
    :data:`HARD_MAX_POSES` (ever); counted in floats first, so no step is too small to be told so."""
    n = grid_count(g)
    if n <= MAX_POSES or (force and n <= HARD_MAX_POSES):
        return
    dims = " x ".join(_count_text(c) for c in axis_counts(g))
    if n > HARD_MAX_POSES:
        raise SpecError([(path, f"the grid would have {_count_text(n)} poses ({dims}), more than the "
                                f"{HARD_MAX_POSES:.3g} any sweep can index exactly; raise the step")])
    raise SpecError([(path, f"the grid would have {_count_text(n)} poses ({dims}), more than the "
                            f"{MAX_POSES:,} swept without --force; raise the step or pass --force")])


def grid3(g: Grid):
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
    lower, step, shape = grid3(g)
    idx = np.arange(start, start + count, dtype=np.int64)
    iz = idx % shape[2]
    r = idx // shape[2]
    iy = r % shape[1]
    ix = r // shape[1]
    pos = np.stack([lower[0] + ix * step[0], lower[1] + iy * step[1], lower[2] + iz * step[2]], axis=1)
    return pos[:, : len(g.lower)]


def positions3(g: Grid, start: int, count: int) -> np.ndarray:
    """Positions (count, 3) [m] of flat grid indices start .. start+count, zero-padded to 3-D."""
    pos = grid_positions(g, start, count)
    P = np.zeros((count, 3))
    P[:, : pos.shape[1]] = pos
    return P


def chunk_poses(design: Design, P: np.ndarray, ori) -> np.ndarray:
    """Poses in the motion's coordinates for positions ``P`` (k, 3) [m] at orientation ``ori`` [rad]."""
    d = design.motion.dim
    poses = np.empty((P.shape[0], len(design.motion.coords)))
    poses[:, :d] = P[:, :d]
    poses[:, d:] = pose_at(design, np.zeros(3), ori)[d:]
    return poses


class Maps:
    """Streaming statistics and (subsampled) maps of a sweep.

    ``add`` takes each chunk's rows with their statistics (feasible count,
    least and largest margin, computed by the sweep's engine); ``result``
    builds the :class:`WorkspaceResult`.  Maps are kept at full resolution
    while the grid has at most :data:`MAP_CELLS` cells, else every
    ``stride``-th cell per axis.
    """

    def __init__(self, g: Grid, m: int, keep_maps: bool, extra_maps: tuple = ()):
        self.g, self.m, self.keep = g, m, keep_maps
        gshape = np.array(g.shape, dtype=np.int64)
        stride = np.ones_like(gshape)
        if keep_maps:
            while np.prod((gshape + stride - 1) // stride) > MAP_CELLS:
                stride[np.argmax((gshape + stride - 1) // stride)] += 1
        self.stride = stride
        shp = tuple(int(x) for x in (gshape + stride - 1) // stride) if keep_maps else (0,) * len(gshape)
        self.fmap = np.zeros(shp, dtype=np.uint8)
        self.mmap = np.full(shp, np.nan, dtype=np.float32)
        self.tmaps = np.full((m,) + shp, np.nan, dtype=np.float32)
        self.xmaps = {name: np.full(shp, np.nan, dtype=np.float32) for name in extra_maps}
        self.nfeas, self.mmin, self.mmax = 0, np.inf, -np.inf
        #: largest tension [N] per cable over the feasible poses so far (the engines raise it)
        self.tpeak = np.full(m, -np.inf)

    def add(self, start: int, stats, feas, marg, ten, extra: dict | None = None) -> None:
        """Rows ``start .. start + len(feas)``; ``stats`` = (feasible count, min margin, max margin)."""
        nf, cmin, cmax = stats
        self.nfeas += nf
        if nf:
            self.mmin, self.mmax = min(self.mmin, cmin), max(self.mmax, cmax)
        if not self.keep:
            return
        cnt = feas.shape[0]
        if not (self.stride > 1).any():
            # full resolution: the chunk is a contiguous run of the flat grid
            self.fmap.reshape(-1)[start:start + cnt] = feas
            self.mmap.reshape(-1)[start:start + cnt] = marg
            self.tmaps.reshape(self.m, -1)[:, start:start + cnt] = ten.T
            for name, v in (extra or {}).items():
                if name in self.xmaps:
                    self.xmaps[name].reshape(-1)[start:start + cnt] = v
            return
        msub, keep = self._cells(start, cnt)
        self.fmap[msub] = feas[keep]
        self.mmap[msub] = marg[keep]
        for i in range(self.m):
            self.tmaps[(i,) + msub] = ten[keep, i]
        for name, v in (extra or {}).items():
            if name in self.xmaps:
                self.xmaps[name][msub] = v[keep]

    def _cells(self, start: int, cnt: int):
        """Map cells of rows start .. start+cnt kept by the stride, and the mask of those rows."""
        idx = np.arange(start, start + cnt, dtype=np.int64)
        sub = np.unravel_index(idx, self.g.shape)
        keep = np.ones(cnt, dtype=bool)
        for ax, s in zip(sub, self.stride):
            if s > 1:
                keep &= ax % s == 0
        return tuple(ax[keep] // s for ax, s in zip(sub, self.stride)), keep

    def result(self, design: Design, kind: str, ori, t0: float, extra: dict | None = None) -> "WorkspaceResult":
        """The :class:`WorkspaceResult`; ``t0`` is the sweep's start (``time.perf_counter()``)."""
        tpeak = self.tpeak.copy()
        tpeak[~np.isfinite(tpeak)] = np.nan
        g = self.g
        axes = [ax[::s] for ax, s in zip(g.axes(), self.stride)]
        return WorkspaceResult(
            design=design, kind=kind, grid=g, orientation=np.asarray(ori, float), poses=g.size,
            feasible=self.nfeas, min_margin=self.mmin if self.nfeas else None,
            max_margin=self.mmax if self.nfeas else None, max_tension=tpeak,
            elapsed_s=time.perf_counter() - t0, feasible_map=self.fmap, margin_map=self.mmap,
            tension_maps=self.tmaps, map_axes=axes,
            map_stride=tuple(int(s) for s in self.stride), extra=dict(extra or {}))


def column_names(design: Design) -> list[str]:
    """The ``workspace.csv`` contract columns: pose coords, feasible, margin, tensions, lengths."""
    names = design.cable_names
    return (list(design.motion.coords) + ["feasible", "margin"]
            + [f"tension_{c}" for c in names] + [f"length_{c}" for c in names])


def representative_pose(result: WorkspaceResult) -> np.ndarray | None:
    """A feasible pose with the largest capacity margin (for drawing), or None."""
    mm = np.where(result.feasible_map.astype(bool), result.margin_map, np.nan)
    if not np.isfinite(mm).any():
        return None
    idx = np.unravel_index(int(np.nanargmax(mm)), mm.shape)
    pos = np.array([ax[i] for ax, i in zip(result.map_axes, idx)])
    return pose_at(result.design, np.pad(pos, (0, 3 - pos.size)), result.orientation)
