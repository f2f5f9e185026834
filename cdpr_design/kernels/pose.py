"""One pose: feasibility, capacity margin and min-norm tensions for any m, n."""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import njit, njit_folded, njit_inline
from cdpr_design.kernels.hsm import basis_factor, hsm_enumerate, make_scratch, square_eval_into, square_work
from cdpr_design.kernels.hsm_small import facet_setup, facets_one, facets_two
from cdpr_design.kernels.linalg import gram_of_inverse
from cdpr_design.kernels.tension_qp import goldfarb_idnani, line_projection, null_space, plane_projection


KIND_STATIC = 0


KIND_WRENCH_FEASIBLE = 1


KIND_WRENCH_CLOSURE = 2


@njit_inline
def eval_general(W, wreq, tmin, tmax, combos, kind, t_out, scr, r):
    """:func:`eval_pose` for any m >= n with caller-provided scratch (no allocation); ``r`` = m - n.

    ``scr`` comes from :func:`make_scratch` (n, m, wreq rows).  The margin is
    the fast hyperplane-shifting one over ``wreq[0]`` (static) or every row
    (wrench-feasible, wrench-closure); the tensions at ``wreq[0]`` come from
    the exact QP, run only where the margin of ``wreq[0]`` is >= 0.  Static
    and wrench-feasible poses are feasible when the margin is >= 0 *and* the
    QP found tensions, so a feasible pose always has tensions; wrench-closure
    poses when W positively spans R^n.  Rank W < n or a zero column
    (zero-length cable): (False, NaN), tensions NaN.

    The methods are chosen by ``r`` as in :func:`~cdpr_design.kernels.hsm.hsm_factored`
    and :func:`~cdpr_design.kernels.tension_qp.project_null`: :func:`pose_two`, :func:`pose_one`
    (closed forms), else :func:`pose_any`.  A sweep's loop calls the one of its robot instead
    (chosen in Python, :func:`cdpr_design.kernels.sweep.grid_block`), so that it compiles only
    the methods it needs.
    """
    if r == 2:
        return pose_two(W, wreq, tmin, tmax, combos, kind, t_out, scr)
    if r == 1:
        return pose_one(W, wreq, tmin, tmax, combos, kind, t_out, scr)
    return pose_any(W, wreq, tmin, tmax, combos, kind, t_out, scr)


@njit_inline
def pose_two(W, wreq, tmin, tmax, combos, kind, t_out, scr):
    """:func:`eval_general` for m - n = 2 (:func:`eval_small` with the closed forms for two)."""
    return eval_small(W, wreq, tmin, tmax, kind, t_out, scr, facets_two, plane_projection)


@njit_inline
def pose_one(W, wreq, tmin, tmax, combos, kind, t_out, scr):
    """:func:`eval_general` for m - n = 1 (:func:`eval_small` with the closed forms for one)."""
    return eval_small(W, wreq, tmin, tmax, kind, t_out, scr, facets_one, line_projection)


@njit_inline
def pose_any(W, wreq, tmin, tmax, combos, kind, t_out, scr):
    """:func:`eval_general` by the general methods, for any m - n: the enumerated hyperplane
    shifting (:func:`~cdpr_design.kernels.hsm.hsm_enumerate`) and the Goldfarb-Idnani QP
    (unique tensions t = G w for m = n)."""
    n, m = W.shape
    r = m - n
    nv = wreq.shape[0] if kind != KIND_STATIC else 1
    if _zero_column(W) or not basis_factor(W, scr.tab, scr.slot, scr.nbc, scr.bcol):
        _no_tensions(m, t_out)
        return False, np.nan
    margin0, margin, closure = hsm_enumerate(W, wreq, nv, tmin, tmax, scr)
    qp_ok = False
    if not margin0 >= 0.0:
        _no_tensions(m, t_out)
    elif r == 0:
        # unique tensions t = G w
        tab = scr.tab
        bcol = scr.bcol
        qp_ok = True
        for s in range(n):
            acc = 0.0
            for i in range(n):
                acc += tab[s, m + i] * wreq[0, i]
            t_out[bcol[s]] = min(max(acc, tmin[bcol[s]]), tmax[bcol[s]])
    else:  # writes t_out, NaN where no tensions exist
        # (tension_qp's null-space reduction on the scratch's arrays, then the general QP)
        null_space(n, m, wreq[0], scr.tab, scr.N, scr.tp, scr.tb, scr.nbc, scr.bcol)
        qp_ok = goldfarb_idnani(m, r, tmin, tmax, t_out, scr)
    return _verdict(kind, closure, margin, qp_ok, r)


@njit_inline
def eval_small(W, wreq, tmin, tmax, kind, t_out, S, facets, project):
    """:func:`eval_general` for m - n = 1 or 2, on the scratch's arrays ``S`` (:func:`make_scratch`):
    the basis factorisation (:func:`~cdpr_design.kernels.hsm.basis_factor`), the margins'
    :func:`~cdpr_design.kernels.hsm_small.facet_setup` and ``facets`` (``facets_one`` or ``facets_two``),
    the null basis (:func:`~cdpr_design.kernels.tension_qp.null_space`) and the tensions' ``project``
    (``line_projection`` or ``plane_projection``).  ``facets`` and ``project`` take the same arguments
    for r = 1 and 2, so this code is the same for both."""
    n, m = W.shape
    nv = wreq.shape[0] if kind != KIND_STATIC else 1
    if _zero_column(W) or not basis_factor(W, S.tab, S.slot, S.nbc, S.bcol):
        _no_tensions(m, t_out)
        return False, np.nan
    closure_wanted = kind == KIND_WRENCH_CLOSURE
    gram_of_inverse(S.tab, n, m, S.M)
    facet_setup(W, wreq, nv, tmin, tmax, S.tab, S.M, S.Gw, S.ranges, S.nbc, S.bcol, closure_wanted)
    margin0, margin, closure = facets(W, wreq, nv, S.tab, S.M, S.Gw, S.ranges, S.minors, S.nbc, closure_wanted)
    qp_ok = False
    if not margin0 >= 0.0:
        _no_tensions(m, t_out)
    else:  # writes t_out, NaN where no tensions exist
        null_space(n, m, wreq[0], S.tab, S.N, S.tp, S.tb, S.nbc, S.bcol)
        qp_ok = project(m, tmin, tmax, t_out, S.N, S.tp, S.half)
    return _verdict(kind, closure, margin, qp_ok, m - n)


@njit_inline
def _zero_column(W):
    """Whether a column of ``W`` (n, m) is zero (a cable of zero length)."""
    n, m = W.shape
    zero = False
    for j in range(m):
        s = 0.0
        for i in range(n):
            s += W[i, j] * W[i, j]
        zero = zero or s == 0.0
    return zero


@njit_inline
def _verdict(kind, closure, margin, qp_ok, r):
    """(feasible, margin) of a pose: wrench closure needs W to span positively (r > 0); the other
    kinds a margin >= 0 and the QP's tensions."""
    if kind == KIND_WRENCH_CLOSURE:
        return closure and r > 0, margin
    return margin >= 0.0 and qp_ok, margin


@njit_inline
def _no_tensions(m, t_out):
    for i in range(m):
        t_out[i] = np.nan


@njit
def eval_pose(W, wreq, tmin, tmax, combos, kind, t_out):
    """Feasibility, capacity margin and tensions of one pose.

    Parameters
    ----------
    W : (n, m) structure matrix.
    wreq : (nv, n) required-wrench vertices [N, N m]; row 0 is the nominal
        wrench (gravity only), the one whose tensions are reported.
    tmin, tmax : (m,) tension bounds [N].
    combos : (C(m, n-1), n-1) int64, the column subsets of the HSM.
    kind : KIND_STATIC (row 0 only), KIND_WRENCH_FEASIBLE (every row),
        KIND_WRENCH_CLOSURE (positive spanning, bounds ignored).
    t_out : (m,) receives the minimum 2-norm feasible tensions for row 0 [N]
        (NaN where there are none).

    Returns
    -------
    (feasible, margin) : margin is NaN where rank W < n.
    """
    n, m = W.shape
    if m == n:
        return eval_square(W, wreq, tmin, tmax, kind, t_out)
    # any m != n: basis-factored HSM + exact Goldfarb-Idnani min-norm QP
    # (allocates its scratch: sweeps call eval_general with per-block scratch)
    return eval_general(W, wreq, tmin, tmax, combos, kind, t_out,
                        make_scratch(n, m, wreq.shape[0]), m - n)


@njit
def eval_square(W, wreq, tmin, tmax, kind, t_out):
    """:func:`eval_pose` for a square W (m = n): the tensions t = W^-1 w are unique.

    A kernel that handles any m calls this for m = n and :func:`eval_general`
    (with its own scratch) otherwise, rather than :func:`eval_pose`: each
    compiled function carries the code of everything it calls, so going
    through ``eval_pose`` would compile ``eval_general`` into it twice.
    """
    Winv, rn, a = square_work(W.shape[0])
    return eval_square_into(W, wreq, tmin, tmax, kind, t_out, Winv, rn, a)


@njit_folded
def eval_square_into(W, wreq, tmin, tmax, kind, t_out, Winv, rn, a):
    """:func:`eval_square` with the work arrays of
    :func:`~cdpr_design.kernels.hsm.square_eval_into` given (allocates nothing)."""
    m = W.shape[1]
    nv = wreq.shape[0] if kind == KIND_WRENCH_FEASIBLE else 1
    for i in range(m):
        t_out[i] = np.nan
    rank_ok, margin = square_eval_into(W, wreq[:nv], tmin, tmax, t_out, Winv, rn, a)
    if not rank_ok:
        return False, np.nan
    # t = W^-1 w is unique: it is the tension distribution where it
    # respects the bounds, and there is none otherwise
    for i in range(m):
        if not (tmin[i] <= t_out[i] <= tmax[i]):
            for j in range(m):
                t_out[j] = np.nan
            break
    # m = n columns can never positively span R^n: no wrench closure
    feasible = kind != KIND_WRENCH_CLOSURE and margin >= 0.0
    return feasible, margin


#: The straight cables' arrays a sweep's poses share: the frame anchors ``A`` (m, 3) [m], the wrench
#: ``rows`` (n,) int64 of the structure matrix, the tension bounds ``tmin``, ``tmax`` (m,) [N], the
#: tension floor ``floor`` (m,) [N/m^2] (:func:`raise_floor`), the HSM's column subsets ``combos``
#: (C(m, n-1), n-1) int64 and the ``kind`` (KIND_*).
Statics = namedtuple("Statics", "A rows tmin tmax floor combos kind")
#: A sweep's outputs, row k a pose: ``feasible`` (count,) uint8, ``margin`` (count,) [N], ``tensions``
#: and ``lengths`` (count, m) [N], [m].
Outputs = namedtuple("Outputs", "feasible margin tensions lengths")
#: What a block of poses works in: the structure matrix ``W`` (n, m), tensions ``t`` (m,) [N], free
#: lengths ``L`` (m,) [m], lower tension bounds ``lo`` (m,) [N], the pose's required wrenches ``w``
#: (nv, n) [N, N m] (row 0 the nominal one) and the :func:`~cdpr_design.kernels.hsm.make_scratch`
#: arrays ``scr``.
Buffers = namedtuple("Buffers", "W t L lo w scr")

#: What a sweep's ``place`` function (below) says of row k: a pose to evaluate, a pose with a cable
#: of zero length (infeasible, margin and tensions NaN), or a row it wrote itself.
ROW_POSE = 0
ROW_EMPTY = 1
ROW_DONE = 2


#: The scratch arrays :func:`rows_small` reads (:class:`~cdpr_design.kernels.hsm.Scratch`'s fields of
#: the same names; the others serve the general methods): a block for m - n = 1 or 2 gets only these,
#: so that its compiled loop takes 12 arrays from Python instead of 31 (each one unpacked at the
#: loop's entry and counted where the loop binds it: less code to compile; docs/performance.md).
SmallScratch = namedtuple("SmallScratch", "tab M Gw N tp slot nbc bcol tb ranges minors half")


def buffers(n, m, w):
    """The :class:`Buffers` of a block of poses of ``n`` wrench rows and ``m`` cables; ``w`` (nv, n)
    is copied (each block its own: the sweep's place may rewrite it per pose).  Its ``scr`` is a
    :class:`SmallScratch` for m - n = 1 or 2 (:func:`rows_small`), the whole
    :func:`~cdpr_design.kernels.hsm.make_scratch` otherwise."""
    scr = make_scratch(n, m, w.shape[0])
    if m - n in (1, 2):
        scr = SmallScratch(*(getattr(scr, f) for f in SmallScratch._fields))
    return Buffers(np.empty((n, m)), np.empty(m), np.empty(m), np.empty(m), w.copy(), scr)


class PoseBlock:
    """Rows k0..k1-1 of a sweep, a compiled ``loop(k0, k1, src, st, out, buf)`` over them: the block
    allocates its :class:`Buffers` (``w`` the sweep's required wrenches (nv, n), copied) and calls
    the loop.  Python, not compiled: the buffers and the call cost microseconds a block."""

    def __init__(self, loop):
        self.loop = loop

    @property
    def signatures(self) -> list:
        """The loop's compiled signatures (:func:`~cdpr_design.kernels.parallel.run_blocks` runs the
        first block of a loop not compiled yet on the calling thread)."""
        return self.loop.signatures

    def __call__(self, k0, k1, src, st, out, w):
        self.loop(k0, k1, src, st, out, buffers(st.rows.shape[0], st.A.shape[0], w))


# The loops over a block's poses, one per method (m - n = 1 or 2, m = n, any other), each inlined into
# a compiled loop of each sweep (grid, hanging orientations, explicit positions).  ``place(k, src, st,
# W, L, lo, w, out)`` (a compiled function of the sweep) puts row k's pose into the buffers: its
# structure matrix ``W``, free lengths ``L`` and lengths ``out.lengths[k]``, lower bounds ``lo``
# (:func:`raise_floor`), its required wrenches ``w`` where they vary, and returns ROW_*.  A pose calls
# only functions that call no other compiled function with an array, so that numba counts no
# reference per pose: an array bound in a function that calls such a function is counted at each
# call (an atomic increment and decrement, per array, per pose).


@njit_inline
def rows_small(k0, k1, place, src, st, out, buf, facets, project):
    """Rows k0..k1-1 for m - n = 1 or 2 (:func:`eval_small`; ``facets``, ``project`` its closed forms)."""
    tmax, kind, feasible, margin, tensions = st.tmax, st.kind, out.feasible, out.margin, out.tensions
    W, t, L, lo, w, S = buf.W, buf.t, buf.L, buf.lo, buf.w, buf.scr
    tab, M, Gw, N, tp, slot, nbc, bcol, tb, ranges, minors, half = (S.tab, S.M, S.Gw, S.N, S.tp, S.slot, S.nbc,
                                                                    S.bcol, S.tb, S.ranges, S.minors, S.half)
    n, m = W.shape
    nv = w.shape[0] if kind != KIND_STATIC else 1
    closure_wanted = kind == KIND_WRENCH_CLOSURE
    w0 = w[0]
    for k in range(k0, k1):
        status = place(k, src, st, W, L, lo, w, out)
        if status == ROW_DONE:
            continue
        f, mg = False, np.nan
        if status == ROW_EMPTY or _zero_column(W) or not basis_factor(W, tab, slot, nbc, bcol):
            _no_tensions(m, t)
        else:
            gram_of_inverse(tab, n, m, M)
            facet_setup(W, w, nv, lo, tmax, tab, M, Gw, ranges, nbc, bcol, closure_wanted)
            margin0, mg, closure = facets(W, w, nv, tab, M, Gw, ranges, minors, nbc, closure_wanted)
            qp_ok = False
            if not margin0 >= 0.0:
                _no_tensions(m, t)
            else:  # writes t, NaN where no tensions exist
                null_space(n, m, w0, tab, N, tp, tb, nbc, bcol)
                qp_ok = project(m, lo, tmax, t, N, tp, half)
            f, mg = _verdict(kind, closure, mg, qp_ok, m - n)
        _put_row(k, f, mg, t, feasible, margin, tensions)


@njit_inline
def rows_square(k0, k1, place, src, st, out, buf):
    """Rows k0..k1-1 for m = n (:func:`eval_square_into`, its work arrays from the scratch)."""
    _rows_each(k0, k1, place, src, st, out, buf, _square_pose)


@njit_inline
def rows_any(k0, k1, place, src, st, out, buf):
    """Rows k0..k1-1 for any m - n, by the general methods (:func:`pose_any`)."""
    _rows_each(k0, k1, place, src, st, out, buf, _any_pose)


@njit_inline
def _rows_each(k0, k1, place, src, st, out, buf, pose):
    """Rows k0..k1-1, each placed pose evaluated by ``pose(W, w, lo, st, t, scr)`` -> (feasible,
    margin [N]) with its tensions [N] in ``t`` (inlined, as ``pose`` is: one loop per method)."""
    feasible, margin, tensions = out.feasible, out.margin, out.tensions
    W, t, L, lo, w, scr = buf.W, buf.t, buf.L, buf.lo, buf.w, buf.scr
    for k in range(k0, k1):
        status = place(k, src, st, W, L, lo, w, out)
        if status == ROW_DONE:
            continue
        if status == ROW_EMPTY:
            _empty_row(k, feasible, margin, tensions)
        else:
            f, mg = pose(W, w, lo, st, t, scr)
            _put_row(k, f, mg, t, feasible, margin, tensions)


@njit_inline
def _square_pose(W, w, lo, st, t, scr):
    """A pose of :func:`rows_square`: :func:`eval_square_into` on the scratch's arrays."""
    return eval_square_into(W, w, lo, st.tmax, st.kind, t, scr.A, scr.Gt, scr.tab)


@njit_inline
def _any_pose(W, w, lo, st, t, scr):
    """A pose of :func:`rows_any`: :func:`pose_any`."""
    return pose_any(W, w, lo, st.tmax, st.combos, st.kind, t, scr)


@njit_inline
def _empty_row(k, feasible, margin, tensions):
    """Row ``k``: infeasible, margin and tensions NaN (a cable of zero length)."""
    feasible[k] = 0
    margin[k] = np.nan
    for i in range(tensions.shape[1]):
        tensions[k, i] = np.nan


@njit_inline
def _put_row(k, f, mg, t, feasible, margin, tensions):
    """Row ``k``: feasibility ``f``, margin ``mg`` (-0.0 as 0.0: one zero in the CSV, whatever the
    engine) [N] and tensions ``t`` [N]."""
    feasible[k] = 1 if f else 0
    margin[k] = mg + 0.0
    for i in range(tensions.shape[1]):
        tensions[k, i] = t[i]


class RowBlock:
    """Rows k0..k1-1 of a sweep: the block's buffers (``buffers(n, m, nv)``, a tuple of work arrays),
    then ``loop`` over its poses, called as
    ``loop(k0, k1, *args, *buffers(n, m, nv), *extra(m))`` (``loop(k0, k1, *args, W, t, L, lo, scr)``).

    ``loop`` is the compiled loop the caller chose in Python for the robot's m - n (each compiled
    with only its own margin and QP method, :func:`eval_general`); ``dims(*args)`` gives (n, m, nv)
    from the block's arguments; ``extra(m)`` more work arrays, if any.  Python, not compiled: a
    compiled function carries the machine code of everything it calls, optimised and emitted again
    with it, so a compiled block around the loop compiled the loop a second time
    (docs/performance.md); from Python, the buffers and the call cost little a block.
    """

    def __init__(self, loop, dims, extra=None, *, buffers):
        self.loop, self.dims, self.extra, self.buffers = loop, dims, extra, buffers

    @property
    def signatures(self) -> list:
        """The loop's compiled signatures (:func:`~cdpr_design.kernels.parallel.run_blocks`
        runs the first block of a loop not compiled yet on the calling thread)."""
        return self.loop.signatures

    def __call__(self, k0, k1, *args):
        n, m, nv = self.dims(*args)
        more = () if self.extra is None else self.extra(m)
        self.loop(k0, k1, *args, *self.buffers(n, m, nv), *more)


@njit_inline
def raise_floor(tmin, floor, L, lo):
    """The pose's lower tension bounds into ``lo`` (m,) [N]: max(``tmin``, ``floor`` L^2) for a cable
    with ``floor`` > 0 [N/m^2] (``requirements.min_cable_frequency``, the robot's ``tension_floor``),
    ``tmin`` otherwise; ``L`` (m,) [m] the cables' free lengths.  Returns ``lo``."""
    for i in range(tmin.shape[0]):
        c = floor[i]
        lo[i] = max(tmin[i], c * L[i] * L[i]) if c > 0.0 else tmin[i]
    return lo
