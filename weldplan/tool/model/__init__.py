"""What the tool is: its mesh in the TCP frame (URDF or mesh), the built-in torches and the shared
spot gun, a tool as the command line names it.

Modules: ``load``, ``tool``, ``torch``.

The names below load on first use (PEP 562, :func:`weldplan.lazy.lazy_exports`): importing
one module of this package does not load the others.
"""

from __future__ import annotations

from weldplan.lazy import lazy_exports

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "PROVENANCE_KEYS": "load",
    "SHARED_GUN_DIR": "torch",
    "TORCH_TIP_CONE": "tool",
    "Tool": "tool",
    "UNITS": "tool",
    "ZONE_EDGE_MM": "tool",
    "arc_torch": "torch",
    "bvh": "tool",
    "load_tool": "load",
    "load_tool_urdf": "tool",
    "outside_sphere": "tool",
    "parse_tcp": "load",
    "provenance_mismatch": "load",
    "shared_spot_gun": "torch",
    "tool_from_mesh": "tool",
}

__all__ = [
    "PROVENANCE_KEYS",
    "SHARED_GUN_DIR",
    "TORCH_TIP_CONE",
    "Tool",
    "UNITS",
    "ZONE_EDGE_MM",
    "arc_torch",
    "bvh",
    "load_tool",
    "load_tool_urdf",
    "outside_sphere",
    "parse_tcp",
    "provenance_mismatch",
    "shared_spot_gun",
    "tool_from_mesh",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
