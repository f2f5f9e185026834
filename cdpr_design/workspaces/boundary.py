"""The workspace's boundary between the grid points: loops (planar) or a closed surface (spatial).

A sweep gives feasibility at the grid points only; the boundary of the feasible set lies
between them.  :class:`BoundaryField` is a part of the sweep plan
(:mod:`cdpr_design.workspaces.plan`) that keeps, while the chunks stream past, one float32 per
grid pose: the capacity margin [N] with its sign set by the pose's feasibility (4 bytes a pose;
the rows themselves are not kept).  After the sweep:

1. the field, scaled into [0.1, 1] in magnitude and padded with one layer of infeasible
   values outside the grid's box, is contoured at 0 by marching squares
   (:func:`skimage.measure.find_contours`) or marching cubes (Lewiner's variant,
   :func:`skimage.measure.marching_cubes`): every vertex lies on one grid edge whose two ends
   differ in feasibility, and the topology between them is decided by the margins;
2. each vertex is moved along its edge to the feasible set's boundary with the sweep's own
   feasibility test at positions on it (:func:`crossings`: regula falsi on the capacity margin
   where it has one, then a Newton step on the margin's local slope, bisection otherwise; within
   step / 2^BISECTIONS of a change of feasibility); a vertex on an edge leaving the box is put on the box's face,
   so the boundary is clipped by the grid's box and encloses a closed region or solid;
3. the measure is the region's area (the loops' shoelace sums; a hole's loop runs the other
   way) or the solid's volume (the divergence theorem over the triangles), the surface its
   perimeter or surface area (the parts on the box's faces included).

Spatial meshes are welded (the vertices put on a box edge or corner coincide), their
degenerate triangles dropped, and checked: every edge shared by exactly two triangles that run
along it in opposite directions (closed and consistently wound), the normals outwards; anything
else is a bug, raised.
(Marching squares and cubes: Lorensen & Cline, SIGGRAPH 1987; Lewiner, Lopes, Vieira & Tavares,
J. Graphics Tools 8(2), 2003.)
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from cdpr_design.model.design import Grid
from cdpr_design.workspaces.grid import Maps, Rows, WorkspaceResult
from cdpr_design.workspaces.parts import Wrapper

#: A vertex is within step / 2**BISECTIONS of where feasibility changes along its grid edge.
BISECTIONS = 10
#: Smallest scaled field magnitude: a vertex's first estimate is never at a grid point.
FLOOR = 0.1
#: A run of feasible (or infeasible) poses between two crossings shorter than this many grid steps
#: is not resolved; more than THIN_SHARE of the crossings bounding such runs: a warning.
MIN_STEPS = 3
THIN_SHARE = 0.1
#: Values of the field contoured at once (a slab of planes of the grid's first axis).
SLAB_VALUES = 1 << 20
#: Positions per call of the feasibility test during the refinement.
BATCH = 1 << 13

_log = logging.getLogger(__name__)


@dataclass
class Boundary:
    """The feasible set's boundary inside the grid's box.

    ``dim`` 2 or 3; ``measure`` [m^2 or m^3] the enclosed area or volume; ``surface`` [m or m^2]
    the perimeter or surface area of the closed region (its parts on the box's faces included).
    Planar: ``loops`` a list of (k, 2) arrays [m], each closed loop in order (the last vertex
    joins the first), outer loops counter-clockwise and holes clockwise.  Spatial: ``vertices``
    (V, 3) [m] and ``faces`` (F, 3) int64 of a closed, consistently wound triangle mesh with
    outward normals (empty without a feasible pose).  ``warning``: why the grid may be too
    coarse to resolve the boundary, or None.
    """

    dim: int
    measure: float = 0.0
    surface: float = 0.0
    loops: list = field(default_factory=list)
    vertices: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    faces: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), dtype=np.int64))
    warning: str | None = None
    #: the time it took after the sweep [s] (contouring and refinement)
    elapsed_s: float = 0.0

    def summary(self) -> dict:
        """``boundary_measure``, ``boundary_surface`` and, when the grid is too coarse,
        ``boundary_warning`` (summary.json keys)."""
        out = {"boundary_measure": float(self.measure), "boundary_surface": float(self.surface)}
        if self.warning:
            out["boundary_warning"] = self.warning
        return out

    def loop_table(self) -> dict:
        """``boundary.csv``'s columns: ``x``, ``y`` [m] and ``loop`` (0, 1, ...) of every vertex."""
        if not self.loops:
            return {"x": np.zeros(0), "y": np.zeros(0), "loop": np.zeros(0, dtype=np.int64)}
        xy = np.concatenate(self.loops)
        ids = np.concatenate([np.full(len(lp), i, dtype=np.int64) for i, lp in enumerate(self.loops)])
        return {"x": xy[:, 0], "y": xy[:, 1], "loop": ids}


class BoundaryField(Wrapper):
    """The sweep plan's part that finds the :class:`Boundary` (see the module doc) from the rows'
    feasibility and margins as the chunks stream past; adds no column.

    ``grid`` the sweep's grid; ``evaluator`` makes, on first use, the feasibility test at
    positions: a callable (k, 3) [m] -> (k,) bool; ``scale`` [N] the margin that maps to the
    middle of the contoured field's magnitudes (the robot's mean finite tension bound).  Summary
    keys ``boundary_measure``, ``boundary_surface`` (and ``boundary_warning``); the result's
    ``boundary``.
    """

    positions = False

    def __init__(self, robot, grid: Grid, evaluator: Callable[[], Callable[[np.ndarray], np.ndarray]]):
        super().__init__(robot)
        tmax = np.asarray(robot.tension_max, float)
        finite = tmax[np.isfinite(tmax) & (tmax > 0)]
        self.slabs = Slabs(grid, float(finite.mean()) if finite.size else 1.0)
        self.evaluator = evaluator
        self.boundary: Boundary | None = None

    def add(self, r: Rows, start: int, P: np.ndarray | None) -> None:
        self.slabs.add(start, r.feasible, r.margin)

    def summary(self, maps: Maps) -> dict:
        t0 = time.perf_counter()
        self.boundary = self.slabs.boundary(self.evaluator)
        self.boundary.elapsed_s = self.slabs.busy_s + time.perf_counter() - t0
        return self.boundary.summary()

    def finish(self, result: WorkspaceResult, maps: Maps) -> None:
        result.boundary = self.boundary


def signed_margin(feasible: np.ndarray, margin: np.ndarray) -> np.ndarray:
    """float32 (k,): |margin| [N] positive where ``feasible``, negative elsewhere; a pose
    without a finite margin (or a zero one) keeps its sign with the magnitude 1e-30."""
    mag = _magnitude(margin)
    return np.where(np.asarray(feasible).astype(bool), mag, -mag)


def _magnitude(margin: np.ndarray) -> np.ndarray:
    """float32 |margin| [N], 1e-30 where it is not finite or smaller."""
    mag = np.abs(np.asarray(margin, dtype=np.float32))
    return np.where(np.isfinite(mag) & (mag > 1e-30), mag, np.float32(1e-30))


class Slabs:
    """The contouring of a streamed field, one slab of consecutive planes of the grid's first axis
    at a time: what it holds is the planes of one slab as float32 (at least two, about
    :data:`SLAB_VALUES` values: 4 MB), the boundary's vertices and faces found so far, and per grid
    line of the first axis the last crossing (the coarse-grid warning).  Rows arrive in grid order
    (C order, first axis slowest), each once, whole planes taken together.

    Vertices are named by their grid edge (its lower end's index in the padded grid, times the
    dimension, plus the edge's axis), so that the pieces of two slabs sharing a plane weld
    exactly; the positions are found for each named edge once, after the sweep.
    """

    def __init__(self, grid: Grid, scale: float):
        self.grid, self.scale = grid, scale
        self.dim = len(grid.shape)
        self.shape = tuple(int(n) for n in grid.shape)
        self.plane_size = int(np.prod(self.shape[1:], dtype=np.int64))
        self.pshape = tuple(n + 2 for n in self.shape)  # the padded grid
        self.prev = self._pad_plane(None)  # the pad plane before the first one
        self.held: list = []  # planes received since the last slab was contoured
        self.cur = np.empty(self.plane_size, dtype=np.float32)
        self.filled = 0  # values of plane `self.plane` received
        self.plane = 0
        self.any_feasible = False
        self.keys, self.lower, self.axis, self.lo_in, self.pieces = [], [], [], [], []
        #: per vertex: the margins [N] at its edge's feasible end, at its other end (<= 0), and signed
        #: one step before the feasible end and one beyond the other (NaN where unknown)
        self.ends_margin: list = []
        self.thin = self.ends = 0
        self.last_cross = np.full(self.plane_size, -(1 << 40), dtype=np.int64)
        self.busy_s = 0.0

    def _pad_plane(self, values) -> np.ndarray:
        """A plane of the padded grid (the other axes padded with one infeasible layer)."""
        out = np.full(self.pshape[1:], -1.0, dtype=np.float32)
        if values is not None:
            out[(slice(1, -1),) * (self.dim - 1)] = values.reshape(self.shape[1:])
        return out

    def add(self, start: int, feasible, margin) -> None:
        """Rows ``start ..`` (feasible flags and margins [N]) in grid order."""
        t0 = time.perf_counter()
        if start != self.plane * self.plane_size + self.filled:
            raise ValueError(f"rows from {start}: the boundary takes the grid's rows in order, each once")
        v = _scaled(feasible, margin, self.scale)
        self.any_feasible |= bool((v > 0).any())
        k = 0
        if self.filled:  # the rest of a plane begun by the last rows
            take = min(len(v), self.plane_size - self.filled)
            self.cur[self.filled:self.filled + take] = v[:take]
            self.filled += take
            k = take
            if self.filled == self.plane_size:
                self._planes(self.cur[None])
        while len(v) - k >= self.plane_size:  # whole planes, as many at once as the slab takes
            room = max(1, -(-SLAB_VALUES // self.prev.size) - len(self.held))
            n = min((len(v) - k) // self.plane_size, room)
            self._planes(v[k:k + n * self.plane_size].reshape(n, self.plane_size))
            k += n * self.plane_size
        if k < len(v):  # the beginning of the next plane
            self.filled = len(v) - k
            self.cur[:self.filled] = v[k:]
        self.busy_s += time.perf_counter() - t0

    def _planes(self, values: np.ndarray) -> None:
        """The next planes of the grid, their values (p, plane size) (at most the slab's room)."""
        p = values.shape[0]
        block = np.full((p,) + self.pshape[1:], -1.0, dtype=np.float32)
        block[(slice(None),) + (slice(1, -1),) * (self.dim - 1)] = values.reshape((p,) + self.shape[1:])
        self._count_runs(block)
        self.held.extend(block)
        self.plane += p
        self.filled = 0
        if len(self.held) * self.prev.size >= SLAB_VALUES:
            self._flush()

    def _flush(self) -> None:
        """Contour the planes held (after the last one contoured) and keep only the last."""
        if self.held:
            self._slab(np.stack([self.prev] + self.held), self.plane - len(self.held))
            self.prev, self.held = self.held[-1], []

    def _count_runs(self, block: np.ndarray) -> None:
        """The coarse-grid tally (:func:`coarse_warning`'s rule) of the next padded planes ``block``
        (p, ...): runs within each and along the first axis up to each, in order."""
        inner = block[(slice(None),) + (slice(1, -1),) * (self.dim - 1)] > 0
        p = inner.shape[0]
        lines = inner.reshape(p, -1)
        last = self.held[-1] if self.held else self.prev
        before = (last[(slice(1, -1),) * (self.dim - 1)] > 0).reshape(1, -1)
        change = np.concatenate([before, lines])
        change = change[1:] != change[:-1]  # (p, lines): plane self.plane + j differs from the one before
        if self.plane == 0:
            change[0] = False  # the first plane has none before it
        col, j = np.nonzero(change.T)  # by grid line, then plane
        if len(col):
            at = self.plane + j
            new_line = np.ones(len(col), dtype=bool)
            new_line[1:] = col[1:] != col[:-1]
            before_at = np.where(new_line, self.last_cross[col], np.roll(at, 1))
            self.ends += len(col)
            self.thin += int(np.count_nonzero(at - before_at < MIN_STEPS))
            last = np.ones(len(col), dtype=bool)
            last[:-1] = new_line[1:]
            self.last_cross[col[last]] = at[last]  # each line's last crossing
        for ax in range(1, inner.ndim):
            if inner.shape[ax] < 2:
                continue
            f = np.moveaxis(inner, ax, -1).reshape(-1, inner.shape[ax])
            rows, cols = np.nonzero(f[:, 1:] != f[:, :-1])
            self.ends += len(rows)
            self.thin += int(np.count_nonzero((rows[1:] == rows[:-1]) & (np.diff(cols) < MIN_STEPS)))

    def _slab(self, f: np.ndarray, i: int) -> None:
        """Contour the slab ``f`` of padded planes i, i + 1, ... (grid planes i - 1, i, ...)."""
        from skimage import measure

        if not (f > 0).any():
            return
        if self.dim == 2:
            pieces = [c for c in measure.find_contours(f, 0.0) if len(c) > 1]
            if not pieces:
                return
            verts = np.concatenate(pieces)
            sizes = np.array([len(c) for c in pieces])
            first = np.concatenate([[0], np.cumsum(sizes)[:-1]])
            seg = np.arange(len(verts) - 1)
            seg = seg[~np.isin(seg, first + sizes - 1)]  # consecutive points of one piece
            faces = np.stack([seg, seg + 1], axis=1)
        else:
            # "ascent": the field rises into the feasible set, so the triangles come wound with their
            # normals outwards (the measure is formed once, :func:`_weld`)
            verts, faces, _, _ = measure.marching_cubes(f, 0.0, method="lewiner", allow_degenerate=True,
                                                        gradient_direction="ascent")
        lower, axis = _edge_ends(verts.astype(float))
        upper = lower.copy()
        upper[np.arange(len(lower)), axis] += 1
        f_lo, f_hi = f[tuple(lower.T)], f[tuple(upper.T)]
        lo_in = f_lo > 0
        e = np.eye(self.dim, dtype=np.int64)[axis]
        f_before, f_after = _field_at(f, lower - e), _field_at(f, upper + e)
        self.ends_margin.append(np.stack([_unscaled(np.where(lo_in, f_lo, f_hi), self.scale),
                                          -_unscaled(np.where(lo_in, f_hi, f_lo), self.scale),
                                          _signed(np.where(lo_in, f_before, f_after), self.scale),
                                          _signed(np.where(lo_in, f_after, f_before), self.scale)], axis=1))
        lower[:, 0] += i  # padded plane index of the slab's first plane
        key = np.ravel_multi_index(tuple(lower.T), self.pshape).astype(np.int64) * self.dim + axis
        self.pieces.append(faces + sum(len(k) for k in self.keys))  # into the vertices of every slab so far
        self.keys.append(key)
        self.lower.append(lower)
        self.axis.append(axis)
        self.lo_in.append(lo_in)

    def boundary(self, evaluator) -> Boundary:
        """The :class:`Boundary`, once every row has arrived; ``evaluator()`` gives the feasibility
        test at positions (k, 3) [m] (called only when a grid edge inside the box crosses)."""
        t0 = time.perf_counter()
        if self.plane == self.shape[0]:  # the pad plane after the last one
            self.held.append(self._pad_plane(None))
            self.plane += 1
            self._flush()
        self.busy_s += time.perf_counter() - t0
        dim = self.dim
        if not self.any_feasible:
            return Boundary(dim)
        if min(self.shape) < 2:  # a flat grid encloses no area or volume
            warning = (f"the grid has one pose along an axis ({' x '.join(map(str, self.shape))}): it encloses no "
                       f"{'area' if dim == 2 else 'volume'}, boundary_measure is 0 (a smaller --step resolves it)")
            _log.warning(warning)
            return Boundary(dim, warning=warning)
        warning = None
        if self.ends and self.thin > THIN_SHARE * self.ends:
            warning = (f"the grid (step {min(self.grid.step):g} m) may be too coarse to resolve the workspace's "
                       f"boundary: {self.thin} runs of poses between two crossings are shorter than {MIN_STEPS} "
                       f"steps; boundary_measure is uncertain there (a smaller --step resolves it)")
            _log.warning(warning)
        keys, first, inverse = np.unique(np.concatenate(self.keys), return_index=True, return_inverse=True)
        lower = np.concatenate(self.lower)[first]
        axis = np.concatenate(self.axis)[first]
        lo_in = np.concatenate(self.lo_in)[first]
        ends = np.concatenate(self.ends_margin)[first]
        pts, snapped = _positions(lower, axis, lo_in, ends, self.grid, evaluator)
        faces = inverse.reshape(-1)[np.concatenate(self.pieces)]
        if dim == 2:
            loops = _loops(faces, pts, snapped, lower, axis, lo_in, self.grid)
            area = sum(_shoelace(lp) for lp in loops)
            perimeter = sum(float(np.linalg.norm(np.diff(np.vstack([lp, lp[:1]]), axis=0), axis=1).sum())
                            for lp in loops)
            return Boundary(2, float(area), perimeter, loops=loops, warning=warning)
        verts, faces, volume, area = _weld(pts, snapped, faces)
        return Boundary(3, volume, area, vertices=verts, faces=faces, warning=warning)


def _scaled(feasible: np.ndarray, margin: np.ndarray, scale: float) -> np.ndarray:
    """The contoured field (float32) of the poses' feasibility and margins [N] (their
    :func:`signed_margin`): the same signs, the magnitudes mapped monotonically into [FLOOR, 1)
    (|m| = ``scale`` to the middle), one map for every slab so that two slabs decide a shared face
    alike."""
    mag = _magnitude(margin)
    v = FLOOR + (1.0 - FLOOR) * mag / (mag + np.float32(scale))
    return np.where(np.asarray(feasible).astype(bool), v, -v)


def _unscaled(v: np.ndarray, scale: float) -> np.ndarray:
    """|margin| [N] back from :func:`_scaled` values (NaN where it was none: the floor)."""
    x = (np.abs(v).astype(float) - FLOOR) / (1.0 - FLOOR)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = scale * x / (1.0 - x)
    return np.where(x > 1e-6, out, np.nan)


def _field_at(f: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """The values of the slab ``f`` at the integer indices ``idx`` (V, d), NaN where one is outside it."""
    inside = np.all((idx >= 0) & (idx < np.asarray(f.shape)), axis=1)
    out = np.full(len(idx), np.nan, dtype=np.float32)
    out[inside] = f[tuple(idx[inside].T)]
    return out


def _signed(v: np.ndarray, scale: float) -> np.ndarray:
    """The signed margins [N] of contoured values ``v`` (NaN: a pad value outside the grid, a pose
    without a margin, or unknown)."""
    with np.errstate(invalid="ignore"):
        known = np.abs(v) < 1.0  # the field's magnitudes are below 1; the pad's is 1
    return np.where(known, np.sign(v) * _unscaled(v, scale), np.nan)


def _edge_ends(idx: np.ndarray):
    """For vertices ``idx`` (V, d) in padded index coordinates, each on one grid edge: the
    integer index of the edge's lower end (V, d) and the edge's axis (V,)."""
    base = np.floor(idx)
    frac = idx - base
    axis = np.argmax(frac, axis=1)
    return base.astype(np.int64), axis


def _positions(lower, axis, lo_in, ends, grid: Grid, evaluator):
    """Positions [m] (V, d) of the vertices on the padded grid edges (``lower`` end, ``axis``,
    ``lo_in``: the lower end feasible; ``ends`` (V, 2) the margins [N] at the feasible and the
    other end) moved onto the boundary, and whether each was put on the box's face (its edge
    leaves the box)."""
    lower_m, step = np.asarray(grid.lower, float), np.asarray(grid.step, float)
    upper = lower.copy()
    upper[np.arange(len(lower)), axis] += 1
    inside_end = np.where(lo_in[:, None], lower, upper) - 1  # grid indices of the feasible end
    outside_end = np.where(lo_in[:, None], upper, lower) - 1
    shape = np.asarray(grid.shape)
    leaves = np.any((outside_end < 0) | (outside_end >= shape), axis=1)
    a = lower_m + inside_end * step
    b = lower_m + outside_end * step
    out = a.copy()
    todo = np.flatnonzero(~leaves)
    if todo.size:
        t = crossings(a[todo], b[todo], ends[todo, 0], ends[todo, 1], evaluator(), ends[todo, 2], ends[todo, 3])
        out[todo] = a[todo] + t[:, None] * (b[todo] - a[todo])
    return out, leaves


def first_guess(m_a, m_b, m_before=None, m_after=None) -> np.ndarray:
    """The first estimate (V,) of where the margin vanishes on edges from t = 0 to 1, from its
    values at t = 0 (``m_a`` > 0) and 1 (``m_b`` < 0) and, where known (not NaN), at t = -1
    (``m_before``) and t = 2 (``m_after``, one grid step on either side): the root in (0, 1) of the
    polynomial through every known value (a cubic through four), by Newton's method from the
    secant's root, which is the estimate where that fails or leaves (0, 1)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        secant = m_a / (m_a - m_b)
    if m_before is None:
        return secant
    xs = np.array([-1.0, 0.0, 1.0, 2.0])
    ys = [m_before, m_a, m_b, m_after]
    use = [np.isfinite(y) for y in ys]
    # the weights 1 / (x_i - x_j) of the known points j (0 for an unknown one), per pair i != j
    w = {(i, j): np.where(use[j], 1.0 / (xs[i] - xs[j]), 0.0) for i in range(4) for j in range(4) if i != j}
    x = secant.copy()
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for _ in range(8):  # Newton on the Lagrange polynomial of the known points
            v, dv = np.zeros_like(x), np.zeros_like(x)
            d = [x - xs[j] for j in range(4)]
            for i in range(4):
                li, dli = np.ones_like(x), np.zeros_like(x)
                for j in range(4):
                    if j != i:
                        factor = np.where(use[j], d[j] * w[i, j], 1.0)
                        dli = dli * factor + li * w[i, j]
                        li = li * factor
                v += np.where(use[i], ys[i] * li, 0.0)
                dv += np.where(use[i], ys[i] * dli, 0.0)
            x = x - v / dv
    good = np.isfinite(x) & (x > 0.0) & (x < 1.0) & (use[0] | use[3])
    return np.where(good, x, secant)


def crossings(a: np.ndarray, b: np.ndarray, m_a: np.ndarray, m_b: np.ndarray, test, m_before=None,
              m_after=None) -> np.ndarray:
    """Where feasibility changes on the segments a -> b (V, d) [m], ``a`` feasible and ``b`` not:
    the fraction t (V,) of the way, within 2**-BISECTIONS of a change (the middle of a bracket
    [lo, hi] with ``a + lo (b - a)`` feasible, ``a + hi (b - a)`` not, hi - lo <= 2**-BISECTIONS).

    ``m_a`` >= 0 and ``m_b`` <= 0 [N] the capacity margins at the ends (NaN where unknown),
    ``m_before`` and ``m_after`` (signed, NaN where unknown) one grid step before ``a`` and beyond
    ``b``; ``test(P)`` gives feasibility and margins at positions (k, 3) [m].  Where the bracket's
    two margins are known and agree with feasibility, the first guess is the root of the polynomial
    through the known margins (:func:`first_guess`; the margin being a continuous function that
    changes sign with feasibility), later ones the bracket's secant (regula falsi), and the test is
    made just either side of it, which closes the bracket when the guess is within half the
    tolerance.  When both tests land on one side, their two margins, a tolerance apart, give the
    margin's slope there, and the next guess is the root of that line (a Newton step), tested the
    same way; after a round that did not halve the bracket without such a guess, it is bisected."""
    n, d = a.shape
    tol = 2.0 ** -BISECTIONS
    eps = 0.5 * tol
    lo, hi = np.zeros(n), np.ones(n)
    mlo = np.where(m_a > 0, m_a, np.nan)
    mhi = np.where(m_b < 0, m_b, np.nan)
    halve = np.zeros(n, dtype=bool)
    step = np.full(n, np.nan)  # the next guess of a Newton step (NaN: none)
    if m_before is not None:  # the first guess from the margins along the grid line
        known = np.isfinite(mlo) & np.isfinite(mhi)
        step[known] = first_guess(mlo[known], mhi[known], m_before[known], m_after[known])
    for _ in range(3 * BISECTIONS):
        act = np.flatnonzero(hi - lo > tol)
        if act.size == 0:
            break
        l, h = lo[act], hi[act]
        newton = (step[act] > l) & (step[act] < h)
        secant = ~newton & np.isfinite(mlo[act]) & np.isfinite(mhi[act]) & ~halve[act]
        two = newton | secant
        with np.errstate(invalid="ignore", divide="ignore"):
            guess = np.where(newton, step[act],
                             np.where(secant, l + (h - l) * mlo[act] / (mlo[act] - mhi[act]), 0.5 * (l + h)))
        t1 = np.where(two, np.clip(guess - eps, l + 0.25 * eps, h - 0.25 * eps), guess)
        t2 = np.clip(guess + eps, l + 0.25 * eps, h - 0.25 * eps)
        idx = np.concatenate([act, act[two]])
        ts = np.concatenate([t1, t2[two]])
        P = np.zeros((len(ts), 3))
        P[:, :d] = a[idx] + ts[:, None] * (b[idx] - a[idx])
        ok, marg = np.empty(len(ts), dtype=bool), np.empty(len(ts))
        for k in range(0, len(ts), BATCH):
            f, mg = test(np.ascontiguousarray(P[k:k + BATCH]))
            ok[k:k + BATCH], marg[k:k + BATCH] = f, mg
        # a secant's two tests on one side, their margins of feasibility's sign: the line through them
        n1 = len(act)
        f1, m1, f2, m2 = ok[:n1][two], marg[:n1][two], ok[n1:], marg[n1:]
        line = secant[two] & (f1 == f2) & ((m1 > 0) == f1) & ((m2 > 0) == f2) & (m1 != m2)
        step[act] = np.nan
        with np.errstate(invalid="ignore", divide="ignore"):
            root = t2[two] - m2 * (t2[two] - t1[two]) / (m2 - m1)
        step[act[two][line]] = root[line]
        width = hi[act] - lo[act]
        for sel in (slice(0, n1), slice(n1, None)):  # the lower points first, then the upper
            i, t, f, mg = idx[sel], ts[sel], ok[sel], marg[sel]
            up = f & (t > lo[i])
            lo[i[up]], mlo[i[up]] = t[up], np.where(mg[up] > 0, mg[up], np.nan)
            down = ~f & (t < hi[i])
            hi[i[down]], mhi[i[down]] = t[down], np.where(mg[down] < 0, mg[down], np.nan)
        halve[act] = ((hi[act] - lo[act]) > 0.5 * width) & ~np.isfinite(step[act])
    return 0.5 * (lo + hi)


def _loops(segments, pts, snapped, lower, axis, lo_in, grid: Grid) -> list:
    """The closed loops (k, 2) [m] of the planar boundary from its segments (pairs of vertex
    ids), each turned so that the feasible set is on its left (outer loops counter-clockwise,
    holes clockwise); vertices put on one box point merged."""
    n = len(pts)
    nbr = np.full((n, 2), -1, dtype=np.int64)
    deg = np.zeros(n, dtype=np.int64)
    for u, v in segments:
        nbr[u, deg[u]] = v
        deg[u] += 1
        nbr[v, deg[v]] = u
        deg[v] += 1
    if np.any(deg != 2):
        raise RuntimeError("the workspace's boundary is not made of closed loops: a bug, please report it "
                           "with the spec")
    step = np.asarray(grid.step, float)
    inside = np.asarray(grid.lower, float) + (np.where(lo_in[:, None], lower, lower + np.eye(2, dtype=np.int64)[axis])
                                             - 1) * step
    seen = np.zeros(n, dtype=bool)
    loops = []
    for s0 in range(n):
        if seen[s0]:
            continue
        order, prev, cur = [], -1, s0
        while not seen[cur]:
            seen[cur] = True
            order.append(cur)
            nxt = nbr[cur, 0] if nbr[cur, 0] != prev else nbr[cur, 1]
            prev, cur = cur, nxt
        idx = np.array(order)
        lp = pts[idx]
        tangent = np.roll(lp, -1, axis=0) - np.roll(lp, 1, axis=0)
        side = inside[idx] - lp
        cross = tangent[:, 0] * side[:, 1] - tangent[:, 1] * side[:, 0]
        free = ~snapped[idx]
        vote = np.sign(cross[free]).sum() if free.any() else np.sign(_shoelace(lp))
        if vote < 0:
            lp = lp[::-1]
        keep = np.any(lp != np.roll(lp, 1, axis=0), axis=1)
        if keep.sum() >= 3:
            loops.append(lp[keep])
    return loops


def _weld(pts, snapped, faces):
    """(vertices, faces, volume [m^3], area [m^2]): the mesh with the vertices at one position merged, its
    degenerate triangles dropped, checked closed (:func:`check_closed`), normals outwards.  Only
    vertices put on the box (``snapped``: a box edge or corner takes several) can share a position:
    the others lie strictly inside distinct grid edges."""
    ids = np.arange(len(pts))
    on_box = np.flatnonzero(snapped)
    if on_box.size:
        _, first, inv = np.unique(pts[on_box], axis=0, return_index=True, return_inverse=True)
        ids[on_box] = on_box[first][inv.reshape(-1)]  # each to the first vertex at its position
    faces = ids[faces]
    good = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    faces = faces[good].astype(np.int64)
    used = np.zeros(len(pts), dtype=bool)
    used[faces.reshape(-1)] = True
    remap = np.cumsum(used) - 1
    verts, faces = pts[used], remap[faces]
    check_closed(verts, faces)
    volume, area = mesh_measures(verts, faces)
    if volume < 0:
        faces = faces[:, ::-1].copy()
        volume, area = mesh_measures(verts, faces)
    return verts, faces, volume, area


def _shoelace(loop: np.ndarray) -> float:
    """Signed area [m^2] of a closed loop (k, 2): positive when counter-clockwise."""
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def check_closed(verts: np.ndarray, faces: np.ndarray) -> None:
    """Raise RuntimeError unless the mesh is closed and consistently wound: every directed edge
    (a, b) of its triangles occurs exactly once and its reverse (b, a) exactly once, so every edge
    is shared by exactly two triangles that run along it in opposite directions."""
    if len(faces) == 0:
        return
    e = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2).astype(np.int64)
    n = int(len(verts))
    # each edge once (its ends in order, times two) plus its direction: every edge must come as a
    # pair, the key 2 k once and 2 k + 1 once, and no key twice (one sort instead of two)
    lo, hi = np.minimum(e[:, 0], e[:, 1]), np.maximum(e[:, 0], e[:, 1])
    key = np.sort((lo * n + hi) * 2 + (e[:, 0] > e[:, 1]))
    first, second = key[0::2], key[1::2]
    if not (len(key) % 2 == 0 and np.all(lo != hi) and np.all(first % 2 == 0) and np.array_equal(second, first + 1)
            and np.all(first[1:] != first[:-1])):
        raise RuntimeError("the workspace's boundary mesh is not closed and consistently wound "
                           f"({len(faces)} triangles): a bug, please report it with the spec")


def mesh_measures(verts: np.ndarray, faces: np.ndarray) -> tuple[float, float]:
    """(signed volume [m^3] enclosed by a closed triangle mesh, positive with outward normals;
    its surface area [m^2])."""
    if len(faces) == 0:
        return 0.0, 0.0
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    return (float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0),
            float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()))
