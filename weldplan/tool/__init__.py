"""The tool a robot carries, and a verified collision-free pose of it for every weld.

::

    from weldplan.tool import shared_spot_gun, plan_weld_poses, verify_poses
    gun = shared_spot_gun()                      # ../shared/data/tools/spot_welding_gun
    poses = plan_weld_poses(cell, route, gun)    # WeldPoses, in route order
    verify_poses(poses, cell.part, gun).ok
    order, _ = tool_order(poses, retract=50.0)   # the weld order on the tool's own costs
    path = plan_transitions(cell.part, gun, poses, order=order)   # ToolPath: swept-gun checked
    verify_sweeps(path, poses, cell.part, gun).ok
    # each search takes one settings object (weldplan.tool.settings): no tilt, no SE(3) re-plan
    poses = plan_weld_poses(cell, route, gun, PoseSearchSettings(cone=0.0))
    path = plan_transitions(cell.part, gun, poses, TransitionSettings(se3=False))

The names above are loaded on first use (PEP 562 module ``__getattr__``): importing a module of
this package (``weldplan.tool.poses.route_frames``, as :mod:`weldplan.io.export` does for a route
with poses) runs this ``__init__`` first, and an eager one would load the pose planner, the sweep
checker and FCL with it.

See docs/tool.md.
"""

from __future__ import annotations

import sys
import types
from typing import TYPE_CHECKING, Any

from weldplan.lazy import lazy_exports

if TYPE_CHECKING:  # the same names, for type checkers and readers
    from weldplan.tool.model.tool import Tool, load_tool_urdf, tool_from_mesh
    from weldplan.tool.model.torch import arc_torch, shared_spot_gun
    from weldplan.tool.poses.plan import plan_weld_poses, surface_approach
    from weldplan.tool.poses.result import Miss, WeldPose, WeldPoses
    from weldplan.tool.settings import OrderSettings, PoseSearchSettings, TransitionSettings
    from weldplan.tool.transitions.order import tool_order
    from weldplan.tool.transitions.plan import plan_transitions
    from weldplan.tool.transitions.result import ToolPath, Transition
    from weldplan.tool.verify.poses import PoseChecker, PosesVerification, verify_poses
    from weldplan.tool.verify.sweeps import SweepsVerification, verify_sweeps

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "Miss": "poses.result",
    "OrderSettings": "settings",
    "PoseChecker": "verify.poses",
    "PoseSearchSettings": "settings",
    "PosesVerification": "verify.poses",
    "SweepsVerification": "verify.sweeps",
    "Tool": "model.tool",
    "ToolPath": "transitions.result",
    "Transition": "transitions.result",
    "TransitionSettings": "settings",
    "WeldPose": "poses.result",
    "WeldPoses": "poses.result",
    "arc_torch": "model.torch",
    "load_tool_urdf": "model.tool",
    "plan_transitions": "transitions.plan",
    "plan_weld_poses": "poses.plan",
    "shared_spot_gun": "model.torch",
    "surface_approach": "poses.plan",
    "tool_from_mesh": "model.tool",
    "tool_order": "transitions.order",
    "verify_poses": "verify.poses",
    "verify_sweeps": "verify.sweeps",
}

__all__ = [
    "Miss",
    "OrderSettings",
    "PoseChecker",
    "PoseSearchSettings",
    "PosesVerification",
    "SweepsVerification",
    "Tool",
    "ToolPath",
    "Transition",
    "TransitionSettings",
    "WeldPose",
    "WeldPoses",
    "arc_torch",
    "load_tool_urdf",
    "plan_transitions",
    "plan_weld_poses",
    "shared_spot_gun",
    "surface_approach",
    "tool_from_mesh",
    "tool_order",
    "verify_poses",
    "verify_sweeps",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)


class _ToolPackage(types.ModuleType):
    """This package's module type: three exports share their module's name (``tool_order``,
    ``verify_poses``, ``verify_sweeps``), and importing such a module anywhere binds the module
    to the package's attribute of that name (``setattr(package, "tool_order", module)``), which
    would hide the function from ``__getattr__``. Bind the function instead, as the eager
    ``from weldplan.tool.transitions.order import tool_order`` did."""

    def __setattr__(self, name: str, value: Any) -> None:
        if (
            isinstance(value, types.ModuleType)
            and _EXPORTS.get(name) == name
            and value.__name__ == f"{__name__}.{name}"
        ):
            value = getattr(value, name)
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _ToolPackage
