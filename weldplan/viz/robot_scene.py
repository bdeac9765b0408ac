"""The robot cell in meshcat: the part, the robot's links and the tool, animated along the timed
trajectory, with the viewer's time slider (its *Animations* panel: play, pause, scrub).

Drawn under ``weldplan_robot``: ``part``, ``links/<link name>`` (the robot's collision meshes, in
each link frame), ``tool`` (the tool mesh in its TCP frame, decimated for display by
:func:`weldplan.viz.tool_scene.display_mesh`) and ``route`` (the TCP polyline). Every link and the
tool get one keyframe per frame of :data:`FRAME_RATE` along the trajectory's own time axis
(:class:`~weldplan.robot.timing.TimedTrajectory`, joint values interpolated linearly between its
samples, which are :data:`~weldplan.robot.timing.DEFAULT_DT` apart), so the animation plays at
the cycle's real speed. Consumes results only: it imports no planner.
"""

from __future__ import annotations

import logging
import os
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
) -> int:
    """Draw the cell into meshcat visualizer ``vis`` and set its animation; returns the number of
    frames.

    Parameters
    ----------
    robot
        :class:`~weldplan.robot.model.Robot` placed in the part frame (``robot.base``).
    timing
        :class:`~weldplan.robot.timing.TimedTrajectory` of the robot's joint route.
    flange_tcp
        ``(4, 4)`` mm: the TCP in the flange frame.
    part
        Mesh or Cell (mm).
    tool
        :class:`~weldplan.tool.model.Tool` (mesh in its TCP frame, mm).
    route_points
        ``(m, 3)`` mm: the TCP route, drawn as a line.
    """
    import meshcat.geometry as g
    from meshcat.animation import Animation

    from weldplan.viz.viewer import _part_mesh, scene_transform

    root = vis["weldplan_robot"]
    root.delete()
    mesh = _part_mesh(part)
    F0 = robot.link_frames(timing.q[:1])[0]  # (7, 4, 4)
    pts = [F0[:, :3, 3]]
    if mesh is not None:
        pts.append(np.asarray(mesh.bounds))
    if route_points is not None and len(route_points):
        pts.append(np.asarray(route_points, dtype=np.float64))
    root.set_transform(scene_transform(np.concatenate(pts, axis=0)))
    if mesh is not None:
        root["part"].set_object(
            g.TriangularMeshGeometry(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
            g.MeshLambertMaterial(color=PART_COLOR, opacity=0.6, transparent=True, side=2),
        )
    if route_points is not None and len(route_points) > 1:
        P = np.asarray(route_points, dtype=np.float32)
        root["route"].set_object(
            g.Line(g.PointsGeometry(P.T), g.LineBasicMaterial(color=0xD62728, linewidth=3))
        )
    links = robot.links
    for link in links:
        root["links"][link.name].set_object(
            g.TriangularMeshGeometry(link.vertices, link.faces),
            g.MeshLambertMaterial(color=ROBOT_COLOR),
        )
    Tft = np.asarray(flange_tcp, dtype=np.float64).reshape(4, 4)
    if tool is not None:
        from weldplan.viz.tool_scene import display_mesh

        v, f = display_mesh(tool)
        root["tool"].set_object(
            g.TriangularMeshGeometry(v, f),
            g.MeshLambertMaterial(color=TOOL_COLOR, opacity=0.85, transparent=True),
        )
    times, fps = frame_times(float(timing.t[-1]) if len(timing.t) else 0.0)
    Q = sample_q(timing, times)
    F = robot.link_frames(Q)  # (f, 7, 4, 4)
    T_tool = robot.fk(Q) @ Tft
    anim = Animation(default_framerate=fps)
    for k in range(len(times)):
        for link in links:
            with anim.at_frame(root["links"][link.name], k) as fr:
                fr.set_transform(F[k, link.index])
        if tool is not None:
            with anim.at_frame(root["tool"], k) as fr:
                fr.set_transform(T_tool[k])
    for link in links:  # the first pose, before the animation plays
        root["links"][link.name].set_transform(F[0, link.index])
    if tool is not None:
        root["tool"].set_transform(T_tool[0])
    vis.set_animation(anim, play=True, repetitions=1000)
    if camera:
        vis["/Cameras/default/rotated/<object>"].set_property("position", [1.6, 1.2, 2.0])
        vis["/Grid"].set_property("visible", False)
        vis["/Axes"].set_property("visible", False)
    log.debug("robot scene: %d links, %d frames at %d fps", len(links), len(times), fps)
    return len(times)


def robot_html(robot: Any, timing: Any, flange_tcp: NDArray[np.float64], **kwargs: Any) -> str:
    """The self-contained HTML page of :func:`build_robot_scene` (no server, no network)."""
    import meshcat

    from weldplan.viz.viewer import RecordingWindow

    window = RecordingWindow()
    build_robot_scene(meshcat.Visualizer(window=window), robot, timing, flange_tcp, **kwargs)
    return window.get_scene(title="weldplan robot cell")


def write_robot_html(
    path: str | os.PathLike[str], robot: Any, timing: Any, flange_tcp: Any, **kwargs: Any
) -> Path:
    """Write :func:`robot_html` atomically."""
    from weldplan.io.export import write_text_atomic

    return write_text_atomic(path, robot_html(robot, timing, flange_tcp, **kwargs))
