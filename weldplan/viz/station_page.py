"""The station page: every robot of a station animated on one time slider, the Gantt chart below.

One self-contained HTML page (issue 30, item 5; the meshcat page of
:mod:`weldplan.viz.viewer`, no server, no network) of a
:class:`~weldplan.multi.station.StationPlan`:

- the part; every robot at its base with its tool, in its own colour (:data:`ROBOT_COLORS`),
  its route (the TCP's path) in that colour and its welds marked and labelled;
- one animation over the station's cycle (the viewer's *Animations* panel: play, pause and the
  time slider): at station time ``t`` each robot stands where its own timed trajectory has it
  at its own time :func:`own_times` ``(t)``, that is ``t`` less the waits it has already spent
  (held still while it waits at an interlock; its welds are dwells of its own timing, so it
  holds during them too; after its last activity it holds its last pose): :func:`station_q`;
- the station's Gantt chart (:func:`weldplan.viz.gantt.gantt_svg`) under the view, with a
  cursor at the slider's time; a click on the chart seeks the animation there. The page's
  address may give the opening time: ``station.html#t=12.5`` (s).

Under ``weldplan_station``: ``part`` and per robot ``robot<k>/links/<link>``, ``robot<k>/tool``,
``robot<k>/route``, ``robot<k>/welds/<n>``, ``robot<k>/labels/<n>`` (k from 1). The page opens
framed on the whole cell (the part, the routes, every link's and tool's box at every frame:
:func:`weldplan.viz.camera.frame_scene`). :func:`station_page` writes it; the CLI renders it with
:func:`station_page_text` and writes it with the station's other files as one set. Consumes
results only: it imports no planner.
"""

from __future__ import annotations

import dataclasses
import json
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.viz.robot_scene import (
    PART_COLOR,
    TOOL_COLOR,
    _box_corners,
    _draw_welds,
    _moved,
    frame_times,
    sample_q,
)

log = logging.getLogger(__name__)

#: the robots' colours, station order (then around again): KUKA orange, teal, magenta, olive,
#: brown, cyan; none near the tool's blue, the part's grey or the welds' red
ROBOT_COLORS = (0xF28C28, 0x1FA187, 0xB03A96, 0x9BBB1F, 0x8C564B, 0x17BECF)
#: deg: the camera stands this far off square to the line the robots' bases spread along
STATION_AZIMUTH_OFFSET_DEG = 20.0


@dataclass(frozen=True, eq=False)
class StationRobot:
    """What the page draws of one robot.

    Attributes
    ----------
    name
        As in the schedule.
    robot
        :class:`~weldplan.robot.model.Robot` at its base, part frame (mm).
    flange_tcp
        ``(4, 4)`` mm: the TCP in the flange frame.
    timing
        Its :class:`~weldplan.robot.program.TimedTrajectory`, or None for an idle robot (drawn
        at ``rest``).
    tool
        :class:`~weldplan.tool.model.Tool` (mesh in its TCP frame, mm), or None.
    route_points
        ``(m, 3)`` mm: the TCP's path, or None.
    weld_ids
        The welds' labels in the order of ``timing.weld_rows``, or None (1, 2, ...).
    rest
        ``(6,)`` rad: an idle robot's configuration (default all zero).
    """

    name: str
    robot: Any
    flange_tcp: NDArray[np.float64]
    timing: Any = None
    tool: Any = None
    route_points: NDArray[np.float64] | None = None
    weld_ids: tuple[str, ...] | None = None
    rest: tuple[float, ...] = (0.0,) * 6


def own_times(schedule: Any, robot: int, t: ArrayLike) -> NDArray[np.float64]:
    """``(f,)`` s: robot ``robot``'s own trajectory time at station times ``t (f,)`` s.

    Station time less the waits of the robot already spent: ``t - sum_w clip(t - w.start, 0,
    w.duration)`` over its ``wait`` activities (:class:`~weldplan.multi.schedule.Activity`),
    so its own clock stands still while it waits and runs with the station's otherwise
    (:func:`weldplan.multi.schedule.station_schedule` shifts each robot's own timing by the
    waits before it)."""
    T = np.asarray(t, dtype=np.float64)
    out = T.copy()
    for a in schedule.of(robot):
        if a.kind == "wait":
            out -= np.clip(T - a.start, 0.0, a.duration)
    return out


def station_q(schedule: Any, timings: Sequence[Any | None], t: ArrayLike) -> list[NDArray | None]:
    """Per robot its ``(f, 6)`` joint values (rad) at station times ``t (f,)`` s (None for an
    idle robot): its own trajectory at :func:`own_times`, linear between its samples, held at
    its ends."""
    out: list[NDArray | None] = []
    for r, timing in enumerate(timings):
        out.append(None if timing is None else sample_q(timing, own_times(schedule, r, t)))
    return out


def station_robots(station_plan: Any) -> list[StationRobot]:
    """Per robot of a :class:`~weldplan.multi.station.StationPlan` what the page draws; an idle
    robot (no plan) is loaded from its station entry and drawn at rest with its tool."""
    out = []
    names = station_plan.schedule.robots
    for k, plan in enumerate(station_plan.plans):
        if plan is None:
            out.append(_idle_robot(names[k], station_plan.station.robots[k]))
            continue
        joint = plan.robot
        out.append(
            StationRobot(
                names[k],
                joint.robot,
                np.asarray(joint.robot_route.flange_tcp),
                plan.program.timing,
                plan.tool.tool if plan.tool is not None else None,
                np.asarray(joint.follow.waypoints()),
                plan.program.welded_ids(),
            )  # fmt: skip
        )
    return out


def _idle_robot(name: str, spec: Any) -> StationRobot:
    from weldplan.robot import load_robot
    from weldplan.robot.placement.reach import base_pose
    from weldplan.station.mount import mount_tool

    robot = load_robot(spec.urdf, spec.opw, base=base_pose(*spec.base))
    mounted = mount_tool(spec.tool, robot)
    return StationRobot(name, robot, np.asarray(mounted.flange_tcp), tool=mounted.tool)


def build_station_scene(
    vis: Any, robots: Sequence[StationRobot], schedule: Any, *, part: Any = None,
    camera: bool = True,
) -> int:  # fmt: skip
    """Draw the station into meshcat visualizer ``vis`` (module docstring) and set its one
    animation over ``schedule``'s cycle (:data:`~weldplan.viz.robot_scene.FRAME_RATE` frames
    a second, at most :data:`~weldplan.viz.robot_scene.MAX_FRAMES`); returns the frames."""
    import meshcat.geometry as g

    from weldplan.viz.viewer import _part_mesh

    if len(robots) != len(schedule.robots):
        raise ValueError(f"{len(robots)} robots drawn for {len(schedule.robots)} scheduled")
    root = vis["weldplan_station"]
    root.delete()
    mesh = _part_mesh(part)
    times, fps = frame_times(float(schedule.cycle_time))
    Qs = station_q(schedule, [r.timing for r in robots], times)
    frames, tools, meshes = [], [], []
    for r, Q in zip(robots, Qs, strict=True):
        Q = np.tile(np.asarray(r.rest, dtype=float), (len(times), 1)) if Q is None else Q
        frames.append(r.robot.link_frames(Q))
        tools.append(r.robot.fk(Q) @ np.asarray(r.flange_tcp, dtype=float).reshape(4, 4))
        meshes.append(_tool_mesh(r.tool))
    scale = _frame(vis, root, robots, frames, tools, meshes, mesh, camera)
    if mesh is not None:
        root["part"].set_object(
            g.TriangularMeshGeometry(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
            g.MeshLambertMaterial(color=PART_COLOR, opacity=0.6, transparent=True, side=2),
        )
    for k, r in enumerate(robots):
        _draw_robot(root[f"robot{k + 1}"], r, robot_color(k), meshes[k], scale)
    _animate(vis, root, robots, frames, tools, meshes, fps)
    log.debug("station scene: %d robots, %d frames at %d fps", len(robots), len(times), fps)
    return len(times)


def robot_color(k: int) -> int:
    """Robot ``k``'s colour (0-based, station order): :data:`ROBOT_COLORS`, then around."""
    return ROBOT_COLORS[k % len(ROBOT_COLORS)]


def _tool_mesh(tool: Any) -> Any:
    if tool is None:
        return None
    from weldplan.viz.tool_scene import display_mesh

    return display_mesh(tool)


def _frame(
    vis: Any, root: Any, robots: Sequence[StationRobot], frames: list, tools: list, meshes: list,
    mesh: Any, camera: bool,
) -> float:  # fmt: skip
    """Frame the part, the routes and every link's and tool's box at every frame; the scale."""
    from weldplan.viz.camera import frame_scene

    pts = []
    for r, F, T, tm in zip(robots, frames, tools, meshes, strict=True):
        pts += [_moved(_box_corners(link.vertices), F[:, link.index]) for link in r.robot.links]
        if tm is not None:
            pts.append(_moved(_box_corners(tm[0]), T))
        if r.route_points is not None and len(r.route_points):
            pts.append(np.asarray(r.route_points, dtype=np.float64))
    if mesh is not None:
        pts.append(np.asarray(mesh.vertices))
    bases = np.array([r.robot.base[:3, 3] for r in robots]).reshape(-1, 3)
    return frame_scene(vis, root, np.concatenate(pts, axis=0), camera=camera,
                       azimuth_deg=station_azimuth(bases))  # fmt: skip


def station_azimuth(bases: ArrayLike) -> float:
    """The camera's azimuth (deg) for robots at ``bases (R, 3)`` mm: across the line the bases
    spread along (their principal horizontal direction), :data:`STATION_AZIMUTH_OFFSET_DEG`
    off square so the cell's depth reads, on the side nearer the pages' usual
    :data:`~weldplan.viz.camera.AZIMUTH_DEG`; that one for a single robot or bases in one
    spot."""
    from weldplan.viz.camera import AZIMUTH_DEG

    P = np.asarray(bases, dtype=float).reshape(-1, 3)[:, :2]
    if len(P) < 2 or np.ptp(P, axis=0).max() < 1.0:
        return AZIMUTH_DEG
    d = np.linalg.svd(P - P.mean(axis=0))[2][0]
    along = float(np.degrees(np.arctan2(d[1], d[0])))
    sides = [along - 90.0 + STATION_AZIMUTH_OFFSET_DEG, along + 90.0 + STATION_AZIMUTH_OFFSET_DEG]
    return min(sides, key=lambda a: abs((a - AZIMUTH_DEG + 180.0) % 360.0 - 180.0))


def _draw_robot(node: Any, r: StationRobot, color: int, tool_mesh: Any, scale: float) -> None:
    """One robot's links and tool (in ``color``; the tool in the tools' blue), route, welds."""
    import meshcat.geometry as g

    for link in r.robot.links:
        node["links"][link.name].set_object(
            g.TriangularMeshGeometry(link.vertices, link.faces), g.MeshLambertMaterial(color=color)
        )
    if tool_mesh is not None:
        node["tool"].set_object(
            g.TriangularMeshGeometry(*tool_mesh),
            g.MeshLambertMaterial(color=TOOL_COLOR, opacity=0.85, transparent=True),
        )
    if r.route_points is not None and len(r.route_points) > 1:
        P = np.asarray(r.route_points, dtype=np.float32)
        node["route"].set_object(
            g.Line(g.PointsGeometry(P.T), g.LineBasicMaterial(color=color, linewidth=3))
        )
    if r.timing is not None:
        Tft = np.asarray(r.flange_tcp, dtype=float).reshape(4, 4)
        _draw_welds(node, r.robot, r.timing, Tft, r.weld_ids, scale)


def _animate(
    vis: Any, root: Any, robots: Sequence[StationRobot], frames: list, tools: list, meshes: list,
    fps: int,
) -> None:  # fmt: skip
    """One keyframe a frame for every link and tool of every robot, on one clip; the first
    pose set before it plays."""
    from meshcat.animation import Animation

    anim = Animation(default_framerate=fps)
    for k, (r, F, T, tm) in enumerate(zip(robots, frames, tools, meshes, strict=True)):
        node = root[f"robot{k + 1}"]
        for f in range(len(F)):
            for link in r.robot.links:
                with anim.at_frame(node["links"][link.name], f) as fr:
                    fr.set_transform(F[f, link.index])
            if tm is not None:
                with anim.at_frame(node["tool"], f) as fr:
                    fr.set_transform(T[f])
        for link in r.robot.links:
            node["links"][link.name].set_transform(F[0, link.index])
        if tm is not None:
            node["tool"].set_transform(T[0])
    vis.set_animation(anim, play=True, repetitions=1000)


def station_html(
    robots: Sequence[StationRobot], schedule: Any, *, part: Any = None,
    bound: float | None = None, title: str = "weldplan station",
) -> str:  # fmt: skip
    """The self-contained page (module docstring) of ``robots`` running ``schedule``, with
    ``bound`` (s, the allocation's lower bound) on the chart."""
    import meshcat

    from weldplan.viz.gantt import gantt_svg
    from weldplan.viz.viewer import RecordingWindow

    window = RecordingWindow()
    build_station_scene(meshcat.Visualizer(window=window), robots, schedule, part=part)
    chart = gantt_svg(schedule, bound=bound)
    return window.get_scene(title=title, overlay=gantt_overlay(chart, schedule, robots))


def gantt_overlay(chart: Any, schedule: Any, robots: Sequence[StationRobot]) -> str:
    """The chart laid under the view with its cursor (:class:`~weldplan.viz.gantt.GanttSvg`),
    and a key of the robots' colours."""
    data = {
        "x0": chart.x0, "x1": chart.x1, "y0": chart.y0, "y1": chart.y1, "tMax": chart.t_max,
        "cycle": float(schedule.cycle_time),
    }  # fmt: skip
    key = " ".join(
        f'<span style="color:#{robot_color(k):06X}">&#9632;</span> {r.name}'
        for k, r in enumerate(robots)
    )
    return _OVERLAY.format(svg=chart.svg, key=key, data=json.dumps(data, separators=(",", ":")))


def station_page(station_plan: Any, path: str | PathLike[str]) -> Path:
    """Write the page of a :class:`~weldplan.multi.station.StationPlan` to ``path``, whole or
    not at all; returns the path. The chart carries the allocation's lower bound."""
    from weldplan.io.export import write_text_atomic

    return write_text_atomic(path, station_page_text(station_plan))


def station_page_text(station_plan: Any) -> str:
    """The page of a :class:`~weldplan.multi.station.StationPlan` (:func:`station_page`) as
    text, for a caller that writes it with other files as one set."""
    robots = station_robots(station_plan)
    part = next((p.cell.part for p in station_plan.plans if p is not None), None)
    return station_html(
        robots, station_plan.schedule, part=part, bound=float(station_plan.report.bound.value),
        title=f"weldplan station: {len(robots)} robots",
    )  # fmt: skip


@dataclass(frozen=True, eq=False)
class SavedTiming:
    """A robot's timed route as its saved files give it: what the page reads of a
    :class:`~weldplan.robot.program.TimedTrajectory`.

    Attributes
    ----------
    t, q
        ``(m,)`` s and ``(m, 6)`` rad: its trajectory CSV's samples, on its own clock.
    row_times
        ``(n,)`` s: the arrival at each stop row on its own clock (the schedule's moves and
        welds before it, its waits taken out; :func:`weldplan.multi.filetiming.file_timing`).
    weld_rows
        ``(w,)``: the timed rows the schedule records a weld at, in order.
    weld_time
        s per weld (the schedule's weld activities).
    """

    t: NDArray[np.float64]
    q: NDArray[np.float64]
    row_times: NDArray[np.float64]
    weld_rows: NDArray[np.int64]
    weld_time: float


def saved_station_robots(saved: Any, station: Any) -> list[StationRobot]:
    """Per robot of a saved station plan (:class:`~weldplan.multi.saved.SavedStationPlan`)
    what the page draws, from its files alone: the URDF, OPW and tool of ``station`` (its
    :class:`~weldplan.station.model.Station`) at the recorded base, its trajectory CSV timed
    by the schedule (:class:`SavedTiming`), its TCP path by forward kinematics of the CSV's
    samples, its welds labelled as the schedule labels them; an idle robot at rest."""
    from weldplan.multi.filetiming import file_timing
    from weldplan.robot import load_robot
    from weldplan.robot.placement.reach import base_pose
    from weldplan.station.mount import mount_tool

    out = []
    for k, (rec, spec) in enumerate(zip(saved.robots, station.robots, strict=True)):
        base = rec.base if rec.base is not None else spec.base
        spec = dataclasses.replace(spec, base=base)
        acts = saved.schedule.of(k)
        if rec.trajectory is None or not acts:
            out.append(_idle_robot(rec.name, spec))
            continue
        robot = load_robot(spec.urdf, spec.opw, base=base_pose(*base))
        mounted = mount_tool(spec.tool, robot)
        ft = file_timing(saved.schedule, k, rec.trajectory)
        welds = [a for a in acts if a.kind == "weld"]
        timing = SavedTiming(
            ft.t, ft.q, ft.row_times, np.array([a.row for a in welds], dtype=np.int64),
            welds[0].duration if welds else 0.0,
        )  # fmt: skip
        Tft = np.asarray(mounted.flange_tcp, dtype=float).reshape(4, 4)
        path = (robot.fk(ft.q) @ Tft)[:, :3, 3]
        ids = tuple(a.label or str(n + 1) for n, a in enumerate(welds))
        out.append(StationRobot(rec.name, robot, Tft, timing, mounted.tool, path, ids))
    return out


def saved_station_part(station: Any) -> Any:
    """The part of ``station`` where the plan had it: its mesh loaded as the station gives it
    and placed in the cell by its part pose (the demo's without a mesh)."""
    from weldplan.io.mesh import load_part

    p = station.part
    if p.is_demo:
        from weldplan.weld import demo_part

        part = load_part(demo_part.DEMO_PART)
    else:
        part = load_part(p.mesh, units=p.units, scale=p.scale, length=p.length)
    pose = station.part_pose
    return part if pose is None else pose.placed(part.vertices).mesh_to_cell(part)


def saved_station_page_text(saved: Any, station: Any) -> str:
    """The page of a saved station plan (:class:`~weldplan.multi.saved.SavedStationPlan`)
    rebuilt from its files (:func:`saved_station_robots`, :func:`saved_station_part`) and
    ``station``: what ``weldplan view route_station.json --html`` writes; the chart carries
    the recorded lower bound."""
    if saved.schedule is None:
        from weldplan.errors import InputError

        raise InputError("the plan records no schedule to draw", path=saved.path, field="schedule")
    robots = saved_station_robots(saved, station)
    bound = None if saved.report is None else float(saved.report.bound.value)
    return station_html(
        robots, saved.schedule, part=saved_station_part(station), bound=bound,
        title=f"weldplan station: {len(robots)} robots",
    )  # fmt: skip


_OVERLAY = """<div id="weldplan-gantt"
 style="margin:0 auto;width:min(960px,98vw);font:13px sans-serif">
<div style="padding:2px 8px">{key} &nbsp; station time <b id="weldplan-t">0.00</b> s</div>
<div id="weldplan-chart" style="position:relative;cursor:crosshair">
{svg}
<div id="weldplan-cursor" style="position:absolute;width:2px;background:#D62728;
pointer-events:none"></div>
</div>
</div>
<style>#weldplan-chart svg {{ width: 100%; height: auto; display: block; }}</style>
<script>
(function () {{
  var d = {data};
  var pane = document.getElementById("meshcat-pane");
  var gantt = document.getElementById("weldplan-gantt");
  var chart = document.getElementById("weldplan-chart");
  var cursor = document.getElementById("weldplan-cursor");
  var label = document.getElementById("weldplan-t");
  cursor.style.top = (100 * d.y0) + "%";
  cursor.style.height = (100 * (d.y1 - d.y0)) + "%";
  function fit() {{  // the 3D view takes the window's height less the chart's
    var h = Math.max(200, window.innerHeight - gantt.offsetHeight);
    if (pane.offsetHeight !== h || viewer.renderer.domElement.height !== h) {{
      pane.style.height = h + "px";
      viewer.set_3d_pane_size(pane.offsetWidth, h);
    }}
  }}
  window.onload = fit;
  window.addEventListener("resize", fit, false);
  function place(t) {{
    t = Math.max(0, Math.min(d.cycle, t));
    cursor.style.left = (100 * (d.x0 + (d.x1 - d.x0) * t / d.tMax)) + "%";
    label.textContent = t.toFixed(2);
  }}
  function seek(t) {{
    t = Math.max(0, Math.min(d.cycle, t));
    viewer.animator.play();
    viewer.animator.pause();
    viewer.animator.seek(t);
    viewer.animator.display_progress(t);
    viewer.set_dirty();
    place(t);
  }}
  chart.addEventListener("click", function (e) {{
    var box = chart.getBoundingClientRect();
    var share = (e.clientX - box.left) / box.width;
    seek((share - d.x0) / (d.x1 - d.x0) * d.tMax);
  }});
  var hash = decodeURIComponent(window.location.hash.slice(1));
  if (hash.indexOf("t=") === 0 && isFinite(Number(hash.slice(2)))) seek(Number(hash.slice(2)));
  function tick() {{
    fit();
    place(viewer.animator.time || 0);
    window.requestAnimationFrame(tick);
  }}
  tick();
}})();
</script>"""
