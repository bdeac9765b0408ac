"""The point-tip route's robot posts: a registry of ``render(route, **options) -> str`` and
the two that ship, ``rapid`` (an ABB RAPID module) and ``krl`` (a KUKA KRL ``.src``).

Robot posts are pluggable: a post is a function ``render(route, **options) -> str`` registered under
a name with :func:`register_post`. Both shipped posts are documented examples rather than
cell-ready programs (tool, work object, speeds and the weld process instructions are the
integrator's). The robot's own programs, from its joint-space route, are :mod:`weldplan.io.posts`.

Both blend corners only where the part leaves room (:mod:`weldplan.io.blending`): a via point
flies by with the largest zone whose radius fits its free margin (exact distance to the part
minus the clearance, and at most half of each adjacent segment), else it is an exact stop. So
they need the part: ``render_post(route, "rapid", part=cell_or_mesh)``; without it they refuse.
The tool's z axis points against the joint's approach direction, into the surface
(:func:`tool_frame`); the posts do not use the tool poses.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import WeldplanError
from weldplan.io.atomic import write_text_atomic
from weldplan.io.blending import allowed_radii, krl_cdis, rapid_zone, route_clearance
from weldplan.io.outputset import comment_lines
from weldplan.io.route_rows import fixed as _fmt
from weldplan.io.route_rows import route_rows
from weldplan.io.smooth_moves import krl_smooth_note, smooth_header, spline_rows
from weldplan.weld.route import Route


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
