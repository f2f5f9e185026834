"""The parts a sweep plan is made of (:mod:`cdpr_design.workspaces.plan`): base evaluators,
which compute the rows of a chunk of grid positions, and wrappers, which add columns to them.
Each declares what it adds to the table, the maps, the pictures and the summary."""

from __future__ import annotations

import numpy as np

from cdpr_design.workspaces.grid import Maps, Rows, WorkspaceResult, chunk_stats


class Part:
    """A part of a sweep plan: what it adds to the table, the maps, the pictures and the summary.

    ``columns`` extra table columns (in order), ``maps`` extra maps kept beside the
    feasibility map (name -> float32 map), ``pictures`` the picture files it draws.
    """

    columns: tuple[str, ...] = ()
    maps: tuple[str, ...] = ()
    pictures: tuple[str, ...] = ()
    #: whether it reads the chunk's positions ``P`` (else it is handed None: the evaluators that
    #: work from grid indices spare the sweep computing them)
    positions: bool = True

    def summary(self, maps: Maps) -> dict:
        """The summary keys this part adds, after the sweep (``maps``: its streaming figures)."""
        return {}

    def finish(self, result: WorkspaceResult, maps: Maps) -> None:
        """Attach what this part keeps for the pictures to ``result``."""


class Base(Part):
    """A base evaluator: the rows of chunks of grid positions; ``kind`` the result's kind."""

    kind: str = "static"
    #: the most rows a chunk of this evaluator holds (None: the plan's chunk, whatever it is)
    max_rows: int | None = None

    def rows(self, start: int, count: int, P: np.ndarray | None) -> Rows:
        """The rows of grid positions ``start .. start + count``, at ``P`` (count, 3) [m] (None
        for a part that does not read them, :attr:`Part.positions`)."""
        raise NotImplementedError

    def feasible_at(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Feasibility (k,) bool and capacity margin (k,) [N] (NaN where there is none) at any
        positions ``P`` (k, 3) [m], with the rows' own test (a part that reads positions: its
        :meth:`rows`; the others say how)."""
        r = self.rows(0, P.shape[0], P)
        return r.feasible.astype(bool), np.asarray(r.margin, float)

    def keep_frame_loads(self) -> bool:
        """Have this evaluator compute, with each chunk's rows, the envelope of the loads on the
        frame of its feasible rows (:attr:`~cdpr_design.workspaces.grid.Rows.loads`); returns
        whether it will (by default not: the loads are computed from the rows,
        :class:`~cdpr_design.workspaces.frame_loads.FrameLoads`)."""
        return False

    def stats(self, r: Rows, tpeak: np.ndarray) -> tuple:
        """(feasible count, least margin [N], largest margin [N]) of ``r``; raises ``tpeak`` [N]
        (:func:`~cdpr_design.workspaces.grid.chunk_stats`)."""
        return chunk_stats(r, tpeak)


class Wrapper(Part):
    """A wrapper of ``robot``'s sweep: adds its declared columns (and maps) to a base evaluator's
    rows; one that only adds summary keys keeps the default :meth:`add`, which adds nothing."""

    def __init__(self, robot):
        self.robot = robot

    def add(self, r: Rows, start: int, P: np.ndarray | None) -> None:
        """Fill this wrapper's columns and maps of the chunk ``r`` (grid rows from ``start``)."""
