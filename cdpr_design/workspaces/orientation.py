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
from dataclasses import dataclass, field

import numpy as np

from cdpr_design.errors import SpecError
from cdpr_design.model.design import Design
from cdpr_design.statics.interference import HIT_NAMES
from cdpr_design.statics.robot import Robot
from cdpr_design.workspaces.grid import Rows
from cdpr_design.workspaces.cables import SagPoints, kind_counts
from cdpr_design.workspaces.hardware import Evaluator
from cdpr_design.workspaces.parts import Base

#: Default total-orientation set: nominal +- 10 deg about the last rotation coordinate, 5 samples.
DEFAULT_SET_HALF = math.radians(10.0)
DEFAULT_SET_COUNT = 5
#: Default orientation range: up to +- 30 deg on every rotation coordinate, 10 levels, 3 samples.
DEFAULT_RANGE_MAX = math.radians(30.0)
DEFAULT_RANGE_LEVELS = 10
DEFAULT_RANGE_COUNT = 3
#: Bytes a chunk of the total orientation workspace may hold in the statics of every orientation
#: of its set (the loads on the frame take them): its rows are limited to fit.
SET_BYTES = 64 << 20


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


class OrientationSweep(Base):
    """The base evaluator of the orientation workspaces (the analysis's ``orientations``:
    ``total`` or ``range``) about the nominal orientation ``nominal`` (3,) [rad].

    ``orientations`` (q, 3) [rad]: the ``total`` mode's set (default :func:`orientation_set`);
    every orientation is evaluated with pulleys and (the analysis's ``collisions``) interference;
    sagging cables (not under wrench closure, which takes the chords) with their catenaries at
    each orientation: the attachments rotated, the moments of the end forces in the balance, the
    interference along the curves (:class:`~cdpr_design.workspaces.cables.SagPoints`; the
    summary adds its cable-model keys, over every evaluated orientation).

    Table rows (the contract columns at the nominal pose):

    - ``total``: ``feasible`` = feasible for every orientation of the set,
      ``margin`` = least capacity margin over the set, ``tension_<c>`` =
      largest tension over the set (empty unless feasible, and where one
      orientation of the set has no tensions within the bounds: wrench closure); extra column
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

    ``total`` rows also carry the statics at every orientation of the set
    (:attr:`~cdpr_design.workspaces.grid.Rows.sets`: the loads on the frame take them), so that a
    chunk holds at most :attr:`max_rows` rows (:data:`SET_BYTES` of them).

    The result gets ``orientation_maps`` (an :class:`OrientationMaps`) and summary extras
    ``orientation_mode``, ``orientation_count`` and (range) ``mean_range``, ``range_levels``.
    (Orientation workspaces: Pott 2018, ch. 6; Gouttefarde, Merlet & Daney, ICRA 2007.)
    """

    maps = ("value",)
    pictures = ("orientation_workspace.png",)

    def __init__(self, robot: Robot, nominal: np.ndarray, orientations=None):
        design = self.design = robot.design
        self.robot, self.kind, self.nominal = robot, robot.kind, nominal
        self.mode = robot.analysis.orientations
        self.interference = robot.analysis.collisions
        self.ev = SagPoints(robot) if robot.cables.sags(robot.kind) else Evaluator(robot)
        self.rot_names = design.motion.rotation_coords
        if self.mode == "total":
            self.oset = orientation_set(design) if orientations is None else np.atleast_2d(
                np.asarray(orientations, float))
            self.level_sets, self.scale = None, np.zeros(len(self.rot_names))
            columns = 4 if isinstance(self.ev, SagPoints) else 1  # a cable's kept columns an orientation
            self.max_rows = max(1024, SET_BYTES // (8 * len(self.oset) * robot.m * columns))
        else:
            self.scale, _, _, self.level_sets = range_levels(design)
            self.oset = self.level_sets[-1]
        self.tally = _Tally(self.interference)
        cols = ["collision_free"] if self.interference else []
        cols += ["orientations_feasible"] if self.mode == "total" else [f"range_{c}" for c in self.rot_names]
        self.columns = tuple(cols)

    def rows(self, start: int, count: int, P: np.ndarray | None) -> Rows:
        if self.mode == "total":
            r = _total_rows(self.ev, P, self.nominal, self.oset, self.tally)
        else:
            r = _range_rows(self.ev, P, self.nominal, self.level_sets, self.scale, self.rot_names, self.tally)
        feas, marg, ten, L, cfree, value, extra, state = r
        if cfree is not None:
            extra = {"collision_free": cfree, **extra}
        if self.mode == "total":
            return Rows(feas, marg, ten, L, extra, {"value": np.asarray(value, float)}, sets=state)
        return Rows(feas, marg, ten, L, extra, {"value": np.asarray(value, float)}, nominal=state)

    def summary(self, maps) -> dict:
        extra = _summary_extra(self.design, self.mode, self.oset, self.level_sets, self.scale, self.tally,
                               self.interference, self.robot.outlets.pulleys)
        if isinstance(self.ev, SagPoints):
            extra.update(self.ev.summary())
        return extra

    def finish(self, result, maps) -> None:
        result.orientation_maps = OrientationMaps(self.mode, maps.xmaps["value"], self.oset, self.scale)


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


def _total_rows(ev, P, nominal, oset, tally: _Tally):
    """One chunk of the total orientation workspace: feasible at every orientation of ``oset``; its
    last item the statics at each (:attr:`~cdpr_design.workspaces.grid.Rows.sets`)."""
    cnt, m = P.shape[0], ev.design.m
    L = None  # the chords' lengths at the nominal orientation
    allok = np.ones(cnt, dtype=bool)
    nok = np.zeros(cnt, dtype=np.int64)
    cfree_all = np.ones(cnt, dtype=bool)
    stat_all = np.ones(cnt, dtype=bool)
    hits = np.zeros(cnt, dtype=np.uint8)
    marg = np.full(cnt, np.inf)
    ten = np.full((cnt, m), -np.inf)
    sets = []
    for o in oset:
        f, mg, t, lengths, mask = ev(P, o)
        sets.append((o, *ev.nominal()) if isinstance(ev, SagPoints) else (o, t, {}))
        if np.array_equal(o, nominal):
            L = lengths
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
        ten = np.maximum(ten, t)  # an orientation without tensions (wrench closure) leaves none to report
    if L is None:
        L = ev(P, nominal)[3]
    marg[~np.isfinite(marg)] = np.nan
    ten[~allok] = np.nan
    cfree = None
    if tally.interference:
        cfree = cfree_all.astype(np.uint8)
        tally.free += int(np.count_nonzero(cfree_all))
        tally.statics += int(np.count_nonzero(stat_all))
        kind_counts(hits, tally.by_kind)
    return allok.astype(np.uint8), marg, ten, L, cfree, nok / len(oset), {"orientations_feasible": nok}, sets


def _range_rows(ev, P, nominal, level_sets, scale, rot_names, tally: _Tally):
    """One chunk of the orientation range: the largest level whose samples are all feasible."""
    cnt = P.shape[0]
    feas, marg, ten, L, mask = ev(P, nominal)
    state = ev.nominal() if isinstance(ev, SagPoints) else None
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
    return feas, marg, ten, L, cfree, best, extra_cols, state


def _summary_extra(design, mode, oset, level_sets, scale, tally: _Tally, interference: bool, pulleys: bool) -> dict:
    """The summary extras of an orientation sweep (``orientation_mode``, counts, set or range)."""
    rot_names = design.motion.rotation_coords
    extra = {"orientation_mode": mode, "orientation_count": int(len(oset)),
             "orientations_evaluated": int(tally.evaluated), "pulleys": pulleys,
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
