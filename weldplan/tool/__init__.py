"""The tool a robot carries, and a verified collision-free pose of it for every weld.

::

    from weldplan.tool import shared_spot_gun, plan_weld_poses, verify_poses
    gun = shared_spot_gun()                      # ../shared/data/tools/spot_welding_gun
    poses = plan_weld_poses(cell, route, gun)    # WeldPoses, in route order
    verify_poses(poses, cell.part, gun).ok

See docs/tool.md.
"""

from weldplan.tool.model import Tool, load_tool_urdf, tool_from_mesh
from weldplan.tool.poses import plan_weld_poses, surface_approach
from weldplan.tool.result import Miss, WeldPose, WeldPoses
from weldplan.tool.torch import arc_torch, shared_spot_gun
from weldplan.tool.verify_poses import PoseChecker, PosesVerification, verify_poses

__all__ = [
    "Miss",
    "PoseChecker",
    "PosesVerification",
    "Tool",
    "WeldPose",
    "WeldPoses",
    "arc_torch",
    "load_tool_urdf",
    "plan_weld_poses",
    "shared_spot_gun",
    "surface_approach",
    "tool_from_mesh",
    "verify_poses",
]
