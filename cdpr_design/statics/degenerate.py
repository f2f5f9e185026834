"""Degenerate poses: a cable of zero length has no direction, so the pose is infeasible.

The rule of the ``pose`` command and of every workspace sweep (the kernels'
``structure_matrix`` returns ``ok = False``): a cable whose free length is at
most :data:`MIN_CABLE_LENGTH` cannot pull in any direction; its column of
the structure matrix is zero, no tensions are reported and the pose is not
feasible, whatever a solver would make of the rounding noise in its
direction.  Trajectory samples and motor sizing apply the same rule through
:func:`directions` and :func:`degenerate`.
"""

from __future__ import annotations

import numpy as np

#: Free cable length [m] at or below which a cable has no direction (= the kernels' threshold).
MIN_CABLE_LENGTH = 1e-12


def directions(vec: np.ndarray, free_lengths: np.ndarray) -> np.ndarray:
    """Unit pulling directions vec / |vec| (..., 3), zero where the free length [m] is at most
    :data:`MIN_CABLE_LENGTH` (or not a number)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        u = vec / free_lengths[..., None]
    u = np.nan_to_num(u)
    u[~(free_lengths > MIN_CABLE_LENGTH)] = 0.0
    return u


def degenerate(u: np.ndarray) -> np.ndarray:
    """Poses (k,) with a cable without direction, from directions ``u`` (k, m, 3) made by
    :func:`directions`: those poses are infeasible."""
    return ~np.all(np.any(u != 0.0, axis=2), axis=1)


def degenerate_structure(W: np.ndarray) -> np.ndarray:
    """Poses (k,) whose structure matrix (k, n, m) has a zero column (a cable without direction)."""
    return ~np.all(np.any(W != 0.0, axis=1), axis=1)
