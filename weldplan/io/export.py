"""Exports of a :class:`~weldplan.weld.route.Route` for offline programming: CSV, JSON, robot posts.

This module writes and reads the route CSV and JSON, and gathers the exporters' names in one
place: the all-or-nothing writer (:mod:`weldplan.io.atomic`: every writer here is atomic, a
failed run leaves an existing file exactly as it was), the waypoint rows
(:mod:`weldplan.io.route_rows`) and the robot posts (:mod:`weldplan.io.route_posts`).

CSV layout (one row per waypoint, in travel order)::

    step,kind,joint_id,x,y,z,tool_x,tool_y,tool_z
    0,weld,15,1549.76,-8.79,903.34,,,
    1,via,,1549.76,-13.79,903.34,,,
    ...

``kind`` is ``weld`` at a weld spot and ``via`` at a waypoint between spots (virtual joints and
local-path points); on a leg with a smooth path (``weldplan plan --smooth``,
:mod:`weldplan.weld.smoothing`) the waypoints between its two virtual joints are the dense
points of its C2 curve instead of the polyline's vias, of kind ``smooth`` (every chord between
them checked at the clearance, at most ``--smooth-spacing`` mm apart); ``tool_*`` is the
joint's unit approach direction as the joints CSV gave it
(columns ``nx, ny, nz``: from the weld spot towards the side the torch comes from), empty where
the CSV gave none and always on via rows. Coordinates are mm, in the frame the route was
planned in: a route planned with the part placed in the cell (:mod:`weldplan.cellframe`,
``plan --up/--part-pose``) is in the cell frame, and its CSV starts with one ``#`` line that
says so and gives the part pose (:func:`frame_comment`). A route planned with a tool
(``weldplan plan --tool``) has five more columns, ``qw,qx,qy,qz,status``: on a weld row the
weld's verified TCP pose (scalar-first quaternion of the TCP frame in the part frame; empty when
the weld has no free pose) and the weld's pose status (docs/tool.md). Via, approach and smooth
rows leave the four orientation cells empty: no orientation between welds was checked along
the point-tip route, so none is written there (no file carries a pose that was not checked).
The tool's verified path between welds is a file of its own (``--tool-csv``,
:mod:`weldplan.io.tool_csv`). The
robot posts point the tool's z axis (the torch axis, towards the work) against that direction,
into the surface; they do not use the tool poses yet.

Robot posts (:mod:`weldplan.io.route_posts`, re-exported here) are pluggable: ``render(route,
**options) -> str`` registered with :func:`register_post`; ``rapid`` (an ABB RAPID module) and
``krl`` (a KUKA KRL ``.src``) ship with weldplan, as documented examples. They blend corners only
where the part leaves room, so they need the part: ``render_post(route, "rapid",
part=cell_or_mesh)``.

The route JSON is a deliverable: the same inputs and seed give the same bytes on any machine.
:func:`write_json` writes it without the run's measured seconds, which
:mod:`weldplan.io.timings` moves to a file of their own.
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Sequence
from os import PathLike
from pathlib import Path

import numpy as np

from weldplan.errors import InputError
from weldplan.io.atomic import write_text_atomic
from weldplan.io.outputset import comment_lines
from weldplan.io.route_posts import (
    POSTS,
    Post,
    euler_zyx_deg,
    quaternion,
    register_post,
    render_krl,
    render_post,
    render_rapid,
    tool_frame,
    write_post,
)
from weldplan.io.route_rows import DIR_DECIMALS, MM_DECIMALS, route_rows, travel_route
from weldplan.io.route_rows import fixed as _fmt
from weldplan.weld.route import Route

__all__ = [
    "CSV_FIELDS",
    "POSE_FIELDS",
    "POSTS",
    "Post",
    "euler_zyx_deg",
    "frame_comment",
    "quaternion",
    "read_route",
    "register_post",
    "render_krl",
    "render_post",
    "render_rapid",
    "route_rows",
    "to_csv_text",
    "tool_frame",
    "travel_route",
    "write_csv",
    "write_json",
    "write_post",
    "write_text_atomic",
]

CSV_FIELDS = ("step", "kind", "joint_id", "x", "y", "z", "tool_x", "tool_y", "tool_z")
#: columns added for a route planned with a tool: TCP orientation in the part frame, weld status
POSE_FIELDS = ("qw", "qx", "qy", "qz", "status")


def to_csv_text(route: Route, header: Sequence[str] = ()) -> str:
    """The CSV text of :func:`write_csv`; ``header``: lines written first as ``#`` comments
    (what produced the file and what was verified, :func:`weldplan.station.outputs.producer`).

    A route that carries weld poses (``weldplan plan --tool``; read typed,
    :func:`weldplan.tool.poses.route_poses`) gains the columns :data:`POSE_FIELDS`,
    filled on weld rows only: the weld's verified TCP orientation (empty at a weld without a
    free pose) and its status (``ok`` or ``no free pose``). Other rows carry no orientation:
    nothing verified the tool there (the verified path between welds is the ``--tool-csv``
    file, :mod:`weldplan.io.tool_csv`).
    """
    from weldplan.tool.poses.route_frames import route_poses, weld_rows

    rows = route_rows(route, smooth=True)
    quats, status = None, None
    poses = route_poses(route)
    if poses is not None:
        quats = np.full((len(rows), 4), np.nan)  # only the verified weld poses are written
        status = [""] * len(rows)
        for i, r in enumerate(weld_rows(travel_route(route))):
            pose = poses.poses[i]
            status[int(r)] = pose.status
            if pose.ok and pose.quaternion is not None:
                quats[int(r)] = pose.quaternion
    buf = io.StringIO()
    buf.write(comment_lines(header, "#"))
    note = frame_comment(route)
    if note is not None:
        buf.write(f"# {note}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_FIELDS if quats is None else CSV_FIELDS + POSE_FIELDS)
    for k, r in enumerate(rows):
        tool = r["tool"]
        tool_cells = ["", "", ""] if tool is None else [f"{v:.{DIR_DECIMALS}f}" for v in tool]
        cells = (
            [r["step"], r["kind"], r["joint_id"]]
            + [f"{r[c]:.{MM_DECIMALS}f}" for c in ("x", "y", "z")]
            + tool_cells
        )
        if quats is not None and status is not None:
            q = quats[k]
            cells += ["", "", "", ""] if np.isnan(q[0]) else [_fmt(v, DIR_DECIMALS) for v in q]
            cells.append(status[k])
        w.writerow(cells)
    return buf.getvalue()


def frame_comment(route: Route) -> str | None:
    """One line saying the route is in the cell frame, with the part pose (row-major 4x4, part
    frame -> cell frame, mm) and the floor; ``None`` for a route in the part frame."""
    prov = route.provenance or {}
    pose = prov.get("part_pose")
    if prov.get("frame") != "cell" or not pose:
        return None
    m = " ".join(f"{float(v):.6g}" for row in pose["matrix"] for v in row)
    return (
        f"frame: cell (z up, floor at z {float(pose.get('floor_z', 0.0)):g} mm); part pose "
        f"({pose.get('given', 'matrix')}), part -> cell 4x4 row-major: {m}"
    )


def write_csv(route: Route, path: str | PathLike[str]) -> Path:
    """Write the route's waypoints as CSV (layout in the module docstring), atomically."""
    return write_text_atomic(path, to_csv_text(route))


def write_json(route: Route, path: str | PathLike[str]) -> Path:
    """Write the route without its measured times, atomically
    (:func:`weldplan.io.timings.route_json_texts` gives both texts)."""
    from weldplan.io.timings import route_json_texts

    return write_text_atomic(path, route_json_texts(route)[0])


def read_route(path: str | PathLike[str]) -> Route:
    """Read a route JSON written by :func:`write_json`.

    Raises
    ------
    InputError
        When the file is not JSON or not a weldplan route, naming the file (and line for JSON
        syntax errors).
    """
    text = Path(path).read_text(encoding="utf-8")
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON ({exc.msg})", path=path, line=exc.lineno) from None
    if not isinstance(data, dict):
        raise InputError("not a weldplan route (expected a JSON object)", path=path)
    try:
        return Route.from_dict(data)
    except (KeyError, TypeError, ValueError) as exc:
        msg = f"missing field {exc}" if isinstance(exc, KeyError) else str(exc)
        raise InputError(f"not a valid weldplan route: {msg}", path=path) from None
