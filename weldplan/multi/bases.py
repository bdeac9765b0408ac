"""Given bases of a station of several robots, checked against the part before any planning.

A robot whose base is inside the part cannot weld anything; planning it would list every weld
as unreached and say nothing of why. :func:`check_bases` refuses it first, naming the station
file and the key (``robot.base``): the robot's base link (the URDF's first link, at its base
pose) touching the part (FCL on the link's collision mesh and the part's BVH), or the base's
origin inside a closed (watertight) part mesh. Two robots at the same place are refused when
the station file is read (:data:`weldplan.station.load.MIN_BASE_SPACING`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from weldplan.errors import InputError


def check_bases(station: Any) -> None:
    """Raise :class:`~weldplan.errors.InputError` naming the first robot whose given base is
    inside the part (module docstring). Robots without a given base or URDF are skipped, and so
    is a station with a part pose (checked in the cell frame by
    :func:`weldplan.multi.cell.place_robots`, after the cell stage)."""
    from weldplan.io.mesh import load_part
    from weldplan.robot import load_robot
    from weldplan.robot.placement.reach import base_pose

    given = [(k, s) for k, s in enumerate(station.robots) if s.base is not None and s.urdf]
    if not given or station.part_pose is not None:
        # with a part pose the bases are in the cell frame, where the part stands only once the
        # cell stage has placed it: weldplan.multi.cell.place_robots checks them there
        return
    part = _part(station, load_part)
    for k, spec in given:
        robot = load_robot(spec.urdf, spec.opw, base=base_pose(*spec.base))
        link = robot.links[0]
        touch = base_link_hits(part, robot)
        inside = part.is_watertight and bool(part.contains(np.asarray([spec.base[:3]]))[0])
        if touch or inside:
            what = "touches the part" if touch else "is inside the part"
            raise InputError(
                f"robot {k + 1}'s base {list(spec.base)} {what} (its base link "
                f"{link.name!r} at that pose)",
                path=station.source, field="robot.base",
            )  # fmt: skip


def _part(station: Any, load_part: Any) -> Any:
    p = station.part
    if p.is_demo:
        from weldplan.weld import demo_part

        return load_part(demo_part.DEMO_PART)
    return load_part(p.mesh, units=p.units, scale=p.scale, length=p.length)


def base_link_hits(part: Any, robot: Any) -> bool:
    """Whether the robot's root link at its base touches the part (FCL on both meshes)."""
    import fcl

    from weldplan.tool.model.tool import bvh

    link = robot.links[0]
    F = robot.link_frames(np.zeros((1, 6)))[0, link.index]
    a = fcl.CollisionObject(bvh(link.vertices, link.faces), fcl.Transform(F[:3, :3], F[:3, 3]))
    b = fcl.CollisionObject(bvh(part.vertices, part.faces), fcl.Transform())
    return bool(fcl.collide(a, b, fcl.CollisionRequest(), fcl.CollisionResult()))
