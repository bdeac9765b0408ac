"""The tool's verified path as CSV: what the gun does, row by row, for offline programming.

``weldplan plan --tool ... --tool-csv F`` writes the transitions of the tool stage
(:class:`~weldplan.tool.transitions.ToolPath`, in the order the tool visits the welds, which may
differ from the point-tip route's) as one row per TCP pose::

    step,kind,joint_id,x,y,z,qw,qx,qy,qz,status
    0,weld,15,1549.76,-8.79,903.34,0.5,0.5,-0.5,0.5,ok
    1,retract,,1549.76,-8.79,913.34,0.5,0.5,-0.5,0.5,direct
    ...

``kind`` is ``weld`` at a weld spot (``joint_id`` set, ``status`` the pose's: ``ok``) and, on
the other rows, the motion that ends there (``retract``, ``move``, ``approach``, ``lift``,
``slide``, ``lower``, ``exit ...``, ``enter ...``, ``se3``; :mod:`weldplan.tool.transitions.plan`),
whose ``status`` is its transition's (``direct``, or ``replanned`` for an SE(3) re-plan).
Between two rows the TCP moves on the straight segment and the orientation turns by spherical
linear interpolation: exactly the motion the planner's swept check and the independent re-check
(:func:`weldplan.tool.verify.verify_sweeps`) proved free. Coordinates are mm in the part
frame; the quaternion is scalar first, of the TCP frame in the part frame.

A blocked transition has no free motion, so none is written: its place holds one row of kind
``blocked`` with empty coordinates and status ``blocked``, and the path goes on from the next
weld. A reader that replays the rows must stop there (the CLI also exits with code 3). Welds
without a free pose are not in the tool's path (the route JSON carries their closest miss).

This differs from the route CSV (``-o``), whose rows are the point-tip route with orientations
interpolated between the weld poses: those orientations are not checked for the swept tool.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from typing import Any

import numpy as np

from weldplan.tool.poses.result import WeldPoses
from weldplan.tool.section import ToolSection
from weldplan.tool.transitions.result import ToolPath, Transition

#: the columns, in order
FIELDS = ("step", "kind", "joint_id", "x", "y", "z", "qw", "qx", "qy", "qz", "status")


def _pose_row(kind: str, joint_id: str, p: Any, q: Any, status: str) -> dict[str, Any]:
    p = np.asarray(p, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    if not (np.isfinite(p).all() and np.isfinite(q).all()):
        raise ValueError(f"a {kind} row of the tool path is not finite: {p}, {q}")
    q = -q if q[0] < 0 else q  # one sign of the quaternion, as every export writes it
    return {
        "kind": kind, "joint_id": joint_id, "x": p[0], "y": p[1], "z": p[2],
        "qw": q[0], "qx": q[1], "qy": q[2], "qz": q[3], "status": status,
    }  # fmt: skip


def _motion_rows(t: Transition) -> list[dict[str, Any]]:
    """The rows after ``t``'s first pose and before its last (the welds' own rows)."""
    if not t.free:
        return [{"kind": "blocked", "status": "blocked"}]
    return [
        _pose_row(t.kinds[j - 1], "", t.positions[j], t.quaternions[j], t.status)
        for j in range(1, len(t.positions) - 1)
    ]


def tool_path_rows(path: ToolPath, poses: WeldPoses) -> list[dict[str, Any]]:
    """The CSV's rows (module docstring), ``step`` numbered from 0.

    Raises
    ------
    ValueError
        When a weld of the path has no verified pose in ``poses``, or a transition's ends are
        not its welds' poses (the two come from different runs).
    """
    rows: list[dict[str, Any]] = []

    def weld(joint_id: str) -> dict[str, Any]:
        pose = poses[joint_id]
        if not pose.ok or pose.quaternion is None:
            raise ValueError(f"weld {joint_id} is on the tool's path but has no verified pose")
        return _pose_row("weld", joint_id, pose.position, pose.quaternion, pose.status)

    if path.order:
        rows.append(weld(path.order[0]))
    for t in path.transitions:
        for end, joint_id in ((t.positions[0], t.from_id), (t.positions[-1], t.to_id)):
            if not np.allclose(end, poses[joint_id].position, atol=1e-6):
                raise ValueError(
                    f"transition {t.from_id}->{t.to_id} does not end at weld {joint_id}"
                )
        rows += _motion_rows(t)
        rows.append(weld(t.to_id))
    for k, r in enumerate(rows):
        r["step"] = k
    return rows


#: decimals written: mm to 0.1 um and quaternion components to 1e-6, as the route CSV
MM_DECIMALS, Q_DECIMALS = 4, 6


def _cell(field: str, v: Any) -> str:
    if v is None:
        return ""
    if field in ("x", "y", "z", "qw", "qx", "qy", "qz"):
        d = MM_DECIMALS if field in ("x", "y", "z") else Q_DECIMALS
        return f"{round(float(v), d) + 0.0:.{d}f}"  # + 0.0: no "-0.000000"
    return str(v)


def tool_path_csv(path: ToolPath, poses: WeldPoses) -> str:
    """The whole CSV text (header and rows; module docstring)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(FIELDS)
    for r in tool_path_rows(path, poses):
        w.writerow([_cell(f, r.get(f)) for f in FIELDS])
    return buf.getvalue()


def route_tool_csv(route: Any, header: Sequence[str] = ()) -> str:
    """The tool path CSV of a route planned with ``--tool`` (its ``route.tool`` carries the
    poses and the transitions); ``header``: lines written first as ``#`` comments (what
    produced the file and what was verified).

    Raises
    ------
    ValueError
        When the route has no tool transitions (the poses were not all re-checked, or no tool).
    """
    from weldplan.io.export import frame_comment
    from weldplan.io.outputset import comment_lines

    section = ToolSection.of(route)
    if section.transitions is None or section.poses is None:
        raise ValueError("the route has no tool transitions to write")
    note = frame_comment(route)  # a route planned in the cell says so, as its route CSV
    text = tool_path_csv(section.transitions, section.poses)
    return comment_lines([*header, *([] if note is None else [note])], "#") + text
