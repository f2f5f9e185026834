"""Workspaces: sweeps of a design over a grid of poses, in bounded memory.

:func:`run` sweeps the design's grid at one fixed orientation: straight
cables from point outlets go to :mod:`~cdpr_design.workspaces.engine` (numpy
closed form or numba kernels), swivel pulleys and interference checks to
:mod:`~cdpr_design.workspaces.hardware`.  :func:`run_orientations` sweeps
orientation sets (:mod:`~cdpr_design.workspaces.orientation`).  Both return
a :class:`~cdpr_design.workspaces.grid.WorkspaceResult` and hand every chunk
of rows to ``on_chunk``.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from cdpr_design.model.design import Design, Grid
from cdpr_design.statics import cables as cable_models
from cdpr_design.statics import kinematics as kin
from cdpr_design.statics.pose import KINDS, check_kind
from cdpr_design.workspaces import hanging
from cdpr_design.workspaces.cables import ChordColumns, ElasticColumns, cable_summary, sweep_sagging
from cdpr_design.workspaces.engine import ENGINES, check_engine, load_kernels, resolve
from cdpr_design.workspaces.engine import sweep as straight_sweep
from cdpr_design.workspaces.grid import (CHUNK, MAX_POSES, Chunk, WorkspaceResult, check_grid_size, chunk_extra,
                                         column_names, extra_columns, first_pose, make_grid,
                                         representative_pose)

__all__ = ["CHUNK", "ENGINES", "KINDS", "MAX_POSES", "Chunk", "WorkspaceResult", "chunk_extra", "column_names", "extra_columns",
           "load_kernels", "make_grid", "representative_pose", "run", "run_orientations", "warm_up"]


def _setup(design: Design, kind: str, step, grid: Grid | None, orientation, force: bool):
    """The grid (size checked) and full orientation (3,) [rad] of a sweep."""
    check_kind(kind)
    g = grid if grid is not None else make_grid(design, step, force)
    if grid is not None:
        check_grid_size(g, force)
    ori = design.default_orientation_full() if orientation is None else np.asarray(orientation, float)
    return g, ori


def run(design: Design, kind: str = "static", step: float | None = None, grid: Grid | None = None,
        orientation=None, on_chunk: Callable[[Chunk], None] | None = None,
        progress: Callable[[int, int], None] | None = None, force: bool = False,
        chunk: int = CHUNK, keep_maps: bool = True, interference: bool = False,
        engine: str = "auto", max_tilt: float | None = None, tilt: bool = True) -> WorkspaceResult:
    """Sweep the workspace grid and return the summary and maps.

    Parameters
    ----------
    design : Design
    kind : {'static', 'wrench-feasible', 'wrench-closure'}
        ``static``: gravity only; ``wrench-feasible``: gravity plus every vertex
        of ``workspace.external_wrench``; ``wrench-closure``: tension bounds
        ignored, the cables positively span the wrench space.
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

    Under-constrained designs with ideal cables (:mod:`~cdpr_design.workspaces.hanging`)
    add the tilt their effector hangs with; with ``effector.orientation: free`` their
    feasibility is judged at that hanging orientation.

    The design's cable model (:mod:`cdpr_design.statics.cables`) picks the
    engine: ideal and elastic cables take the straight-cable sweeps (elastic
    adds the unstretched lengths to each chunk), sagging cables the catenary
    sweep of :mod:`~cdpr_design.workspaces.cables`.

    Swivel pulleys (``cables[i].pulley``) are honoured whenever present; a
    design without pulleys and without ``interference`` takes the point-outlet
    engines.
    """
    check_engine(engine)
    g, ori = _setup(design, kind, step, grid, orientation, force)
    if hanging.wanted(design, tilt):  # under-constrained: the tilt it hangs with (`free`: its statics there)
        return hanging.sweep(design, kind, g, ori, lambda oc: _fixed(design, kind, g, ori, oc, progress, chunk,
                                                                     keep_maps, interference, engine),
                             on_chunk=on_chunk, progress=progress, chunk=chunk, keep_maps=keep_maps,
                             interference=interference, engine=engine, max_tilt=max_tilt)
    if max_tilt is not None:
        hanging.tilt_limit(design, max_tilt)  # refused: the design does not hang
    result = _fixed(design, kind, g, ori, on_chunk, progress, chunk, keep_maps, interference, engine)
    if tilt:  # an under-constrained design without a hanging solve is still classified
        result.extra.update(hanging.classification(design))
    return result


def _fixed(design, kind, g, ori, on_chunk, progress, chunk, keep_maps, interference, engine):
    """The sweep at the fixed orientation ``ori`` (3,) [rad], by cable model: pulley- and
    interference-aware, straight, or sagging."""
    model = cable_models.design_model(design)
    cable_models.check_supported(design, pulleys=kin.has_pulleys(design), interference=interference)
    if model == "sagging" and kind != "wrench-closure":
        return sweep_sagging(design, kind, g, ori, on_chunk=on_chunk, progress=progress,
                             chunk=chunk, keep_maps=keep_maps)
    if model != "ideal":  # sagging here: wrench closure, from the chords
        on_chunk = (ChordColumns if model == "sagging" else ElasticColumns)(design, on_chunk)
    if interference or kin.has_pulleys(design):
        from cdpr_design.workspaces.hardware import run_hardware  # numba kernels, loaded on first use

        res = run_hardware(design, kind, g, ori, on_chunk=on_chunk, progress=progress,
                           chunk=chunk, keep_maps=keep_maps, interference=interference)
    else:
        res = straight_sweep(design, kind, g, ori, on_chunk=on_chunk, progress=progress,
                             chunk=chunk, keep_maps=keep_maps, engine=engine)
    if model != "ideal":
        res.extra.update(cable_summary(design, None, res.max_tension if model == "elastic" else None))
    return res


def run_orientations(design: Design, mode: str = "total", kind: str = "static", step: float | None = None,
                     grid: Grid | None = None, orientation=None, orientations=None,
                     on_chunk: Callable[[Chunk], None] | None = None,
                     progress: Callable[[int, int], None] | None = None, force: bool = False,
                     chunk: int = CHUNK, keep_maps: bool = True, interference: bool = False,
                     engine: str = "auto") -> WorkspaceResult:
    """Total orientation workspace (``mode='total'``) or orientation range per position (``'range'``).

    ``orientation`` is the nominal orientation (3,) [rad] (default
    ``workspace.orientation``); ``orientations`` the set (q, 3) [rad] of the
    ``total`` mode (default ``workspace.orientation_set``).  The other
    parameters are those of :func:`run`; ``engine`` is checked but every
    orientation sweep runs the kernels (pulley- and interference-aware).
    See :func:`cdpr_design.workspaces.orientation.sweep_orientations`.
    """
    check_engine(engine)
    hanging.refuse_commanded_orientations(design)
    cable_models.check_supported(design, pulleys=kin.has_pulleys(design), interference=interference,
                                 orientations=True)
    g, nominal = _setup(design, kind, step, grid, orientation, force)
    from cdpr_design.workspaces.orientation import sweep_orientations  # numba kernels, loaded on first use

    res = sweep_orientations(design, mode, kind, g, nominal, orientations=orientations,
                             on_chunk=on_chunk, progress=progress, chunk=chunk,
                             keep_maps=keep_maps, interference=interference)
    if cable_models.design_model(design) != "ideal":  # elastic: straight, so the same statics
        res.extra.update(cable_summary(design, None, res.max_tension))
    return res


def warm_up(design: Design, kind: str = "static", grid: Grid | None = None, orientations: str | None = None,
            interference: bool = False, engine: str = "auto", max_tilt: float | None = None) -> str:
    """Sweep ``grid``'s first pose alone, as :func:`run` (or, with ``orientations``,
    :func:`run_orientations`) would sweep the whole grid: every numba kernel the whole sweep
    will run is loaded from numba's on-disk cache, or compiled on a machine's first run.

    Lets a caller time numba's start-up apart from the sweep.  Returns the engine to sweep
    ``grid`` with (:func:`~cdpr_design.workspaces.engine.resolve`: the choice of ``auto``
    made for the whole grid, not for one pose).  The other parameters are those of :func:`run`.
    """
    g = grid if grid is not None else make_grid(design)
    engine = resolve(engine, g.size)
    one = first_pose(g)
    if orientations:
        run_orientations(design, orientations, kind=kind, grid=one, keep_maps=False,
                         interference=interference, engine=engine)
    else:
        run(design, kind=kind, grid=one, keep_maps=False, interference=interference, engine=engine,
            max_tilt=max_tilt)
    return engine
