"""The tool in the meshcat scene: the tool mesh at weld poses, and welds without a pose in red.

Drawn under ``weldplan/tool``: ``tool/<id>`` a copy of the tool mesh at weld ``<id>``'s pose (the
TCP frame in the part frame), ``tool_miss/<id>`` a red halo about each weld without a free pose.
With transitions (``route.tool["transitions"]``, :mod:`weldplan.tool.transitions`):
``path/<k>`` the TCP path of transition ``k`` (free ones in the tool copies' colour, blocked
ones in magenta), and ``gun`` the tool itself, animated along the whole path
(:func:`animate_tool`: one keyframe per waypoint, so the viewer's linear position and slerped
rotation between keyframes are the motion that was checked).
The tool is drawn at every weld with a pose up to :data:`MAX_INSTANCES`, else at that many
welds spread evenly along the route order (each copy costs the page the whole mesh).

The displayed mesh is a quadric decimation (open3d) of the tool to at most
:data:`DISPLAY_TRIANGLES` triangles, for the page's size only: every check used the full mesh.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.tool.route_frames import route_poses
from weldplan.weld.route import Route

log = logging.getLogger(__name__)

#: tool copies drawn at most (all welds with a pose on small stations)
MAX_INSTANCES = 15
#: triangles of the displayed tool mesh at most
DISPLAY_TRIANGLES = 3000
#: colour of welds without a free pose, and of those with one when a tool is drawn
MISS_COLOR = 0xE00000
OK_COLOR = 0x2CA02C
#: the tool copies, see-through so that the welds and the route stay visible
TOOL_COLOR = 0x4A6FA5


def display_mesh(tool: Any) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """``(vertices mm, faces)`` of the tool in its TCP frame, decimated for display.

    Duplicate vertices are merged first (an STL repeats each vertex per triangle), and vertices
    no triangle uses are dropped.
    """
    import trimesh

    tm = trimesh.Trimesh(np.array(tool.vertices), np.array(tool.faces), process=True)
    if len(tm.faces) > DISPLAY_TRIANGLES:
        import open3d as o3d

        m = o3d.geometry.TriangleMesh(
            o3d.utility.Vector3dVector(np.array(tm.vertices)),
            o3d.utility.Vector3iVector(np.array(tm.faces, dtype=np.int32)),
        )
        m = m.simplify_quadric_decimation(DISPLAY_TRIANGLES).remove_unreferenced_vertices()
        return np.asarray(m.vertices), np.asarray(m.triangles, dtype=np.int64)
    tm.remove_unreferenced_vertices()
    return np.asarray(tm.vertices), np.asarray(tm.faces, dtype=np.int64)


def shown_welds(ok_ids: list[str], limit: int = MAX_INSTANCES) -> list[str]:
    """Which welds get a tool copy: all when at most ``limit``, else ``limit`` spread evenly."""
    if len(ok_ids) <= limit:
        return list(ok_ids)
    idx = np.unique(np.round(np.linspace(0, len(ok_ids) - 1, limit)).astype(int))
    return [ok_ids[i] for i in idx]


def draw_tool(root: Any, route: Route, tool: Any, r_joint: float) -> None:
    """Draw the tool at the route's weld poses and highlight welds without one (module docstring).

    ``root`` is the meshcat node of the route (part frame, mm); ``r_joint`` the joint marker
    radius (mm). Without poses in ``route.tool`` nothing is drawn.
    """
    import meshcat.geometry as g

    poses = route_poses(route)
    if poses is None:
        return
    node = root["tool"]
    ok = [p for p in poses.poses if p.ok]
    shown = set(shown_welds([p.id for p in ok])) if tool is not None else set()
    if shown:
        V, F = display_mesh(tool)
        for p in ok:
            if p.id not in shown:
                continue
            T = np.eye(4)
            T[:3, :3] = p.rotation()
            T[:3, 3] = p.position
            node["tool"][p.id].set_object(
                g.TriangularMeshGeometry(V, F),
                g.MeshLambertMaterial(color=TOOL_COLOR, opacity=0.3, transparent=True),
            )
            node["tool"][p.id].set_transform(T)
    for p in poses.poses:
        jid = p.id
        color = OK_COLOR if p.ok else MISS_COLOR
        root["joints"][jid].set_object(g.Sphere(r_joint), g.MeshLambertMaterial(color=color))
        if not p.ok:
            halo = node["tool_miss"][jid]
            halo.set_object(
                g.Sphere(4.0 * r_joint),
                g.MeshLambertMaterial(color=MISS_COLOR, opacity=0.45, transparent=True),
            )
            T = np.eye(4)
            T[:3, 3] = p.position
            halo.set_transform(T)
    log.debug(
        "tool drawn at %d of %d welds; %d without a pose",
        len(shown),
        len(ok),
        len(poses.poses) - len(ok),
    )


#: colour of the animated tool (free transitions are drawn in TOOL_COLOR)
GUN_COLOR = 0x8E44AD
#: colour of blocked transitions: magenta, so that red stays the welds without a pose
BLOCKED_COLOR = 0xD000D0


def keyframe_times(positions: NDArray[np.float64], quaternions: NDArray[np.float64],
                   reach: float) -> NDArray[np.float64]:  # fmt: skip
    """``(m,)`` from 0 to 1: each waypoint's share of the path, by the motion bound of each
    motion (TCP distance + rotation angle x ``reach`` mm), so a turn on the spot takes time."""
    from weldplan.tool.transit import path_rotation

    step = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    turn = np.array(
        [np.radians(path_rotation(quaternions[k : k + 2])) for k in range(len(quaternions) - 1)]
    )
    cum = np.concatenate([[0.0], np.cumsum(step + turn * reach)])
    return cum / max(float(cum[-1]), 1e-9)


def animate_tool(anim: Any, root: Any, route: Route, tool: Any, seconds: float, fps: int) -> bool:
    """Draw the tool path and animate the tool along it in ``anim`` (a meshcat ``Animation``).

    Returns whether anything was drawn (no transitions or no tool: nothing).
    """
    import meshcat.geometry as g

    from weldplan.tool.route_frames import route_tool_path

    path = route_tool_path(route)
    if path is None or not path.transitions:
        return False
    node = root["tool"]
    for k, t in enumerate(path.transitions):
        color = TOOL_COLOR if t.free else BLOCKED_COLOR
        node["path"][str(k)].set_object(
            g.Line(
                g.PointsGeometry(np.asarray(t.positions, dtype=np.float32).T),
                g.LineBasicMaterial(color=color, linewidth=3),
            )
        )
    if tool is None:
        return True
    P, Q = path.waypoints()
    V, F = display_mesh(tool)
    gun = node["gun"]
    gun.set_object(
        g.TriangularMeshGeometry(V, F),
        g.MeshLambertMaterial(color=GUN_COLOR, opacity=0.85, transparent=True),
    )
    times = keyframe_times(P, Q, float(np.linalg.norm(tool.vertices, axis=1).max()))
    frames = np.round(times * seconds * fps).astype(int)
    from scipy.spatial.transform import Rotation

    R = Rotation.from_quat(np.roll(Q, -1, axis=1)).as_matrix()
    T = np.tile(np.eye(4), (len(P), 1, 1))
    T[:, :3, :3] = R
    T[:, :3, 3] = P
    gun.set_transform(T[0])
    for f, Tk in zip(frames, T, strict=True):
        with anim.at_frame(gun, int(f)) as frame:
            frame.set_transform(Tk)
    log.debug("tool animated along %d waypoints", len(P))
    return True
