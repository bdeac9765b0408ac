"""A robot arm for the route: URDF + OPW model, IK branches, placement, configurations, collision.

::

    from weldplan.robot import load_robot
    robot = load_robot("../shared/data/robots/kuka_kr150r3100_2/kr150r3100_2.urdf")

See :mod:`weldplan.robot.model.arm` for the frames.
"""

from weldplan.robot.model.arm import Robot, RobotLink, load_robot
from weldplan.robot.model.ik import (
    ELBOW,
    SHOULDER,
    WRIST,
    IKBranches,
    IKSolutions,
    OPWParams,
    load_opw,
)

__all__ = [
    "ELBOW",
    "SHOULDER",
    "WRIST",
    "IKBranches",
    "IKSolutions",
    "OPWParams",
    "Robot",
    "RobotLink",
    "load_opw",
    "load_robot",
]
