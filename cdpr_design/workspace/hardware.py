"""Workspace sweeps with real hardware geometry and orientation sets.

- :func:`run_hardware` is what :func:`cdpr_design.workspace.engine.run` does when a
  design has swivel pulleys or interference is checked: the same chunked
  grid sweep, through :func:`cdpr_design.kernels.sweep_points` (pulley-aware
  structure matrix, interference mask per pose).
- :func:`run_orientations` sweeps orientation sets for the rotational motions
  (``1R2T``, ``3R3T``):

  ``total``: the *total orientation workspace* - positions feasible for every
  orientation of a sampled box (``workspace.orientation_set``); by
  construction the intersection of the fixed-orientation workspaces of the
  samples (Pott 2018, ch. 6; Gouttefarde, Merlet & Daney, "Wrench-feasible
  workspace of parallel cable-driven mechanisms", ICRA 2007).

  ``range``: the *orientation range* per position - the largest box
  nominal +- s * max (s = k / levels, k = 0..levels) whose samples, and those of
  every smaller level, are all feasible (``workspace.orientation_range``).

The core never touches files: results are data, chunks go to ``on_chunk``.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass

import numpy as np

from cdpr_design import kernels as K
from cdpr_design.statics import kinematics as kin
from cdpr_design.errors import SpecError
from cdpr_design.statics.interference import HIT_NAMES, hardware_arrays
from cdpr_design.model.design import Design, Grid

#: Default total-orientation set: nominal +- 10 deg about the last rotation coordinate, 5 samples.
DEFAULT_SET_HALF = math.radians(10.0)
DEFAULT_SET_COUNT = 5
#: Default orientation range: up to +- 30 deg on every rotation coordinate, 10 levels, 3 samples.
DEFAULT_RANGE_MAX = math.radians(30.0)
DEFAULT_RANGE_LEVELS = 10
DEFAULT_RANGE_COUNT = 3


class Evaluator:
    """Evaluates explicit positions at one orientation (pulleys and interference included)."""

    def __init__(self, design: Design, kind: str, interference: bool):
        from cdpr_design.workspace import engine as ws

        self.design = design
        self.kind = kind
        self.kcode = ws.KINDS[kind]
        self.interference = bool(interference)
        self.hw = hardware_arrays(design)
        self.A = np.ascontiguousarray(design.outlets)
        self.Bp = np.ascontiguousarray(design.attachments)
        self.rows = design.rows
        self.tmin, self.tmax = design.tension_min, design.tension_max
        self.combos = ws.combinations(design.m, design.n)
        self._wreq = {}

    def wrench(self, ori) -> np.ndarray:
        from cdpr_design.workspace import engine as ws

        key = tuple(float(x) for x in ori)
        if key not in self._wreq:
            self._wreq[key] = ws.wrench_vertices(self.design, self.kind, np.asarray(ori, float))
        return self._wreq[key]

    def __call__(self, P: np.ndarray, ori, full: bool = True):
        """(feasible uint8, margin, tensions, lengths, mask uint8) at positions ``P`` (k, 3).

        ``feasible`` is the statics result only; ``mask`` the interference bits
        (zero when interference is not checked).
        """
        ori = np.asarray(ori, float)
        R = np.ascontiguousarray(kin.rotation_matrix(*ori))
        Rb = np.ascontiguousarray(self.Bp @ R.T)
        k, m = P.shape[0], self.design.m
        feas = np.empty(k, dtype=np.uint8)
        marg = np.empty(k)
        ten = np.empty((k, m))
        L = np.empty((k, m))
        mask = np.empty(k, dtype=np.uint8)
        hw = self.hw
        K.sweep_points(np.ascontiguousarray(P, dtype=float), Rb, R, self.A, hw.axes, hw.eref,
                       hw.radii, self.rows, self.wrench(ori), self.tmin, self.tmax, self.combos,
                       self.kcode, self.interference, self.Bp, hw.half, hw.rho, hw.frame_lower,
                       hw.frame_upper, hw.dim, hw.tol, full, feas, marg, ten, L, mask)
        return feas, marg, ten, L, mask


class _Maps:
    """Streaming statistics and (subsampled) maps of a sweep, as in workspace.run."""

    def __init__(self, g: Grid, m: int, keep_maps: bool, extra_maps: tuple = ()):
        from cdpr_design.workspace import engine as ws

        self.g, self.m, self.keep = g, m, keep_maps
        gshape = np.array(g.shape, dtype=np.int64)
        stride = np.ones_like(gshape)
        if keep_maps:
            while np.prod((gshape + stride - 1) // stride) > ws.MAP_CELLS:
                stride[np.argmax((gshape + stride - 1) // stride)] += 1
        self.stride = stride
        shp = tuple(int(x) for x in (gshape + stride - 1) // stride) if keep_maps else (0,) * len(gshape)
        self.fmap = np.zeros(shp, dtype=np.uint8)
        self.mmap = np.full(shp, np.nan, dtype=np.float32)
        self.tmaps = np.full((m,) + shp, np.nan, dtype=np.float32)
        self.xmaps = {name: np.full(shp, np.nan, dtype=np.float32) for name in extra_maps}
        self.nfeas, self.mmin, self.mmax = 0, np.inf, -np.inf
        self.tpeak = np.full(m, -np.inf)

    def add(self, start: int, feas, marg, ten, extra: dict | None = None):
        cnt = feas.shape[0]
        nf, cmin, cmax = K.chunk_stats(np.ascontiguousarray(feas), np.ascontiguousarray(marg),
                                       np.ascontiguousarray(ten), cnt, self.tpeak)
        self.nfeas += nf
        if nf:
            self.mmin, self.mmax = min(self.mmin, cmin), max(self.mmax, cmax)
        if not self.keep:
            return
        idx = np.arange(start, start + cnt, dtype=np.int64)
        sub = np.unravel_index(idx, self.g.shape)
        keep = np.ones(cnt, dtype=bool)
        for ax, s in zip(sub, self.stride):
            if s > 1:
                keep &= ax % s == 0
        msub = tuple(ax[keep] // s for ax, s in zip(sub, self.stride))
        self.fmap[msub] = feas[keep]
        self.mmap[msub] = marg[keep]
        for i in range(self.m):
            self.tmaps[(i,) + msub] = ten[keep, i]
        for name, v in (extra or {}).items():
            if name in self.xmaps:
                self.xmaps[name][msub] = v[keep]

    def result(self, design, kind, g, ori, t0, extra, cls=None, **more):
        from cdpr_design.workspace import engine as ws

        tpeak = self.tpeak.copy()
        tpeak[~np.isfinite(tpeak)] = np.nan
        axes = [ax[::s] for ax, s in zip(g.axes(), self.stride)]
        cls = cls or ws.WorkspaceResult
        return cls(
            design=design, kind=kind, grid=g, orientation=np.asarray(ori, float), poses=g.size,
            feasible=self.nfeas, min_margin=self.mmin if self.nfeas else None,
            max_margin=self.mmax if self.nfeas else None, max_tension=tpeak,
            elapsed_s=time.perf_counter() - t0, feasible_map=self.fmap, margin_map=self.mmap,
            tension_maps=self.tmaps, map_axes=axes,
            map_stride=tuple(int(s) for s in self.stride), extra=extra, **more)


def _positions3(g: Grid, start: int, cnt: int) -> np.ndarray:
    from cdpr_design.workspace import engine as ws

    pos = ws.grid_positions(g, start, cnt)
    P = np.zeros((cnt, 3))
    P[:, : pos.shape[1]] = pos
    return P


def _setup(design, kind, step, grid, orientation, force):
    from cdpr_design.workspace import engine as ws

    if kind not in ws.KINDS:
        raise SpecError([("--kind", f"expected one of {', '.join(ws.KINDS)}, got {kind!r}")])
    g = grid if grid is not None else ws.make_grid(design, step, force)
    if grid is not None:
        ws.check_grid_size(g, force)
    ori = design.default_orientation_full() if orientation is None else np.asarray(orientation, float)
    return g, ori


def _poses(design, P, ori):
    from cdpr_design.workspace import engine as ws

    d = design.motion.dim
    poses = np.empty((P.shape[0], len(design.motion.coords)))
    poses[:, :d] = P[:, :d]
    poses[:, d:] = ws._pose_at(design, np.zeros(3), ori)[d:]
    return poses


def _kind_counts(mask: np.ndarray, counts: dict) -> None:
    for bit, name in HIT_NAMES.items():
        counts[name] += int(np.count_nonzero(mask & bit))


def run_hardware(design: Design, kind: str = "static", step=None, grid=None, orientation=None,
                 on_chunk=None, progress=None, force: bool = False, chunk: int | None = None,
                 keep_maps: bool = True, interference: bool = False):
    """The grid sweep of :func:`cdpr_design.workspace.engine.run` with pulleys and interference.

    With ``interference`` the ``feasible`` flag is statics-feasible and
    collision free; tensions are blanked (NaN) where a pose collides; the
    margin stays the capacity margin.  Summary extras: ``interference``,
    ``collision_free`` (collision-free poses), ``feasible_statics`` (feasible
    before the interference checks), ``collisions_by_kind`` (poses hit by
    each kind of interference), ``pulleys``.
    """
    from cdpr_design.workspace import engine as ws

    t0 = time.perf_counter()
    g, ori = _setup(design, kind, step, grid, orientation, force)
    ev = Evaluator(design, kind, interference)
    total = g.size
    chunk = max(1, min(chunk or ws.CHUNK, total))
    maps = _Maps(g, design.m, keep_maps)
    n_free = n_stat = 0
    counts = {name: 0 for name in HIT_NAMES.values()}
    done = 0
    while done < total:
        cnt = min(chunk, total - done)
        P = _positions3(g, done, cnt)
        feas, marg, ten, L, mask = ev(P, ori)
        cfree = None
        if interference:
            n_stat += int(np.count_nonzero(feas))
            cfree = (mask == 0).astype(np.uint8)
            n_free += int(np.count_nonzero(cfree))
            _kind_counts(mask, counts)
            feas &= cfree
            ten[cfree == 0] = np.nan
        maps.add(done, feas, marg, ten)
        if on_chunk is not None:
            on_chunk(ws.Chunk(done, _poses(design, P, ori), feas, marg, ten, L, collision_free=cfree))
        done += cnt
        if progress is not None:
            progress(done, total)
    extra = {"pulleys": bool(kin.has_pulleys(design)), "interference": bool(interference)}
    if interference:
        extra.update(collision_free=n_free, feasible_statics=n_stat, collisions_by_kind=counts)
    return maps.result(design, kind, g, ori, t0, extra)


# ----------------------------------------------------------------------------
# Orientation sets
# ----------------------------------------------------------------------------


@dataclass
class OrientationMaps:
    """Extra maps of an orientation sweep (same shape as ``feasible_map``).

    ``value`` is the fraction of the set's orientations that are feasible
    (``total``) or the range scale s in [0, 1] (``range``; NaN where the
    nominal orientation is infeasible).
    """

    mode: str
    value: np.ndarray
    orientations: np.ndarray   # (q, 3) the full (rx, ry, rz) samples of the set / largest level
    scale: np.ndarray          # (nrot,) max half-width per rotation coordinate (range mode) [rad]


def _rot_index(design: Design) -> list[int]:
    """Indices into (rx, ry, rz) of the motion's rotation coordinates."""
    return [i - 3 for i in design.motion.pose_index[design.motion.dim:]]


def _per_coord(v, n, what):
    a = np.atleast_1d(np.asarray(v, float))
    if a.size == 1:
        a = np.repeat(a, n)
    if a.size != n:
        raise SpecError([(what, f"expected 1 or {n} numbers, got {a.size}")])
    return a


def orientation_set(design: Design, lower=None, upper=None, count=None) -> np.ndarray:
    """The sampled orientation box of the total orientation workspace, (q, 3) (rx, ry, rz) [rad].

    Arguments default to ``workspace.orientation_set``, else nominal +- 10 deg
    about the last rotation coordinate (phi or rz) with 5 samples.  ``count``
    samples per coordinate, evenly spaced including both ends (1: the lower value).
    """
    mot = design.motion
    if not mot.rotational:
        raise SpecError([("--orientations", f"motion {mot.name} has a fixed orientation")])
    idx = _rot_index(design)
    nrot = len(idx)
    nominal = design.default_orientation_full()[idx]
    spec = design.workspace.orientation_set
    if lower is None and spec is not None:
        lower, upper, count = spec.lower, spec.upper, spec.count
    if lower is None:
        lower = nominal.copy()
        upper = nominal.copy()
        lower[-1] -= DEFAULT_SET_HALF
        upper[-1] += DEFAULT_SET_HALF
        count = [1] * (nrot - 1) + [DEFAULT_SET_COUNT]
    lo = _per_coord(lower, nrot, "workspace.orientation_set.lower")
    hi = _per_coord(upper, nrot, "workspace.orientation_set.upper")
    cnt = _per_coord(count if count is not None else DEFAULT_SET_COUNT, nrot,
                     "workspace.orientation_set.count").astype(int)
    axes = [np.array([a]) if c == 1 or a == b else np.linspace(a, b, c) for a, b, c in zip(lo, hi, cnt)]
    full = design.default_orientation_full()
    out = []
    for combo in itertools.product(*axes):
        o = full.copy()
        o[idx] = combo
        out.append(o)
    return np.array(out)


def range_levels(design: Design, max_=None, levels=None, count=None):
    """Orientation-range settings: (scale (nrot,) [rad], levels, count, list of (q_k, 3) level sets).

    Level k (1..levels) samples nominal +- (k / levels) * scale with ``count``
    values per coordinate whose scale is non-zero (both ends included).
    """
    mot = design.motion
    if not mot.rotational:
        raise SpecError([("--orientations", f"motion {mot.name} has a fixed orientation")])
    idx = _rot_index(design)
    nrot = len(idx)
    spec = design.workspace.orientation_range
    if spec is not None:
        max_ = spec.max if max_ is None else max_
        levels = spec.levels if levels is None else levels
        count = spec.count if count is None else count
    scale = _per_coord(DEFAULT_RANGE_MAX if max_ is None else max_, nrot, "workspace.orientation_range.max")
    levels = int(levels or DEFAULT_RANGE_LEVELS)
    count = int(count or DEFAULT_RANGE_COUNT)
    full = design.default_orientation_full()
    nominal = full[idx]
    sets = []
    for k in range(1, levels + 1):
        s = k / levels
        axes = [np.array([c]) if h == 0 else np.linspace(c - s * h, c + s * h, count)
                for c, h in zip(nominal, scale)]
        lev = []
        for combo in itertools.product(*axes):
            o = full.copy()
            o[idx] = combo
            lev.append(o)
        sets.append(np.array(lev))
    return scale, levels, count, sets


def run_orientations(design: Design, mode: str = "total", kind: str = "static", step=None,
                     grid=None, orientation=None, orientations=None,
                     on_chunk=None, progress=None, force: bool = False, chunk: int | None = None,
                     keep_maps: bool = True, interference: bool = False):
    """Total orientation workspace (``mode='total'``) or orientation range per position (``'range'``).

    Parameters
    ----------
    mode : {'total', 'range'}
    orientations : (q, 3) array, optional
        ``total``: the orientation set (rx, ry, rz) [rad]; default
        :func:`orientation_set`.
    orientation : (3,) nominal orientation [rad] (default ``workspace.orientation``):
        the orientation of the reported poses, lengths and (``range``) the
        centre of the range boxes.
    interference : bool
        Intersect every orientation's feasibility with its interference check.

    CSV chunks (``on_chunk``): the contract columns at the nominal pose, with

    - ``total``: ``feasible`` = feasible for every orientation of the set,
      ``margin`` = least capacity margin over the set, ``tension_<c>`` =
      largest tension over the set (empty unless feasible); extra column
      ``orientations_feasible`` (count of feasible set orientations) and,
      with interference, ``collision_free`` (no interference at any of them).
      Summary extras with interference: ``collision_free`` (poses collision
      free at every orientation), ``feasible_statics`` (statics feasible at
      every orientation), ``collisions_by_kind`` (poses each kind hits at one
      orientation of the set or more).
    - ``range``: ``feasible``, ``margin``, tensions at the nominal orientation;
      extra columns ``range_<coord>`` (largest feasible half-width [rad] per
      rotation coordinate; empty where the nominal is infeasible) and, with
      interference, ``collision_free`` at the nominal; the summary extras
      ``collision_free``, ``feasible_statics`` and ``collisions_by_kind``
      count the nominal orientation's poses.

    Returns a :class:`~cdpr_design.workspace.engine.WorkspaceResult` whose maps are
    those of the swept workspace, with ``orientation_maps`` (an
    :class:`OrientationMaps`) set and summary extras ``orientation_mode``,
    ``orientation_count`` and (range) ``mean_range``, ``range_levels``.
    """
    from cdpr_design.workspace import engine as ws

    if mode not in ("total", "range"):
        raise SpecError([("--orientations", f"expected total or range, got {mode!r}")])
    t0 = time.perf_counter()
    g, nominal = _setup(design, kind, step, grid, orientation, force)
    ev = Evaluator(design, kind, interference)
    m = design.m
    rot_names = design.motion.rotation_coords
    if mode == "total":
        oset = orientation_set(design) if orientations is None else np.atleast_2d(np.asarray(orientations, float))
        level_sets = None
        scale = np.zeros(len(rot_names))
    else:
        scale, levels, count, level_sets = range_levels(design)
        oset = level_sets[-1]
    total = g.size
    chunk = max(1, min(chunk or ws.CHUNK, total))
    maps = _Maps(g, m, keep_maps, extra_maps=("value",))
    counts = {name: 0 for name in HIT_NAMES.values()}
    done = 0
    n_eval = 0
    n_free = n_stat = 0
    range_sum, range_n = 0.0, 0
    while done < total:
        cnt = min(chunk, total - done)
        P = _positions3(g, done, cnt)
        extra_cols = {}
        if mode == "total":
            _, _, _, L, _ = ev(P, nominal) if on_chunk is not None else (None,) * 5
            allok = np.ones(cnt, dtype=bool)
            nok = np.zeros(cnt, dtype=np.int64)
            cfree_all = np.ones(cnt, dtype=bool)
            stat_all = np.ones(cnt, dtype=bool)
            hits = np.zeros(cnt, dtype=np.uint8)
            marg = np.full(cnt, np.inf)
            ten = np.full((cnt, m), -np.inf)
            for o in oset:
                f, mg, t, _, mask = ev(P, o)
                n_eval += cnt
                ok = f.astype(bool)
                if interference:
                    stat_all &= ok
                    hits |= mask
                    cf = mask == 0
                    cfree_all &= cf
                    ok &= cf
                nok += ok
                allok &= ok
                marg = np.fmin(marg, mg)
                ten = np.fmax(ten, t)
            marg[~np.isfinite(marg)] = np.nan
            ten[~allok] = np.nan
            feas = allok.astype(np.uint8)
            value = nok / len(oset)
            extra_cols["orientations_feasible"] = nok
            cfree = cfree_all.astype(np.uint8) if interference else None
            if interference:
                n_free += int(np.count_nonzero(cfree_all))
                n_stat += int(np.count_nonzero(stat_all))
                _kind_counts(hits, counts)
        else:
            feas, marg, ten, L, mask = ev(P, nominal)
            n_eval += cnt
            cfree = None
            if interference:
                cfree = (mask == 0).astype(np.uint8)
                _kind_counts(mask, counts)
                n_free += int(np.count_nonzero(cfree))
                n_stat += int(np.count_nonzero(feas))
                feas &= cfree
                ten[cfree == 0] = np.nan
            best = np.zeros(cnt)
            alive = np.flatnonzero(feas)
            for k, lev in enumerate(level_sets, start=1):
                if alive.size == 0:
                    break
                for o in lev:
                    if alive.size == 0:
                        break
                    f, _, _, _, mask = ev(P[alive], o)
                    n_eval += alive.size
                    ok = f.astype(bool)
                    if interference:
                        ok &= mask == 0
                    alive = alive[ok]
                best[alive] = k / len(level_sets)
            best[feas == 0] = np.nan
            value = best
            for j, c in enumerate(rot_names):
                extra_cols[f"range_{c}"] = best * scale[j]
            fin = np.isfinite(best)
            range_sum += float(best[fin].sum())
            range_n += int(fin.sum())
        maps.add(done, feas, marg, ten, {"value": np.asarray(value, float)})
        if on_chunk is not None:
            on_chunk(ws.Chunk(done, _poses(design, P, nominal), feas, marg, ten, L,
                              collision_free=cfree, extra=extra_cols))
        done += cnt
        if progress is not None:
            progress(done, total)
    extra = {"orientation_mode": mode, "orientation_count": int(len(oset)),
             "orientations_evaluated": int(n_eval), "pulleys": bool(kin.has_pulleys(design)),
             "interference": bool(interference)}
    if interference:
        # total: over the whole set (collision free / statics feasible at every
        # orientation; a kind counts a pose it hits at any orientation); range: at the nominal
        extra.update(collision_free=n_free, feasible_statics=n_stat, collisions_by_kind=counts)
    if mode == "total":
        extra["orientation_set"] = {c: [float(oset[:, i].min()), float(oset[:, i].max())]
                                    for c, i in zip(rot_names, _rot_index(design))}
    else:
        extra["range_levels"] = len(level_sets)
        extra["range_max"] = {c: float(s) for c, s in zip(rot_names, scale)}
        extra["mean_range"] = {c: (float(range_sum / range_n * s) if range_n else None)
                               for c, s in zip(rot_names, scale)}
    res = maps.result(design, kind, g, nominal, t0, extra)
    res.orientation_maps = OrientationMaps(mode, maps.xmaps["value"], oset, scale)
    return res
