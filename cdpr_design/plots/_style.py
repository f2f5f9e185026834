"""The plotting backend (Agg, set here once), the PNG resolution and shared colours.

Continuous maps are perceptually uniform and colour-blind safe (viridis,
cividis); markers use Okabe & Ito's palette and differ in shape too.
"""

from __future__ import annotations

#: Resolution of every PNG [dots per inch].
DPI = 120
#: Colour of masked (infeasible, NaN) cells: light grey.
GREY = (0.85, 0.85, 0.85, 1.0)
#: Marker and line colours told apart with any colour vision (Okabe & Ito's palette).
BLUE, VERMILLION, ORANGE, SKY = "#0072B2", "#D55E00", "#E69F00", "#56B4E9"
#: Passing / failing variants and samples.
PASS, FAIL = BLUE, VERMILLION

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
