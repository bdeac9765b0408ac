"""Exports of a :class:`~weldplan.weld.route.Route` for offline programming: CSV, JSON, robot posts.

Every writer is atomic: the text is written to a temporary file in the destination folder, flushed
to disk, then renamed over the destination with :func:`os.replace`. A run that fails (an error
while rendering, a full disk, an interrupt) leaves an existing file exactly as it was.

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

Robot posts are pluggable: a post is a function ``render(route, **options) -> str`` registered under
a name with :func:`register_post`. Two ship with weldplan, both documented examples rather than
cell-ready programs (tool, work object, speeds and the weld process instructions are the
integrator's): ``rapid`` (an ABB RAPID module) and ``krl`` (a KUKA KRL ``.src``).

Both blend corners only where the part leaves room (:mod:`weldplan.io.blending`): a via point
flies by with the largest zone whose radius fits its free margin (exact distance to the part
minus the clearance, and at most half of each adjacent segment), else it is an exact stop. So
they need the part: ``render_post(route, "rapid", part=cell_or_mesh)``; without it they refuse.

The route JSON is a deliverable: the same inputs and seed give the same bytes on any machine.
:func:`write_json` writes it without the run's measured seconds, which
:mod:`weldplan.io.timings` moves to a file of their own.
"""

from __future__ import annotations

import csv
import io
import json
import logging
import os
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError, WeldplanError
from weldplan.io.blending import allowed_radii, krl_cdis, rapid_zone, route_clearance
from weldplan.io.outputset import comment_lines
from weldplan.io.smooth_moves import krl_smooth_note, smooth_header, spline_rows
from weldplan.weld.route import Route

log = logging.getLogger(__name__)

CSV_FIELDS = ("step", "kind", "joint_id", "x", "y", "z", "tool_x", "tool_y", "tool_z")
#: columns added for a route planned with a tool: TCP orientation in the part frame, weld status
POSE_FIELDS = ("qw", "qx", "qy", "qz", "status")

#: decimals written for coordinates (mm) and unit directions
_MM_DECIMALS = 4
_DIR_DECIMALS = 6


# ---------------------------------------------------------------------------- atomic writes
def write_text_atomic(path: str | PathLike[str], text: str, *, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` whole or not at all (temp file in the same folder + rename).

    Returns the path written. Raises :class:`~weldplan.errors.WeldplanError` when the folder does
    not exist, so the CLI reports it in one line.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise WeldplanError(f"{path}: folder {folder} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding=encoding, newline="") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        if path.exists():
            os.chmod(tmp, path.stat().st_mode & 0o777)
        else:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    log.debug("wrote %s (%d chars)", path, len(text))
    return path


# ---------------------------------------------------------------------------- rows
def route_rows(route: Route, smooth: bool = False) -> list[dict[str, Any]]:
    """The route as waypoint rows (see the module docstring), in travel order.

    Weld spots shared by consecutive legs appear once. ``smooth=True``: the legs' smooth paths
    where they have one (rows of kind ``smooth`` between the virtual joints), as the exports
    write them; False (default): the polylines, the rows of :meth:`Route.waypoints`.
    """
    rows: list[dict[str, Any]] = []

    def add(kind: str, joint_id: str, p: NDArray[np.float64]) -> None:
        d = None
        if kind == "weld" and route.directions is not None:
            d = route.directions[route.index_of(joint_id)]
        rows.append(
            {
                "step": len(rows),
                "kind": kind,
                "joint_id": joint_id if kind == "weld" else "",
                "x": float(p[0]),
                "y": float(p[1]),
                "z": float(p[2]),
                "tool": None if d is None or not np.all(np.isfinite(d)) else d,
            }
        )

    if not route.legs:
        for jid in route.order:
            add("weld", jid, route.joint_xyz[route.index_of(jid)])
        return rows
    first = route.legs[0]
    add("weld", first.from_id, first.points[0])
    for leg in route.legs:
        vias = leg.points[1:-1]
        for p in (leg.path if smooth else leg.points)[1:-1]:
            on_polyline = leg.smooth is None or not smooth or bool(np.all(vias == p, axis=1).any())
            add("via" if on_polyline else "smooth", "", p)
        add("weld", leg.to_id, leg.points[-1])
    return rows


def travel_route(route: Route) -> Route:
    """``route`` with each leg's polyline replaced by its :attr:`~weldplan.weld.route.Leg.path`
    (its smooth path where it has one): the route whose :meth:`Route.waypoints` are the rows of
    ``route_rows(route, smooth=True)``. ``route`` itself when no leg is smoothed."""
    if not route.has_smooth:
        return route
    import dataclasses

    legs = tuple(
        dataclasses.replace(leg, points=leg.path, smooth=None, length=float("nan"))
        for leg in route.legs
    )
    return dataclasses.replace(route, legs=legs)


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
        tool_cells = ["", "", ""] if tool is None else [f"{v:.{_DIR_DECIMALS}f}" for v in tool]
        cells = (
            [r["step"], r["kind"], r["joint_id"]]
            + [f"{r[c]:.{_MM_DECIMALS}f}" for c in ("x", "y", "z")]
            + tool_cells
        )
        if quats is not None and status is not None:
            q = quats[k]
            cells += ["", "", "", ""] if np.isnan(q[0]) else [_fmt(v, _DIR_DECIMALS) for v in q]
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


# ---------------------------------------------------------------------------- orientations
def tool_frame(direction: NDArray[np.float64] | None) -> NDArray[np.float64]:
    """``(3, 3)`` rotation whose z column is the tool axis.

    With a ``direction`` (unit, (3,)) the tool's z axis points along it and its x axis is world x
    projected onto the normal plane (world y when the tool axis is parallel to x). Without one the
    tool points straight down (world -z), x along world x.
    """
    if direction is None or not np.all(np.isfinite(direction)):
        return np.diag([1.0, -1.0, -1.0])
    z = np.asarray(direction, dtype=float)
    z = z / np.linalg.norm(z)
    ref = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = ref - z * np.dot(ref, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


def quaternion(R: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(4,)`` unit quaternion ``[w, x, y, z]`` of rotation ``R (3, 3)`` (ABB's q1..q4 order)."""
    t = np.trace(R)
    if t > 0:
        s = 2.0 * np.sqrt(1.0 + t)
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = [(R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
    elif R[1, 1] > R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s]
    q = np.asarray(q)
    q /= np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def euler_zyx_deg(R: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(3,)`` KUKA A, B, C in degrees: ``R = Rz(A) @ Ry(B) @ Rx(C)``."""
    B = np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0]))
    if np.hypot(R[0, 0], R[1, 0]) < 1e-9:  # gimbal lock: put everything in A
        A = np.arctan2(-R[0, 1], R[1, 1])
        C = 0.0
    else:
        A = np.arctan2(R[1, 0], R[0, 0])
        C = np.arctan2(R[2, 1], R[2, 2])
    return np.degrees([A, B, C])


def _program_rows(route: Route) -> list[dict[str, Any]]:
    """Rows for a robot program: the route's rows framed by an approach and a retreat.

    The robot comes from anywhere, so the program first moves (joint move) to the first virtual
    joint, the approach point of the first weld, and ends by retreating to the last virtual
    joint; both points are already on the verified route.
    """
    rows = route_rows(route, smooth=True)
    if not route.legs:
        return rows
    first, last = route.legs[0].points[1], route.legs[-1].points[-2]
    pre = {"kind": "approach", "joint_id": "", "x": first[0], "y": first[1], "z": first[2]}
    post = {"kind": "retreat", "joint_id": "", "x": last[0], "y": last[1], "z": last[2]}
    out = [pre, *rows, post]
    for k, r in enumerate(out):
        r["step"] = k
        r.setdefault("tool", None)
    return out


def _fmt(v: float, decimals: int) -> str:
    """Fixed-point text without a negative zero."""
    return f"{round(float(v), decimals) + 0.0:.{decimals}f}"


def _row_frames(route: Route, rows: list[dict[str, Any]]) -> list[NDArray[np.float64]]:
    """Tool frame per row: a weld row uses its joint's approach direction, a via the next weld's.

    The tool z axis points along the torch towards the work: against the approach direction.
    """
    frames: list[NDArray[np.float64]] = [np.eye(3)] * len(rows)
    nxt: NDArray[np.float64] | None = None
    for k in range(len(rows) - 1, -1, -1):
        if rows[k]["kind"] == "weld":
            nxt = rows[k]["tool"]
        frames[k] = tool_frame(None if nxt is None else -np.asarray(nxt, dtype=float))
    # the retreat keeps the orientation of the last weld
    if rows and rows[-1]["kind"] == "retreat" and len(rows) > 1:
        frames[-1] = frames[-2]
    return frames


# ---------------------------------------------------------------------------- posts
@dataclass(frozen=True)
class Post:
    """A robot-language post: ``render(route, **options) -> str`` and the file suffix it writes.

    ``needs_part``: the post takes the part as option ``part`` (a mesh, cell or CollisionModel),
    for example to check its corner blends; :func:`render_post` passes it on.
    """

    name: str
    suffix: str
    render: Callable[..., str]
    description: str = ""
    needs_part: bool = False


#: name -> Post; add one with :func:`register_post`
POSTS: dict[str, Post] = {}


def register_post(
    name: str, suffix: str, description: str = "", *, needs_part: bool = False
) -> Callable[[Callable[..., str]], Callable[..., str]]:
    """Decorator registering ``render(route, **options) -> str`` as post ``name``.

    Example
    -------
    >>> @register_post("csv-xyz", ".txt", "bare coordinates")
    ... def _xyz(route, **options):
    ...     return "".join(f"{x} {y} {z}\\n" for x, y, z in route.waypoints())
    """

    def deco(render: Callable[..., str]) -> Callable[..., str]:
        POSTS[name] = Post(name, suffix, render, description, needs_part)
        return render

    return deco


def render_post(route: Route, post: str, part: Any = None, **options: Any) -> str:
    """The program text of ``route`` in the language of registered post ``post``.

    ``part`` (a trimesh.Trimesh, a Cell or a CollisionModel) is required by posts registered
    with ``needs_part`` (``rapid`` and ``krl``: they check every corner blend against it) and
    ignored by the others. A missing part is a :class:`WeldplanError`.
    """
    if post not in POSTS:
        raise WeldplanError(f"unknown post {post!r}; known posts: {', '.join(sorted(POSTS))}")
    if POSTS[post].needs_part:
        options["part"] = part
    return POSTS[post].render(route, **options)


def write_post(
    route: Route, path: str | PathLike[str], post: str = "rapid", part: Any = None, **options: Any
) -> Path:
    """Write ``route`` as a robot program with post ``post``, atomically (``part``: see
    :func:`render_post`)."""
    return write_text_atomic(path, render_post(route, post, part, **options))


def _blend_radii(route: Route, rows: list[dict[str, Any]], part: Any, clearance: float | None):
    """``(n,)`` allowed blend radius (mm) per program row: vias only (:mod:`.blending`)."""
    c = route_clearance(route, clearance)
    pts = np.array([[float(r[k]) for k in ("x", "y", "z")] for r in rows]).reshape(-1, 3)
    return allowed_radii(pts, [r["kind"] in ("via", "smooth") for r in rows], part, c), c


def _name(path_stem: str, default: str) -> str:
    """A robot-language identifier: letters, digits, underscores, a letter first."""
    s = "".join(c if (c.isascii() and c.isalnum()) else "_" for c in path_stem)
    if not s or not s[0].isalpha():
        s = default
    return s[:24]


@register_post("rapid", ".mod", "ABB RAPID module of robtargets with MoveJ/MoveL", needs_part=True)
def render_rapid(
    route: Route,
    part: Any = None,
    *,
    clearance: float | None = None,
    module: str = "weldplan_route",
    tool: str = "tool0",
    wobj: str = "wobj0",
    air_speed: str = "v200",
    approach_speed: str = "v50",
    zone: str = "z5",
    header: Sequence[str] = (),
) -> str:
    """An ABB RAPID module: one ``CONST robtarget`` per waypoint and a ``PROC main()``;
    ``header``: comment lines after the first (what produced it, what was verified).

    The first move is a ``MoveJ`` to the approach point of the first weld (its virtual joint,
    from wherever the robot is); every other move is ``MoveL``, because the route was verified
    as straight Cartesian segments and a joint move between them could leave the checked
    corridor. Weld spots are reached with zone ``fine`` at ``approach_speed`` and carry a
    comment naming the joint: add the process instructions (``SpotL``, ``ArcL``, a gun routine)
    there. A via point flies by with the largest predefined zone (``z0`` 0.3 mm, ``z1``, ``z5``,
    ``z10``, ...) not above ``zone`` whose radius fits the corner's free margin against ``part``
    at ``clearance`` (default: the route's), else it is ``fine`` (:mod:`weldplan.io.blending`);
    the approach and retreat points are ``fine``. The header says how the zones were chosen.
    Orientation: the tool z axis against the joint's
    approach direction (into the surface) when the joints CSV gave one, else straight down; via
    points take the orientation of the next weld. Configuration data ``[0,0,0,0]`` and external
    axes ``9E+09`` (unused) are placeholders for the integrator. Coordinates are mm in the work
    object ``wobj``.
    """
    module = _name(module, "weldplan_route")
    rows = _program_rows(route)
    frames = _row_frames(route, rows)
    rapid_zone(0.0, zone)  # validates ``zone`` even where no corner blends
    radii, c = _blend_radii(route, rows, part, clearance)
    zones = [rapid_zone(float(r), zone) if r > 0 else "fine" for r in radii]
    n_via = sum(r["kind"] in ("via", "smooth") for r in rows)
    n_fly = sum(z != "fine" for z in zones)
    out = [
        f"MODULE {module}",
        "    ! Generated by weldplan: an ordered, collision-checked torch route.",
        *comment_lines(header, "!", "    ").splitlines(),
        f"    ! {len(route.joint_ids)} weld joints, {len(rows)} targets, "
        f"length {route.length:.2f} mm, order {'-'.join(route.order)}",
        "    ! Tool, work object, speeds, configurations and weld instructions are placeholders.",
        f"    ! Zones: a via point flies by with the largest zonedata up to {zone} whose radius is",
        f"    ! within its free margin (distance to the part - {c:g} mm clearance) and half of",
        f"    ! each adjacent segment, else fine: {n_fly} of {n_via} via points fly by.",
        *smooth_header(route, rows, "    ! ", "dense MoveL targets (RAPID has no spline move)"),
    ]
    names = []
    for r, R in zip(rows, frames, strict=True):
        name = f"p{r['step']:04d}"
        names.append(name)
        q = quaternion(R)
        xyz = ",".join(_fmt(r[k], 3) for k in ("x", "y", "z"))
        quat = ",".join(_fmt(v, 6) for v in q)
        tag = f" ! weld {r['joint_id']}" if r["kind"] == "weld" else ""
        out.append(
            f"    CONST robtarget {name}:=[[{xyz}],[{quat}],[0,0,0,0],"
            f"[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];{tag}"
        )
    out += ["", "    PROC main()"]
    for k, (r, name) in enumerate(zip(rows, names, strict=True)):
        weld = r["kind"] == "weld"
        speed = approach_speed if weld else air_speed
        z = zones[k]
        move = "MoveJ" if k == 0 else "MoveL"
        line = f"        {move} {name},{speed},{z},{tool}\\WObj:={wobj};"
        if weld:
            line += f" ! weld joint {r['joint_id']}"
        out.append(line)
    out += ["    ENDPROC", "ENDMODULE", ""]
    return "\n".join(out)


@register_post("krl", ".src", "KUKA KRL program with PTP/LIN moves", needs_part=True)
def render_krl(
    route: Route,
    part: Any = None,
    *,
    clearance: float | None = None,
    cdis: float = 5.0,
    program: str = "weldplan_route",
    tool: int = 1,
    base: int = 1,
    vel_cp: float = 0.2,
    smooth: str = "spline",
    header: Sequence[str] = (),
) -> str:
    """A KUKA KRL ``.src``: ``PTP`` to the first weld's approach point, then ``LIN`` moves
    (``header``: comment lines after the first, what produced it and what was verified).

    A leg with a smooth path (``weldplan plan --smooth``) runs from its first virtual joint
    through its dense waypoints as one ``SPLINE`` block of ``SPL`` points (``smooth="spline"``,
    the default) ending on its second virtual joint, or as ``LIN`` moves along the checked
    chords (``smooth="lin"``). The controller's spline through the waypoints is its own
    interpolation, not the C2 curve weldplan checked; a block is written only where every chord
    is free at the clearance plus twice the sagitta of the circle through its neighbouring
    waypoints (an estimate of how far a spline through them bulges off the chord, not a
    proof), else that leg's waypoints are ``LIN`` moves; the header counts both.

    Frames are ``{X, Y, Z, A, B, C}`` in mm and degrees (``A, B, C`` = Z-Y-X Euler angles of the
    tool frame, see :func:`euler_zyx_deg`). A via point uses ``C_DIS`` approximation with its own
    ``$APO.CDIS``: its allowed blend radius against ``part`` at ``clearance`` (default: the
    route's; :mod:`weldplan.io.blending`), rounded down to 0.1 mm and capped at ``cdis`` mm; where
    that is 0 it is an exact stop (no ``C_DIS``). Weld spots, the approach and the retreat are
    exact stops, weld spots followed by a comment where the process instructions go.
    ``$TOOL``/``$BASE`` indices and ``$VEL.CP`` (m/s) are placeholders for the integrator.
    """
    program = _name(program, "weldplan_route")
    rows = _program_rows(route)
    frames = _row_frames(route, rows)
    krl_cdis(0.0, cdis)  # validates ``cdis`` even where no corner blends
    radii, c = _blend_radii(route, rows, part, clearance)
    cd = [krl_cdis(float(r), cdis) for r in radii]
    spl = spline_rows(rows, part, c) if smooth == "spline" else np.zeros(len(rows), dtype=bool)
    if smooth not in ("spline", "lin"):
        raise WeldplanError(f"smooth must be 'spline' or 'lin', got {smooth!r}")
    n_via = sum(r["kind"] in ("via", "smooth") for r in rows)
    out = [
        f"DEF {program}()",
        "  ; Generated by weldplan: an ordered, collision-checked torch route.",
        *comment_lines(header, ";", "  ").splitlines(),
        f"  ; {len(route.joint_ids)} weld joints, {len(rows)} points, length {route.length:.2f} mm",
        f"  $TOOL = TOOL_DATA[{tool}]",
        f"  $BASE = BASE_DATA[{base}]",
        f"  ; Approximation: each via point's $APO.CDIS is the largest value up to {cdis:g} mm",
        f"  ; within its free margin (distance to the part - {c:g} mm clearance) and half of each",
        f"  ; adjacent segment, else an exact stop: {sum(v > 0 for v in cd)} of {n_via} via "
        "points approximated.",
        *smooth_header(route, rows, "  ; ", krl_smooth_note(smooth, spl)),
        f"  $VEL.CP = {vel_cp}",
    ]
    current = None
    for k, (r, R) in enumerate(zip(rows, frames, strict=True)):
        a, b, c = euler_zyx_deg(R)
        vals = [r["x"], r["y"], r["z"], a, b, c]
        frame = (
            "{" + ", ".join(f"{n} {_fmt(v, 3)}" for n, v in zip("XYZABC", vals, strict=True)) + "}"
        )
        move = "PTP" if k == 0 else "LIN"
        if spl[k]:
            if not spl[k - 1]:
                out.append("  SPLINE")
            out.append(f"    SPL {frame}")
            if k + 1 == len(spl) or not spl[k + 1]:
                out.append("  ENDSPLINE")
        elif r["kind"] == "weld":
            out.append(f"  {move} {frame} ; weld joint {r['joint_id']}")
        elif cd[k] > 0:
            if cd[k] != current:
                out.append(f"  $APO.CDIS = {cd[k]:g}")
                current = cd[k]
            out.append(f"  {move} {frame} C_DIS")
        else:
            out.append(f"  {move} {frame}")
    out += ["END", ""]
    return "\n".join(out)
