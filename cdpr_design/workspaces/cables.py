"""Workspace sweeps with elastic and sagging cables (:mod:`cdpr_design.statics.cables`).

- ``elastic``: the straight-cable sweep's rows, with the unstretched lengths
  L / (1 + T/EA) added to each chunk (the wrapper :class:`ElasticColumns`).
- ``sagging``: every pose solved with elastic catenaries by the batched
  kernel :func:`cdpr_design.kernels.sagging.sweep_grid_sagging`
  (the base evaluator :class:`SaggingSweep`); each chunk carries the outlet
  tensions, unstretched lengths, sag and a ``cable_status`` per pose; with interference
  checks (``--collisions``) the poses go through
  :func:`cdpr_design.kernels.sag_clearance.sag_rows_at` (:class:`SagPoints`), which checks
  the converged catenaries, and the orientation workspaces evaluate each orientation with it.

Extra ``workspace.csv`` columns, per cable c: ``outlet_tension_<c>`` [N],
``unstretched_length_<c>`` [m], ``sag_<c>`` [m]; sagging sweeps add
``cable_status`` (:data:`cdpr_design.statics.cables.STATUS` index: 0 ok,
1 no tensions, 2 no catenary, 3 not converged, 4 singular).
"""

from __future__ import annotations

import numpy as np

from cdpr_design.model.design import Grid
from cdpr_design.statics import cables
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.interference import HIT_NAMES, sagging_clearance
from cdpr_design.statics.wrenches import wrench_vertices
from cdpr_design.statics.robot import Robot
from cdpr_design.workspaces.grid import Rows, grid3
from cdpr_design.workspaces.parts import Base, Wrapper


def _extra(robot: Robot, outlet, L0, sag, status=None) -> dict:
    out = {}
    names = robot.design.cable_names
    for i, c in enumerate(names):
        out[f"outlet_tension_{c}"] = outlet[:, i]
    for i, c in enumerate(names):
        out[f"unstretched_length_{c}"] = L0[:, i]
    for i, c in enumerate(names):
        out[f"sag_{c}"] = sag[:, i]
    if status is not None:
        out["cable_status"] = status
    return out


def cable_state(robot: Robot, r: Rows, k: int) -> cables.CableState | None:
    """The :class:`~cdpr_design.statics.cables.CableState` of row ``k`` of ``r``, read back from the
    cable model's columns (:func:`cable_columns`); None where the rows have none (ideal cables)."""
    names = robot.design.cable_names
    if not names or f"outlet_tension_{names[0]}" not in r.extra:
        return None

    def per_cable(prefix):
        return np.array([r.extra[f"{prefix}_{c}"][k] for c in names], dtype=float)

    status = int(r.extra["cable_status"][k]) if "cable_status" in r.extra else 0
    return cables.CableState(per_cable("outlet_tension"), per_cable("unstretched_length"), per_cable("sag"),
                             cables.STATUS[status])


class CableSummary(Wrapper):
    """The summary keys of a non-ideal cable model over straight cables: ``cable_model`` and
    ``max_outlet_tension_per_cable`` (the outlet tension is the effector's); no columns (an
    orientation workspace's rows stand for a set of orientations, not one pose whose cables a
    winch pays out)."""

    positions = False

    def summary(self, maps) -> dict:
        peak = maps.tpeak.copy()
        peak[~np.isfinite(peak)] = np.nan
        return cable_summary(self.robot, None, peak)


class ElasticColumns(CableSummary):
    """Elastic cables over straight-cable rows: the columns outlet tension = tension, no sag,
    unstretched length L / (1 + T/EA)."""

    def __init__(self, robot: Robot):
        super().__init__(robot)
        self.columns = tuple(cable_columns(robot))

    def add(self, r: Rows, start: int, P: np.ndarray) -> None:
        s = cables.straight_state(self.robot, r.lengths, r.tensions)
        r.extra.update(_extra(self.robot, s.outlet_tensions, s.unstretched_lengths, s.sag))


class ChordColumns(Wrapper):
    """Sagging cables under ``wrench-closure``: closure ignores the tensions (as they grow without
    bound every catenary straightens onto its chord), so the rows are the chords' and the cables
    have no shapes: the sagging columns are empty and ``cable_status`` is 0 (nothing was solved
    that could fail).  Draws ``cable_models.png``."""

    pictures = ("cable_models.png",)
    positions = False

    def __init__(self, robot: Robot):
        super().__init__(robot)
        self.columns = tuple(cable_columns(robot))

    def add(self, r: Rows, start: int, P: np.ndarray) -> None:
        empty = np.full(r.tensions.shape, np.nan)
        r.extra.update(_extra(self.robot, empty, empty, empty, np.zeros(len(empty), dtype=np.int8)))

    def summary(self, maps) -> dict:
        return cable_summary(self.robot, None, None)


def cable_columns(robot: Robot) -> list[str]:
    """The table columns a non-ideal cable model adds, per cable c: ``outlet_tension_<c>`` [N],
    ``unstretched_length_<c>`` [m], ``sag_<c>`` [m]; sagging cables add ``cable_status``
    (an index into :data:`cdpr_design.statics.cables.STATUS`)."""
    return robot.cables.state_columns(robot.design.cable_names)


def cable_summary(robot: Robot, status_counts: np.ndarray | None, outlet_peak: np.ndarray | None) -> dict:
    """The keys a non-ideal cable model adds to the workspace summary."""
    out: dict = {"cable_model": robot.cables.name}
    if status_counts is not None:
        out["cable_status"] = {name: int(n) for name, n in zip(cables.STATUS, status_counts)}
    if outlet_peak is not None:
        out["max_outlet_tension_per_cable"] = {
            c: (float(v) if np.isfinite(v) else None) for c, v in zip(robot.design.cable_names, outlet_peak)}
    return out


class SagPoints:
    """Sagging statics at explicit positions, one orientation at a time, with (the analysis's
    ``collisions``) the interference of the converged catenaries
    (:func:`cdpr_design.kernels.sag_clearance.sag_rows_at`).  Called as the straight cables'
    :class:`~cdpr_design.workspaces.hardware.Evaluator` is (the orientation workspaces), it also
    keeps the cable model's summary figures: poses per status and the largest outlet tension of
    a feasible pose (:meth:`summary`)."""

    def __init__(self, robot: Robot):
        self.robot, self.design = robot, robot.design
        self.scl = sagging_clearance(robot, False) if robot.analysis.collisions else None
        self._at: dict = {}
        self.counts = np.zeros(len(cables.STATUS), dtype=np.int64)
        self.opeak = np.full(robot.m, -np.inf)

    def _statics(self, ori: np.ndarray) -> tuple:
        """(R, Rb, the kernels' SagRobot) at orientation ``ori`` (3,) [rad], made once each."""
        key = tuple(float(v) for v in ori)
        if key not in self._at:
            r = self.robot
            R = np.ascontiguousarray(kin.rotation_matrix(*ori))
            wreq = wrench_vertices(r.design, r.kind, np.asarray(ori, float))
            self._at[key] = (R, np.ascontiguousarray(r.attachments @ R.T), cables.sag_robot(r, wreq, r.kcode))
        return self._at[key]

    def rows(self, P: np.ndarray, ori: np.ndarray):
        """The kernel's :data:`~cdpr_design.kernels.sag_clearance.SagRows` at positions ``P`` (k, 3)
        [m] and orientation ``ori`` (3,) [rad] (the cables' shapes not kept)."""
        from cdpr_design.kernels import sag_clearance as KC

        R, Rb, srob = self._statics(ori)
        k, m = P.shape[0], self.robot.m
        out = KC.SagRows(np.empty(k, dtype=np.uint8), np.empty(k), *(np.empty((k, m)) for _ in range(5)),
                         np.empty(k, dtype=np.int8), np.empty(k, dtype=np.uint8), np.empty((0, m, 3)))
        KC.sag_rows_at(np.ascontiguousarray(P, dtype=float), Rb, R, srob, self.scl, out)
        return out

    def __call__(self, P: np.ndarray, ori, full: bool = True):
        """(feasible uint8, margin [N], tensions [N], lengths [m], mask uint8) at positions ``P``
        (k, 3) [m] and orientation ``ori`` [rad], as
        :class:`~cdpr_design.workspaces.hardware.Evaluator`: ``feasible`` the statics' alone,
        ``mask`` the interference bits (zero when not checked)."""
        o = self.last = self.rows(P, np.asarray(ori, float))
        self.counts += np.bincount(o.status, minlength=len(cables.STATUS))
        f = o.feasible.astype(bool)
        if f.any():
            np.fmax(self.opeak, o.outlet[f].max(axis=0), out=self.opeak)
        return o.feasible, o.margin, o.tensions, o.lengths, o.mask

    def nominal(self) -> tuple:
        """The last call's statics as :attr:`~cdpr_design.workspaces.grid.Rows.nominal`: (effector
        tensions (k, m) [N], the columns ``outlet_tension_<c>`` [N], ``unstretched_length_<c>`` [m])."""
        o = self.last
        return o.tensions.copy(), _extra(self.robot, o.outlet, o.L0, o.sag)

    def summary(self) -> dict:
        """``cable_model``, ``cable_status`` (evaluated poses per status) and
        ``max_outlet_tension_per_cable`` (over the feasible ones)."""
        opeak = self.opeak.copy()
        opeak[~np.isfinite(opeak)] = np.nan
        return cable_summary(self.robot, self.counts, opeak)


class SaggingSweep(Base):
    """The base evaluator of sagging cables from point outlets at one orientation ``ori`` (3,)
    [rad] (not wrench closure, which takes the chords): every pose solved with elastic
    catenaries by :func:`cdpr_design.kernels.sagging.sweep_grid_sagging`, or, with the
    analysis's ``collisions``, at the chunk's positions by :class:`SagPoints`, which checks the
    interference of the converged catenaries.  Rows are independent of the chunking: every pose
    starts from its own straight solution.  Summary keys: ``cable_model``, ``cable_status``
    (poses per status), ``max_outlet_tension_per_cable``; with interference as
    :class:`~cdpr_design.workspaces.hardware.HardwareSweep`'s (``feasible`` statics-feasible and
    collision free, tensions blanked where a pose collides, column ``collision_free``: 0 also
    where the shapes did not converge, so nothing was checked)."""

    pictures = ("cable_models.png",)
    positions = False  # the kernel works from the grid's indices

    def __init__(self, robot: Robot, ori: np.ndarray, g: Grid):
        from cdpr_design.kernels import sagging as KS

        self.robot, self.kind, self.kernel, self.outputs = robot, robot.kind, KS.sweep_grid_sagging, KS.GridOutputs
        self.ori = np.asarray(ori, float)
        self.interference = bool(robot.analysis.collisions)
        self.columns = tuple(cable_columns(robot)) + (("collision_free",) if self.interference else ())
        self.Rb = np.ascontiguousarray(robot.attachments @ kin.rotation_matrix(*ori).T)
        self.wreq = wrench_vertices(robot.design, robot.kind, ori)
        self.grid = KS.SagGrid(*grid3(g))
        self.sag_robot = cables.sag_robot(robot, self.wreq, robot.kcode)
        self.counts = np.zeros(len(cables.STATUS), dtype=np.int64)
        self.opeak = np.full(robot.m, -np.inf)
        self.points = SagPoints(robot)
        if self.interference:
            self.positions = True  # the interference's rows are solved at the chunk's positions
            self.n_free = self.n_stat = 0
            self.hit_counts = {name: 0 for name in HIT_NAMES.values()}

    def rows(self, start: int, count: int, P: np.ndarray | None) -> Rows:
        r, cnt, m = self.robot, count, self.robot.m
        if self.interference:
            o = self.points.rows(P, self.ori)
            feas, marg, ten, lens, outlet, L0, sag, status = o[:8]
        else:
            feas, marg = np.empty(cnt, dtype=np.uint8), np.empty(cnt)
            ten, lens, outlet, L0, sag = (np.empty((cnt, m)) for _ in range(5))
            status = np.empty(cnt, dtype=np.int8)
            self.kernel(start, cnt, self.grid, self.Rb, self.sag_robot,
                        self.outputs(feas, marg, ten, lens, outlet, L0, sag, status))
        self.counts += np.bincount(status, minlength=len(cables.STATUS))
        extra = _extra(r, outlet, L0, sag, status)
        if self.interference:
            self.n_stat += int(np.count_nonzero(feas))
            cfree = (o.mask == 0).astype(np.uint8)
            self.n_free += int(np.count_nonzero(cfree))
            kind_counts(o.mask, self.hit_counts)
            feas &= cfree
            ten[cfree == 0] = np.nan
            extra["collision_free"] = cfree
        f = feas.astype(bool)
        if f.any():
            np.fmax(self.opeak, outlet[f].max(axis=0), out=self.opeak)
        return Rows(feas, marg, ten, lens, extra)

    def feasible_at(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Feasibility (k,) bool at positions ``P`` (k, 3) [m]: the same pose solve at explicit
        positions (:func:`cdpr_design.kernels.sagging.sag_points`; with interference
        :class:`SagPoints`, collision free too); no margins (NaN)."""
        from cdpr_design.kernels.sagging import sag_points

        k = P.shape[0]
        if self.interference:
            o = self.points.rows(np.ascontiguousarray(P, dtype=float), self.ori)
            return (o.feasible.astype(bool) & (o.mask == 0)), np.full(k, np.nan)
        out = sag_points(P, self.Rb, self.sag_robot, structures=False)
        return out.feasible.astype(bool), np.full(k, np.nan)

    def summary(self, maps) -> dict:
        opeak = self.opeak.copy()
        opeak[~np.isfinite(opeak)] = np.nan
        extra = cable_summary(self.robot, self.counts, opeak)
        if self.interference:
            extra.update(pulleys=False, interference=True, collision_free=self.n_free, feasible_statics=self.n_stat,
                         collisions_by_kind=self.hit_counts)
        return extra


def kind_counts(mask: np.ndarray, counts: dict) -> None:
    """Add to ``counts`` (interference kind -> poses) the poses each kind's bit hits in ``mask``."""
    for bit, name in HIT_NAMES.items():
        counts[name] += int(np.count_nonzero(mask & bit))
