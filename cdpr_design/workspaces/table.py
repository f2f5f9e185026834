"""A whole workspace sweep held in memory, row by row: the Python API's workspace result.

The command line streams a sweep to ``workspace.csv`` chunk by chunk and never
holds the grid; a notebook wants the arrays.  :func:`collect` runs the same
sweep (:func:`cdpr_design.workspaces.run`) and keeps every row, refusing
grids above ``max_poses`` rows so that a typo in a step cannot exhaust memory
(about (k + 2 + 2 m) x 8 bytes per pose for k pose coordinates and m cables).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cdpr_design.errors import InputError
from cdpr_design.io.tables import Table
from cdpr_design.model.design import Design
from cdpr_design.statics.robot import Analysis
from cdpr_design.workspaces.grid import Chunk, WorkspaceResult, column_names, make_grid

#: Default largest grid :func:`collect` keeps in memory (poses).
MAX_COLLECT = 5_000_000


@dataclass
class WorkspaceTable(Table):
    """Every grid pose of a workspace sweep, in grid order (C order over x, y[, z]).

    Attributes
    ----------
    poses : (N, k) float
        Pose coordinates (``design.motion.coords``) [m, rad].
    feasible : (N,) bool
    margin : (N,) float
        Capacity margin [N]; negative where infeasible, NaN where W is rank deficient.
    tensions : (N, m) float
        Minimum 2-norm feasible tensions [N]; NaN where infeasible.
    lengths : (N, m) float
        Cable lengths [m].
    extra : dict
        Further columns (``collision_free``, orientation-workspace columns).
    result : WorkspaceResult
        The sweep's summary figures and picture maps (``result.summary()``).
    """

    design: Design
    poses: np.ndarray
    feasible: np.ndarray
    margin: np.ndarray
    tensions: np.ndarray
    lengths: np.ndarray
    result: WorkspaceResult
    extra: dict = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, ...]:
        """The grid's shape (nx, ny[, nz]): ``feasible.reshape(shape)`` is a map."""
        return self.result.grid.shape

    @property
    def boundary(self):
        """The boundary between the grid points (a :class:`~cdpr_design.workspaces.boundary.Boundary`:
        ``measure``, ``surface``, ``loops`` or ``vertices`` and ``faces``)."""
        return self.result.boundary

    @property
    def frame_loads(self):
        """The loads on the frame (a :class:`~cdpr_design.workspaces.frame_loads.FrameLoadTable`:
        ``rows(cable_names)`` is ``frame_loads.csv``, ``summary(cable_names)`` the summary's object)."""
        return self.result.frame_loads

    def summary(self) -> dict:
        """The ``summary.json`` figures of the sweep."""
        return self.result.summary()

    def columns(self) -> dict:
        """The ``workspace.csv`` columns, in its order (name -> (N,) array)."""
        names = column_names(self.design)
        k, m = self.poses.shape[1], self.design.m
        arrays = ([self.poses[:, j] for j in range(k)] + [self.feasible, self.margin]
                  + [self.tensions[:, i] for i in range(m)] + [self.lengths[:, i] for i in range(m)])
        out = dict(zip(names, arrays))
        out.update(self.extra)
        return out


def collect(design: Design, analysis: Analysis | None = None, *, step: float | None = None, grid=None,
            orientation=None, force: bool = False, max_poses: int = MAX_COLLECT) -> WorkspaceTable:
    """Sweep like :func:`cdpr_design.workspaces.run` (``analysis``, ``step`` [m], ``grid``,
    ``orientation`` [rad], ``force`` as there) and keep every row.

    The boundary between the grid points and the frame loads come with it (``boundary``,
    ``frame_loads``; summary keys ``boundary_measure``, ``boundary_surface``, ``frame_loads``).
    Raises :class:`InputError` when the grid holds more than ``max_poses``
    poses (raise it, or stream with ``on_chunk``, for larger grids).
    """
    from cdpr_design import workspaces as ws

    g = grid if grid is not None else make_grid(design, step, force)
    if g.size > max_poses:
        raise InputError(f"max_poses: the grid has {g.size:,} poses, more than the {max_poses:,} kept in "
                         "memory; raise max_poses, coarsen the step, or stream the rows with on_chunk")
    chunks: list[Chunk] = []
    res = ws.run(design, analysis, grid=g, orientation=orientation, force=force, on_chunk=chunks.append, solid=True)
    extra_names = list(chunks[0].extra) if chunks else []
    return WorkspaceTable(
        design=design,
        poses=np.concatenate([c.poses for c in chunks]),
        feasible=np.concatenate([c.feasible for c in chunks]).astype(bool),
        margin=np.concatenate([c.margin for c in chunks]),
        tensions=np.concatenate([c.tensions for c in chunks]),
        lengths=np.concatenate([c.lengths for c in chunks]),
        result=res,
        extra={k: np.concatenate([c.extra[k] for c in chunks]) for k in extra_names},
    )
