"""cdpr-design: workspace, sizing and simulation explorer for cable-driven parallel robots.

The Python API (docs/api.md)::

    import cdpr_design as cd
    design = cd.load("designs/planar2.yaml")
    r = cd.workspace(design, kind="static")          # every grid pose: r.feasible, r.margin, r.tensions
    p = cd.pose(design, [0.75, 0.75])                # lengths, tensions, margin, W at one pose
    f = cd.fk(design, p.lengths)                     # the pose back from the lengths
    s = cd.size_motors(design)                       # motors, gears and drums against the catalogue
    t = cd.sweep(design, {"effector.mass": [0.5, 1, 2]})   # variants of the design

Results convert to tables (``to_dict()``, ``to_arrow()``).  Lower-level names
(``run_workspace`` streams chunks in bounded memory, ``evaluate_pose``,
``inverse_kinematics``, ``structure_matrix``, ``evaluate_design``) stay
available.  Names are imported on first use, so ``import cdpr_design`` (and
every command's start-up) stays fast: numba, scipy and cvxpy load only when needed.
"""

from __future__ import annotations

import importlib

from cdpr_design.errors import CdprError, CheckFailed, InputError, SpecError

__version__ = "0.1.0"

_LAZY = {
    "Design": ("model.design", "Design"),
    "load": ("api", "load"),
    "workspace": ("api", "workspace"),
    "pose": ("api", "pose"),
    "fk": ("api", "fk"),
    "equilibrium": ("statics.hanging", "equilibrium"),
    "hanging_pose": ("api", "hanging_pose"),
    "size_motors": ("api", "size_motors"),
    "sweep": ("api", "sweep"),
    "from_dict": ("model.spec", "from_dict"),
    "load_catalogue": ("model.spec", "load_catalogue"),
    "json_schema": ("model.spec", "json_schema"),
    "inverse_kinematics": ("statics.kinematics", "inverse_kinematics"),
    "forward_kinematics": ("statics.kinematics", "forward_kinematics"),
    "structure_matrix": ("statics.kinematics", "structure_matrix"),
    "run_workspace": ("workspaces", "run"),
    "evaluate_pose": ("workspaces.pose", "evaluate_pose"),
    "WorkspaceResult": ("workspaces", "WorkspaceResult"),
    "evaluate_design": ("design.evaluate", "evaluate"),
    "certify": ("api", "certify"),
    "CertifyResult": ("workspaces.certify", "CertifyResult"),
}

__all__ = ["CdprError", "CheckFailed", "InputError", "SpecError", "__version__", *_LAZY]


def __getattr__(name):
    if name in _LAZY:
        mod, attr = _LAZY[name]
        value = getattr(importlib.import_module(f".{mod}", __name__), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(__all__)

