"""The sweep plan: what a workspace sweep of a resolved robot computes, declared before it runs.

:func:`plan` composes, for a :class:`~cdpr_design.statics.robot.Robot` and a grid,

- one **base evaluator**, which computes the rows of a chunk of positions:
  straight cables from point outlets (numpy closed form or kernels,
  :mod:`~cdpr_design.workspaces.engine`), swivel pulleys and interference
  (:mod:`~cdpr_design.workspaces.hardware`), sagging cables
  (:mod:`~cdpr_design.workspaces.cables`), a hanging effector
  (:mod:`~cdpr_design.workspaces.hanging`) or orientation sets
  (:mod:`~cdpr_design.workspaces.orientation`);
- **wrappers**, which add columns to those rows: the elastic cables' unstretched
  lengths, the chords of sagging cables under wrench closure, the tilt a held
  under-constrained effector would hang with, the stiffness, the acceleration radius.

Each part declares its table columns, its maps, its pictures and its summary keys;
:attr:`Plan.columns` and :attr:`Plan.pictures` are what the jobs write, known before
the sweep, and :meth:`Plan.run` is the one chunk loop of every sweep.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from cdpr_design.model.design import Grid
from cdpr_design.statics.robot import Robot
from cdpr_design.workspaces import cables, engine, hanging
from cdpr_design.workspaces.boundary import BoundaryField
from cdpr_design.workspaces.frame_loads import FrameLoads
from cdpr_design.workspaces.grid import (CHUNK, Chunk, Maps, Rows, WorkspaceResult, chunk_poses, column_names,
                                         positions3)
from cdpr_design.workspaces.parts import Base, Part, Wrapper


@dataclass
class Plan:
    """A sweep of ``robot`` over ``grid`` at orientation ``orientation`` (3,) [rad]: ``base`` and
    ``wrappers`` (see the module doc); ``kind`` is the result's kind."""

    robot: Robot
    grid: Grid
    orientation: np.ndarray
    base: Base
    wrappers: tuple[Wrapper, ...] = ()
    #: the options :func:`plan` was given (:meth:`on` makes the same plan for another grid)
    tilt: bool = True
    orientations: np.ndarray | None = None
    solid: bool = False
    frame_loads: bool = False

    def on(self, grid: Grid) -> "Plan":
        """The same plan (robot, orientation, options) over another grid."""
        return plan(self.robot, grid, self.orientation, tilt=self.tilt, orientations=self.orientations,
                    solid=self.solid, frame_loads=self.frame_loads)

    def point_test(self) -> Callable[[np.ndarray], tuple]:
        """The feasibility test of the plan's robot at any positions, at the plan's orientation: a
        function of ``P`` (k, 3) [m] giving feasibility (k,) bool and the capacity margin (k,) [N]
        (NaN where there is none), the base evaluator's own
        (:meth:`~cdpr_design.workspaces.parts.Base.feasible_at`) on a new plan over the same grid,
        so that the sweep's tallies are left alone."""
        return plan(self.robot, self.grid, self.orientation, tilt=False, orientations=self.orientations).base.feasible_at

    @property
    def parts(self) -> tuple[Part, ...]:
        return (self.base,) + tuple(self.wrappers)

    @property
    def extra_columns(self) -> list[str]:
        """The table columns after the contract's, in order."""
        return [c for p in self.parts for c in p.columns]

    @property
    def columns(self) -> list[str]:
        """Every table column, in order: the contract's (:func:`column_names`), then the parts'."""
        return column_names(self.robot.design) + self.extra_columns

    @property
    def pictures(self) -> list[str]:
        """The picture files of the sweep (``workspace.png``, ``tension_map.png``, then the parts')."""
        names = ["workspace.png", "tension_map.png"]
        for p in self.parts:
            names += [n for n in p.pictures if n not in names]
        return names

    @property
    def reads_positions(self) -> bool:
        """Whether a part reads the chunks' positions (:attr:`~cdpr_design.workspaces.parts.Part.positions`)."""
        return any(p.positions for p in self.parts)

    def rows(self, start: int, count: int, P: np.ndarray | None = None) -> Rows:
        """The rows of grid positions ``start .. start + count`` (at ``P`` (count, 3) [m], computed
        here when a part reads them and they are not given): the base evaluator's, with every
        wrapper's columns.  The body of :meth:`run`'s chunk loop, and the whole of a one-pose
        evaluation (:func:`cdpr_design.workspaces.pose.evaluate_pose`)."""
        if P is None and self.reads_positions:
            P = positions3(self.grid, start, count)
        r = self.base.rows(start, count, P)
        for w in self.wrappers:
            w.add(r, start, P)
        return r

    def run(self, on_chunk: Callable[[Chunk], None] | None = None,
            progress: Callable[[int, int], None] | None = None, chunk: int = CHUNK,
            keep_maps: bool = True) -> WorkspaceResult:
        """Sweep the grid chunk by chunk (bounded memory): each :class:`Chunk` goes to ``on_chunk``
        in grid order, ``progress(done, total)`` after each; returns the result."""
        t0 = time.perf_counter()
        robot, g = self.robot, self.grid
        design = robot.design
        maps = Maps(g, design.m, keep_maps, extra_maps=tuple(n for p in self.parts for n in p.maps))
        names = self.extra_columns
        wants_positions = on_chunk is not None or self.reads_positions
        total = g.size
        chunk = max(1, min(chunk, total, self.base.max_rows or chunk))
        done = 0
        while done < total:
            cnt = min(chunk, total - done)
            P = positions3(g, done, cnt) if wants_positions else None
            r = self.rows(done, cnt, P)
            maps.add(done, self.base.stats(r, maps.tpeak), r.feasible, r.margin, r.tensions, r.maps)
            if on_chunk is not None:
                poses = r.poses if r.poses is not None else chunk_poses(design, P, self.orientation)
                on_chunk(Chunk(done, poses, r.feasible, r.margin, r.tensions, r.lengths,
                               extra={name: r.extra[name] for name in names}))
            done += cnt
            if progress is not None:
                progress(done, total)
        extra: dict = {}
        for p in self.parts:
            extra.update(p.summary(maps))
        result = maps.result(design, self.base.kind, self.orientation, t0, extra)
        result.robot, result.pictures = robot, self.pictures
        for p in self.parts:
            p.finish(result, maps)
        return result


def plan(robot: Robot, grid: Grid, orientation=None, *, tilt: bool = True, orientations=None,
         solid: bool = False, frame_loads: bool = False) -> Plan:
    """The :class:`Plan` of a workspace sweep of ``robot`` over ``grid`` at ``orientation`` (3,) [rad]
    (default ``workspace.orientation``; with ``robot.analysis.orientations`` the nominal one).

    ``tilt``: False leaves out the tilt a *held* under-constrained effector would hang with (a
    figure only; a hanging effector's orientation is always found: its statics depend on it).
    ``orientations`` (q, 3) [rad]: the ``total`` mode's set (default ``workspace.orientation_set``).
    ``solid``: also the boundary between the grid points and the loads on the frame
    (:mod:`~cdpr_design.workspaces.boundary`, :mod:`~cdpr_design.workspaces.frame_loads`);
    ``frame_loads``: the loads on the frame alone.
    """
    p = _plan(robot, grid, orientation, tilt, orientations)
    if not (solid or frame_loads):
        return p
    parts: tuple = (FrameLoads(robot, p.orientation, inline=p.base.keep_frame_loads()),)
    if solid:
        parts += (BoundaryField(robot, grid, p.point_test),)
    return dataclasses.replace(p, wrappers=p.wrappers + parts, solid=solid, frame_loads=frame_loads)


def _plan(robot: Robot, grid: Grid, orientation, tilt: bool, orientations) -> Plan:
    """:func:`plan` without the ``solid`` parts."""
    design = robot.design
    ori = design.default_orientation_full() if orientation is None else np.asarray(orientation, float)
    a = robot.analysis
    wrappers: list[Wrapper] = []
    if a.orientations is not None:
        from cdpr_design.workspaces.orientation import OrientationSweep  # the kernels' package, on first use

        base: Base = OrientationSweep(robot, ori, orientations)
        if not robot.cables.rigid and not robot.cables.sags(a.kind):  # straight: the same statics
            wrappers.append(cables.CableSummary(robot))
        return Plan(robot, grid, ori, base, tuple(wrappers), tilt, orientations)
    if robot.orientation.free:  # elastic cables: the unstretched lengths that hold it there
        wrappers = [cables.ElasticColumns(robot)] if robot.cables.stretches else []
        return Plan(robot, grid, ori, hanging.FreeSweep(robot, ori, grid), tuple(wrappers), tilt, orientations)
    if robot.cables.sags(a.kind):
        base = cables.SaggingSweep(robot, ori, grid)
    elif a.collisions or robot.outlets.pulleys:
        from cdpr_design.workspaces.hardware import HardwareSweep  # the kernels' package, on first use

        base = HardwareSweep(robot, ori)
    else:
        base = engine.StraightSweep(robot, ori, grid)
    if robot.cables.stretches:
        wrappers.append(cables.ElasticColumns(robot))
    elif robot.cables.chords(a.kind):
        wrappers.append(cables.ChordColumns(robot))
    if robot.orientation.tilt_beside and tilt:
        wrappers.append(hanging.HeldTilt(robot, ori))
    elif tilt:
        wrappers.append(hanging.Classification(robot))
    if a.stiffness:
        from cdpr_design.workspaces.stiffness import StiffnessColumns  # the kernels, on first use

        wrappers.append(StiffnessColumns(robot, ori, grid))
    if a.accelerations:
        from cdpr_design.workspaces.acceleration import AccelerationColumns  # the kernels, on first use

        wrappers.append(AccelerationColumns(robot, ori))
    return Plan(robot, grid, ori, base, tuple(wrappers), tilt, orientations)
