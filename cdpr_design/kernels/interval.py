"""Interval arithmetic with outward rounding, for certified workspaces.

An interval is a pair of floats ``(lo, hi)``; every operation returns an
interval that contains the exact result of the operation on every pair of
reals of its operands.  Each floating-point operation is rounded to nearest
(IEEE 754: the exact result lies within half a unit in the last place of the
rounded one) and its bounds are then moved one step outward with
``np.nextafter`` (Moore, Kearfott & Cloud, "Introduction to Interval
Analysis", SIAM 2009, sec. 4.1; Jaulin, Kieffer, Didrit & Walter, "Applied
Interval Analysis", Springer 2001).  ``sqrt`` and ``/`` are correctly rounded
in IEEE 754 too, so the same step covers them.  These kernels are compiled
without fast-math (no reassociation or fused contraction), so every operation
is the one written; ``tests/test_certify_interval.py`` checks each against
python-flint's arb balls on random operands.

An operation that cannot be enclosed by finite bounds (a division by an
interval holding 0) returns ``(-inf, inf)``; a NaN operand gives a NaN bound,
and callers only ever decide on comparisons that are false for NaN, so a NaN
never proves anything.
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.kernels._jit import njit


@njit
def down(x):
    """The next float below ``x`` (a lower bound of any real that rounds to ``x``)."""
    return np.nextafter(x, -np.inf)


@njit
def up(x):
    """The next float above ``x``."""
    return np.nextafter(x, np.inf)


@njit
def iadd(al, ah, bl, bh):
    """[a] + [b]."""
    return down(al + bl), up(ah + bh)


@njit
def isub(al, ah, bl, bh):
    """[a] - [b]."""
    return down(al - bh), up(ah - bl)


@njit
def imul(al, ah, bl, bh):
    """[a] * [b] (the extreme products of the bounds; ``(-inf, inf)`` if one is NaN, as 0 * inf)."""
    p1 = al * bl
    p2 = al * bh
    p3 = ah * bl
    p4 = ah * bh
    if p1 != p1 or p2 != p2 or p3 != p3 or p4 != p4:
        return -np.inf, np.inf
    return down(min(min(p1, p2), min(p3, p4))), up(max(max(p1, p2), max(p3, p4)))


@njit
def iscale(c, bl, bh):
    """The float ``c`` times [b]."""
    return imul(c, c, bl, bh)


@njit
def idiv(al, ah, bl, bh):
    """[a] / [b]; ``(-inf, inf)`` when [b] holds 0."""
    if not (bl > 0.0 or bh < 0.0):
        return -np.inf, np.inf
    q1 = al / bl
    q2 = al / bh
    q3 = ah / bl
    q4 = ah / bh
    if q1 != q1 or q2 != q2 or q3 != q3 or q4 != q4:
        return -np.inf, np.inf
    return down(min(min(q1, q2), min(q3, q4))), up(max(max(q1, q2), max(q3, q4)))


@njit
def isqr(al, ah):
    """[a]^2, the range of x^2 (not [a] * [a], which would be wider when [a] holds 0)."""
    if al >= 0.0:
        return max(0.0, down(al * al)), up(ah * ah)
    if ah <= 0.0:
        return max(0.0, down(ah * ah)), up(al * al)
    return 0.0, up(max(al * al, ah * ah))


@njit
def isqrt(al, ah):
    """sqrt([a]) over its non-negative part (NaN bounds when [a] is wholly negative)."""
    if ah < 0.0:
        return np.nan, np.nan
    return max(0.0, down(math.sqrt(max(al, 0.0)))), up(math.sqrt(ah))


@njit
def iabs(al, ah):
    """|[a]|."""
    if al >= 0.0:
        return al, ah
    if ah <= 0.0:
        return -ah, -al
    return 0.0, max(-al, ah)


@njit
def unit_at(x, r):
    """x / sqrt(x^2 + r) for the floats x and r >= 0, as an interval ([-1, 1] when the
    denominator may be 0)."""
    sl, sh = isqr(x, x)
    sl, sh = iadd(sl, sh, r, r)
    dl, dh = isqrt(sl, sh)
    if not (dl > 0.0):
        return -1.0, 1.0
    return idiv(x, x, dl, dh)


@njit
def unit_component(xl, xh, rl, rh):
    """The range of x / sqrt(x^2 + r) for x in [xl, xh] and r in [rl, rh] (r >= 0): one component
    of a unit vector whose other squared components sum to r.

    The function increases with x (its derivative r / (x^2 + r)^1.5 >= 0) and, for fixed x,
    decreases in r where x > 0 and increases where x < 0, so its extremes over the box are at
    (xl, rl if xl < 0 else rh) and (xh, rh if xh < 0 else rl), each evaluated with outward
    rounding (:func:`unit_at`), and clipped to [-1, 1].
    """
    lo = unit_at(xl, rl if xl < 0.0 else rh)[0]
    hi = unit_at(xh, rh if xh < 0.0 else rl)[1]
    return max(-1.0, lo), min(1.0, hi)
