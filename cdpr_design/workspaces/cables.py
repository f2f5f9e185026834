"""Workspace sweeps with elastic and sagging cables (:mod:`cdpr_design.statics.cables`).

- ``elastic``: the straight-cable sweep's rows, with the unstretched lengths
  L / (1 + T/EA) added to each chunk (the wrapper :class:`ElasticColumns`).
- ``sagging``: every pose solved with elastic catenaries by the batched
  kernel :func:`cdpr_design.kernels.sagging.sweep_grid_sagging`
  (the base evaluator :class:`SaggingSweep`); each chunk carries the outlet
  tensions, unstretched lengths, sag and a ``cable_status`` per pose.

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


class SaggingSweep(Base):
    """The base evaluator of sagging cables from point outlets at one orientation ``ori`` (3,)
    [rad] (not wrench closure, which takes the chords): every pose solved with elastic
    catenaries by :func:`cdpr_design.kernels.sagging.sweep_grid_sagging`.  Rows are independent
    of the chunking: every pose starts from its own straight solution.  Summary keys:
    ``cable_model``, ``cable_status`` (poses per status), ``max_outlet_tension_per_cable``."""

    pictures = ("cable_models.png",)
    positions = False  # the kernel works from the grid's indices

    def __init__(self, robot: Robot, ori: np.ndarray, g: Grid):
        from cdpr_design.kernels import sagging as KS

        self.robot, self.kind, self.kernel, self.outputs = robot, robot.kind, KS.sweep_grid_sagging, KS.GridOutputs
        self.columns = tuple(cable_columns(robot))
        self.Rb = np.ascontiguousarray(robot.attachments @ kin.rotation_matrix(*ori).T)
        self.wreq = wrench_vertices(robot.design, robot.kind, ori)
        self.grid = KS.SagGrid(*grid3(g))
        self.sag_robot = cables.sag_robot(robot, self.wreq, robot.kcode)
        self.counts = np.zeros(len(cables.STATUS), dtype=np.int64)
        self.opeak = np.full(robot.m, -np.inf)

    def rows(self, start: int, count: int, P: np.ndarray | None) -> Rows:
        r, cnt, m = self.robot, count, self.robot.m
        feas, marg = np.empty(cnt, dtype=np.uint8), np.empty(cnt)
        ten, lens, outlet, L0, sag = (np.empty((cnt, m)) for _ in range(5))
        status = np.empty(cnt, dtype=np.int8)
        self.kernel(start, cnt, self.grid, self.Rb, self.sag_robot,
                    self.outputs(feas, marg, ten, lens, outlet, L0, sag, status))
        self.counts += np.bincount(status, minlength=len(cables.STATUS))
        f = feas.astype(bool)
        if f.any():
            np.fmax(self.opeak, outlet[f].max(axis=0), out=self.opeak)
        return Rows(feas, marg, ten, lens, _extra(r, outlet, L0, sag, status))

    def feasible_at(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Feasibility (k,) bool at positions ``P`` (k, 3) [m]: the same pose solve at explicit
        positions (:func:`cdpr_design.kernels.sagging.sag_points`); no margins (NaN)."""
        from cdpr_design.kernels.sagging import PointOutputs, sag_points

        r, k, m = self.robot, P.shape[0], self.robot.m
        out = PointOutputs(np.empty(k, dtype=np.uint8), np.empty((k, r.n, m)), np.empty((k, m)), np.empty((k, m)),
                           np.empty(k, dtype=np.int8))
        sag_points(np.ascontiguousarray(P, dtype=float), self.Rb, self.sag_robot, out)
        return out.feasible.astype(bool), np.full(k, np.nan)

    def summary(self, maps) -> dict:
        opeak = self.opeak.copy()
        opeak[~np.isfinite(opeak)] = np.nan
        return cable_summary(self.robot, self.counts, opeak)
