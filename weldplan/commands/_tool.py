"""The ``--tool`` options of ``plan``, ``demo``, ``verify`` and ``view``; the pose stage.

With ``--tool`` a planning run, after the point-tip route has been planned and verified, plans a
pose of the whole tool at every weld in the route's order
(:func:`weldplan.tool.poses.plan_weld_poses`), re-checks them independently
(:func:`weldplan.tool.verify_poses.verify_poses`, fresh FCL models) and only then renders the
outputs. A weld without a free pose is listed with its closest miss; the run then exits with
:data:`weldplan.errors.EXIT_PARTIAL`.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import math
from typing import Any

from weldplan.errors import WeldplanError

log = logging.getLogger(__name__)


def _degrees(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (0.0 <= value <= 90.0):
        raise argparse.ArgumentTypeError(f"must lie in [0, 90] degrees, got {text!r}")
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
        metavar="URDF|MESH",
        help="plan (or check) a collision-free pose of this tool at every weld: a URDF (TCP = "
        "its last fixed joint) or a mesh with --tcp (docs/tool.md)",
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
    if search:
        p.add_argument(
            "--tool-cone",
            metavar="DEG",
            type=_degrees,
            default=15.0,
            help="largest tilt of the tool off the weld's approach axis, degrees (default 15)",
        )
        p.add_argument(
            "--contact-radius",
            metavar="MM",
            type=_nonneg_mm,
            default=20.0,
            help="the tool may touch the part only inside this sphere about the weld spot, mm "
            "(default 20: the electrode tip)",
        )


def tool_from_args(args: argparse.Namespace) -> tuple[Any, dict[str, Any]] | None:
    """The tool and its provenance (:func:`weldplan.tool.load.load_tool`), ``None`` without one."""
    if not getattr(args, "tool", None):
        for opt in ("tcp", "tool_units", "tool_mesh"):
            if getattr(args, opt, None) is not None:
                raise WeldplanError(f"--{opt.replace('_', '-')} needs --tool")
        return None
    from weldplan.tool.load import load_tool

    return load_tool(args.tool, tcp=args.tcp, units=args.tool_units, mesh=args.tool_mesh)


def plan_poses(
    args: argparse.Namespace, cell: Any, route: Any, tool: Any, prov: dict[str, Any]
) -> tuple[Any, Any]:
    """The pose stage: plan the poses in route order and re-check them independently.

    Returns
    -------
    route, check
        The route carrying the poses (``route.tool``) and the
        :class:`~weldplan.tool.verify_poses.PosesVerification`; the caller writes nothing when
        ``check.ok`` is false.
    """
    from weldplan.tool import plan_weld_poses, verify_poses

    poses = plan_weld_poses(
        cell, route, tool, cone=args.tool_cone, contact_radius=args.contact_radius
    )
    check = verify_poses(poses, cell.part, tool)
    return dataclasses.replace(route, tool={"provenance": prov, "poses": poses.to_dict()}), check


def pose_rows(route: Any, check: Any) -> list[tuple[str, str]]:
    """Summary rows of the pose stage: the tool, welds reached, and each miss."""
    from weldplan.tool.result import WeldPoses

    poses = WeldPoses.from_dict(route.tool["poses"])
    n = len(poses.poses)
    rows = [
        ("tool", f"{poses.tool}, sha256 {route.tool['provenance']['file_sha256'][:12]}"),
        (
            "tool poses",
            f"{poses.n_ok} / {n} welds with a free pose (re-checked: {check.checked} ok poses, "
            f"fresh FCL models); total orientation change {poses.total_rotation:.1f} deg"
            + ("" if poses.n_ok == n else "; exit code 3"),
        ),
    ]
    rows += [
        (f"  weld {p.id}", f"no free pose; {p.miss.describe()}" if p.miss else "no free pose")
        for p in poses.poses
        if not p.ok
    ]
    return rows
