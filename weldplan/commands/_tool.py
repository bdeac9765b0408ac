"""The ``--tool`` options of ``plan``, ``demo``, ``verify`` and ``view``.

They fill the station's tool (:class:`~weldplan.station.model.ToolSpec`) and the tool stage's
settings (:class:`~weldplan.station.model.ToolSettings`); the stages themselves are
:mod:`weldplan.station.toolstage`'s. A weld without a free pose or a blocked transition is
listed; the run then exits with :data:`weldplan.errors.EXIT_PARTIAL`.
"""

from __future__ import annotations

import argparse
import logging
import math
from typing import Any

from weldplan.station.model import ToolSettings

log = logging.getLogger(__name__)


def _degrees(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (0.0 <= value <= 90.0):
        raise argparse.ArgumentTypeError(f"must lie in [0, 90] degrees, got {text!r}")
    return value


def _cone(text: str) -> float:
    value = _degrees(text)
    if value <= 0.0:
        raise argparse.ArgumentTypeError(f"must lie in (0, 90] degrees, got {text!r}")
    return value


def _nonneg_mm(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (0.0 <= value < math.inf):
        raise argparse.ArgumentTypeError(f"must be a finite number of mm >= 0, got {text!r}")
    return value


def add_tool_arguments(p: argparse.ArgumentParser, *, search: bool = True) -> None:
    """``--tool``, ``--tcp``, ``--tool-units``, ``--tool-mesh`` (and the pose search's options)."""
    p.add_argument(
        "--tool",
        metavar="URDF|MESH|builtin:arc_torch",
        help="plan (or check) a collision-free pose of this tool at every weld: a URDF (TCP = "
        "its last fixed joint), a mesh with --tcp (docs/tool.md), or the built-in arc torch "
        "'builtin:arc_torch[,bend_angle=0,stickout=15,...]' (weldplan.tool.arc_torch)",
    )
    p.add_argument(
        "--tcp",
        metavar="X,Y,Z,RX,RY,RZ",
        help="with a mesh --tool: the TCP in the mesh frame (position in --tool-units, fixed-axis "
        "x-y-z rotations in degrees, +z into the part); with a URDF: the TCP joint or link name",
    )
    p.add_argument(
        "--tool-units",
        choices=("m", "mm"),
        help="unit of the tool mesh (default mm for a mesh, m for a URDF's --tool-mesh)",
    )
    p.add_argument(
        "--tool-mesh",
        metavar="F",
        help="with a URDF --tool: a mesh in its root-link frame instead of the URDF's own",
    )
    p.add_argument(
        "--tip-cone",
        metavar="DEG",
        type=_cone,
        help="with --tool: the tool may touch the part only within this many degrees of its "
        "axis behind the TCP, inside the contact sphere (an arc torch's wire and contact tip: "
        "its nozzle never passes through a sheet near the spot); default: the tool's own (none "
        "for a mesh: the whole sphere, as a spot gun's electrodes close over the sheet)",
    )
    if search:
        _add_pose_arguments(p)
        add_transition_arguments(p)


def _add_pose_arguments(p: argparse.ArgumentParser) -> None:
    """``--tool-cone``, ``--contact-radius``, ``--tool-csv`` (defaults: ToolSettings')."""
    d = ToolSettings()
    p.add_argument(
        "--tool-cone",
        metavar="DEG",
        type=_degrees,
        default=d.cone,
        help="largest tilt of the tool off the weld's approach axis, degrees (default 15)",
    )
    p.add_argument(
        "--contact-radius",
        metavar="MM",
        type=_nonneg_mm,
        default=d.contact_radius,
        help="the tool may touch the part only inside this sphere about the weld spot, mm "
        "(default 20: the electrode tip)",
    )
    p.add_argument(
        "--tool-csv",
        metavar="F",
        help="with --tool: also write the tool's verified path as CSV (the transitions in "
        "the tool's order, one row per TCP pose with its quaternion: the motion the swept "
        "check proved free; weldplan.tool.path_csv)",
    )


def _seconds(text: str) -> float:
    return _nonneg_mm(text)  # the same rule: a finite number >= 0


def add_transition_arguments(p: argparse.ArgumentParser) -> None:
    """``--retract``, ``--side-exit``, ``--no-slide``, ``--rot-weight``, ``--tool-order``,
    ``--no-exit-check``, ``--se3-time`` (the transitions; defaults: ToolSettings')."""
    d = ToolSettings()
    _add_exit_arguments(p, d)
    p.add_argument(
        "--rot-weight",
        metavar="MM/RAD",
        type=_nonneg_mm,
        default=d.rot_weight,
        help="with --tool: the weld order minimises TCP length + this x orientation change "
        "(default 200 mm per rad)",
    )
    p.add_argument(
        "--tool-order",
        choices=("tool", "route"),
        default=d.order,
        help="with --tool: order the welds on the tool's costs (default) or keep the point-tip "
        "route's order",
    )
    p.add_argument(
        "--se3-time",
        metavar="S",
        type=_seconds,
        default=d.se3_time,
        help="with --tool: the CPU-seconds safety net of re-planning one blocked transition in "
        "SE(3), whose budget is a number of checks; a re-plan stopped at 3x this makes the run "
        "not reproducible (default 10; 0: report blocked transitions without re-planning)",
    )


def _add_exit_arguments(p: argparse.ArgumentParser, d: ToolSettings) -> None:
    """How the tool leaves and reaches a weld: ``--retract``, ``--side-exit``, ``--no-slide``,
    ``--no-exit-check``."""
    p.add_argument(
        "--retract",
        metavar="MM",
        type=_nonneg_mm,
        default=d.retract,
        help="with --tool: leave and approach each weld along the tool axis over this many mm "
        "(default 50; every motion of the swept tool is checked)",
    )
    p.add_argument(
        "--side-exit",
        metavar="MM",
        type=_nonneg_mm,
        default=d.side_exit,
        help="with --tool: where the axial retract is blocked, try leaving sideways by this many "
        "mm first (a C-gun round a flange; default 250, 0: never)",
    )
    p.add_argument(
        "--no-slide",
        dest="slide",
        action="store_false",
        help="with --tool: never slide between welds (lift 4-20 mm off the sheet, slide, lower: "
        "a C-gun stays straddled over the flange; tried after the axial retract by default)",
    )
    p.add_argument(
        "--no-exit-check",
        dest="exit_check",
        action="store_false",
        help="with --tool: choose each weld's pose without asking whether the tool can leave it "
        "(a lift off the sheet, the axial retract or a side exit; on by default, docs/tool.md)",
    )


def tool_from_args(args: argparse.Namespace) -> tuple[Any, dict[str, Any]] | None:
    """The tool and its provenance (:func:`weldplan.station.mount.load_tool_spec`), ``None``
    without one."""
    from weldplan.commands._station_args import tool_spec
    from weldplan.station.mount import load_tool_spec

    spec = tool_spec(args)
    return None if spec is None else load_tool_spec(spec)
