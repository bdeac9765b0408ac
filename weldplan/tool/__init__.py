"""The tool a robot carries (a mesh in its TCP frame). See docs/tool.md."""

from weldplan.tool.model import Tool, load_tool_urdf, tool_from_mesh
from weldplan.tool.torch import arc_torch, shared_spot_gun

__all__ = ["Tool", "arc_torch", "load_tool_urdf", "shared_spot_gun", "tool_from_mesh"]
