"""The tool a robot carries, and a verified collision-free pose of it for every weld.

::

    from weldplan.tool import shared_spot_gun, plan_weld_poses, verify_poses
    gun = shared_spot_gun()                      # ../shared/data/tools/spot_welding_gun
    poses = plan_weld_poses(cell, route, gun)    # WeldPoses, in route order
    verify_poses(poses, cell.part, gun).ok
    order, _ = tool_order(poses, retract=50.0)   # the weld order on the tool's own costs
    path = plan_transitions(cell.part, gun, poses, order=order)   # ToolPath: swept-gun checked
    verify_sweeps(path, poses, cell.part, gun).ok

See docs/tool.md.
"""

from weldplan.tool.model import Tool, load_tool_urdf, tool_from_mesh
from weldplan.tool.poses import plan_weld_poses, surface_approach
from weldplan.tool.result import Miss, WeldPose, WeldPoses
from weldplan.tool.tool_order import tool_order
from weldplan.tool.torch import arc_torch, shared_spot_gun
from weldplan.tool.transit import ToolPath, Transition
from weldplan.tool.transitions import plan_transitions
from weldplan.tool.verify_poses import PoseChecker, PosesVerification, verify_poses
from weldplan.tool.verify_sweeps import SweepsVerification, verify_sweeps

__all__ = [
    "Miss",
    "PoseChecker",
    "PosesVerification",
    "SweepsVerification",
    "Tool",
    "ToolPath",
    "Transition",
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
