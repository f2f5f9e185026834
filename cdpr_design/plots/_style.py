"""The plotting backend (Agg, set here once), the PNG resolution and shared colours."""

from __future__ import annotations

#: Resolution of every PNG [dots per inch].
DPI = 120
#: Colour of masked (infeasible, NaN) cells: light grey.
GREY = (0.85, 0.85, 0.85, 1.0)

_pyplot = None


def pyplot():
    """``matplotlib.pyplot`` on the non-interactive Agg backend (imported on first use)."""
    global _pyplot
    if _pyplot is None:
        import matplotlib

        matplotlib.use("Agg", force=True)
        import matplotlib.pyplot as plt

        _pyplot = plt
    return _pyplot


def cmap_grey_bad(name: str):
    """The colour map ``name`` with masked cells drawn :data:`GREY`."""
    return pyplot().get_cmap(name).with_extremes(bad=GREY)
