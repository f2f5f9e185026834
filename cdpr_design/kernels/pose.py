"""One pose: feasibility, capacity margin and min-norm tensions for any m, n."""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from cdpr_design.kernels._jit import jitable, njit, njit_inline, njit_noref
from cdpr_design.kernels.hsm import basis_factor, hsm_enumerate, make_scratch, square_eval_into, square_work
from cdpr_design.kernels.hsm_small import facet_setup, facets_one, facets_two
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
    and :func:`~cdpr_design.kernels.tension_qp.project_null` (closed forms for
    r = 1, 2: :func:`eval_small`), but called here directly, and this function is inlined
    into its callers: a caller passing ``r`` as a constant
    (:func:`cdpr_design.kernels.sweep.grid_block`) compiles only the methods it
    needs.  Going through those two functions instead, called or inlined,
    costs time a pose (an inlined layer passing the scratch tuple on costs by
    itself; docs/performance.md).
    """
    if r == 2:
        return eval_small(W, wreq, tmin, tmax, kind, t_out, small_scratch(scr),
                          basis_factor, null_space, facet_setup, facets_two, plane_projection)
    if r == 1:
        return eval_small(W, wreq, tmin, tmax, kind, t_out, small_scratch(scr),
                          basis_factor, null_space, facet_setup, facets_one, line_projection)
    n, m = W.shape
    nv = wreq.shape[0] if kind != KIND_STATIC else 1
    if _zero_column(W) or not basis_factor(W, scr[0], scr[18], scr[19], scr[20]):
        _no_tensions(m, t_out)
        return False, np.nan
    margin0, margin, closure = hsm_enumerate(W, wreq, nv, tmin, tmax, scr)
    qp_ok = False
    if not margin0 >= 0.0:
        _no_tensions(m, t_out)
    elif r == 0:
        # unique tensions t = G w
        tab = scr[0]
        bcol = scr[20]
        qp_ok = True
        for s in range(n):
            acc = 0.0
            for i in range(n):
                acc += tab[s, m + i] * wreq[0, i]
            t_out[bcol[s]] = min(max(acc, tmin[bcol[s]]), tmax[bcol[s]])
    else:  # writes t_out, NaN where no tensions exist
        # (tension_qp's null_space_setup on the scratch's arrays, then the general QP)
        null_space(n, m, wreq[0], scr[0], scr[8], scr[9], scr[25], scr[19], scr[20])
        qp_ok = goldfarb_idnani(m, r, tmin, tmax, t_out, scr)
    return _verdict(kind, closure, margin, qp_ok, r)


@njit_inline
def eval_small(W, wreq, tmin, tmax, kind, t_out, S, factor, null, setup, facets, project):
    """:func:`eval_general` for m - n = 1 or 2, with the five functions it calls given: the basis
    factorisation ``factor`` (:func:`~cdpr_design.kernels.hsm.basis_factor`), the null basis ``null``
    (:func:`~cdpr_design.kernels.tension_qp.null_space`), the margins' ``setup`` and ``facets``
    (:mod:`~cdpr_design.kernels.hsm_small`: :func:`facet_setup`, then ``facets_one`` or
    ``facets_two``) and the tensions' ``project`` (``line_projection`` or ``plane_projection``),
    each on the scratch's arrays ``S`` (:func:`small_scratch`).  ``facets`` and ``project`` take the
    same arguments for r = 1 and 2, so this code is the same for both.

    :func:`eval_general` passes the compiled functions themselves (numba calls them directly);
    the grid sweep's loops pass pointers to them (:mod:`cdpr_design.kernels.pointers`), so that
    a loop compiles without compiling them into it again.
    """
    n, m = W.shape
    nv = wreq.shape[0] if kind != KIND_STATIC else 1
    if _zero_column(W) or not factor(W, S.tab, S.slot, S.nbc, S.bcol):
        _no_tensions(m, t_out)
        return False, np.nan
    closure_wanted = kind == KIND_WRENCH_CLOSURE
    setup(W, wreq, nv, tmin, tmax, S.tab, S.M, S.Gw, S.ranges, S.nbc, S.bcol, closure_wanted)
    margin0, margin, closure = facets(W, wreq, nv, S.tab, S.M, S.Gw, S.ranges, S.minors, S.nbc, closure_wanted)
    qp_ok = False
    if not margin0 >= 0.0:
        _no_tensions(m, t_out)
    else:  # writes t_out, NaN where no tensions exist
        null(n, m, wreq[0], S.tab, S.N, S.tp, S.tb, S.nbc, S.bcol)
        qp_ok = project(m, tmin, tmax, t_out, S.N, S.tp, S.half)
    return _verdict(kind, closure, margin, qp_ok, m - n)


#: The arrays of the scratch (:func:`~cdpr_design.kernels.hsm.make_scratch`, its positions in brackets)
#: that :func:`eval_small` works in: ``tab`` [0] (n, m + n), ``M`` [1], ``Gw`` [2], the null basis ``N``
#: [8], ``tp`` [9], the basis' ``slot`` [18], ``nbc`` [19] and ``bcol`` [20], ``tb`` [25], the margins'
#: ``ranges`` [28] and ``minors`` [29], the projection's ``half`` planes [30].  A loop given these
#: twelve compiles faster than one given all 31 (:mod:`cdpr_design.kernels.pointers`).
SmallScratch = namedtuple("SmallScratch", "tab M Gw N tp slot nbc bcol tb ranges minors half")


@jitable
def small_scratch(scr):
    """The :class:`SmallScratch` of ``scr`` (:func:`~cdpr_design.kernels.hsm.make_scratch`): the same arrays."""
    return SmallScratch(scr[0], scr[1], scr[2], scr[8], scr[9], scr[18], scr[19], scr[20], scr[25], scr[28],
                        scr[29], scr[30])


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


@njit_noref
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


@njit_inline
def eval_row(k, ok, W, wreq, tmin, tmax, combos, kind, t, scr, feasible, margin, tensions, r):
    """Row ``k`` of a sweep's outputs from the pose's structure matrix ``W`` (n, m); ``r`` = m - n
    (a constant where the caller specialises on it, see :func:`eval_general`).

    ``ok`` False (a zero-length cable): infeasible, margin and tensions NaN.
    Otherwise :func:`eval_square_into` (m = n, its work arrays from ``scr``) or :func:`eval_general` with the
    block's scratch ``scr`` and tension buffer ``t`` (m,), written to
    ``feasible[k]`` (uint8), ``margin[k]`` (-0.0 as 0.0: one zero in the CSV,
    whatever the engine) [N] and ``tensions[k]`` [N].
    """
    if not ok:
        _empty_row(k, feasible, margin, tensions)
        return
    if r == 0:  # the square case's work arrays from the scratch: (n, n), (n,) and (n, m + n = 2n)
        f, mg = eval_square_into(W, wreq, tmin, tmax, kind, t, scr[4], scr[3], scr[0])
    else:
        f, mg = eval_general(W, wreq, tmin, tmax, combos, kind, t, scr, r)
    _put_row(k, f, mg, t, feasible, margin, tensions)


@njit_inline
def eval_row_small(k, ok, W, wreq, tmin, tmax, kind, t, scr, feasible, margin, tensions,
                   factor, null, setup, facets, project):
    """:func:`eval_row` for m - n = 1 or 2 with the five functions of :func:`eval_small` given (the
    grid sweep's pointers, :mod:`cdpr_design.kernels.pointers`)."""
    if not ok:
        _empty_row(k, feasible, margin, tensions)
        return
    f, mg = eval_small(W, wreq, tmin, tmax, kind, t, scr, factor, null, setup, facets, project)
    _put_row(k, f, mg, t, feasible, margin, tensions)


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


@jitable
def row_buffers(n, m, nv):
    """What :func:`eval_row` works in, for one block of poses: the structure matrix W (n, m),
    tensions t (m,) [N], lengths L (m,) [m], the pose's lower tension bounds lo (m,) [N]
    (:func:`raise_floor`) and the scratch (:func:`make_scratch`, ``nv`` required-wrench rows).
    A plain function from Python, as :func:`make_scratch`."""
    return np.empty((n, m)), np.empty(m), np.empty(m), np.empty(m), make_scratch(n, m, nv)


class RowBlock:
    """Rows k0..k1-1 of a sweep: the block's buffers (``buffers(n, m, nv)``, by default the straight
    cables' :func:`row_buffers`), then ``loop`` over its poses, called as
    ``loop(k0, k1, *args, *buffers(n, m, nv), *extra(m))`` (``loop(k0, k1, *args, W, t, L, lo, scr)``).

    ``loop`` is the compiled loop the caller chose in Python for the robot's m - n (each compiled
    with only its own margin and QP method, :func:`eval_general`); ``dims(*args)`` gives (n, m, nv)
    from the block's arguments; ``extra(m)`` more work arrays, if any.  Python, not compiled: a
    compiled function carries the machine code of everything it calls, optimised and emitted again
    with it, so a compiled block around the loop compiled the loop a second time
    (docs/performance.md); from Python, the buffers and the call cost little a block.
    """

    def __init__(self, loop, dims, extra=None, buffers=None):
        self.loop, self.dims, self.extra = loop, dims, extra
        self.buffers = row_buffers if buffers is None else buffers

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


def pose_kernels(n: int, m: int, wreq=None, tmax=None) -> tuple[list, list]:
    """The compiled functions a pose calls for ``n`` DOF and ``m`` cables (:func:`eval_general`), with
    the types a sweep gives them: (tensions, margins), each a list of (dispatcher, signature); both
    empty for m <= n (:func:`eval_square_into`: one small function).  Two independent sets, for
    :func:`cdpr_design.kernels.warm.compile_pose`.

    The types are those of the block's buffers (:func:`row_buffers`) and of the sweep's ``wreq``
    (nv, n) [N, N m] and ``tmax`` (m,) [N] (default: new C-contiguous arrays).  For m - n = 1, 2
    the signatures are complete, return type and all, in the order of :func:`eval_small`'s
    arguments (tensions: ``factor``, ``null``, ``project``; margins: ``setup``, ``facets``): the C
    signatures of the pointers to them (:mod:`cdpr_design.kernels.pointers`)."""
    from numba import typeof, types

    r = m - n
    if r <= 0:
        return [], []
    W, t, _, _, scr = row_buffers(n, m, 1)
    wreq = np.empty((1, n)) if wreq is None else wreq
    T = {name: typeof(a) for name, a in (("W", W), ("wreq", wreq), ("w", wreq[0]), ("t", t))}
    tx = T["t"] if tmax is None else typeof(tmax)
    S = [typeof(a) for a in scr]
    i64, flag, ok = typeof(m), typeof(True), types.boolean
    facets = types.Tuple((types.float64, types.float64, types.boolean))  # (margin0, margin, closure)
    tensions = [(basis_factor, ok(T["W"], S[0], S[18], S[19], S[20])),
                (null_space, types.none(i64, i64, T["w"], S[0], S[8], S[9], S[25], S[19], S[20]))]
    if r <= 2:
        project = plane_projection if r == 2 else line_projection
        tensions.append((project, ok(i64, T["t"], tx, T["t"], S[8], S[9], S[30])))
        margins = [(facet_setup, types.none(T["W"], T["wreq"], i64, T["t"], tx, S[0], S[1], S[2], S[28], S[19],
                                            S[20], flag)),
                   (facets_two if r == 2 else facets_one, facets(T["W"], T["wreq"], i64, S[0], S[1], S[2], S[28],
                                                                 S[29], S[19], flag))]
    else:
        tensions.append((goldfarb_idnani, ok(i64, i64, T["t"], tx, T["t"], typeof(scr))))
        margins = [(hsm_enumerate, facets(T["W"], T["wreq"], i64, T["t"], tx, typeof(scr)))]
    return tensions, margins
