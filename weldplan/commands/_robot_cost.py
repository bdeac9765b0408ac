"""``--cost time`` on ``plan``/``demo``, and the tool as the robot's flange carries it.

With ``--cost time`` the sequencer orders the welds by the robot's time, so the robot must be
known before the order is (:func:`time_leg_cost`): the weld poses are planned once per weld
(:func:`weldplan.tool.plan_weld_poses` over the cell's joints: a weld's pose does not depend on
the order), the base is ``--robot-base`` or searched from those poses
(:func:`weldplan.robot.reach.search_base`, then kept for the robot stage), and the leg times
come from :mod:`weldplan.robot.legtime`. After the route: :func:`with_time_stats` writes the
order's seconds and the proved bound into ``Route.stats``; the robot stage adds the timed cycle.

The poses are planned twice with ``--cost time``, and the first result is not handed to the pose
stage, on purpose: the least-rotation choice minimises the rotation between *consecutive* welds,
so its answer depends on the order (file order here, the route's order in the pose stage), and
the pose stage also applies the robot's reach test at this base
(:func:`weldplan.commands._robot.pose_acceptance`). Checked on the demo with the shared gun: all
15 poses differ between the two orders (summed rotation 318.8 deg over the file order, 473.2 deg
over the route's order). Only the tool's collision table could be shared; it is internal to
:func:`weldplan.tool.plan_weld_poses`.

The tool (:func:`flange_tcp`, :func:`tool_load`): a URDF tool's root link is its mounting frame
(:func:`weldplan.robot.plan.tool_flange_tcp`, mass and centre of gravity from ``<inertial>``);
a mesh tool (``--tool gun.stl --tcp x,y,z,rx,ry,rz``) is mounted by its mesh frame in the same
way, with ``--tool-mass`` required and its centre of gravity the centre of mass of the mesh at
uniform density (watertight meshes; else the centre of its bounding box: named assumption).
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError

log = logging.getLogger(__name__)


def is_urdf(tool: str | None) -> bool:
    return bool(tool) and Path(str(tool)).suffix.lower() == ".urdf"


def flange_tcp(args: argparse.Namespace, robot: Any) -> NDArray[np.float64]:
    """``(4, 4)`` mm: the TCP in the robot's flange frame for ``--tool`` / ``--tcp``."""
    if is_urdf(args.tool):
        from weldplan.robot.plan import tool_flange_tcp

        return tool_flange_tcp(robot, args.tool, args.tcp)
    from scipy.spatial.transform import Rotation

    from weldplan.tool.load import parse_tcp
    from weldplan.tool.model import UNITS

    vals = parse_tcp(args.tcp)
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", np.radians(vals[3:])).as_matrix()
    T[:3, 3] = np.asarray(vals[:3]) * UNITS[getattr(args, "tool_units", None) or "mm"]
    return robot.tool_transform(T)


def tool_load(
    args: argparse.Namespace, robot: Any, tool: Any, Tft: NDArray[np.float64]
) -> tuple[float, NDArray[np.float64]]:
    """Tool mass (kg) and centre of gravity in the flange frame (mm), module docstring."""
    if is_urdf(args.tool):
        from weldplan.robot.payload import urdf_payload

        load = urdf_payload(args.tool)
        if args.tool_mass is None and load is None:
            raise InputError(
                "the tool URDF has no <mass>: give --tool-mass", path=args.tool, field="--tool-mass"
            )
        cog_root = np.zeros(3) if load is None else load[1]
        mass = float(args.tool_mass if args.tool_mass is not None else load[0])  # type: ignore[index]
        return mass, (robot.mount @ np.r_[cog_root, 1.0])[:3]
    if args.tool_mass is None:
        raise InputError(
            "a mesh tool has no mass: give --tool-mass with --robot",
            path=args.tool,
            field="--tool-mass",
        )
    import trimesh

    mesh = trimesh.Trimesh(tool.vertices, tool.faces, process=False)
    c_tcp = mesh.center_mass if mesh.is_watertight else mesh.bounds.mean(axis=0)
    return float(args.tool_mass), (Tft @ np.r_[c_tcp, 1.0])[:3]


def time_leg_cost(args: argparse.Namespace, cell: Any, tool: Any, robot: Any) -> tuple[Any, Any]:
    """``(LegTimes, robot placed)`` for ``--cost time``
    (:func:`weldplan.robot.legtime.cell_leg_times` with the run's options)."""
    from weldplan.robot.legtime import cell_leg_times
    from weldplan.robot.reach import BaseSearch

    return cell_leg_times(
        cell,
        tool,
        robot,
        flange_tcp(args, robot),
        weld_time=args.weld_time,
        velocity_scale=args.vel_scale,
        acceleration_scale=args.acc_scale,
        search=BaseSearch(floor_z=getattr(args, "floor_z", None))
        if args.robot_base is None
        else None,
        cone=args.tool_cone,
        contact_radius=args.contact_radius,
    )


def with_time_stats(route: Any, legs: Any, joint_ids: tuple[str, ...]) -> Any:
    """The route with :func:`weldplan.robot.legtime.time_stats` in ``stats["cost_time"]``."""
    from weldplan.robot.legtime import time_stats

    stats = dict(route.stats)
    stats["cost_time"] = time_stats(legs, joint_ids, route.order)
    return dataclasses.replace(route, stats=stats)


def cost_rows(route: Any, cycle: float | None) -> list[tuple[str, str]]:
    """The summary row of ``--cost time``: seconds of the order, the proved bound, the gap of
    the timed cycle (``cycle``, s) to it."""
    st = route.stats.get("cost_time")
    if not st:
        return []
    b = st["time_bound"]
    timed = (
        f"; timed cycle {cycle:.2f} s, {100 * (cycle / b - 1):.1f} % over the bound"
        if cycle is not None and b > 0 and math.isfinite(cycle)
        else ""
    )
    return [
        (
            "cost time",
            f"order {st['time_cost']:.2f} s (rest-to-rest bounds on IK branch "
            f"{st['station_branch']}, {st['weld_time']:g} s a weld); proved bound {b:.2f} s "
            f"({st['time_bound_method']}, any order and configuration){timed}",
        )
    ]
