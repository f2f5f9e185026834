"""Rows of ``bridge.csv``: the ``simulation.csv`` layout, one row per bridged cycle."""

from __future__ import annotations

import numpy as np

from cdpr_design.plc.delay import axis_delays


def csv_header(design) -> list[str]:
    """``bridge.csv`` columns: the ``simulation.csv`` layout (cli.md ``simulate``)."""
    coords = list(design.motion.coords)
    names = design.cable_names
    return (["time"] + [f"{c}_target" for c in coords] + coords
            + [f"length_{c}_target" for c in names] + [f"length_{c}" for c in names]
            + [f"tension_{c}" for c in names])


def motion_pose(design, pose) -> np.ndarray:
    """A simulator pose (motion coordinates or the full 6-vector) in motion coordinates."""
    p = np.asarray(pose, dtype=float).reshape(-1)
    k = len(design.motion.coords)
    if p.size == k:
        return p
    if p.size == 6:
        return p[list(design.motion.pose_index)]
    raise ValueError(f"simulator pose has {p.size} numbers, expected {k} or 6")


class RowMaker:
    """Turns (set-points, simulator state) into ``bridge.csv`` rows.

    The target pose is the forward kinematics of the set-point lengths
    (closed form for the paper's planar 2-cable robot, eq. 4-5), warm-started
    from the previous target.  Keeps the last ``keep`` (time, target lengths,
    actual lengths) in memory for :meth:`delay`.
    """

    def __init__(self, design, keep: int = 1 << 20):
        from cdpr_design.statics.kinematics import forward_kinematics

        self.design = design
        self._fk = forward_kinematics
        self._guess = None
        self._last_sp = None
        self._last_target = None
        m = design.m
        self.keep = int(keep)
        self._buf = np.empty((min(self.keep, 4096), 1 + 2 * m))
        self.n = 0

    def target_pose(self, sp) -> np.ndarray:
        if self._last_sp is not None and np.array_equal(sp, self._last_sp):
            return self._last_target
        try:
            r = self._fk(self.design, sp, guess=self._guess)
            p = np.asarray(r.pose, dtype=float)
        except (ValueError, ArithmeticError):
            p = np.full(len(self.design.motion.coords), np.nan)
        if np.all(np.isfinite(p)):
            self._guess = p
        self._last_sp, self._last_target = np.array(sp, copy=True), p
        return p

    def values(self, sp, state) -> list[float]:
        t = float(state.time)
        sp = np.asarray(sp, dtype=float)
        lengths = np.asarray(state.lengths, dtype=float)
        row = [t, *self.target_pose(sp), *motion_pose(self.design, state.pose), *sp, *lengths,
               *np.asarray(state.tensions, dtype=float)]
        if self.n < self.keep:
            if self.n == self._buf.shape[0]:
                self._buf = np.concatenate([self._buf, np.empty_like(self._buf)])[: self.keep]
            self._buf[self.n, 0] = t
            self._buf[self.n, 1:] = np.concatenate([sp, lengths])
            self.n += 1
        return row

    def delay(self) -> dict:
        """Delay [s] of each simulated axis behind its set-point, keyed ``length_<cable>``.

        Cross-correlation of the logged set-point and actual length
        (:func:`cdpr_design.motion.compare.estimate_delay`); None where an axis did
        not move or lags by more than the window searched.
        """
        return axis_delays(self.design.cable_names, self._buf[: self.n, 0],
                           self._buf[: self.n, 1: 1 + self.design.m],
                           self._buf[: self.n, 1 + self.design.m:])


__all__ = ["RowMaker", "csv_header", "motion_pose"]
