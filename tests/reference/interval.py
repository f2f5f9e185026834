"""Interval sums built from the product's outward-rounded operations
(:mod:`cdpr_design.kernels.interval`): what the tests check those operations compose into.
The product never imports it."""

from __future__ import annotations

import numba

from cdpr_design.kernels.interval import iadd, imul

#: numba's documented options only: compiled on first use, cached on disk
njit = numba.njit(cache=True)


@njit
def idot(al, ah, bl, bh):
    """The dot product of the interval vectors [a] and [b] (1-D arrays of bounds): (lower, upper)."""
    sl = 0.0
    sh = 0.0
    for i in range(al.shape[0]):
        pl, ph = imul(al[i], ah[i], bl[i], bh[i])
        sl, sh = iadd(sl, sh, pl, ph)
    return sl, sh
