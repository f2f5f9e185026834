"""cdpr-design: workspace, sizing and simulation explorer for cable-driven parallel robots.

The public Python API::

    import cdpr_design as cd
    design = cd.load("designs/planar2.yaml")
    result = cd.run_workspace(design, kind="static")      # WorkspaceResult
    pose = cd.evaluate_pose(design, [0.75, 0.75])          # tensions, margin, W
    lengths = cd.inverse_kinematics(design, [0.75, 0.75])
    sizing = cd.size_motors(design, cd.load_catalogue())   # SizingResult
    row = cd.evaluate_design(design)                       # design_report.csv figures

Names are imported on first use, so ``import cdpr_design`` (and every
command's start-up) stays fast: numba, scipy and cvxpy load only when needed.
"""

from __future__ import annotations

import importlib

from cdpr_design.errors import CdprError, CheckFailed, InputError, SpecError

__version__ = "0.1.0"

_LAZY = {
    "Design": ("model.design", "Design"),
    "load": ("model.spec", "load"),
    "from_dict": ("model.spec", "from_dict"),
    "load_catalogue": ("model.spec", "load_catalogue"),
    "json_schema": ("model.spec", "json_schema"),
    "inverse_kinematics": ("statics.kinematics", "inverse_kinematics"),
    "forward_kinematics": ("statics.kinematics", "forward_kinematics"),
    "structure_matrix": ("statics.kinematics", "structure_matrix"),
    "run_workspace": ("workspaces", "run"),
    "evaluate_pose": ("statics.pose", "evaluate_pose"),
    "WorkspaceResult": ("workspaces", "WorkspaceResult"),
    "size_motors": ("design.sizing", "size_motors"),
    "evaluate_design": ("design.evaluate", "evaluate"),
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

