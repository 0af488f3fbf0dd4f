"""Robot descriptions: the JSON format, the numpy model, geometry, statics, elasticity.

* :mod:`.schema`   -- pydantic models of robot files, errors naming the field
* :mod:`.model`    -- :class:`Robot`: validated arrays
* :mod:`.geometry` -- poses, platform points, wire directions, wrench matrix ``H`` (eq. 4)
* :mod:`.elastic`  -- Merlet's elastic wire model (eqs. 1, 2, 5, 6, 7)
* :mod:`.presets`  -- the robots of the two papers, built programmatically
"""

from .geometry import (
    Pose,
    gravity_wrench,
    parse_pose,
    platform_points,
    wire_geometry,
    wrench_matrix,
)
from .model import Robot
from .schema import RobotFileError, RobotSpec, load_robot_spec, robot_json_schema

__all__ = [
    "Pose",
    "Robot",
    "RobotFileError",
    "RobotSpec",
    "gravity_wrench",
    "load_robot_spec",
    "parse_pose",
    "platform_points",
    "robot_json_schema",
    "wire_geometry",
    "wrench_matrix",
]
