"""cdpr-design: workspace, sizing and simulation explorer for cable-driven parallel robots.

The public Python API::

    import cdpr_design as cd
    design = cd.load("designs/planar2.yaml")
    result = cd.workspace(design)            # WorkspaceResult
    lengths = cd.inverse_kinematics(design, [0.75, 0.75])
"""

from .errors import CdprError, CheckFailed, InputError, SpecError
from .kinematics import forward_kinematics, inverse_kinematics, structure_matrix
from .model import Design
from .spec import from_dict, load

__version__ = "0.1.0"

__all__ = [
    "CdprError", "CheckFailed", "Design", "InputError", "SpecError", "forward_kinematics",
    "from_dict", "inverse_kinematics", "load", "structure_matrix", "__version__",
]
