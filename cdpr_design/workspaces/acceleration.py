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
        box = robot.design.workspace.external_wrench
        #: whether a negative capacity margin of the sweep's rows means the pose is not held at rest for
        #: every external wrench (radius 0): the margin of the nominal wrench alone (static) or of it
        #: and the external box's vertices (wrench-feasible), and a box holding the zero wrench (the
        #: wrench set is convex: not held at zero, not held at some vertex)
        self.margin_decides = robot.kind in ("static", "wrench-feasible") and (
            box is None or bool(np.all((np.asarray(box.lower) <= 0.0) & (np.asarray(box.upper) >= 0.0))))

    def add(self, r: Rows, start: int, P: np.ndarray) -> None:
        if self.margin_decides:
            radius = np.zeros(len(r.margin))
            held = ~(r.margin < 0.0)  # NaN (no margin): computed
            if held.any():
                radius[held] = at_positions(self.robot, self.loads, P[held])[0]
        else:
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
