"""Workspaces: sweeps of a resolved robot over a grid of poses, in bounded memory.

A command resolves its design once (:func:`cdpr_design.statics.robot.resolve`), makes the
sweep plan (:func:`~cdpr_design.workspaces.plan.plan`: the base evaluator and the wrappers
the robot's strategies call for, with the table columns and pictures they declare) and runs
it (:meth:`~cdpr_design.workspaces.plan.Plan.run`).  :func:`run` does the three for a design
and an :class:`~cdpr_design.statics.robot.Analysis`, as a script calls it: it returns a
:class:`~cdpr_design.workspaces.grid.WorkspaceResult` and hands every chunk of rows to ``on_chunk``.
"""

from __future__ import annotations

from typing import Callable

from cdpr_design.model.design import Design, Grid
from cdpr_design.statics.robot import ENGINES, KINDS, Analysis, resolve
from cdpr_design.workspaces.engine import StraightSweep
from cdpr_design.workspaces.grid import (CHUNK, MAX_POSES, Chunk, WorkspaceResult, check_grid_size, column_names,
                                         first_pose, make_grid, representative_pose)
from cdpr_design.workspaces.plan import Plan, plan

__all__ = ["CHUNK", "ENGINES", "KINDS", "MAX_POSES", "Analysis", "Chunk", "Plan", "WorkspaceResult",
           "column_names", "make_grid", "plan", "representative_pose", "run", "warm_up"]


def _grid(design: Design, step, grid: Grid | None, force: bool) -> Grid:
    """The grid of a sweep (size checked): ``grid``, else the design's with ``step`` [m]."""
    if grid is None:
        return make_grid(design, step, force)
    check_grid_size(grid, force)
    return grid


def run(design: Design, analysis: Analysis | None = None, *, step: float | None = None, grid: Grid | None = None,
        orientation=None, orientations=None, on_chunk: Callable[[Chunk], None] | None = None,
        progress: Callable[[int, int], None] | None = None, force: bool = False, chunk: int = CHUNK,
        keep_maps: bool = True, tilt: bool = True, solid: bool = False,
        frame_loads: bool = False) -> WorkspaceResult:
    """Sweep the workspace grid and return the summary and maps.

    Parameters
    ----------
    design : Design
    analysis : Analysis, optional
        What is computed (:class:`~cdpr_design.statics.robot.Analysis`, default ``Analysis()``:
        the static workspace): ``kind`` (``static``: gravity only; ``wrench-feasible``: gravity
        plus every vertex of ``workspace.external_wrench``; ``wrench-closure``: tension bounds
        ignored, the cables positively span the wrench space; ``dynamic``: as
        ``wrench-feasible``, and every acceleration of ``requirements.acceleration`` reachable
        from rest, :mod:`cdpr_design.statics.wrenches`); ``collisions``: also the cable-cable,
        cable-effector, effector-frame and cable-frame interference
        (:mod:`cdpr_design.statics.interference`): ``feasible`` becomes statics-feasible *and*
        collision free, chunks carry ``collision_free``, and the summary gains
        ``collision_free``, ``feasible_statics`` and ``collisions_by_kind``; ``orientations``:
        ``total`` (feasible for every orientation of the set) or ``range`` (the largest
        feasible orientation range per position), the orientation workspaces of rotational
        motions (:class:`cdpr_design.workspaces.orientation.OrientationSweep`); ``engine``
        (``auto``, ``numba`` or ``numpy``, for straight cables from point outlets,
        :mod:`~cdpr_design.workspaces.engine`; both give the same results, tested);
        ``max_tilt`` [deg] the largest hanging tilt of a feasible pose (under-constrained
        designs with ``effector.orientation: free``; default ``requirements.max_tilt``);
        ``stiffness``: also the least stiffness [N/m] and the lowest natural frequency [Hz] of
        every feasible pose (:mod:`~cdpr_design.workspaces.stiffness`: columns, maps and summary
        keys); ``accelerations``: also the acceleration radius [m/s^2] of every pose
        (:mod:`~cdpr_design.workspaces.acceleration`: the column ``acceleration_radius``, its
        map and summary keys).
    step : float, optional
        Grid step [m] overriding ``workspace.grid.step``.
    grid : Grid, optional
        Sweep this grid instead of the design's (e.g. the task box).
    orientation : (3,) array, optional
        Fixed (rx, ry, rz) [rad]; default ``workspace.orientation`` (with
        ``analysis.orientations``: the nominal orientation).
    orientations : (q, 3) array, optional
        The orientation set [rad] of ``analysis.orientations='total'`` (default
        ``workspace.orientation_set``).
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
    tilt : bool
        False: leave out the tilt a *held* under-constrained effector would hang
        with (a figure only, and the costliest part of such a sweep: callers that
        use just feasibility, margins and tensions pass False).  A ``free``
        design's hanging orientation is always found: its statics depend on it.
    solid : bool
        Also the boundary between the grid points (``result.boundary``, summary keys
        ``boundary_measure``, ``boundary_surface``; :mod:`~cdpr_design.workspaces.boundary`) and
        the loads on the frame (``result.frame_loads``, summary key ``frame_loads``;
        :mod:`~cdpr_design.workspaces.frame_loads`).
    frame_loads : bool
        The loads on the frame alone (``result.frame_loads``, summary key ``frame_loads``).

    What is computed (cable model, outlets, how the orientation is decided, engine) is the
    robot resolved for ``analysis`` (:func:`~cdpr_design.statics.robot.resolve`: a refused
    combination raises an :class:`~cdpr_design.errors.InputError` with the reason); the sweep is
    its :func:`~cdpr_design.workspaces.plan.plan`.
    """
    g = _grid(design, step, grid, force)
    robot = resolve(design, analysis if analysis is not None else Analysis())
    return plan(robot, g, orientation, tilt=tilt, orientations=orientations, solid=solid,
                frame_loads=frame_loads).run(on_chunk, progress, chunk, keep_maps)


def warm_up(p: Plan) -> None:
    """Sweep the plan's first pose alone, with the same robot: every numba kernel the whole
    sweep will run is loaded from numba's on-disk cache, or compiled on a machine's first run.
    Lets a caller time numba's start-up apart from the sweep."""
    # the frame loads' kernel too; no boundary (a one-pose grid encloses nothing)
    plan(p.robot, first_pose(p.grid), p.orientation, tilt=p.tilt, orientations=p.orientations,
         frame_loads=p.solid or p.frame_loads).run(keep_maps=False)
