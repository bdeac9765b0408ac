"""The joint route: configurations per waypoint, the walk over the welds, detours re-planned with
OMPL, the route that follows the gun, linear moves, leg times.

Modules: ``configs``, ``gunpath``, ``legtime``, ``legtrial``, ``linear``, ``plan``, ``replan``,
``walk``, ``walkpath``, ``walkstats``.

The names below load on first use (PEP 562, :func:`weldplan.lazy.lazy_exports`): importing
one module of this package does not load the others.
"""

from __future__ import annotations

from weldplan.lazy import lazy_exports

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "Assembled": "walkstats",
    "BUDGET": "walkstats",
    "Detour": "replan",
    "FLIP_PENALTY_S": "configs",
    "GunRoute": "gunpath",
    "JointPath": "walkpath",
    "LegTimes": "legtime",
    "NO_APPROACH": "walkstats",
    "NO_EXIT": "walkstats",
    "NO_TRANSFER": "walkstats",
    "OK": "configs",
    "RETRACE_TRIES": "walk",
    "RETRACT_DIRS": "replan",
    "RETRACT_MM": "replan",
    "RobotRoute": "configs",
    "TRANSFERS_PER_WELD": "walk",
    "TRAP": "walkstats",
    "TRAP_FAILS": "walk",
    "TRAP_TESTS": "walk",
    "WalkStats": "walkstats",
    "WeldConfigurations": "legtime",
    "assemble": "walk",
    "cell_leg_times": "legtime",
    "check_linear_moves": "linear",
    "choose_configurations": "configs",
    "gun_exits": "gunpath",
    "gun_route": "gunpath",
    "joint_path": "configs",
    "leg_times": "legtime",
    "legs_taken": "gunpath",
    "line_poses": "linear",
    "motion_cost": "configs",
    "plan_robot_route": "plan",
    "rest_to_rest_bound": "legtime",
    "subdivide": "walkpath",
    "tcp_waypoint_poses": "plan",
    "time_stats": "legtime",
    "tool_flange_tcp": "plan",
    "turn_variants": "configs",
    "weld_configurations": "legtime",
}

__all__ = [
    "Assembled",
    "BUDGET",
    "Detour",
    "FLIP_PENALTY_S",
    "GunRoute",
    "JointPath",
    "LegTimes",
    "NO_APPROACH",
    "NO_EXIT",
    "NO_TRANSFER",
    "OK",
    "RETRACE_TRIES",
    "RETRACT_DIRS",
    "RETRACT_MM",
    "RobotRoute",
    "TRANSFERS_PER_WELD",
    "TRAP",
    "TRAP_FAILS",
    "TRAP_TESTS",
    "WalkStats",
    "WeldConfigurations",
    "assemble",
    "cell_leg_times",
    "check_linear_moves",
    "choose_configurations",
    "gun_exits",
    "gun_route",
    "joint_path",
    "leg_times",
    "legs_taken",
    "line_poses",
    "motion_cost",
    "plan_robot_route",
    "rest_to_rest_bound",
    "subdivide",
    "tcp_waypoint_poses",
    "time_stats",
    "tool_flange_tcp",
    "turn_variants",
    "weld_configurations",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
