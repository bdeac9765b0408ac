"""What is written: the robot program and its timing, the route JSON's robot and tool sections and
their re-check.

Modules: ``build``, ``routejson``, ``timing``, ``toolroute``.

The names below load on first use (PEP 562, :func:`weldplan.lazy.lazy_exports`): importing
one module of this package does not load the others.
"""

from __future__ import annotations

from weldplan.lazy import lazy_exports

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "DEFAULT_TCP_SPEED": "timing",
    "DEFAULT_TOLERANCE_RAD": "timing",
    "FollowedRoute": "toolroute",
    "ProgramBuild": "build",
    "RobotCheck": "routejson",
    "SavedRobotRoute": "toolroute",
    "TimedTrajectory": "timing",
    "ToolRoute": "toolroute",
    "attach_robot_route": "routejson",
    "check_weld_time": "timing",
    "constant_speed_time": "timing",
    "joint_line_deviation": "build",
    "pair_time": "timing",
    "poses_contact_radius": "routejson",
    "robot_program": "build",
    "robot_route_of": "routejson",
    "saved_robot_route": "routejson",
    "time_route": "timing",
    "tool_route": "routejson",
    "verify_robot_route": "routejson",
}

__all__ = [
    "DEFAULT_TCP_SPEED",
    "DEFAULT_TOLERANCE_RAD",
    "FollowedRoute",
    "ProgramBuild",
    "RobotCheck",
    "SavedRobotRoute",
    "TimedTrajectory",
    "ToolRoute",
    "attach_robot_route",
    "check_weld_time",
    "constant_speed_time",
    "joint_line_deviation",
    "pair_time",
    "poses_contact_radius",
    "robot_program",
    "robot_route_of",
    "saved_robot_route",
    "time_route",
    "tool_route",
    "verify_robot_route",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
