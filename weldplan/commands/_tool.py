"""The ``--tool`` options of ``plan``, ``demo``, ``verify`` and ``view``.

They fill the station's tool (:class:`~weldplan.station.model.ToolSpec`) and the tool stage's
settings (:class:`~weldplan.station.model.ToolSettings`); the stages themselves are
:mod:`weldplan.station.toolstage`'s. A weld without a free pose or a blocked transition is
listed; the run then exits with :data:`weldplan.errors.EXIT_PARTIAL`.
"""

from __future__ import annotations

import argparse
import logging
from typing import Any

from weldplan.commands._settings_args import add_settings_options
from weldplan.commands._types import cone_degrees
from weldplan.station.model import ToolSettings

log = logging.getLogger(__name__)


def add_tool_arguments(p: argparse.ArgumentParser, *, search: bool = True) -> None:
    """The tool (``--tool``, ``--tcp``, ``--tool-units``, ``--tool-mesh``, ``--tip-cone``) and,
    with ``search``, the tool stage's options (:class:`ToolSettings`' fields)."""
    g = p.add_argument_group("tool: what the robot's flange carries (station file: [robot.tool])")
    g.add_argument(
        "--tool",
        metavar="URDF|MESH|builtin:arc_torch",
        help="plan (or check) a collision-free pose of this tool at every weld: a URDF (TCP = "
        "its last fixed joint), a mesh with --tcp (docs/tool.md), or the built-in arc torch "
        "'builtin:arc_torch[,bend_angle=0,stickout=15,...]' (weldplan.tool.arc_torch)",
    )
    g.add_argument(
        "--tcp",
        metavar="X,Y,Z,RX,RY,RZ|NAME",
        help="the tool's TCP, one of two forms by the --tool file: with a mesh --tool, six "
        "numbers: the TCP in the mesh frame (position in --tool-units, fixed-axis x-y-z "
        "rotations in degrees, +z into the part); with a URDF --tool, a name: the URDF's TCP "
        "joint or link (default its last fixed joint). A property of the tool, not of the robot",
    )
    _add_tool_file_arguments(g)
    if search:
        add_transition_arguments(p)


def _add_tool_file_arguments(g: Any) -> None:
    """``--tool-units``, ``--tool-mesh``, ``--tip-cone``: how the tool's files are read."""
    g.add_argument(
        "--tool-units",
        choices=("m", "mm"),
        help="unit of the tool mesh (default mm for a mesh, m for a URDF's --tool-mesh)",
    )
    g.add_argument(
        "--tool-mesh",
        metavar="F",
        help="with a URDF --tool: a mesh in its root-link frame instead of the URDF's own",
    )
    g.add_argument(
        "--tip-cone",
        metavar="DEG",
        type=cone_degrees,
        help="the tool's own contact cone, degrees in (0, 90] (a property of the tool; not the "
        "tool stage's --tool-cone nor the cell's --approach-cone): the tool may touch the part "
        "only within this angle of its axis behind the TCP, inside the contact sphere (an arc "
        "torch's wire and contact tip); default: the tool's own (none for a mesh: the whole "
        "sphere, as a spot gun's electrodes close over the sheet)",
    )


def add_transition_arguments(p: argparse.ArgumentParser) -> None:
    """The tool stage's options: the fields of :class:`ToolSettings` (weld poses, transitions,
    tool order), their defaults and help."""
    g = p.add_argument_group(
        "tool stage: a collision-free pose of the --tool at every weld, the transitions "
        "between them, the tool's weld order (with --tool; station file: [tool_settings])"
    )
    add_settings_options(g, ToolSettings, "[tool_settings]")


def tool_from_args(args: argparse.Namespace) -> tuple[Any, dict[str, Any]] | None:
    """The tool and its provenance (:func:`weldplan.station.mount.load_tool_spec`), ``None``
    without one."""
    from weldplan.commands._station_args import tool_spec
    from weldplan.station.mount import load_tool_spec

    spec = tool_spec(args)
    return None if spec is None else load_tool_spec(spec)
