"""Workspaces of under-constrained designs: the tilt the effector hangs with, and its statics there.

An under-constrained design (:func:`cdpr_design.statics.hanging.underconstrained`)
cannot hold its effector's orientation; at each grid position the effector
turns until the cables balance its weight, force and moment
(:func:`cdpr_design.statics.hanging.at_positions.hanging_orientations`).
:func:`sweep` is what :func:`cdpr_design.workspaces.run` does for such a design:

- ``effector.orientation: fixed`` (the default, the spec's model of an
  effector held at the commanded orientation): the usual sweep, untouched,
  with the hanging tilt added beside it, so that the held model's
  feasibility is never read without the tilt the real body would take;
- ``free``: feasibility judged at the hanging orientation - the effector
  hangs there stably with every cable pulling, its tensions are within their
  bounds (and the capacity margin below is >= 0 where the motion's rows
  define one), and its tilt is at most ``max_tilt`` (``--max-tilt``, default
  ``requirements.max_tilt``).  The tensions are the hanging ones (unique:
  they balance force and moment), the lengths those that put it there, the
  margin the capacity margin of the motion's wrench rows at the hanging
  orientation (:func:`cdpr_design.kernels.hanging.eval_rotated`); where it
  cannot hang the lengths, tensions and margin are empty.

Both add the CSV columns :func:`columns` to every chunk (``tilt`` [deg] and
the orientation per rotation axis [rad]), keep the tilt map for the
``tilt_map.png`` picture (:class:`HangingMaps`) and add the summary keys
``effector_orientation``, ``hangs``, ``max_tilt``, ``max_tilt_hanging`` (and
``tilt_limit``, ``tilt_limited`` under ``free``).  Rows stream in chunks: the
grid is never held in memory.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.model.design import Design
from cdpr_design.statics import hanging as H
from cdpr_design.statics.hanging.at_positions import hanging_orientations
from cdpr_design.statics.hanging.geometry import Geometry
from cdpr_design.statics.hanging.results import HangingOrientations
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.cables import is_ideal
from cdpr_design.statics.pose import combinations
from cdpr_design.workspaces.engine import use_numpy
from cdpr_design.workspaces.grid import CHUNK, Chunk, Maps, chunk_poses, positions3


@dataclass
class HangingMaps:
    """The hanging tilt behind ``tilt_map.png``: ``tilt`` [deg] on the result's map cells
    (NaN where the effector cannot hang), the design's ``orientation_mode`` and, under
    ``free``, the ``tilt_limit`` [deg] in force (None: no limit)."""

    tilt: np.ndarray
    orientation_mode: str
    tilt_limit: float | None = None


def wanted(design: Design, tilt: bool = True) -> bool:
    """Whether a sweep of ``design`` goes through :func:`sweep`: it :func:`applies`, and either its
    effector hangs freely (its feasibility is judged at the hanging orientation) or ``tilt``
    asks for the tilt a held effector would hang with (only a figure: sweeps that use just
    feasibility, margins and tensions leave it out)."""
    return applies(design) and (tilt or H.hangs_freely(design))


def applies(design: Design) -> bool:
    """Whether a sweep of ``design`` goes through :func:`sweep`: under-constrained, with a weight
    (a weightless ``fixed`` effector hangs in no particular orientation: no tilt), point outlets and
    ideal cables (the hanging solvers model neither swivel pulleys nor elastic or sagging cables;
    ``free`` with either, or without a weight, is refused)."""
    if not H.underconstrained(design):
        return False
    if not H.has_weight(design.effector.mass, design.gravity):
        if H.hangs_freely(design):
            H.check_weight(design.effector.mass, design.gravity)  # the spec checks refuse it at load
        return False
    if kin.has_pulleys(design) or not is_ideal(design):
        if H.hangs_freely(design):
            hanging_model(design)
        return False
    return True


def hanging_model(design: Design) -> None:
    """Refuse what the hanging solvers do not model: swivel pulleys, elastic or sagging cables."""
    H.point_outlets(design, "effector.orientation: free")
    if not is_ideal(design):
        raise InputError("cable model: an effector with effector.orientation: free hangs on ideal cables "
                         "(the hanging solver models rigid, weightless cables); use --cable-model ideal")


def refuse_commanded_orientations(design: Design) -> None:
    """Orientation workspaces sweep commanded orientations: refused when the effector hangs freely."""
    if H.hangs_freely(design):
        raise InputError("--orientations: an under-constrained design with effector.orientation: free does "
                         "not command its orientation (it hangs); use effector.orientation: fixed to sweep "
                         "commanded orientations")


def columns(design: Design) -> list[str]:
    """The extra ``workspace.csv`` columns of an under-constrained design: ``tilt`` [deg] and
    the hanging orientation per rotation axis [rad] (``orientation_phi``, or ``orientation_rx``,
    ``orientation_ry``, ``orientation_rz``)."""
    axes = ["phi"] if design.motion.planar else ["rx", "ry", "rz"]
    return ["tilt"] + [f"orientation_{a}" for a in axes]


def classification(design: Design) -> dict:
    """The summary keys of an under-constrained design's sweep, ``effector_orientation`` and
    ``underconstrained`` (cli.md), whether or not it hangs (a weightless effector, swivel
    pulleys and elastic or sagging cables have no hanging solve); none for other designs."""
    if not H.underconstrained(design):
        return {}
    return {"effector_orientation": design.effector.orientation, "underconstrained": True}


def tilt_limit(design: Design, max_tilt: float | None) -> float | None:
    """The tilt limit [deg] of a sweep: ``max_tilt``, else ``requirements.max_tilt`` (free designs)."""
    if max_tilt is not None:
        if not H.hangs_freely(design):
            raise InputError("max_tilt: a tilt limit applies to an under-constrained design with "
                             "effector.orientation: free (a fixed effector is held at its commanded orientation)")
        if not (0.0 <= max_tilt <= 180.0):
            raise InputError(f"max_tilt: expected an angle in [0, 180] degrees, got {max_tilt}")
        return float(max_tilt)
    return design.requirements.max_tilt if H.hangs_freely(design) else None


class _Hanger:
    """The hanging orientation at a chunk's positions, for one design."""

    def __init__(self, design: Design, ori, engine: str, poses: int):
        A, B, c, mass, g, planar = H.design_arrays(design)
        self.geo = Geometry(A, B, c, mass, g)
        self.planar = planar
        self.design = design
        self.nominal = kin.rotation_matrix(*ori)
        # the planar two-cable kernel where numba is (or will be) loaded: numba asked for, a
        # free design (its statics run the kernels), or a sweep the engines give to numba
        two = planar and design.m == 2 and not H.is_point_mass(B)
        numba = engine == "numba" or (engine == "auto" and (H.hangs_freely(design) or not use_numpy(engine, True, poses)))
        self.engine = "numba" if two and numba else "numpy"
        # the numpy search on the kernels' threads where the sweep runs the kernels anyway (their
        # thread setting and pool are then there); the planar two-cable kernel runs on them itself
        self.threaded = numba and self.engine == "numpy"

    def __call__(self, P3):
        if self.threaded:
            h = _hang_in_blocks(self.geo, P3, self.planar, self.nominal)
        else:
            h = hanging_orientations(self.geo, P3, self.planar, nominal=self.nominal, engine=self.engine)
        ori = h.orientation.reshape(len(P3), -1)
        extra = {"tilt": h.tilt_deg}
        for j, name in enumerate(columns(self.design)[1:]):
            extra[name] = ori[:, j]
        return h, extra


#: Fewest positions in a block of :func:`_hang_in_blocks` (a call costs milliseconds of Python).
HANG_GRAIN = 256
#: Positions in a block at most, where the rows allow (``run_blocks`` makes at most
#: ``BLOCKS_PER_THREAD`` a thread, so a 262,144-row chunk still gets blocks of 16,384): Ctrl-C
#: waits for the blocks begun, seconds rather than the whole chunk.  Blocks are otherwise as
#: large as the threads allow: two threads of small numpy calls mostly wait for each other's GIL
#: (crane4 in 12 blocks on two threads took 2.2 s, in 2 blocks 0.97 s, on one thread 1.45 s).
HANG_BLOCK = 4096


def _hang_in_blocks(geo: Geometry, P, planar: bool, nominal) -> HangingOrientations:
    """:func:`~cdpr_design.statics.hanging.at_positions.hanging_orientations` (numpy) at positions
    ``P`` (k, 3) [m], in blocks of rows on the kernels' threads (:func:`~cdpr_design.kernels.parallel.run_blocks`):
    its stacked linear algebra and einsum release the GIL, so the blocks share the cores
    (crane4's 2,873 positions: 1.4 s -> 0.95 s on two).  Each position is solved on its own,
    so the answers do not depend on the blocks (tests/test_parallel.py)."""
    from cdpr_design.kernels.parallel import run_blocks, threads

    k = len(P)
    if k == 0:
        return hanging_orientations(geo, P, planar, nominal=nominal)
    parts: dict[int, HangingOrientations] = {}

    def block(k0, k1):
        parts[k0] = hanging_orientations(geo, P[k0:k1], planar, nominal=nominal)  # one key a block: no race

    run_blocks(block, k, grain=max(HANG_GRAIN, min(-(-k // threads()), HANG_BLOCK)))
    return HangingOrientations.joined([parts[k0] for k0 in sorted(parts)])


class _Stats:
    """Streaming summary figures of the hanging tilt."""

    def __init__(self):
        self.hangs, self.max_hanging, self.max_feasible, self.limited = 0, -np.inf, -np.inf, 0

    def add(self, tilt, feasible):
        ok = np.isfinite(tilt)
        self.hangs += int(np.count_nonzero(ok))
        if ok.any():
            self.max_hanging = max(self.max_hanging, float(tilt[ok].max()))
        f = feasible.astype(bool) & ok
        if f.any():
            self.max_feasible = max(self.max_feasible, float(tilt[f].max()))

    def summary(self, design, limit) -> dict:
        num = lambda x: float(x) if np.isfinite(x) else None  # noqa: E731
        out = {**classification(design),
               "hangs": self.hangs, "max_tilt": num(self.max_feasible), "max_tilt_hanging": num(self.max_hanging)}
        if design.effector.orientation == "free":
            out.update(tilt_limit=limit, tilt_limited=self.limited if limit is not None else None)
        return out


def sweep(design: Design, kind: str, g, ori, fixed_sweep, *, on_chunk=None, progress=None,
          chunk: int = CHUNK, keep_maps: bool = True, interference: bool = False, engine: str = "auto",
          max_tilt: float | None = None):
    """Sweep grid ``g`` of an under-constrained design (see the module doc).

    ``fixed_sweep(on_chunk)`` runs the design's usual sweep (the caller's, at
    orientation ``ori`` (3,) [rad]); the other parameters are those of
    :func:`cdpr_design.workspaces.run`.  ``max_tilt`` [deg] applies to ``free``
    designs only.
    """
    limit = tilt_limit(design, max_tilt)
    hanger = _Hanger(design, ori, engine, g.size)
    tilt_maps = Maps(g, 0, keep_maps, extra_maps=("tilt",))
    stats = _Stats()
    if H.hangs_freely(design):
        if kind != "static" or interference:
            what = "--collisions" if interference else f"--kind {kind}"
            raise InputError(f"{what}: an under-constrained design with effector.orientation: free is swept "
                             "statically only (it hangs under gravity; interference at the hanging pose is "
                             "not modelled)")
        result = _free_sweep(design, g, ori, hanger, limit, stats, tilt_maps, on_chunk, progress, chunk, keep_maps)
    else:
        def add_tilt(c):
            h, extra = hanger(positions3(g, c.start, len(c.feasible)))
            c.extra.update(extra)
            stats.add(extra["tilt"], c.feasible)
            tilt_maps.add(c.start, (0, np.inf, -np.inf), c.feasible, c.margin, c.tensions[:, :0], extra)
            if on_chunk is not None:
                on_chunk(c)

        result = fixed_sweep(add_tilt)
    result.extra.update(stats.summary(design, limit))
    result.hanging = HangingMaps(tilt_maps.xmaps["tilt"], design.effector.orientation, limit)
    return result


@dataclass
class FreeRows:
    """The statics of a ``free`` design at k positions, at its hanging orientations.

    ``hanging`` the :class:`~cdpr_design.statics.hanging.results.HangingOrientations`; ``extra`` the
    :func:`columns` (name -> (k,)); ``feasible`` uint8, ``margin`` [N], ``tensions``
    (k, m) [N] (NaN where infeasible), ``lengths`` (k, m) [m] (NaN where it cannot hang);
    ``within`` where it hangs within the tension bounds (before the tilt limit).
    """

    hanging: HangingOrientations
    extra: dict
    feasible: np.ndarray
    margin: np.ndarray
    tensions: np.ndarray
    lengths: np.ndarray
    within: np.ndarray


def free_rows(design: Design, P, hanger: "_Hanger", limit: float | None) -> FreeRows:
    """Hanging orientation, then feasibility, margin, tensions and lengths there, at positions
    ``P`` (k, 3) [m] (see the module doc; the workspace's rows and ``pose --at``'s)."""
    from cdpr_design.kernels import hanging as K  # numba, on first use

    k, m = len(P), design.m
    h, extra = hanger(P)
    R = np.ascontiguousarray(h.rotation)
    f = design.effector.mass * np.asarray(design.gravity, float)
    wg = np.concatenate([np.broadcast_to(f, (k, 3)), np.cross(R @ design.effector.center_of_mass, f)], axis=1)
    wreq = np.ascontiguousarray(-wg[:, design.rows][:, None, :])
    feas, marg = np.empty(k, np.uint8), np.empty(k)
    ten, L = np.empty((k, m)), np.empty((k, m))
    K.eval_rotated(np.ascontiguousarray(P, dtype=float), R, design.outlets,
                   np.ascontiguousarray(design.attachments), design.rows, wreq, design.tension_min,
                   design.tension_max, combinations(m, design.n), 0, feas, marg, ten, L)
    t, tol = h.tensions, 1e-9 * max(1.0, hanger.geo.weight)
    with np.errstate(invalid="ignore"):
        within = h.feasible & np.all((t >= design.tension_min - tol) & (t <= design.tension_max + tol), axis=1)
        # the margin's verdict where the motion's rows have one, with the hanging tensions' tolerance: a
        # cable that hangs slack in theory (tension 0 at its bound 0) is not decided by rounding
        within &= (marg >= -tol) | ~np.isfinite(marg)
        upright = within if limit is None else within & within_tilt(extra["tilt"], limit)
        # an infeasible pose's margin says so: its own negative verdict, else empty (it is rejected
        # for its tilt or its hanging tensions, which the capacity margin does not measure)
        marg = np.where(upright | (marg < 0), marg, np.nan)
    return FreeRows(h, extra, upright.astype(np.uint8), marg, np.where(upright[:, None], t, np.nan), L, within)


#: Tolerance [deg] of the tilt limit: a pose tilted by at most ``max_tilt + TILT_TOL_DEG`` is
#: within it (1e-9 rad: a level effector's computed tilt is round-off, about 1e-15 deg).
TILT_TOL_DEG = math.degrees(1e-9)


def within_tilt(tilt, limit: float):
    """Whether tilts [deg] are within the limit [deg] (:data:`TILT_TOL_DEG`); NaN is not."""
    return np.asarray(tilt) <= limit + TILT_TOL_DEG


def _free_sweep(design, g, ori, hanger, limit, stats, tilt_maps, on_chunk, progress, chunk, keep_maps):
    """The grid at the hanging orientations, chunk by chunk (see the module doc)."""
    from cdpr_design.workspaces.hardware import chunk_stats

    t0 = time.perf_counter()
    total = g.size
    maps = Maps(g, design.m, keep_maps)
    chunk = max(1, min(chunk, total))
    done = 0
    while done < total:
        cnt = min(chunk, total - done)
        P = positions3(g, done, cnt)
        r = free_rows(design, P, hanger, limit)
        stats.limited += int(np.count_nonzero(r.within & (r.feasible == 0)))
        stats.add(r.extra["tilt"], r.feasible)
        maps.add(done, chunk_stats(r.feasible, r.margin, r.tensions, maps.tpeak), r.feasible, r.margin, r.tensions)
        tilt_maps.add(done, (0, np.inf, -np.inf), r.feasible, r.margin, r.tensions[:, :0], {"tilt": r.extra["tilt"]})
        if on_chunk is not None:
            poses = chunk_poses(design, P, ori)
            if design.motion.rotational:  # the orientation columns hold the hanging orientation
                poses[:, design.motion.dim:] = r.hanging.orientation.reshape(cnt, -1)
            on_chunk(Chunk(done, poses, r.feasible, r.margin, r.tensions, r.lengths, extra=r.extra))
        done += cnt
        if progress is not None:
            progress(done, total)
    return maps.result(design, "static", ori, t0)


def free_pose(design: Design, position, max_tilt: float | None = None) -> FreeRows:
    """:func:`free_rows` at one position [m] of a ``free`` under-constrained design, about
    ``workspace.orientation``, with the sweep's tilt limit (``max_tilt``, else the requirement)."""
    if not H.hangs_freely(design):
        raise InputError("free_pose: the design's orientation is commanded (not free and under-constrained)")
    hanging_model(design)
    P = np.zeros((1, 3))
    pos = np.asarray(position, float).ravel()
    P[0, : pos.size] = pos
    hanger = _Hanger(design, design.default_orientation_full(), "numpy", 1)
    return free_rows(design, P, hanger, tilt_limit(design, max_tilt))
