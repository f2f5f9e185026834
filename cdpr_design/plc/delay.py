"""Delays of a bridged run: the set-point -> axis motion lag (the seed paper's Table 1).

Three views of the same delay (see :mod:`cdpr_design.plc.bridge`):
:class:`DelayTrace` records the wall-clock times of the set-points read and
of the states written (the end-to-end delay as the PLC sees it);
:func:`axis_delays` compares two logged series, e.g. ``bridge.csv`` in model
time or the test PLC's log.  Both estimate each axis's lag by sub-sample
cross-correlation (:func:`cdpr_design.motion.compare.estimate_delay`).
"""

from __future__ import annotations

import numpy as np


def _delays_on_grid(names, step: float, targets, actuals, max_delay: float) -> dict:
    """Delay [s] of each axis's ``actuals[j]`` behind ``targets[j]`` (series sampled every ``step`` [s]).

    Keyed ``length_<cable>``; None where an axis did not move or lags by more than ``max_delay``
    (:func:`~cdpr_design.motion.compare.estimate_delay` gives no delay beyond its window).
    """
    from cdpr_design.motion.compare import estimate_delay

    out = {}
    for c, x, y in zip(names, targets, actuals):
        d = estimate_delay(step, x, y, max_delay=max_delay)
        out[f"length_{c}"] = float(d) if np.isfinite(d) else None
    return out


class DelayTrace:
    """Wall-clock record of a bridged run: when each set-point was read, when each state was written.

    Bounded memory: the first ``keep`` cycles.
    """

    def __init__(self, keep: int = 1 << 20):
        self.keep = int(keep)
        self._r = None
        self._w = None
        self.nr = 0
        self.nw = 0

    @staticmethod
    def _put(buf, n, keep, row):
        if buf is None:
            buf = np.empty((64, len(row)))
        if n >= keep:
            return buf, n
        if n == buf.shape[0]:
            buf = np.concatenate([buf, np.empty_like(buf)])[:keep]
        buf[n] = row
        return buf, n + 1

    def read(self, t: float, setpoints) -> None:
        """Set-points [m] read at wall time ``t`` [s]."""
        self._r, self.nr = self._put(self._r, self.nr, self.keep, [t, *setpoints])

    def wrote(self, t: float, lengths, model_wall: float) -> None:
        """Axis lengths [m] written at wall time ``t`` [s], standing for wall time ``model_wall``."""
        self._w, self.nw = self._put(self._w, self.nw, self.keep, [t, model_wall, *lengths])

    def delay(self, names, cycle_time: float, max_delay: float = 1.0) -> dict:
        """End-to-end delay [s] of each axis as the PLC sees it, keyed ``length_<cable>``.

        The set-points are taken as read (linear between reads: the value
        the PLC held at the read's time); the axis positions as the PLC sees
        them: each written value held until the next write (zero-order hold).
        The delay is the sub-sample cross-correlation lag between the two
        (:func:`cdpr_design.motion.compare.estimate_delay`) on a uniform grid of
        cycle_time / 4 (at most 1 ms).  Positive: the axes lag the
        set-points.  It includes the model's own lag, the computation and the
        write, and the hold; it leaves out the time a set-point waited in the
        PLC before the read and an actual waited before the PLC's task read
        it (the test PLC's log, ``plc_delay``, sees those too).
        """
        out = {f"length_{c}": None for c in names}
        if self.nr < 8 or self.nw < 8:
            return out
        r, w = self._r[: self.nr], self._w[: self.nw]
        t0, t1 = max(r[0, 0], w[0, 0]), min(r[-1, 0], w[-1, 0])
        if not t1 > t0:
            return out
        g = min(cycle_time / 4, 1e-3)
        g = max(g, (t1 - t0) / (1 << 20))
        grid = t0 + g * np.arange(int((t1 - t0) / g) + 1)
        idx = np.clip(np.searchsorted(w[:, 0], grid, side="right") - 1, 0, w.shape[0] - 1)
        md = min(max_delay, 0.45 * (t1 - t0))
        read = [np.interp(grid, r[:, 0], r[:, 1 + j]) for j in range(len(names))]
        held = [w[idx, 2 + j] for j in range(len(names))]
        return _delays_on_grid(names, g, read, held, md)


def axis_delays(names, t, target, actual, max_delay: float = 1.0) -> dict:
    """Per-axis delay [s] of ``actual`` behind ``target`` (k, m) logged at times ``t`` (k,) [s].

    Both are resampled on a uniform grid
    (:func:`cdpr_design.motion.compare.uniform_grid`); keyed ``length_<cable>``,
    None where unknown (NaN-free).
    """
    from cdpr_design.motion.compare import resample, uniform_grid

    out = {f"length_{c}": None for c in names}
    t = np.asarray(t, float)
    if t.size < 8:
        return out
    grid = uniform_grid(t)
    dt = float(grid[1] - grid[0]) if grid.size > 1 else 0.0
    if not dt > 0:
        return out
    md = min(max_delay, 0.45 * (grid[-1] - grid[0]))
    x = [resample(t, target[:, j], grid) for j in range(len(names))]
    y = [resample(t, actual[:, j], grid) for j in range(len(names))]
    return _delays_on_grid(names, dt, x, y, md)


__all__ = ["DelayTrace", "axis_delays"]
