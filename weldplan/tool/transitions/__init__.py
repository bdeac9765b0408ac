"""The whole tool from weld to weld: the order on the tool's costs, the swept-tool check,
axial/slide/side exits, the SE(3) re-plan, the tool path.

Modules: ``axis_walk``, ``order``, ``plan``, ``reorder``, ``result``, ``se3_replan``, ``sweep``,
``sweep_bound``, ``sweep_fast``, ``sweep_motion``.

The names below load on first use (PEP 562, :func:`weldplan.lazy.lazy_exports`): importing
one module of this package does not load the others.
"""

from __future__ import annotations

from weldplan.lazy import lazy_exports

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "AxisWalk": "axis_walk",
    "BLOCKED": "result",
    "DIRECT": "result",
    "FastSweep": "sweep_fast",
    "Interpolator": "sweep_bound",
    "REPLANNED": "result",
    "SLIDE_LIFTS": "plan",
    "SphereTree": "sweep_bound",
    "SweepBound": "sweep_bound",
    "SweepChecker": "sweep",
    "SweepMotion": "sweep_motion",
    "SweptChecks": "sweep_motion",
    "THETA_PAD": "sweep_bound",
    "TOUCH_GRID_MM": "sweep",
    "ToolPath": "result",
    "ToolStateChecker": "sweep",
    "Transition": "result",
    "TransitionPlanner": "plan",
    "entering": "se3_replan",
    "interpolate": "sweep",
    "max_samples": "sweep",
    "motion_bound": "sweep",
    "order_cost": "order",
    "outside_sphere": "sweep",
    "path_rotation": "result",
    "plan_ordered_transitions": "reorder",
    "plan_transitions": "plan",
    "quat_to_matrix": "sweep",
    "replan": "se3_replan",
    "tool_leg_costs": "order",
    "tool_order": "order",
    "tool_zone": "sweep",
}

__all__ = [
    "AxisWalk",
    "BLOCKED",
    "DIRECT",
    "FastSweep",
    "Interpolator",
    "REPLANNED",
    "SLIDE_LIFTS",
    "SphereTree",
    "SweepBound",
    "SweepChecker",
    "SweepMotion",
    "SweptChecks",
    "THETA_PAD",
    "TOUCH_GRID_MM",
    "ToolPath",
    "ToolStateChecker",
    "Transition",
    "TransitionPlanner",
    "entering",
    "interpolate",
    "max_samples",
    "motion_bound",
    "order_cost",
    "outside_sphere",
    "path_rotation",
    "plan_ordered_transitions",
    "plan_transitions",
    "quat_to_matrix",
    "replan",
    "tool_leg_costs",
    "tool_order",
    "tool_zone",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
