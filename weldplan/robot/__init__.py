"""A robot arm for the route: URDF + OPW model, IK branches, placement, configurations, collision.

::

    from weldplan.robot import load_robot
    robot = load_robot("../shared/data/robots/kuka_kr150r3100_2/kr150r3100_2.urdf")

See :mod:`weldplan.robot.model` for the frames.
"""

from weldplan.robot.ik import ELBOW, SHOULDER, WRIST, IKBranches, IKSolutions, OPWParams, load_opw
from weldplan.robot.model import Robot, RobotLink, load_robot

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
