"""Workspaces: sweeps of a resolved robot over a grid of poses, in bounded memory.

A command resolves its design once (:func:`cdpr_design.statics.robot.resolve`), makes the
sweep plan (:func:`~cdpr_design.workspaces.plan.plan`: the base evaluator and the wrappers
the robot's strategies call for, with the table columns and pictures they declare) and runs
it (:meth:`~cdpr_design.workspaces.plan.Plan.run`).  :func:`run` and :func:`run_orientations`
do the three for a design, as a script calls them; both return a
:class:`~cdpr_design.workspaces.grid.WorkspaceResult` and hand every chunk of rows to
``on_chunk``.
"""

from __future__ import annotations

from typing import Callable

from cdpr_design.model.design import Design, Grid
from cdpr_design.statics.robot import ENGINES, KINDS, Analysis, Robot, resolve
from cdpr_design.workspaces.engine import StraightSweep
from cdpr_design.workspaces.grid import (CHUNK, MAX_POSES, Chunk, WorkspaceResult, check_grid_size, column_names,
                                         first_pose, make_grid, representative_pose)
from cdpr_design.workspaces.plan import Plan, plan

__all__ = ["CHUNK", "ENGINES", "KINDS", "MAX_POSES", "Chunk", "Plan", "WorkspaceResult", "column_names",
           "make_grid", "plan", "representative_pose", "robot_for", "run", "run_orientations",
           "warm_up"]


def robot_for(design: Design, kind: str = "static", interference: bool = False,
              orientations: str | None = None, engine: str = "auto", max_tilt: float | None = None,
              stiffness: bool = False, accelerations: bool = False) -> Robot:
    """The robot of a workspace sweep of ``design`` (refused combinations raise an
    :class:`~cdpr_design.errors.InputError` with the reason; see :func:`~cdpr_design.statics.robot.resolve`)."""
    return resolve(design, Analysis(command="workspace", kind=kind, collisions=interference,
                                    orientations=orientations, max_tilt=max_tilt, engine=engine,
                                    stiffness=stiffness, accelerations=accelerations))


def _grid(design: Design, step, grid: Grid | None, force: bool) -> Grid:
    """The grid of a sweep (size checked): ``grid``, else the design's with ``step`` [m]."""
    if grid is None:
        return make_grid(design, step, force)
    check_grid_size(grid, force)
    return grid


def run(design: Design, kind: str = "static", step: float | None = None, grid: Grid | None = None,
        orientation=None, on_chunk: Callable[[Chunk], None] | None = None,
        progress: Callable[[int, int], None] | None = None, force: bool = False,
        chunk: int = CHUNK, keep_maps: bool = True, interference: bool = False,
        engine: str = "auto", max_tilt: float | None = None, tilt: bool = True,
        stiffness: bool = False, solid: bool = False, frame_loads: bool = False,
        accelerations: bool = False) -> WorkspaceResult:
    """Sweep the workspace grid and return the summary and maps.

    Parameters
    ----------
    design : Design
    kind : {'static', 'wrench-feasible', 'wrench-closure', 'dynamic'}
        ``static``: gravity only; ``wrench-feasible``: gravity plus every vertex
        of ``workspace.external_wrench``; ``wrench-closure``: tension bounds
        ignored, the cables positively span the wrench space; ``dynamic``: as
        ``wrench-feasible``, and every acceleration of ``requirements.acceleration``
        reachable from rest (:mod:`cdpr_design.statics.wrenches`).
    step : float, optional
        Grid step [m] overriding ``workspace.grid.step``.
    grid : Grid, optional
        Sweep this grid instead of the design's (e.g. the task box).
    orientation : (3,) array, optional
        Fixed (rx, ry, rz) [rad]; default ``workspace.orientation``.
    on_chunk : callable, optional
        Called with each :class:`Chunk` in grid order (stream rows to a file).
    progress : callable, optional
        Called as ``progress(done, total)`` after each chunk.
    force : bool
        Sweep grids larger than :data:`MAX_POSES`.
    chunk : int
        Rows per chunk (bounded memory).
    keep_maps : bool
        Keep the (subsampled) maps behind the pictures.
    interference : bool
        Also check cable-cable, cable-effector, effector-frame and cable-frame
        interference (:mod:`cdpr_design.statics.interference`): ``feasible`` becomes
        statics-feasible *and* collision free, chunks carry ``collision_free``,
        and the summary gains ``collision_free``, ``feasible_statics`` and
        ``collisions_by_kind``.
    engine : {'auto', 'numba', 'numpy'}
        For straight cables from point outlets (:mod:`~cdpr_design.workspaces.engine`);
        both engines give the same results (tested).
    max_tilt : float, optional
        Largest hanging tilt [deg] of a feasible pose (under-constrained designs
        with ``effector.orientation: free``; default ``requirements.max_tilt``).
    tilt : bool
        False: leave out the tilt a *held* under-constrained effector would hang
        with (a figure only, and the costliest part of such a sweep: callers that
        use just feasibility, margins and tensions pass False).  A ``free``
        design's hanging orientation is always found: its statics depend on it.
    stiffness : bool
        Also the least stiffness [N/m] and the lowest natural frequency [Hz] of every feasible
        pose (:mod:`~cdpr_design.workspaces.stiffness`): columns, maps and summary keys.
    solid : bool
        Also the boundary between the grid points (``result.boundary``, summary keys
        ``boundary_measure``, ``boundary_surface``; :mod:`~cdpr_design.workspaces.boundary`) and
        the loads on the frame (``result.frame_loads``, summary key ``frame_loads``;
        :mod:`~cdpr_design.workspaces.frame_loads`).
    frame_loads : bool
        The loads on the frame alone (``result.frame_loads``, summary key ``frame_loads``).
    accelerations : bool
        Also the acceleration radius [m/s^2] of every pose (:mod:`~cdpr_design.workspaces.acceleration`):
        the column ``acceleration_radius``, its map and summary keys.

    What is computed (cable model, outlets, how the orientation is decided, engine) is the
    resolved robot's (:func:`~cdpr_design.statics.robot.resolve`); the sweep is its
    :func:`~cdpr_design.workspaces.plan.plan`.
    """
    g = _grid(design, step, grid, force)
    robot = robot_for(design, kind, interference, None, engine, max_tilt, stiffness, accelerations)
    return plan(robot, g, orientation, tilt=tilt, solid=solid, frame_loads=frame_loads).run(on_chunk, progress, chunk,
                                                                                            keep_maps)


def run_orientations(design: Design, mode: str = "total", kind: str = "static", step: float | None = None,
                     grid: Grid | None = None, orientation=None, orientations=None,
                     on_chunk: Callable[[Chunk], None] | None = None,
                     progress: Callable[[int, int], None] | None = None, force: bool = False,
                     chunk: int = CHUNK, keep_maps: bool = True, interference: bool = False,
                     engine: str = "auto", solid: bool = False) -> WorkspaceResult:
    """Total orientation workspace (``mode='total'``) or orientation range per position (``'range'``).

    ``orientation`` is the nominal orientation (3,) [rad] (default
    ``workspace.orientation``); ``orientations`` the set (q, 3) [rad] of the
    ``total`` mode (default ``workspace.orientation_set``).  The other
    parameters are those of :func:`run`; every orientation sweep runs the
    kernels (pulley- and interference-aware).  See
    :class:`cdpr_design.workspaces.orientation.OrientationSweep`.
    """
    g = _grid(design, step, grid, force)
    robot = robot_for(design, kind, interference, mode, engine)
    return plan(robot, g, orientation, orientations=orientations, solid=solid).run(on_chunk, progress, chunk,
                                                                                  keep_maps)


def warm_up(p: Plan) -> None:
    """Sweep the plan's first pose alone, with the same robot: every numba kernel the whole
    sweep will run is loaded from numba's on-disk cache, or compiled on a machine's first run.
    Lets a caller time numba's start-up apart from the sweep."""
    # the frame loads' kernel too; no boundary (a one-pose grid encloses nothing)
    plan(p.robot, first_pose(p.grid), p.orientation, tilt=p.tilt, orientations=p.orientations,
         frame_loads=p.solid or p.frame_loads).run(keep_maps=False)
