"""The tool as a robot's flange carries it: :class:`MountedTool` (tool, flange -> TCP, load).

As roboticstoolbox keeps ``robot.tool`` with the robot (../shared/DESIGN.md), the flange-to-TCP
transform and the tool's load travel with the tool here instead of beside every call.

- A URDF tool's root link is its mounting frame (:func:`weldplan.robot.route.tool_flange_tcp`),
  its mass and centre of gravity from ``<inertial>`` (``mass`` overrides the mass).
- A mesh tool (``file`` a mesh, ``tcp = "x,y,z,rx,ry,rz"``) is mounted by its mesh frame in the
  same way; ``mass`` is required and its centre of gravity is the centre of mass of the mesh at
  uniform density (watertight meshes; else the centre of its bounding box: named assumption).
- The built-in arc torch (:func:`weldplan.tool.arc_torch`) is mounted with the end of its body on
  the flange (the robot's ``tool0`` frame), its body axis along the flange's z: for the straight
  torch the TCP lies ``stickout + nozzle + neck + body`` mm (425 at the defaults) out along z;
  its centre of gravity is its mesh's, as for a mesh tool.
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError
from weldplan.station.model import ToolSpec


@dataclass(frozen=True, eq=False)
class MountedTool:
    """A loaded tool with its mounting.

    Attributes
    ----------
    spec
        What the station said (:class:`~weldplan.station.model.ToolSpec`).
    tool
        The :class:`~weldplan.tool.model.Tool` (mm, TCP frame).
    provenance
        What the route JSON records of it (files and their sha256, the TCP, the units).
    flange_tcp
        ``(4, 4)`` mm: the TCP in the robot's flange frame; None without a robot.
    mass, cog
        kg and ``(3,)`` mm in the flange frame: the load the programs declare; None without a
        robot.
    """

    spec: ToolSpec
    tool: Any
    provenance: dict[str, Any] = field(default_factory=dict)
    flange_tcp: NDArray[np.float64] | None = None
    mass: float | None = None
    cog: NDArray[np.float64] | None = None


def load_tool_spec(spec: ToolSpec) -> tuple[Any, dict[str, Any]]:
    """The tool of ``spec`` and its provenance (:func:`weldplan.tool.model.load_tool` for a file,
    :func:`weldplan.tool.arc_torch` for the builtin)."""
    if spec.builtin is not None:
        from weldplan.tool import arc_torch

        tool = arc_torch(**spec.params)
        prov = {
            "name": tool.name,
            "file": None,
            "file_sha256": hashlib.sha256(tool.source.encode()).hexdigest(),
            "mesh": None,
            "mesh_sha256": None,
            "tcp": None,
            "units": "mm",
            "builtin": tool.source,
        }
    else:
        from weldplan.tool.model.load import load_tool

        tool, prov = load_tool(spec.file, tcp=spec.tcp, units=spec.units, mesh=spec.mesh)  # type: ignore[arg-type]
    if spec.tip_cone is not None:
        tool = dataclasses.replace(tool, tip_cone=float(spec.tip_cone), _cache={})
        prov = {**prov, "tip_cone": float(spec.tip_cone)}
    return tool, prov


def mount_tool(spec: ToolSpec, robot: Any = None) -> MountedTool:
    """Load ``spec`` and, with a ``robot``, mount it on its flange (module docstring)."""
    tool, prov = load_tool_spec(spec)
    if robot is None:
        return MountedTool(spec, tool, prov)
    F = flange_tcp(spec, robot)
    mass, cog = tool_load(spec, robot, tool, F)
    return MountedTool(spec, tool, prov, F, mass, cog)


def torch_flange_tcp(params: dict[str, float]) -> NDArray[np.float64]:
    """``(4, 4)`` mm: flange (``tool0``) -> TCP of the built-in arc torch (module docstring)."""
    import inspect

    from scipy.spatial.transform import Rotation

    from weldplan.tool import arc_torch

    p = {
        k: v.default
        for k, v in inspect.signature(arc_torch).parameters.items()
        if v.default is not inspect.Parameter.empty
    }
    p.update(params)
    b = np.radians(p["bend_angle"])
    bent = np.array([-np.sin(b), 0.0, -np.cos(b)])
    end = np.array([0.0, 0.0, -1.0]) * (p["stickout"] + p["nozzle_length"])
    end = end + bent * (p["neck_length"] + p["body_length"])
    T_tcp_flange = np.eye(4)  # the flange in the TCP frame: at the body's end, z along -bent
    T_tcp_flange[:3, :3] = Rotation.from_rotvec([0.0, b, 0.0]).as_matrix()
    T_tcp_flange[:3, 3] = end
    return np.linalg.inv(T_tcp_flange)


def flange_tcp(spec: ToolSpec, robot: Any) -> NDArray[np.float64]:
    """``(4, 4)`` mm: the TCP in the robot's flange frame (module docstring)."""
    if spec.builtin is not None:
        return torch_flange_tcp(dict(spec.params))
    if spec.is_urdf:
        from weldplan.robot.route.plan import tool_flange_tcp

        return tool_flange_tcp(robot, spec.file, spec.tcp)  # type: ignore[arg-type]
    from scipy.spatial.transform import Rotation

    from weldplan.tool.model.load import parse_tcp
    from weldplan.tool.model.tool import UNITS

    vals = parse_tcp(spec.tcp or "")
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", np.radians(vals[3:])).as_matrix()
    T[:3, 3] = np.asarray(vals[:3]) * UNITS[spec.units or "mm"]
    return robot.tool_transform(T)


def tool_load(
    spec: ToolSpec, robot: Any, tool: Any, Tft: NDArray[np.float64]
) -> tuple[float, NDArray[np.float64]]:
    """Tool mass (kg) and centre of gravity in the flange frame (mm), module docstring."""
    if spec.is_urdf:
        from weldplan.robot.model.payload import urdf_payload

        load = urdf_payload(spec.file)  # type: ignore[arg-type]
        if spec.mass is None and load is None:
            raise InputError(
                "the tool URDF has no <mass>: give --tool-mass", path=spec.file, field="--tool-mass"
            )
        cog_root = np.zeros(3) if load is None else load[1]
        mass = float(spec.mass if spec.mass is not None else load[0])  # type: ignore[index]
        return mass, (robot.mount @ np.r_[cog_root, 1.0])[:3]
    if spec.mass is None:
        what = "the built-in torch" if spec.builtin is not None else "a mesh tool"
        raise InputError(
            f"{what} has no mass: give --tool-mass with --robot (station file: the tool's mass)",
            path=spec.file,
            field="--tool-mass",
        )
    import trimesh

    mesh = trimesh.Trimesh(tool.vertices, tool.faces, process=False)
    c_tcp = mesh.center_mass if mesh.is_watertight else mesh.bounds.mean(axis=0)
    return float(spec.mass), (Tft @ np.r_[c_tcp, 1.0])[:3]
