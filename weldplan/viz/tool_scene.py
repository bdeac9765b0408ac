"""The tool in the meshcat scene: the tool at one weld at a time, and welds without a pose in red.

Drawn under ``weldplan/tool``: ``gun`` the tool mesh (in its TCP frame) at the first weld with a
free pose; the page's weld slider (:class:`~weldplan.viz.overlay.WeldSlider`, returned by
:func:`draw_tool`) moves it to any other weld's pose, so the welds and the route stay visible
instead of being covered by a copy at every weld. ``tool_miss/<id>`` is a red halo about each
weld without a free pose.
With transitions (:attr:`weldplan.tool.section.ToolSection.transitions`,
:mod:`weldplan.tool.transitions.plan`): ``path/<k>`` the TCP path of transition ``k`` (free ones in
:data:`TOOL_COLOR`, blocked ones in magenta), and the same ``gun`` animated along the whole path
(:func:`animate_tool`: one keyframe per waypoint, so the viewer's linear position and slerped
rotation between keyframes are the motion that was checked), loaded paused: the viewer's
*Animations* panel plays it.

The displayed mesh is a quadric decimation (open3d) of the tool to at most
:data:`DISPLAY_TRIANGLES` triangles, for the page's size only: every check used the full mesh.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.tool.poses.route_frames import route_poses
from weldplan.viz.overlay import WeldSlider
from weldplan.weld.route import Route

log = logging.getLogger(__name__)

#: triangles of the displayed tool mesh at most
DISPLAY_TRIANGLES = 3000
#: colour of welds without a free pose, and of those with one when a tool is drawn
MISS_COLOR = 0xE00000
OK_COLOR = 0x2CA02C
#: colour of the free transitions' lines
TOOL_COLOR = 0x4A6FA5
#: colour of the tool (at the slider's weld, and animated along the transitions)
GUN_COLOR = 0x8E44AD
#: colour of blocked transitions: magenta, so that red stays the welds without a pose
BLOCKED_COLOR = 0xD000D0


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


def _pose_matrices(poses: list[Any]) -> NDArray[np.float64]:
    """``(w, 4, 4)`` the TCP frames (part frame, mm) of weld poses ``poses``."""
    T = np.tile(np.eye(4), (len(poses), 1, 1))
    for k, p in enumerate(poses):
        T[k, :3, :3] = p.rotation()
        T[k, :3, 3] = p.position
    return T


def tool_corners(route: Route, tool: Any) -> NDArray[np.float64]:
    """``(8, 3)`` mm: the corners of the tool's bounding box at the route's first weld pose,
    where the page opens with it (none without a pose); the weld slider moves it from there."""
    poses = route_poses(route)
    ok = [] if poses is None else [p for p in poses.poses if p.ok]
    if not ok:
        return np.empty((0, 3))
    V = np.asarray(tool.vertices, dtype=np.float64)
    lo, hi = V.min(axis=0), V.max(axis=0)
    box = np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                    for i in (0, 1) for j in (0, 1) for k in (0, 1)])  # fmt: skip
    T = _pose_matrices(ok[:1])[0]
    return box @ T[:3, :3].T + T[:3, 3]


def draw_tool(root: Any, route: Route, tool: Any, r_joint: float) -> WeldSlider | None:
    """Draw the tool at the route's first weld pose and highlight welds without one (module
    docstring).

    ``root`` is the meshcat node of the route (part frame, mm); ``r_joint`` the joint marker
    radius (mm). Without weld poses (:func:`~weldplan.tool.poses.route_poses`) nothing
    is drawn. Returns the weld slider over the welds with a pose (None without a ``tool`` mesh
    or without such a weld).
    """
    import meshcat.geometry as g

    poses = route_poses(route)
    if poses is None:
        return None
    node = root["tool"]
    ok = [p for p in poses.poses if p.ok]
    slider = None
    if tool is not None and ok:
        V, F = display_mesh(tool)
        T = _pose_matrices(ok)
        gun = node["gun"]
        gun.set_object(
            g.TriangularMeshGeometry(V, F),
            g.MeshLambertMaterial(color=GUN_COLOR, opacity=0.85, transparent=True),
        )
        gun.set_transform(T[0])
        slider = WeldSlider.from_poses([p.id for p in ok], T, gun.path.lower())
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
            T1 = np.eye(4)
            T1[:3, 3] = p.position
            halo.set_transform(T1)
    log.debug("tool at 1 of %d welds; %d without a pose", len(ok), len(poses.poses) - len(ok))
    return slider


def keyframe_times(positions: NDArray[np.float64], quaternions: NDArray[np.float64],
                   reach: float) -> NDArray[np.float64]:  # fmt: skip
    """``(m,)`` from 0 to 1: each waypoint's share of the path, by the motion bound of each
    motion (TCP distance + rotation angle x ``reach`` mm), so a turn on the spot takes time."""
    from weldplan.tool.transitions.result import path_rotation

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

    from weldplan.tool.poses.route_frames import route_tool_path

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
    gun = node["gun"]  # drawn by draw_tool at the first weld
    times = keyframe_times(P, Q, float(np.linalg.norm(tool.vertices, axis=1).max()))
    frames = np.round(times * seconds * fps).astype(int)
    from scipy.spatial.transform import Rotation

    R = Rotation.from_quat(np.roll(Q, -1, axis=1)).as_matrix()
    T = np.tile(np.eye(4), (len(P), 1, 1))
    T[:, :3, :3] = R
    T[:, :3, 3] = P
    for f, Tk in zip(frames, T, strict=True):
        with anim.at_frame(gun, int(f)) as frame:
            frame.set_transform(Tk)
    log.debug("tool animated along %d waypoints", len(P))
    return True
