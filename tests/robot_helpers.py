"""Scenes and poses the robot tests share (the KUKA over the box scene of route_fixtures)."""

from __future__ import annotations

import numpy as np
import trimesh

from weldplan.robot.placement import base_pose
from weldplan.robot.route import OK
from weldplan.tool.poses import WeldPose, WeldPoses

#: the arc torch of :func:`weldplan.tool.arc_torch` (straight): TCP 425 mm out along the
#: flange's z axis
TORCH_TCP = np.eye(4)
TORCH_TCP[2, 3] = 425.0
#: a base 1.8 m from the box scene of route_fixtures, 0.7 m below its floor plate
BOX_BASE = base_pose(-1800.0, 0.0, -700.0, 0.0)


def down_poses(route) -> WeldPoses:
    """Every weld of the box route welded from above (TCP z = -z), spin 0."""
    q_down = (0.0, 1.0, 0.0, 0.0)  # 180 deg about x: TCP z -> -z
    poses = []
    for jid in route.order:
        p = route.joint_xyz[route.joint_ids.index(jid)]
        poses.append(WeldPose(jid, OK, tuple(p), (0.0, 0.0, -1.0), q_down, 0.0, 0.0, 0.0, 1))
    return WeldPoses(tuple(poses), tool="arc torch", total_rotation=0.0)


def make_plate(centre, normal_axis, size=300.0, thickness=2.0) -> trimesh.Trimesh:
    """A square plate ``size`` mm wide, ``thickness`` mm thin along ``normal_axis``."""
    ext = [size, size, size]
    ext[normal_axis] = thickness
    return trimesh.creation.box(ext).apply_translation(centre)
