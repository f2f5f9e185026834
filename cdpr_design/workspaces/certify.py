"""Certified workspaces: branch-and-prune over a box of positions with interval tests.

Every box is classified by the rigorous interval tests of
:mod:`cdpr_design.kernels.certify`: ``inside`` (every position in it is
feasible, proven), ``outside`` (none is, proven) or undecided; an undecided
box is cut in two across its widest edge until that edge is at most
``resolution``, and then reported as ``boundary`` (Jaulin, Kieffer, Didrit &
Walter, "Applied Interval Analysis", Springer 2001, ch. 3; Gouttefarde, Daney
& Merlet, IEEE T-RO 27(1) 2011 for cable robots).  The inner measure (the
inside boxes) is a proven lower bound of the workspace's area or volume, the
outer measure (inside + boundary) a proven upper bound.

Positions are taken at the spec's fixed orientation for every motion type.
What the tests do not cover (sagging cables, swivel pulleys, a hanging
effector) is refused by the resolved robot's table
(:data:`cdpr_design.statics.robot.REFUSALS`).
"""

from __future__ import annotations

import contextlib
import itertools
import math
import time
from dataclasses import dataclass, field
from typing import Callable, ContextManager, Sequence

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.model.design import Design
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.robot import Analysis, Robot, resolve
from cdpr_design.statics.wrenches import wrench_vertices

#: status codes of the kernels and their names in the outputs
STATUS = {1: "inside", -1: "outside", 0: "boundary"}
#: kinds of workspace certified
KINDS = ("static", "wrench-feasible", "dynamic")
#: Largest number of boxes classified by default (bounded memory: a box is 6 floats and a code).
MAX_BOXES = 5_000_000

def check_certifiable(design: Design, kind: str = "static") -> Robot:
    """The robot certified: ``design`` resolved for ``certify`` and ``kind``; an
    :class:`InputError` with the reason when ``design`` or ``kind`` is not certified."""
    if kind not in KINDS:
        raise InputError(f"--kind: certify covers {', '.join(KINDS)}, got {kind!r}")
    return resolve(design, Analysis(command="certify", kind=kind))  # the refusals' one table


@dataclass
class CertifyResult:
    """The paving of a box of positions.

    ``lower``, ``upper`` (K, d) [m]: the boxes, over the motion's position axes
    ``axes``; ``status`` (K,) int8 (:data:`STATUS`).  ``box`` is the box certified,
    ``resolution`` [m] the finest edge; ``truncated`` names the limit that stopped the
    bisection early (``max_boxes`` or ``time_limit``; the boxes left are then ``boundary``).
    ``unsplit``: the boxes left ``boundary`` wider than ``resolution`` because their halves
    cannot be represented in floating point (a resolution below the spacing of the box's
    coordinates).
    """

    design: Design
    kind: str
    axes: tuple
    box: tuple
    resolution: float
    min_margin: float
    lower: np.ndarray
    upper: np.ndarray
    status: np.ndarray
    classified: int
    elapsed_s: float
    truncated: str | None = None
    tolerance: dict = field(default_factory=dict)
    unsplit: int = 0
    extra: dict = field(default_factory=dict)

    @property
    def unit(self) -> str:
        return "m^2" if len(self.axes) == 2 else "m^3"

    def measure(self, status: int) -> float:
        """The total area or volume [m^2 or m^3] of the boxes of one status code."""
        sel = self.status == status
        return float(np.prod(self.upper[sel] - self.lower[sel], axis=1).sum())

    def fraction(self, status: int) -> float:
        """The share (0 to 1) of the certified box covered by the boxes of one status code,
        measured over the axes along which the box has an extent: of its area for a box flat in
        one axis, and for a single point 1 for the point's own code (0 for the others)."""
        lo, hi = np.asarray(self.box[0], float), np.asarray(self.box[1], float)
        ext = hi > lo
        sel = self.status == status
        part = float(np.prod((self.upper[sel] - self.lower[sel])[:, ext], axis=1).sum())
        return part / float(np.prod((hi - lo)[ext]))

    def counts(self) -> dict:
        return {name: int(np.count_nonzero(self.status == code)) for code, name in STATUS.items()}

    def summary(self) -> dict:
        inner, boundary = self.measure(1), self.measure(0)
        total = float(np.prod(np.asarray(self.box[1]) - np.asarray(self.box[0])))
        out = {"design": self.design.name, "kind": self.kind, "axes": list(self.axes),
               "box": {"lower": list(self.box[0]), "upper": list(self.box[1])},
               "orientation": [float(v) for v in self.design.default_orientation_full()],
               "resolution": self.resolution, "min_margin": self.min_margin,
               "inner_measure": inner, "boundary_measure": boundary, "outer_measure": inner + boundary,
               "box_measure": total, "unit": self.unit, "counts": self.counts(),
               "boxes_classified": self.classified, "truncated": self.truncated,
               "inner_fraction": self.fraction(1), "boundary_fraction": self.fraction(0),
               "unsplit_boxes": self.unsplit, "elapsed_s": round(self.elapsed_s, 4)}
        if self.tolerance:
            out["tolerance"] = self.tolerance
        out.update(self.extra)
        return out

    def columns(self) -> dict:
        """``boxes.csv``: ``lower_<axis>``, ``upper_<axis>`` [m] per axis, then ``status``."""
        cols = {}
        for j, a in enumerate(self.axes):
            cols[f"lower_{a}"] = self.lower[:, j]
            cols[f"upper_{a}"] = self.upper[:, j]
        cols["status"] = np.array([STATUS[int(s)] for s in self.status], dtype=object)
        return cols


def spec_tolerances(design: Design) -> tuple:
    """(outlets, attachments) [m] of the spec's ``tolerance:`` (a number for every point, or
    ``outlets`` / ``attachments`` each a number or one per cable); None where not given."""
    tol = (design.raw or {}).get("tolerance")
    if tol is None:
        return None, None
    if isinstance(tol, (int, float)):
        return float(tol), float(tol)
    return tol.get("outlets"), tol.get("attachments")


def geometry_boxes(design: Design, tolerance_outlets=None, tolerance_attachments=None):
    """(Alo, Ahi, Blo, Bhi, A, Rb, Re, tb): the outlets and rotated attachments (m, 3) [m] as boxes
    of half-width the tolerances (scalars or (m,) [m], default 0) at the fixed orientation, and
    their nominal values; the rotated attachment j is R b_j + Re e with e in [-tb_j, tb_j]^3
    (effector coordinates), ``Re`` (3, 3) the rotation with the columns of the axes that carry no
    tolerance zeroed, ``tb`` (m,) [m].  Planar designs keep z = 0 (tolerances act in the plane)."""
    m, dim = design.m, design.motion.dim
    R = kin.rotation_matrix(*design.default_orientation_full())
    A = np.ascontiguousarray(design.outlets)
    Rb = np.ascontiguousarray(design.attachments @ R.T)
    ta = np.broadcast_to(np.asarray(0.0 if tolerance_outlets is None else tolerance_outlets, float), (m,))
    tb = np.broadcast_to(np.asarray(0.0 if tolerance_attachments is None else tolerance_attachments, float), (m,))
    mask = np.zeros(3)
    mask[:dim] = 1.0
    ra = ta[:, None] * mask  # outlet box half-widths
    # R (b + e), |e_k| <= tb: half-width sum_k |R_ik| tb (rounded up, with room for the rounding of
    # the sum), about R b
    rb = np.nextafter((np.abs(R) @ mask)[None, :] * tb[:, None] * (1.0 + 1e-12), np.inf) * mask
    if design.motion.planar:
        rb[:, 2] = 0.0
    Alo = np.where(ra > 0, np.nextafter(A - ra, -np.inf), A)
    Ahi = np.where(ra > 0, np.nextafter(A + ra, np.inf), A)
    Blo = np.where(rb > 0, np.nextafter(Rb - rb, -np.inf), Rb)
    Bhi = np.where(rb > 0, np.nextafter(Rb + rb, np.inf), Rb)
    Re = R * mask[None, :]
    if design.motion.planar:
        Re[2, :] = 0.0
    return (np.ascontiguousarray(Alo), np.ascontiguousarray(Ahi), np.ascontiguousarray(Blo),
            np.ascontiguousarray(Bhi), A, Rb, np.ascontiguousarray(Re), np.ascontiguousarray(tb, dtype=float))


class Classifier:
    """The interval test of boxes of positions for one certified robot (:func:`check_certifiable`:
    its design and kind), margin [N] and tolerances [m]."""

    def __init__(self, robot: Robot, min_margin: float = 0.0, tolerance_outlets=None, tolerance_attachments=None):
        from cdpr_design.kernels import certify as KC  # numba, on first use

        self.K = KC
        design = robot.design
        self.dim = design.motion.dim
        Alo, Ahi, Blo, Bhi, A, Rb, Re, tb = geometry_boxes(design, tolerance_outlets, tolerance_attachments)
        f64 = [np.ascontiguousarray(a, dtype=float) for a in (Alo, Ahi, Blo, Bhi, A, Rb)]
        self.geometry = KC.Geometry(*f64, np.ascontiguousarray(robot.rows, dtype=np.int64),
                                    np.ascontiguousarray(Re, dtype=float), np.ascontiguousarray(tb, dtype=float))
        wv = wrench_vertices(design, robot.kind, design.default_orientation_full())
        bases = np.array(list(itertools.combinations(range(design.m), design.n)),
                         dtype=np.int64).reshape(-1, design.n)
        self.task = KC.Task(np.ascontiguousarray(wv if robot.every_vertex else wv[:1], dtype=float),
                            np.ascontiguousarray(robot.tension_min, dtype=float),
                            np.ascontiguousarray(robot.tension_max, dtype=float), float(min_margin),
                            np.ascontiguousarray(robot.combos, dtype=np.int64), bases)

    def __call__(self, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
        """Status codes (K,) int8 of the boxes ``lower``, ``upper`` (K, d) [m]."""
        from cdpr_design.kernels.parallel import run_blocks

        k = lower.shape[0]
        lo = np.zeros((k, 3))
        hi = np.zeros((k, 3))
        lo[:, :self.dim] = lower
        hi[:, :self.dim] = upper
        status = np.zeros(k, dtype=np.int8)
        run_blocks(self.K.classify_block, k, lo, hi, self.geometry, self.task, status, grain=64)
        return status


def default_box(design: Design) -> tuple:
    """The workspace grid's box (lower, upper) [m]: what ``certify`` paves by default."""
    g = design.workspace.grid
    return tuple(float(v) for v in g.lower), tuple(float(v) for v in g.upper)


def check_box(box, dim: int, name: str = "box") -> tuple:
    """A box (lower, upper) of ``dim`` finite coordinates each with lower <= upper (InputError naming ``name``)."""
    lo, hi = (np.asarray(v, float).reshape(-1) for v in box)
    if lo.size != dim or hi.size != dim or not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise InputError(f"{name}: expected {dim} finite lower and upper coordinates")
    if np.any(hi < lo):
        raise InputError(f"{name}: every upper coordinate must be >= its lower one")
    return tuple(map(float, lo)), tuple(map(float, hi))


def certify(robot: Robot, resolution: float | None = None, box=None,
            min_margin: float | None = None, max_boxes: int | None = MAX_BOXES, time_limit: float | None = None,
            tolerance_outlets=None, tolerance_attachments=None,
            progress: Callable[[int, int], None] | None = None,
            classifier: Callable[..., ContextManager[Callable]] | None = None,
            replay: Sequence[np.ndarray] = (), on_level: Callable[[int, np.ndarray], None] | None = None
            ) -> CertifyResult:
    """Pave ``box`` (lower, upper) [m] (default the workspace grid's box) into proven
    ``inside``, proven ``outside`` and ``boundary`` boxes at the spec's fixed orientation.

    ``robot``: the design resolved for ``certify`` (:func:`check_certifiable`); its kind,
    ``static`` (gravity) or ``wrench-feasible`` (gravity plus every vertex of
    ``workspace.external_wrench``).  ``resolution`` [m]: the finest box edge (default the grid
    step).  ``min_margin`` [N]: prove a capacity margin of at least this much (inside) or
    less (outside) instead of feasibility.  ``max_boxes``, ``time_limit`` [s]: stop bisecting
    (the boxes left are ``boundary``; ``truncated`` says which).  ``tolerance_outlets``,
    ``tolerance_attachments`` [m] (scalars or per cable): geometric tolerances (default the
    spec's ``tolerance:``); ``inside`` then holds for every geometry within them.  ``progress(classified, pending)`` after each
    level of bisection.

    ``classifier(robot, min_margin, tolerance_outlets, tolerance_attachments)``: a context
    manager giving the box test used for the paving (default a :class:`Classifier` in this
    process; ``cdpr_design.batch.certify`` gives one spreading each level over worker processes
    or Dask).  ``replay``, ``on_level``: see :func:`pave` (a resumed run's journal).  The boxes do
    not depend on either.
    """
    if "interval-tests" not in robot.analysis.needs:
        raise ValueError(f"a robot resolved for {robot.analysis.command!r}, not for certify")
    design, kind = robot.design, robot.kind
    spec_outlets, spec_attachments = spec_tolerances(design)
    tolerance_outlets = spec_outlets if tolerance_outlets is None else tolerance_outlets
    tolerance_attachments = spec_attachments if tolerance_attachments is None else tolerance_attachments
    for name, v in (("outlets", tolerance_outlets), ("attachments", tolerance_attachments)):
        a = np.asarray(0.0 if v is None else v, float)
        if a.ndim > 1 or (a.ndim == 1 and a.size != design.m) or not np.all(np.isfinite(a) & (a >= 0)):
            raise InputError(f"tolerance.{name}: expected a non-negative number of metres or one per cable "
                             f"({design.m})")
    dim = design.motion.dim
    lo0, hi0 = check_box(default_box(design) if box is None else box, dim)
    res = float(min(design.workspace.grid.step) if resolution is None else resolution)
    if not (math.isfinite(res) and res > 0):
        raise InputError(f"--resolution: expected a positive number of metres, got {resolution}")
    mu = 0.0 if min_margin is None else float(min_margin)
    if not (math.isfinite(mu) and mu >= 0):
        raise InputError(f"--min-margin: expected a non-negative number of newtons, got {min_margin}")
    max_boxes = MAX_BOXES if max_boxes is None else max_boxes
    if max_boxes < 1:
        raise InputError(f"--max-boxes: expected a positive count, got {max_boxes}")
    if time_limit is not None and not (math.isfinite(time_limit) and time_limit > 0):
        raise InputError(f"--time-limit: expected a positive number of seconds, got {time_limit}")
    make = classifier or (lambda *args: contextlib.nullcontext(Classifier(*args)))
    t0 = time.perf_counter()
    with make(robot, mu, tolerance_outlets, tolerance_attachments) as classify:
        lower, upper, status, classified, truncated = pave(classify, np.array([lo0]), np.array([hi0]), res,
                                                          max_boxes, time_limit, progress, replay, on_level)
    tol = {k: v for k, v in (("outlets", tolerance_outlets), ("attachments", tolerance_attachments))
           if v is not None and np.any(np.asarray(v) > 0)}
    unsplit = int(np.count_nonzero((status == 0) & ((upper - lower).max(axis=1, initial=0.0) > res)
                                   & ~halvable(lower, upper))) if truncated is None else 0
    return CertifyResult(design, kind, design.motion.position_coords, (lo0, hi0), res, mu, lower, upper, status,
                         classified, time.perf_counter() - t0, truncated,
                         {k: np.asarray(v, float).tolist() for k, v in tol.items()}, unsplit)


def pave(classify: Callable, lower: np.ndarray, upper: np.ndarray, resolution: float, max_boxes: int = MAX_BOXES,
         time_limit: float | None = None, progress: Callable[[int, int], None] | None = None,
         replay: Sequence[np.ndarray] = (), on_level: Callable[[int, np.ndarray], None] | None = None):
    """Branch and prune from the boxes ``lower``, ``upper`` (K, d) [m], level by level.

    ``replay``: the status codes of the first levels, classified by an earlier run of the same
    paving (its journal): used instead of classifying those levels again.  ``on_level(level,
    status)`` after each level classified here (not replayed).

    ``classify(lower, upper)`` gives status codes; undecided boxes wider than ``resolution``
    are cut in two at the middle of their widest edge (the first such axis on ties), the
    others become ``boundary`` (0), and so do those whose halves cannot be represented in
    floating point (:func:`halvable`).  Returns (lower, upper, status, classified, truncated):
    the decided boxes in a fixed order (level by level, each level in its boxes' order), so the
    result does not depend on how the classifier splits its work.
    """
    t0 = time.perf_counter()
    out_lo, out_hi, out_st = [], [], []
    classified = 0
    truncated = None
    levels = iter(replay)
    level = 0
    while lower.shape[0]:
        if classified + lower.shape[0] > max_boxes:
            truncated = "max_boxes"
        elif time_limit is not None and time.perf_counter() - t0 > time_limit:
            truncated = "time_limit"
        if truncated:
            out_lo.append(lower)
            out_hi.append(upper)
            out_st.append(np.zeros(lower.shape[0], np.int8))
            break
        st = next(levels, None)
        if st is None:
            st = classify(lower, upper)
            if on_level is not None:
                on_level(level, st)
        elif st.shape != (lower.shape[0],):
            raise InputError(f"--resume: the journal's level {level} holds {st.size} boxes, the paving "
                             f"{lower.shape[0]} there: it is from another paving; run without --resume")
        level += 1
        classified += lower.shape[0]
        width = upper - lower
        axis = np.argmax(width, axis=1)
        widest = width[np.arange(width.shape[0]), axis]
        final = (st != 0) | (widest <= resolution) | ~halvable(lower, upper)
        out_lo.append(lower[final])
        out_hi.append(upper[final])
        out_st.append(st[final])
        split = ~final
        lower, upper = bisect(lower[split], upper[split], axis[split])
        if progress is not None:
            progress(classified, lower.shape[0])
    d = lower.shape[1]
    return (np.concatenate(out_lo) if out_lo else np.empty((0, d)),
            np.concatenate(out_hi) if out_hi else np.empty((0, d)),
            np.concatenate(out_st) if out_st else np.empty(0, np.int8), classified, truncated)


def halvable(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(K,) bool: whether each box (K, d) [m] can be cut in two across its widest edge (the first
    on ties) into halves narrower than itself, i.e. its middle lies strictly between the edge's
    ends in floating point (not so for an edge one or two units in the last place wide)."""
    axis = np.argmax(upper - lower, axis=1)
    rows = np.arange(lower.shape[0])
    lo, hi = lower[rows, axis], upper[rows, axis]
    mid = 0.5 * (lo + hi)
    return (lo < mid) & (mid < hi)


def bisect(lower: np.ndarray, upper: np.ndarray, axis: np.ndarray):
    """Each box (K, d) cut in two across ``axis`` (K,) at its middle: (2K, d) lower and upper,
    the two halves of a box next to each other (their union is the box exactly)."""
    k = lower.shape[0]
    rows = np.arange(k)
    mid = 0.5 * (lower[rows, axis] + upper[rows, axis])
    lo = np.repeat(lower, 2, axis=0)
    hi = np.repeat(upper, 2, axis=0)
    hi[2 * rows, axis] = mid
    lo[2 * rows + 1, axis] = mid
    return lo, hi


def warm_up(robot: Robot) -> None:
    """Classify one box of ``robot`` (resolved for ``certify``): numba loads the kernels from its
    on-disk cache (or compiles them on a machine's first run), so a caller can time that apart
    from the paving."""
    lo, hi = default_box(robot.design)
    Classifier(robot)(np.array([lo]), np.array([lo]))
