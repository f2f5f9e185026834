"""Scalar helpers of the hot loops, inlined into their callers."""

from __future__ import annotations

import math

from cdpr_design.kernels._jit import njit_inline

#: Where x^2 + y^2 is a normal float with room to spare: the bounds of :func:`hypot`'s fast form.
_SQUARES_LO = 1e-290
_SQUARES_HI = 1e290


@njit_inline
def hypot(x, y):
    """sqrt(x^2 + y^2), in the units of ``x`` and ``y``.

    Within one ulp of :func:`math.hypot` (which is correctly rounded) and several times
    faster in a compiled loop: the sagging cables' shapes take it several times per cable
    and iteration.  :func:`math.hypot` itself where the sum of squares would underflow or
    overflow, and for NaN or infinite arguments.
    """
    s = x * x + y * y
    if _SQUARES_LO < s < _SQUARES_HI:
        return math.sqrt(s)
    return math.hypot(x, y)
