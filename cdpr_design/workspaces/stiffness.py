"""The stiffness and the lowest natural frequency of every pose of a sweep (``workspace --stiffness``).

:class:`StiffnessColumns` is a wrapper of the sweep plan (:mod:`cdpr_design.workspaces.plan`):
at each pose the base evaluator found feasible, the effector held by the minimum-norm tensions
on its elastic cables, or by its sagging cables of the sweep's unstretched lengths
(:mod:`cdpr_design.statics.stiffness`, the kernel :mod:`cdpr_design.kernels.stiffness`) gives

- ``min_stiffness`` [N/m]: the smallest stiffness against a force at the reference point, the
  effector free to rotate;
- ``lowest_frequency`` [Hz]: the lowest natural frequency of the effector on its cables
  (straight cables massless, a third of each sagging cable's mass at its attachment);

both empty where the pose is infeasible (no tensions hold it) or the equilibrium is unstable.
The map of ``min_stiffness`` is drawn as ``stiffness_map.png``; the summary adds the least of
each over the feasible poses (``min_stiffness``, ``lowest_frequency``).
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.model.design import Grid
from cdpr_design.statics.robot import Robot
from cdpr_design.statics.stiffness import grid_figures, sweep_arrays
from cdpr_design.workspaces.grid import Rows, grid3
from cdpr_design.workspaces.parts import Wrapper


class StiffnessColumns(Wrapper):
    """The columns ``min_stiffness`` and ``lowest_frequency`` of a robot whose stiffness is defined
    (the resolved robot refuses ``--stiffness`` otherwise), at the sweep's orientation ``ori`` (3,) [rad]
    over the grid ``g`` (the kernel counts its indices: it reads no positions)."""

    columns = ("min_stiffness", "lowest_frequency")
    maps = ("min_stiffness", "lowest_frequency")
    pictures = ("stiffness_map.png",)
    positions = False

    def __init__(self, robot: Robot, ori, g: Grid):
        self.arrays = sweep_arrays(robot.design, ori)
        self.grid3 = grid3(g)
        #: the unstretched-length columns a sagging sweep writes (its cables' shapes), else None
        self.L0 = (None if robot.cables.straight
                   else tuple(f"unstretched_length_{c}" for c in robot.design.cable_names))
        self.least = {"min_stiffness": math.inf, "lowest_frequency": math.inf}

    def add(self, r: Rows, start: int, P: np.ndarray) -> None:
        L0 = None if self.L0 is None else np.column_stack([r.extra[c] for c in self.L0])
        kmin, flow = grid_figures(self.arrays, self.grid3, start, r.tensions, r.feasible, L0)
        for name, v in (("min_stiffness", kmin), ("lowest_frequency", flow)):
            r.extra[name] = v
            r.maps[name] = v
            self.least[name] = min(self.least[name], float(np.fmin.reduce(v, initial=math.inf)))  # NaN left out

    def summary(self, maps) -> dict:
        return {k: (v if math.isfinite(v) else None) for k, v in self.least.items()}

    def finish(self, result, maps) -> None:
        result.stiffness = {name: maps.xmaps[name] for name in self.maps}
