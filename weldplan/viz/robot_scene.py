"""The robot cell in meshcat: the part, the robot's links and the tool, animated along the timed
trajectory, with the viewer's time slider (its *Animations* panel: play, pause, scrub).

Drawn under ``weldplan_robot``: ``part``, ``links/<link name>`` (the robot's collision meshes, in
each link frame), ``tool`` (the tool mesh in its TCP frame, decimated for display by
:func:`weldplan.viz.tool_scene.display_mesh`) and ``route`` (the TCP polyline). Every link and the
tool get one keyframe per frame of :data:`FRAME_RATE` along the trajectory's own time axis
(:class:`~weldplan.robot.program.TimedTrajectory`, joint values interpolated linearly between its
samples, which are :data:`~weldplan.robot.program.timing.DEFAULT_DT` apart), so the animation plays
at the cycle's real speed. ``welds/<k>`` and ``labels/<k>`` mark the TCP at each weld (forward
kinematics at the weld's dwell), labelled with the weld's id.

The page opens framed on the part, the route, and the robot and the tool over the whole cycle
(the bounding box of every link's and the tool's box at every frame:
:func:`weldplan.viz.camera.frame_scene`), paused at the first weld; the weld slider laid over it
(:func:`robot_slider`) seeks the animation to any weld's dwell, and the *Animations* panel plays
the cycle. Consumes results only: it imports no planner.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

log = logging.getLogger(__name__)

#: animation frames per second of trajectory time
FRAME_RATE = 30
#: frames at most (a longer cycle is shown at a lower frame rate, same duration)
MAX_FRAMES = 3000
ROBOT_COLOR = 0xF28C28  # KUKA orange
TOOL_COLOR = 0x4A6FA5
PART_COLOR = 0x9AA6B2
WELD_COLOR = 0xD62728


def frame_times(total: float, fps: int = FRAME_RATE, max_frames: int = MAX_FRAMES):
    """``(times (f,) s, fps used)``: one frame per ``1 / fps`` s, at most ``max_frames``."""
    fps_used = fps if total * fps <= max_frames else max(1, int(max_frames / max(total, 1e-9)))
    n = int(np.floor(total * fps_used + 1e-9)) + 1
    return np.arange(n) / fps_used, fps_used


def sample_q(timing: Any, times: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(f, 6)`` joint values at ``times`` (linear between the trajectory's samples)."""
    t = np.asarray(timing.t)
    Q = np.asarray(timing.q)
    return np.column_stack([np.interp(times, t, Q[:, j]) for j in range(Q.shape[1])])


def _box_corners(V: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(8, 3)`` the corners of the bounding box of points ``V (n, 3)``."""
    lo, hi = V.min(axis=0), V.max(axis=0)
    return np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                     for i in (0, 1) for j in (0, 1) for k in (0, 1)])  # fmt: skip


def _moved(corners: NDArray[np.float64], T: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(f * 8, 3)``: ``corners (8, 3)`` moved by each of ``T (f, 4, 4)``."""
    return (np.einsum("fij,kj->fki", T[:, :3, :3], corners) + T[:, None, :3, 3]).reshape(-1, 3)


def weld_times(timing: Any) -> NDArray[np.float64]:
    """``(w,)`` s: the middle of each weld's dwell on the trajectory's time axis."""
    rows = np.asarray(timing.weld_rows, dtype=np.int64)
    return np.asarray(timing.row_times, dtype=np.float64)[rows] + 0.5 * float(timing.weld_time)


def build_robot_scene(
    vis: Any,
    robot: Any,
    timing: Any,
    flange_tcp: NDArray[np.float64],
    *,
    part: Any = None,
    tool: Any = None,
    route_points: NDArray[np.float64] | None = None,
    camera: bool = True,
    weld_ids: Sequence[str] | None = None,
) -> int:
    """Draw the cell into meshcat visualizer ``vis`` and set its animation; returns the number of
    frames.

    Parameters
    ----------
    robot
        :class:`~weldplan.robot.model.Robot` placed in the part frame (``robot.base``).
    timing
        :class:`~weldplan.robot.program.TimedTrajectory` of the robot's joint route.
    flange_tcp
        ``(4, 4)`` mm: the TCP in the flange frame.
    part
        Mesh or Cell (mm).
    tool
        :class:`~weldplan.tool.model.Tool` (mesh in its TCP frame, mm).
    route_points
        ``(m, 3)`` mm: the TCP route, drawn as a line.
    camera
        Frame the view on the cell (:mod:`weldplan.viz.camera`).
    weld_ids
        ``(w,)`` the welds' labels, in the order of ``timing.weld_rows`` (default 1, 2, ...).
    """
    import meshcat.geometry as g

    from weldplan.viz.viewer import _part_mesh

    root = vis["weldplan_robot"]
    root.delete()
    mesh = _part_mesh(part)
    times, fps = frame_times(float(timing.t[-1]) if len(timing.t) else 0.0)
    Q = sample_q(timing, times)
    F = robot.link_frames(Q)  # (f, 7, 4, 4)
    Tft = np.asarray(flange_tcp, dtype=np.float64).reshape(4, 4)
    T_tool = robot.fk(Q) @ Tft
    tool_mesh = None
    if tool is not None:
        from weldplan.viz.tool_scene import display_mesh

        tool_mesh = display_mesh(tool)
    scale = _frame_cell(vis, root, robot, F, T_tool, mesh, tool_mesh, route_points, camera)
    if mesh is not None:
        root["part"].set_object(
            g.TriangularMeshGeometry(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
            g.MeshLambertMaterial(color=PART_COLOR, opacity=0.6, transparent=True, side=2),
        )
    if route_points is not None and len(route_points) > 1:
        P = np.asarray(route_points, dtype=np.float32)
        root["route"].set_object(
            g.Line(g.PointsGeometry(P.T), g.LineBasicMaterial(color=WELD_COLOR, linewidth=3))
        )
    for link in robot.links:
        root["links"][link.name].set_object(
            g.TriangularMeshGeometry(link.vertices, link.faces),
            g.MeshLambertMaterial(color=ROBOT_COLOR),
        )
    if tool_mesh is not None:
        root["tool"].set_object(
            g.TriangularMeshGeometry(*tool_mesh),
            g.MeshLambertMaterial(color=TOOL_COLOR, opacity=0.85, transparent=True),
        )
    _draw_welds(root, robot, timing, Tft, weld_ids, scale)
    _animate(vis, root, robot, F, T_tool if tool_mesh is not None else None, fps)
    log.debug("robot scene: %d links, %d frames at %d fps", len(robot.links), len(times), fps)
    return len(times)


def _frame_cell(
    vis: Any, root: Any, robot: Any, F: NDArray, T_tool: NDArray, mesh: Any, tool_mesh: Any,
    route_points: Any, camera: bool,
) -> float:  # fmt: skip
    """Frame the part, the route, every link's box at every frame ``F (f, 7, 4, 4)`` and the
    tool's at ``T_tool (f, 4, 4)``; returns the scene's scale (viewer units per mm)."""
    from weldplan.viz.camera import ROBOT_ELEVATION_DEG, frame_scene, robot_azimuth

    pts = [_moved(_box_corners(link.vertices), F[:, link.index]) for link in robot.links]
    if tool_mesh is not None:
        pts.append(_moved(_box_corners(tool_mesh[0]), T_tool))
    work = [T_tool[:, :3, 3]]  # what the robot reaches for: the part, else the TCP's path
    if mesh is not None:
        pts.append(np.asarray(mesh.vertices))
        work = [np.asarray(mesh.bounds)]
    if route_points is not None and len(route_points):
        pts.append(np.asarray(route_points, dtype=np.float64))
    W = np.concatenate(work)
    azimuth = robot_azimuth(robot.base[:3, 3], (W.min(axis=0) + W.max(axis=0)) / 2)
    return frame_scene(vis, root, np.concatenate(pts, axis=0), camera=camera,
                       azimuth_deg=azimuth, elevation_deg=ROBOT_ELEVATION_DEG)  # fmt: skip


def _draw_welds(
    root: Any, robot: Any, timing: Any, Tft: NDArray, ids: Sequence[str] | None, scale: float
) -> None:
    """A sphere and a label at the TCP of each weld (FK at :func:`weld_times`)."""
    import meshcat.geometry as g

    from weldplan.viz.viewer import _translation, draw_label

    if not len(timing.weld_rows):
        return
    P = (robot.fk(sample_q(timing, weld_times(timing))) @ Tft)[:, :3, 3]
    labels = _weld_labels(ids, len(P))
    r = 0.006 / scale  # spheres of 0.6 % of the framed scene's size
    for k, (jid, p) in enumerate(zip(labels, P, strict=True)):
        root["welds"][str(k)].set_object(g.Sphere(r), g.MeshLambertMaterial(color=WELD_COLOR))
        root["welds"][str(k)].set_transform(_translation(p))
        draw_label(root["labels"][str(k)], jid, p + [0.0, 0.0, 2.0 * r], scale)


def _weld_labels(ids: Sequence[str] | None, n: int) -> list[str]:
    if ids is None:
        return [str(k + 1) for k in range(n)]
    if len(ids) != n:
        raise ValueError(f"{len(ids)} weld ids for {n} welds on the trajectory")
    return [str(i) for i in ids]


def _animate(vis: Any, root: Any, robot: Any, F: NDArray, T_tool: NDArray | None, fps: int):
    """One keyframe a frame for every link and the tool; the first pose set before it plays."""
    from meshcat.animation import Animation

    anim = Animation(default_framerate=fps)
    for k in range(len(F)):
        for link in robot.links:
            with anim.at_frame(root["links"][link.name], k) as fr:
                fr.set_transform(F[k, link.index])
        if T_tool is not None:
            with anim.at_frame(root["tool"], k) as fr:
                fr.set_transform(T_tool[k])
    for link in robot.links:  # the first pose, before the animation plays
        root["links"][link.name].set_transform(F[0, link.index])
    if T_tool is not None:
        root["tool"].set_transform(T_tool[0])
    vis.set_animation(anim, play=True, repetitions=1000)


def robot_slider(timing: Any, weld_ids: Sequence[str] | None = None) -> Any:
    """The page's :class:`~weldplan.viz.overlay.WeldSlider`: the animation at each weld's dwell
    (:func:`weld_times`)."""
    from weldplan.viz.overlay import WeldSlider

    ids = _weld_labels(weld_ids, len(timing.weld_rows))
    return WeldSlider.from_times(ids, weld_times(timing), "robot at weld")


def robot_html(robot: Any, timing: Any, flange_tcp: NDArray[np.float64], **kwargs: Any) -> str:
    """The self-contained HTML page of :func:`build_robot_scene` (no server, no network)."""
    import meshcat

    from weldplan.viz.viewer import RecordingWindow

    window = RecordingWindow()
    build_robot_scene(meshcat.Visualizer(window=window), robot, timing, flange_tcp, **kwargs)
    slider = robot_slider(timing, kwargs.get("weld_ids"))
    return window.get_scene(title="weldplan robot cell", overlay=slider.html())


def write_robot_html(
    path: str | os.PathLike[str], robot: Any, timing: Any, flange_tcp: Any, **kwargs: Any
) -> Path:
    """Write :func:`robot_html` atomically."""
    from weldplan.io.export import write_text_atomic

    return write_text_atomic(path, robot_html(robot, timing, flange_tcp, **kwargs))
