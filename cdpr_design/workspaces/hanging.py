"""Workspaces of under-constrained designs: the tilt the effector hangs with, and its statics there.

An under-constrained design (:func:`cdpr_design.statics.robot.underconstrained`)
cannot hold its effector's orientation; at each grid position the effector
turns until the cables balance its weight, force and moment
(:func:`cdpr_design.statics.hanging.at_positions.hanging_orientations`).  The resolved robot's
``orientation`` says which part of a sweep plan (:mod:`cdpr_design.workspaces.plan`)
takes it:

- ``held`` (``effector.orientation: fixed``, the spec's model of an effector
  held at the commanded orientation): the wrapper :class:`HeldTilt` adds the
  hanging tilt beside the usual rows, so that the held model's feasibility is
  never read without the tilt the real body would take;
- ``hanging`` (``free``; the base evaluator :class:`FreeSweep`): feasibility judged at the hanging orientation - the effector
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

import copy
import math
from dataclasses import dataclass, field

import numpy as np

from cdpr_design.model.design import Design
from cdpr_design.statics import hanging as H
from cdpr_design.statics.hanging import geometry as hg
from cdpr_design.statics.hanging.at_positions import hanging_orientations
from cdpr_design.statics.hanging.compliance import HangingStiffness, hanging_stiffness
from cdpr_design.statics.hanging.geometry import Geometry
from cdpr_design.statics.hanging.results import UNSTABLE, HangingOrientations
from cdpr_design.statics.hanging.sagging import SaggingCables
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.robot import Robot, tension_lower
from cdpr_design.workspaces.cables import cable_summary
from cdpr_design.workspaces.grid import Rows, chunk_poses
from cdpr_design.workspaces.parts import Base, Wrapper


@dataclass
class HangingMaps:
    """The hanging tilt behind ``tilt_map.png``: ``tilt`` [deg] on the result's map cells
    (NaN where the effector cannot hang), the design's ``orientation_mode`` and, under
    ``free``, the ``tilt_limit`` [deg] in force (None: no limit)."""

    tilt: np.ndarray
    orientation_mode: str
    tilt_limit: float | None = None


def columns(design: Design) -> list[str]:
    """The extra ``workspace.csv`` columns of an under-constrained design: ``tilt`` [deg] and
    the hanging orientation per rotation axis [rad] (``orientation_phi``, or ``orientation_rx``,
    ``orientation_ry``, ``orientation_rz``)."""
    axes = ["phi"] if design.motion.planar else ["rx", "ry", "rz"]
    return ["tilt"] + [f"orientation_{a}" for a in axes]


def classification(robot: Robot) -> dict:
    """The summary keys of an under-constrained design's sweep, ``effector_orientation`` and
    ``underconstrained`` (cli.md), whether or not it hangs (a weightless effector, swivel
    pulleys and elastic or sagging cables have no hanging solve); none for other designs."""
    if not robot.underconstrained:
        return {}
    return {"effector_orientation": robot.design.effector.orientation, "underconstrained": True}


class Hanger:
    """The hanging orientation of ``robot``'s effector at a chunk's positions, about ``ori`` (3,) [rad]."""

    def __init__(self, robot: Robot, ori):
        design = robot.design
        A, B, c, mass, g, planar = H.design_arrays(design)
        self.geo = Geometry(A, B, c, mass, g)
        self.planar = planar
        self.design = design
        self.nominal = kin.rotation_matrix(*ori)
        # on the kernels' threads where the sweep runs the kernels anyway (their thread setting
        # and pool are then there; a hanging effector's statics always do)
        self.threaded = robot.engine == "numba"

    def loaded(self, force) -> Hanger:
        """This hanger with a constant external force ``force`` (3,) [N] on the effector at its
        reference point (:class:`~cdpr_design.statics.hanging.geometry.Geometry`)."""
        out = copy.copy(self)
        g = self.geo
        out.geo = Geometry(g.A, g.B, g.c, g.mass, g.g, force)
        return out

    def __call__(self, P3):
        if self.threaded:
            h = _hang_in_blocks(self.geo, P3, self.planar, self.nominal)
        else:
            h = hanging_orientations(self.geo, P3, self.planar, nominal=self.nominal)
        return h, tilt_columns(self.design, h)


def tilt_columns(design: Design, h: HangingOrientations) -> dict:
    """The :func:`columns` of hanging orientations ``h`` (name -> (k,)): ``tilt`` [deg] and the
    orientation per rotation axis [rad], NaN where the effector cannot hang."""
    ori = h.orientation.reshape(len(h.status), -1)
    extra = {"tilt": h.tilt_deg}
    for j, name in enumerate(columns(design)[1:]):
        extra[name] = ori[:, j]
    return extra


#: Fewest positions in a block of :func:`_hang_in_blocks` (a call costs milliseconds of Python).
HANG_GRAIN = 256
#: Positions in a block at most, where the rows allow (``run_blocks`` makes at most
#: ``BLOCKS_PER_THREAD`` a thread, so a 262,144-row chunk still gets blocks of 16,384): Ctrl-C
#: waits for the blocks begun, seconds rather than the whole chunk.  Blocks are otherwise as
#: large as the threads allow: two threads of small numpy calls mostly wait for each other's GIL
#: (docs/performance.md).
HANG_BLOCK = 4096


def _hang_in_blocks(geo: Geometry, P, planar: bool, nominal) -> HangingOrientations:
    """:func:`~cdpr_design.statics.hanging.at_positions.hanging_orientations` (numpy) at positions
    ``P`` (k, 3) [m], in blocks of rows on the kernels' threads (:func:`~cdpr_design.kernels.parallel.run_blocks`):
    its stacked linear algebra and einsum release the GIL, so the blocks share the cores
    (docs/performance.md).  Each position is solved on its own,
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

    def summary(self, robot: Robot, limit) -> dict:
        num = lambda x: float(x) if np.isfinite(x) else None  # noqa: E731
        out = {**classification(robot),
               "hangs": self.hangs, "max_tilt": num(self.max_feasible), "max_tilt_hanging": num(self.max_hanging)}
        if robot.orientation.free:
            out.update(tilt_limit=limit, tilt_limited=self.limited if limit is not None else None)
        return out


class Classification(Wrapper):
    """The summary keys ``effector_orientation`` and ``underconstrained`` of an under-constrained
    design whose tilt is not solved (:func:`classification`); nothing for other designs."""

    positions = False

    def summary(self, maps) -> dict:
        return classification(self.robot)


class HeldTilt(Wrapper):
    """The tilt a *held* under-constrained effector (``effector.orientation: fixed``) would hang
    with, beside the commanded orientation's rows: columns :func:`columns`, the ``tilt`` map
    (``tilt_map.png``) and the summary keys of :class:`_Stats`."""

    maps = ("tilt",)
    pictures = ("tilt_map.png",)

    def __init__(self, robot: Robot, ori):
        super().__init__(robot)
        self.hanger = Hanger(robot, ori)
        self.columns = tuple(columns(robot.design))
        self.tally = _Stats()

    def add(self, r: Rows, start: int, P: np.ndarray) -> None:
        _, extra = self.hanger(P)
        r.extra.update(extra)
        r.maps["tilt"] = extra["tilt"]
        self.tally.add(extra["tilt"], r.feasible)

    def summary(self, maps) -> dict:
        return self.tally.summary(self.robot, None)

    def finish(self, result, maps) -> None:
        result.hanging = HangingMaps(maps.xmaps["tilt"], self.robot.design.effector.orientation, None)


@dataclass
class FreeRows:
    """The statics of a ``free`` design at k positions, at its hanging orientations.

    ``hanging`` the :class:`~cdpr_design.statics.hanging.results.HangingOrientations`; ``extra`` the
    :func:`columns` (name -> (k,)); ``feasible`` uint8, ``margin`` [N], ``tensions``
    (k, m) [N] (NaN where infeasible), ``lengths`` (k, m) [m] (NaN where it cannot hang);
    ``within`` where it hangs within the tension bounds (before the tilt limit and the
    interference checks); ``stiffness`` the
    :class:`~cdpr_design.statics.hanging.compliance.HangingStiffness` of the hanging poses on the
    robot's cables (None unless the cables stretch or the analysis asks for the stiffness);
    ``collisions`` (k,) uint8 the interference bits at the hanging pose (None unless the analysis
    checks interference; 0 where it cannot hang); on sagging cables ``cables`` the
    :class:`~cdpr_design.statics.hanging.sagging.SaggingCables` (unstretched lengths, outlet
    tensions, sag) and ``cable_status`` (k,) int8 (:data:`cdpr_design.statics.cables.STATUS`: 0, or
    3 where the ideal cables hang but the catenaries' balance did not converge).
    """

    hanging: HangingOrientations
    extra: dict
    feasible: np.ndarray
    margin: np.ndarray
    tensions: np.ndarray
    lengths: np.ndarray
    within: np.ndarray
    stiffness: HangingStiffness | None = None
    collisions: np.ndarray | None = None
    cables: SaggingCables | None = None
    cable_status: np.ndarray | None = None
    #: under a ``wrench-feasible`` analysis, the :class:`FreeRows` of gravity alone, then of each
    #: vertex of the external wrench (gravity plus the vertex, at the orientation it hangs in then;
    #: :func:`free_rows`); empty otherwise
    vertices: list = field(default_factory=list)

    @property
    def judged_tilt(self) -> np.ndarray:
        """The tilt [deg] the tilt limit judges: the largest over the external wrench's vertices
        (``tilt_loaded``) where they are judged, else the hanging ``tilt``."""
        return self.extra.get("tilt_loaded", self.extra["tilt"])


def hanging_dofs(geo: Geometry, planar: bool) -> tuple[int, ...]:
    """The degrees of freedom of a hanging effector (:mod:`cdpr_design.statics.hanging.geometry`)."""
    if H.is_point_mass(geo.B):
        return hg.DOFS_POINT2 if planar else hg.DOFS_POINT3
    return hg.DOFS_PLANAR if planar else hg.DOFS_SPATIAL


def pose_stiffness(robot: Robot, hanger: Hanger, P, h: HangingOrientations) -> HangingStiffness:
    """The stiffness of the hanging poses ``h`` at positions ``P`` (k, 3) [m] on the robot's cables
    (:func:`~cdpr_design.statics.hanging.compliance.hanging_stiffness`: rigid for ideal cables,
    their axial stiffness for elastic ones)."""
    return hanging_stiffness(hanger.geo, P, h.rotation, h.tensions, hanging_dofs(hanger.geo, hanger.planar),
                             robot.cable.EA, robot.design.effector.inertia_matrix)


def free_rows(robot: Robot, P, hanger: Hanger) -> FreeRows:
    """Hanging orientation, then feasibility, margin, tensions and lengths there, at positions
    ``P`` (k, 3) [m] (see the module doc; the workspace's rows and ``pose --at``'s), within the
    robot's tension bounds (its per-pose floor included) and tilt limit.  On elastic cables a
    hanging pose must also be stable with the cables' stretch (:func:`pose_stiffness`): one that
    is not is reported unable to hang there (``UNSTABLE``), never as a result.  With the
    analysis's ``collisions``, a pose that interferes is infeasible and its tensions empty.

    Under ``wrench-feasible`` the effector is also hung under gravity plus each vertex of
    ``workspace.external_wrench`` (a force at its reference point;
    :func:`~cdpr_design.statics.wrenches.external_loads`), each at the orientation it then hangs
    in: a row is feasible when it is feasible under every vertex (the tilt limit and the
    interference checks at each vertex's orientation), its margin the least of the vertices'; its
    orientation, tilt, tensions, lengths, cables and stiffness are those of gravity alone (the
    nominal wrench's, as a straight-cable ``wrench-feasible`` row reports), and the column
    ``tilt_loaded`` [deg] is the largest tilt over the vertices.  The vertices are tested, not
    the box between them: the orientation moves nonlinearly with the load.
    """
    from cdpr_design.statics.wrenches import external_loads

    r = _load_rows(robot, P, hanger)
    if not robot.every_vertex:
        return r
    loaded = [_load_rows(robot, P, hanger.loaded(v[:3])) for v in external_loads(robot.design)]
    return _with_loads([r] + loaded)


def _with_loads(rows: list[FreeRows]) -> FreeRows:
    """The rows of gravity alone, ``rows[0]``, judged under every vertex's rows ``rows[1:]`` too
    (:func:`free_rows`)."""
    r = rows[0]
    feasible = np.logical_and.reduce([x.feasible.astype(bool) for x in rows])
    M = np.stack([x.margin for x in rows])
    with np.errstate(invalid="ignore"):
        least = np.fmin.reduce(M, axis=0)
        negative = np.fmin.reduce(np.where(M < 0, M, np.nan), axis=0)
    extra = dict(r.extra, tilt_loaded=np.max(np.stack([x.extra["tilt"] for x in rows]), axis=0))
    hits = None if r.collisions is None else np.bitwise_or.reduce(np.stack([x.collisions for x in rows]), axis=0)
    status = None if r.cable_status is None else np.max(np.stack([x.cable_status for x in rows]), axis=0)
    return FreeRows(r.hanging, extra, feasible.astype(np.uint8), np.where(feasible, least, negative),
                    np.where(feasible[:, None], r.tensions, np.nan), r.lengths,
                    np.logical_and.reduce([x.within for x in rows]), r.stiffness, hits, r.cables, status, rows)


def _load_rows(robot: Robot, P, hanger: Hanger) -> FreeRows:
    """:func:`free_rows` under the loads of ``hanger``'s effector (its weight and external force) alone."""
    from cdpr_design.kernels import hanging as K  # numba, on first use
    from cdpr_design.kernels.pose import Outputs, Statics

    design, limit = robot.design, robot.tilt_limit
    k, m = len(P), design.m
    h, extra = hanger(P)
    if not robot.cables.straight:
        return _sagging_rows(robot, P, hanger, h)
    stiff = None
    if not robot.cables.rigid or robot.analysis.stiffness:
        stiff = pose_stiffness(robot, hanger, P, h)
        unstable = h.feasible & ~stiff.stable
        if unstable.any():  # stable on rigid cables, not with their stretch
            h.status[unstable] = UNSTABLE
            h.rotation[unstable], h.tensions[unstable] = np.nan, np.nan
            extra = tilt_columns(design, h)
        h.hessian_min[h.feasible] = stiff.hessian_min[h.feasible]
    R = np.ascontiguousarray(h.rotation)
    wreq = np.ascontiguousarray(-hanger.geo.loads_many(R)[:, design.rows][:, None, :])
    feas, marg = np.empty(k, np.uint8), np.empty(k)
    ten, L = np.empty((k, m)), np.empty((k, m))
    K.eval_rotated(np.ascontiguousarray(P, dtype=float), R, robot.attachments,
                   Statics(design.outlets, robot.rows, robot.tension_min, robot.tension_max, robot.tension_floor,
                           robot.combos, 0),
                   wreq, Outputs(feas, marg, ten, L))
    t, tol = h.tensions, 1e-9 * max(1.0, hanger.geo.weight)
    with np.errstate(invalid="ignore"):
        lower = tension_lower(robot.tension_min, robot.tension_floor, L)
        within = h.feasible & np.all((t >= lower - tol) & (t <= robot.tension_max + tol), axis=1)
        # the margin's verdict where the motion's rows have one, with the hanging tensions' tolerance: a
        # cable that hangs slack in theory (tension 0 at its bound 0) is not decided by rounding
        within &= (marg >= -tol) | ~np.isfinite(marg)
        upright = within if limit is None else within & within_tilt(extra["tilt"], limit)
        # an infeasible pose's margin says so: its own negative verdict, else empty (it is rejected
        # for its tilt or its hanging tensions, which the capacity margin does not measure)
        marg = np.where(upright | (marg < 0), marg, np.nan)
    hits = None
    if robot.analysis.collisions:
        from cdpr_design.statics.interference import interference_masks  # the kernels, on first use

        hits = interference_masks(design, P, h.rotation)
        upright = upright & (hits == 0)
    return FreeRows(h, extra, upright.astype(np.uint8), marg, np.where(upright[:, None], t, np.nan), L, within,
                    stiff, hits)


def _sagging_rows(robot: Robot, P, hanger: Hanger, ideal: HangingOrientations) -> FreeRows:
    """:func:`free_rows` on sagging cables (:mod:`cdpr_design.statics.hanging.sagging`): the
    orientation balanced by the catenaries' end forces, from the ideal cables' answer ``ideal``;
    feasible where it hangs stably, every cable's tension within its bounds along the whole cable
    (the least, at the effector or at the lowest point of a cable that dips, >= its lower bound;
    the largest, at an end, <= its upper bound), the tilt within the limit and, with the analysis's
    ``collisions``, no interference along the catenaries
    (:func:`cdpr_design.statics.interference.sagging_masks`).  No capacity
    margin (NaN): the catenaries' wrench is not linear in their tensions.  The lengths are the
    chords."""
    from cdpr_design.statics.hanging.sagging import hang_on_sagging_cables

    design, geo = robot.design, hanger.geo
    h, cab, stiff = hang_on_sagging_cables(geo, P, hanger.planar, ideal, robot.cable.w, robot.cable.EA,
                                           hanging_dofs(geo, hanger.planar), design.effector.inertia_matrix)
    extra = tilt_columns(design, h)
    L = np.where(h.feasible[:, None], geo.cables_many(P, np.where(h.feasible[:, None, None], h.rotation,
                                                                     np.eye(3)))[2], np.nan)
    VA = cab.VB + robot.cable.w * cab.unstretched
    dips = (cab.VB < 0.0) & (VA > 0.0)
    least = np.where(dips, cab.H, np.minimum(cab.tensions, cab.outlet_tensions))
    most = np.maximum(cab.tensions, cab.outlet_tensions)
    tol = 1e-9 * max(1.0, geo.weight)
    with np.errstate(invalid="ignore"):
        within = h.feasible & np.all((least >= robot.tension_min - tol) & (most <= robot.tension_max + tol), axis=1)
        upright = within if robot.tilt_limit is None else within & within_tilt(extra["tilt"], robot.tilt_limit)
    status = np.where(ideal.feasible & ~h.feasible & (h.status != UNSTABLE), 3, 0).astype(np.int8)
    hits = None
    if robot.analysis.collisions:  # along the catenaries (where it hangs: every heavy cable has its shape)
        from cdpr_design.kernels.codes import HIT_UNKNOWN
        from cdpr_design.statics.interference import sagging_masks  # the kernels, on first use

        # where it does not hang there are no catenaries to check: not known to be collision free
        # (as pose says, collisions null)
        hits = np.full(len(P), HIT_UNKNOWN, np.uint8)
        ok = np.flatnonzero(h.feasible)
        if ok.size:
            shapes = np.stack([cab.H[ok], cab.VB[ok], cab.unstretched[ok]], axis=2)
            hits[ok] = sagging_masks(robot, P[ok], h.rotation[ok], shapes)
        upright = upright & (hits == 0)
    return FreeRows(h, extra, upright.astype(np.uint8), np.full(len(P), np.nan),
                    np.where(upright[:, None], cab.tensions, np.nan), L, within, stiff, hits, cab, status)


#: Tolerance [deg] of the tilt limit: a pose tilted by at most ``max_tilt + TILT_TOL_DEG`` is
#: within it (1e-9 rad: a level effector's computed tilt is round-off, about 1e-15 deg).
TILT_TOL_DEG = math.degrees(1e-9)


def within_tilt(tilt, limit: float):
    """Whether tilts [deg] are within the limit [deg] (:data:`TILT_TOL_DEG`); NaN is not."""
    return np.asarray(tilt) <= limit + TILT_TOL_DEG


class FreeSweep(Base):
    """The base evaluator of a hanging effector (``effector.orientation: free``): the grid at the
    hanging orientations (see the module doc), the tilt limit ``robot.tilt_limit``.

    With the analysis's ``stiffness``, the columns and maps ``min_stiffness`` [N/m] and
    ``lowest_frequency`` [Hz] and the column ``min_rotational_stiffness`` [N m/rad] of the hanging
    pose (:mod:`cdpr_design.statics.hanging.compliance`; empty where infeasible), drawn as
    ``stiffness_map.png``, the least of each a summary key.  With ``collisions``, the column
    ``collision_free`` and the summary keys of :class:`~cdpr_design.workspaces.hardware.HardwareSweep`
    (``interference``, ``collision_free``, ``feasible_statics``, ``collisions_by_kind``): the
    interference checks at the hanging orientation.
    """

    STIFFNESS = ("min_stiffness", "lowest_frequency", "min_rotational_stiffness")

    def __init__(self, robot: Robot, ori, g):
        self.robot, self.ori, self.kind = robot, ori, robot.kind
        self.hanger = Hanger(robot, ori)
        a = robot.analysis
        self.sagging = not robot.cables.straight
        self.columns = tuple(columns(robot.design)) + (("tilt_loaded",) if robot.every_vertex else ()) \
            + (("collision_free",) if a.collisions else ()) \
            + (self.STIFFNESS if a.stiffness else ()) \
            + (tuple(robot.cables.state_columns(robot.design.cable_names)) if self.sagging else ())
        self.outlet_peak = np.full(robot.design.m, -np.inf)
        self.status_counts = np.zeros(5, np.int64)
        self.maps = ("tilt",) + (self.STIFFNESS[:2] if a.stiffness else ())
        self.pictures = ("tilt_map.png",) + (("stiffness_map.png",) if a.stiffness else ())
        self.tally = _Stats()
        self.least = dict.fromkeys(self.STIFFNESS, math.inf)
        self.n_free = self.n_stat = 0
        self.counts: dict = {}

    def rows(self, start: int, count: int, P: np.ndarray | None) -> Rows:
        design, cnt = self.robot.design, P.shape[0]
        r = free_rows(self.robot, P, self.hanger)
        limit = self.robot.tilt_limit
        if limit is not None:
            self.tally.limited += int(np.count_nonzero(r.within & ~within_tilt(r.judged_tilt, limit)))
        self.tally.add(r.extra["tilt"], r.feasible)
        poses = chunk_poses(design, P, self.ori)
        if design.motion.rotational:  # the orientation columns hold the hanging orientation
            poses[:, design.motion.dim:] = r.hanging.orientation.reshape(cnt, -1)
        extra, maps = dict(r.extra), {"tilt": r.extra["tilt"]}
        if r.collisions is not None:
            self._count_collisions(r)
            extra["collision_free"] = (r.collisions == 0).astype(np.uint8)
        if self.robot.analysis.stiffness:
            ok = r.feasible.astype(bool)
            for name in self.STIFFNESS:
                v = np.where(ok, getattr(r.stiffness, name), np.nan)
                extra[name] = v
                self.least[name] = min(self.least[name], float(np.fmin.reduce(v, initial=math.inf)))
            maps.update({name: extra[name] for name in self.STIFFNESS[:2]})
        if self.sagging:
            extra.update(self._cable_columns(r))
        return Rows(r.feasible, r.margin, r.tensions, r.lengths, extra, maps, poses)

    def _cable_columns(self, r: FreeRows) -> dict:
        """The sagging cables' columns (:func:`cdpr_design.workspaces.cables.cable_columns`), empty
        where the row is infeasible (as its tensions), and their summary tallies."""
        ok = r.feasible.astype(bool)[:, None]
        c = r.cables
        out = {}
        names = self.robot.design.cable_names
        for prefix, v in (("outlet_tension", c.outlet_tensions), ("unstretched_length", c.unstretched),
                          ("sag", c.sag)):
            v = np.where(ok, v, np.nan)
            out.update({f"{prefix}_{n}": v[:, i] for i, n in enumerate(names)})
        out["cable_status"] = r.cable_status
        self.outlet_peak = np.fmax(self.outlet_peak, np.fmax.reduce(np.where(ok, c.outlet_tensions, np.nan), axis=0,
                                                                     initial=-np.inf))
        self.status_counts += np.bincount(r.cable_status, minlength=5)[:5]
        return out

    def _count_collisions(self, r: FreeRows) -> None:
        from cdpr_design.statics.interference import HIT_NAMES

        upright = r.within if self.robot.tilt_limit is None else \
            r.within & within_tilt(r.judged_tilt, self.robot.tilt_limit)
        self.n_stat += int(np.count_nonzero(upright))
        self.n_free += int(np.count_nonzero(r.collisions == 0))
        for bit, name in HIT_NAMES.items():
            self.counts[name] = self.counts.get(name, 0) + int(np.count_nonzero(r.collisions & bit))

    def summary(self, maps) -> dict:
        out = self.tally.summary(self.robot, self.robot.tilt_limit)
        a = self.robot.analysis
        if a.collisions:
            from cdpr_design.statics.interference import HIT_NAMES

            out.update(interference=True, collision_free=self.n_free, feasible_statics=self.n_stat,
                       collisions_by_kind={name: self.counts.get(name, 0) for name in HIT_NAMES.values()})
        if a.stiffness:
            out.update({k: (v if math.isfinite(v) else None) for k, v in self.least.items()})
        if self.sagging:
            out.update(cable_summary(self.robot, self.status_counts,
                                     np.where(np.isfinite(self.outlet_peak), self.outlet_peak, np.nan)))
        return out

    def finish(self, result, maps) -> None:
        result.hanging = HangingMaps(maps.xmaps["tilt"], self.robot.design.effector.orientation,
                                     self.robot.tilt_limit)
        if self.robot.analysis.stiffness:
            result.stiffness = {name: maps.xmaps[name] for name in self.STIFFNESS[:2]}


def free_pose(robot: Robot, position) -> FreeRows:
    """:func:`free_rows` at one position [m] of a hanging robot (``effector.orientation: free``),
    about ``workspace.orientation``, with the robot's tilt limit."""
    design = robot.design
    P = np.zeros((1, 3))
    pos = np.asarray(position, float).ravel()
    P[0, : pos.size] = pos
    return free_rows(robot, P, Hanger(robot, design.default_orientation_full()))
