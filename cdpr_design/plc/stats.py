"""Streaming statistics of durations (bounded memory on runs of any length)."""

from __future__ import annotations

import math

import numpy as np

_EDGES = np.logspace(-7, 2, 901)  # 1e-7 .. 1e2 s, 1 % bins


class StreamStats:
    """Mean, max and p99 of a stream of durations [s] in bounded memory.

    The percentile comes from a histogram with logarithmic bins 1 % wide
    (1e-7 s to 100 s), so it is exact to within 1 %.
    """

    def __init__(self):
        self.count = 0
        self.total = 0.0
        self.max = 0.0
        self.hist = np.zeros(_EDGES.size + 1, dtype=np.int64)

    def add(self, v: float) -> None:
        self.count += 1
        self.total += v
        if v > self.max:
            self.max = v
        self.hist[int(np.searchsorted(_EDGES, v))] += 1

    def percentile(self, q: float) -> float:
        if not self.count:
            return math.nan
        k = int(np.searchsorted(np.cumsum(self.hist), math.ceil(q / 100 * self.count)))
        if k == 0:
            return float(_EDGES[0])
        if k >= _EDGES.size:
            return self.max
        return float(min(_EDGES[k], self.max))  # upper edge of the bin

    def summary(self) -> dict:
        if not self.count:
            return {"mean": None, "p99": None, "max": None, "count": 0}
        return {"mean": self.total / self.count, "p99": self.percentile(99.0),
                "max": self.max, "count": self.count}


__all__ = ["StreamStats"]
