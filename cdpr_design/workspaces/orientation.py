"""Orientation workspaces of the rotational motions (``1R2T``, ``3R3T``).

``total``: the *total orientation workspace* - positions feasible for every
orientation of a sampled box (``workspace.orientation_set``); by construction
the intersection of the fixed-orientation workspaces of the samples (Pott
2018, ch. 6; Gouttefarde, Merlet & Daney, "Wrench-feasible workspace of
parallel cable-driven mechanisms", ICRA 2007).

``range``: the *orientation range* per position - the largest box
nominal +- s * max (s = k / levels, k = 0..levels) whose samples, and those of
every smaller level, are all feasible (``workspace.orientation_range``).
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field

import numpy as np

from cdpr_design.errors import SpecError
from cdpr_design.model.design import Design
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.interference import HIT_NAMES
from cdpr_design.workspaces.grid import CHUNK, Chunk, Maps, chunk_poses, positions3
from cdpr_design.workspaces.hardware import Evaluator, chunk_stats, kind_counts

#: Default total-orientation set: nominal +- 10 deg about the last rotation coordinate, 5 samples.
DEFAULT_SET_HALF = math.radians(10.0)
DEFAULT_SET_COUNT = 5
#: Default orientation range: up to +- 30 deg on every rotation coordinate, 10 levels, 3 samples.
DEFAULT_RANGE_MAX = math.radians(30.0)
DEFAULT_RANGE_LEVELS = 10
DEFAULT_RANGE_COUNT = 3


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


def sweep_orientations(design: Design, mode: str, kind: str, g, nominal, *, orientations=None,
                       on_chunk=None, progress=None, chunk: int = CHUNK, keep_maps: bool = True,
                       interference: bool = False):
    """Total orientation workspace (``mode='total'``) or orientation range per position (``'range'``).

    Parameters
    ----------
    mode : {'total', 'range'}
    orientations : (q, 3) array, optional
        ``total``: the orientation set (rx, ry, rz) [rad]; default
        :func:`orientation_set`.
    nominal : (3,) nominal orientation [rad]:
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

    Returns a :class:`~cdpr_design.workspaces.grid.WorkspaceResult` whose maps are
    those of the swept workspace, with ``orientation_maps`` (an
    :class:`OrientationMaps`) set and summary extras ``orientation_mode``,
    ``orientation_count`` and (range) ``mean_range``, ``range_levels``.
    """

    if mode not in ("total", "range"):
        raise SpecError([("--orientations", f"expected total or range, got {mode!r}")])
    t0 = time.perf_counter()
    ev = Evaluator(design, kind, interference)
    rot_names = design.motion.rotation_coords
    if mode == "total":
        oset = orientation_set(design) if orientations is None else np.atleast_2d(np.asarray(orientations, float))
        level_sets, scale = None, np.zeros(len(rot_names))
    else:
        scale, _, _, level_sets = range_levels(design)
        oset = level_sets[-1]
    tally = _Tally(interference)
    total = g.size
    chunk = max(1, min(chunk, total))
    maps = Maps(g, design.m, keep_maps, extra_maps=("value",))
    done = 0
    while done < total:
        cnt = min(chunk, total - done)
        P = positions3(g, done, cnt)
        if mode == "total":
            rows = _total_rows(ev, P, nominal, oset, tally, lengths=on_chunk is not None)
        else:
            rows = _range_rows(ev, P, nominal, level_sets, scale, rot_names, tally)
        feas, marg, ten, L, cfree, value, extra_cols = rows
        maps.add(done, chunk_stats(feas, marg, ten, maps.tpeak), feas, marg, ten,
                 {"value": np.asarray(value, float)})
        if on_chunk is not None:
            on_chunk(Chunk(done, chunk_poses(design, P, nominal), feas, marg, ten, L,
                           collision_free=cfree, extra=extra_cols))
        done += cnt
        if progress is not None:
            progress(done, total)
    extra = _summary_extra(design, mode, oset, level_sets, scale, tally, interference)
    res = maps.result(design, kind, nominal, t0, extra)
    res.orientation_maps = OrientationMaps(mode, maps.xmaps["value"], oset, scale)
    return res


@dataclass
class _Tally:
    """Counts over a whole orientation sweep (interference and evaluated orientations)."""

    interference: bool
    evaluated: int = 0
    free: int = 0
    statics: int = 0
    range_sum: float = 0.0
    range_n: int = 0
    by_kind: dict = field(default_factory=lambda: {name: 0 for name in HIT_NAMES.values()})


def _total_rows(ev: Evaluator, P, nominal, oset, tally: _Tally, lengths: bool):
    """One chunk of the total orientation workspace: feasible at every orientation of ``oset``."""
    cnt, m = P.shape[0], ev.design.m
    L = ev(P, nominal)[3] if lengths else None
    allok = np.ones(cnt, dtype=bool)
    nok = np.zeros(cnt, dtype=np.int64)
    cfree_all = np.ones(cnt, dtype=bool)
    stat_all = np.ones(cnt, dtype=bool)
    hits = np.zeros(cnt, dtype=np.uint8)
    marg = np.full(cnt, np.inf)
    ten = np.full((cnt, m), -np.inf)
    for o in oset:
        f, mg, t, _, mask = ev(P, o)
        tally.evaluated += cnt
        ok = f.astype(bool)
        if tally.interference:
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
    cfree = None
    if tally.interference:
        cfree = cfree_all.astype(np.uint8)
        tally.free += int(np.count_nonzero(cfree_all))
        tally.statics += int(np.count_nonzero(stat_all))
        kind_counts(hits, tally.by_kind)
    return allok.astype(np.uint8), marg, ten, L, cfree, nok / len(oset), {"orientations_feasible": nok}


def _range_rows(ev: Evaluator, P, nominal, level_sets, scale, rot_names, tally: _Tally):
    """One chunk of the orientation range: the largest level whose samples are all feasible."""
    cnt = P.shape[0]
    feas, marg, ten, L, mask = ev(P, nominal)
    tally.evaluated += cnt
    cfree = None
    if tally.interference:
        cfree = (mask == 0).astype(np.uint8)
        kind_counts(mask, tally.by_kind)
        tally.free += int(np.count_nonzero(cfree))
        tally.statics += int(np.count_nonzero(feas))
        feas &= cfree
        ten[cfree == 0] = np.nan
    best = np.zeros(cnt)
    alive = np.flatnonzero(feas)
    for k, lev in enumerate(level_sets, start=1):
        for o in lev:
            if alive.size == 0:
                break
            f, _, _, _, mask = ev(P[alive], o)
            tally.evaluated += alive.size
            ok = f.astype(bool)
            if tally.interference:
                ok &= mask == 0
            alive = alive[ok]
        if alive.size == 0:
            break
        best[alive] = k / len(level_sets)
    best[feas == 0] = np.nan
    extra_cols = {f"range_{c}": best * scale[j] for j, c in enumerate(rot_names)}
    fin = np.isfinite(best)
    tally.range_sum += float(best[fin].sum())
    tally.range_n += int(fin.sum())
    return feas, marg, ten, L, cfree, best, extra_cols


def _summary_extra(design, mode, oset, level_sets, scale, tally: _Tally, interference: bool) -> dict:
    """The summary extras of an orientation sweep (``orientation_mode``, counts, set or range)."""
    rot_names = design.motion.rotation_coords
    extra = {"orientation_mode": mode, "orientation_count": int(len(oset)),
             "orientations_evaluated": int(tally.evaluated), "pulleys": bool(kin.has_pulleys(design)),
             "interference": bool(interference)}
    if interference:
        # total: over the whole set (collision free / statics feasible at every
        # orientation; a kind counts a pose it hits at any orientation); range: at the nominal
        extra.update(collision_free=tally.free, feasible_statics=tally.statics,
                     collisions_by_kind=tally.by_kind)
    if mode == "total":
        extra["orientation_set"] = {c: [float(oset[:, i].min()), float(oset[:, i].max())]
                                    for c, i in zip(rot_names, _rot_index(design))}
    else:
        extra["range_levels"] = len(level_sets)
        extra["range_max"] = {c: float(s) for c, s in zip(rot_names, scale)}
        extra["mean_range"] = {c: (float(tally.range_sum / tally.range_n * s) if tally.range_n else None)
                               for c, s in zip(rot_names, scale)}
    return extra
