"""The hanging orientation of a planar body on two cables over a grid, from the reference kernel.

The tests' tilt map of a design (the published figures of planar2 in
tests/test_hanging.py): every position of a grid over the frame through
:func:`tests.reference.hanging_kernel.hanging_tilt_batch`.  The product's grid of
the hanging tilt is the workspace sweep's (``tilt`` column, ``tilt_map.png``);
this stays beside the tests as the kernel's plain wrapper.  Units: SI (m, N,
rad); ``tilt_deg`` in degrees.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cdpr_design.statics.hanging import design_arrays
from cdpr_design.statics.hanging.geometry import checked_geometry
from tests.reference import hanging_kernel as K


@dataclass(frozen=True)
class TiltMap:
    """Hanging orientation over a grid of positions (planar body on two cables).

    ``axes`` the x and y samples [m]; ``phi`` [rad], ``tilt_deg`` [deg],
    ``tensions`` [N] (..., 2) and ``status`` (``hanging_kernel.TILT_*``) on the
    grid (shape (nx, ny)); ``within_limits`` where the hanging tensions respect
    the design's limits.
    """

    axes: tuple
    phi: np.ndarray
    tensions: np.ndarray
    status: np.ndarray
    within_limits: np.ndarray

    @property
    def tilt_deg(self) -> np.ndarray:
        return np.degrees(np.abs(self.phi))

    @property
    def feasible(self) -> np.ndarray:
        return self.status == K.TILT_OK


def tilt_map(design, step: float = 0.01) -> TiltMap:
    """The hanging orientation of a planar two-cable ``design`` over its frame every ``step`` [m]
    (planar2: 151 x 151 positions)."""
    A, B, c, mass, g, planar = design_arrays(design)
    geo = checked_geometry(A, B, c, mass, g, True)
    assert planar and geo.m == 2
    lo, hi = design.frame_lower, design.frame_upper
    axes = tuple(lo[k] + step * np.arange(int(np.floor((hi[k] - lo[k]) / step + 1e-9)) + 1) for k in range(2))
    X, Y = np.meshgrid(axes[0], axes[1], indexing="ij")
    P = np.ascontiguousarray(np.column_stack([X.ravel(), Y.ravel()]))
    phi, t, _, status, _ = K.hanging_tilt_batch(geo.A, geo.B, geo.c, geo.mass, geo.g, P)
    shape = X.shape
    t = t.reshape(shape + (2,))
    with np.errstate(invalid="ignore"):
        within = (status.reshape(shape) == K.TILT_OK) & np.all(
            (t >= design.tension_min - 1e-9) & (t <= design.tension_max + 1e-9), axis=2)
    return TiltMap(tuple(np.asarray(a) for a in axes), phi.reshape(shape), t, status.reshape(shape), within)
