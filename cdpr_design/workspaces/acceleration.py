"""The acceleration radius of every pose of a sweep (``workspace --accelerations``).

:class:`AccelerationColumns` is a wrapper of the sweep plan (:mod:`cdpr_design.workspaces.plan`):
at every pose, the radius [m/s^2] of the largest ball of translational accelerations the
effector can reach from rest there (:mod:`cdpr_design.statics.acceleration`; 0 where the
pose cannot be held at rest), whatever the kind of the sweep.  The map is drawn as
``acceleration_map.png``; the summary adds the least and the greatest radius over the
feasible poses (``min_acceleration_radius``, ``max_acceleration_radius``).
"""

from __future__ import annotations

import math

import numpy as np

from cdpr_design.statics.acceleration import at_positions, loads
from cdpr_design.statics.robot import Robot
from cdpr_design.workspaces.grid import Rows
from cdpr_design.workspaces.parts import Wrapper


class AccelerationColumns(Wrapper):
    """The column ``acceleration_radius`` [m/s^2] of a robot whose acceleration capability is
    computed (the resolved robot refuses ``--accelerations`` otherwise), at the sweep's
    orientation ``ori`` (3,) [rad]."""

    columns = ("acceleration_radius",)
    maps = ("acceleration_radius",)
    pictures = ("acceleration_map.png",)

    def __init__(self, robot: Robot, ori):
        super().__init__(robot)
        self.loads = loads(robot, ori)
        self.least, self.greatest = math.inf, -math.inf

    def add(self, r: Rows, start: int, P: np.ndarray) -> None:
        radius = at_positions(self.robot, self.loads, P)[0]
        r.extra["acceleration_radius"] = radius
        r.maps["acceleration_radius"] = radius
        feasible = radius[r.feasible.astype(bool) & ~np.isnan(radius)]
        if feasible.size:
            self.least = min(self.least, float(feasible.min()))
            self.greatest = max(self.greatest, float(feasible.max()))

    def summary(self, maps) -> dict:
        def num(v):
            return v if math.isfinite(v) else None

        return {"min_acceleration_radius": num(self.least), "max_acceleration_radius": num(self.greatest)}

    def finish(self, result, maps) -> None:
        result.acceleration = maps.xmaps["acceleration_radius"]
