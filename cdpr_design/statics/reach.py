"""Whether a forward-kinematics solution has the lengths asked for: an unreachable set of
lengths is an input error, never a pose.

Forward kinematics minimises the length residuals |L_i(pose) - L_i|; for
lengths no pose has (two cables shorter than the distance between their
outlets, say) the minimiser is still *a* pose, the one that misses them
least, and reporting it as the answer would be a physically impossible
result.  :func:`require_reached` is the rule every caller applies.
"""

from __future__ import annotations

import numpy as np

from cdpr_design.errors import InputError

#: Residual [m] (2-norm over the cables) up to which lengths count as reached: 1 um plus
#: 1e-9 of the longest cable.  A reachable set solves to about 1e-12 m.
RESIDUAL_ABS = 1e-6
RESIDUAL_REL = 1e-9


def residual_tolerance(lengths) -> float:
    """The residual [m] up to which ``lengths`` [m] count as reached."""
    L = np.asarray(lengths, dtype=float)
    return RESIDUAL_ABS + RESIDUAL_REL * (float(np.max(np.abs(L))) if L.size else 0.0)


def reached(residual: float, lengths) -> bool:
    """Whether a solution with this length ``residual`` [m] has the ``lengths`` [m] asked for."""
    return bool(np.isfinite(residual) and residual <= residual_tolerance(lengths))


def require_reached(residual: float, lengths, option: str = "--lengths") -> None:
    """Raise an :class:`InputError` naming ``option`` and giving the residual unless :func:`reached`."""
    if not reached(residual, lengths):
        raise InputError(f"{option}: no pose found with these cable lengths: the solver's best misses them by "
                         f"{residual:.4g} m (residual, 2-norm over the cables; at most "
                         f"{residual_tolerance(lengths):.2g} m counts as reached). Lengths no pose has are "
                         "refused so; if they should be reachable, start the solver nearer (--guess)")
