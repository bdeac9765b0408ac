"""ABB RAPID post: a module a controller (or RobotStudio) loads, with real tool, work object,
configurations, zones and speeds.

Layout of what :func:`render_rapid` writes (and :func:`weldplan.io.posts.parse.parse_rapid`
reads back)::

    MODULE <name>
        ! comments: what generated it, how zones and speeds were chosen, the cycle time
        PERS tooldata tWeldplan := [TRUE,[[x,y,z],[q1,q2,q3,q4]],[mass,[cx,cy,cz],[1,0,0,0],0,0,0]];
        PERS wobjdata wPart := [FALSE,TRUE,"",[[x,y,z],[q1,q2,q3,q4]],[[x,y,z],[q1,q2,q3,q4]]];
        CONST speeddata vw<mm/s> := [<mm/s>,500,5000,1000];      ! one per speed used
        CONST robtarget p0000 := [[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[9E+09 x 6]];
        PROC main()
            ConfJ\\On;
            ConfL\\On;
            MoveJ p0000,vw..,fine,tWeldplan\\WObj:=wPart;
            MoveL p0001,vw..,fine,tWeldplan\\WObj:=wPart;
            weld_spot "15";                                     ! the weld template, after a weld
            MoveJ p0002,vw..,z5,tWeldplan\\WObj:=wPart;
            ...
        ENDPROC
        PROC weld_spot(string id)                               ! only with the default template
            WaitTime <weld time>;
        ENDPROC
    ENDMODULE

* ``tooldata``: TCP = the program's ``tool_frame`` (mm, quaternion), ``mass`` kg, centre of
  gravity in the flange frame; inertia axes along the flange, moments 0 (not known).
* ``wobjdata``: user frame = the planning frame in the robot base frame (world = base), object
  frame = the part pose in it (identity without one, :attr:`RobotProgram.part_pose`); every
  robtarget is the TCP pose in the part frame.
* ``confdata``: from the target's joint values (:func:`weldplan.io.posts.config.abb_confdata`);
  ``ConfJ\\On`` / ``ConfL\\On`` make the controller keep exactly that configuration.
* zones: the largest predefined ``zonedata`` within the target's allowed blend radius
  (:func:`weldplan.io.blending.rapid_zone`), ``fine`` where it is 0; weld spots are ``fine``.
* speeds: ``speeddata`` with the target's TCP speed (mm/s, rounded up to 1 mm/s), reorientation
  500 deg/s, external axes as ABB's predefined ``v1000``.
* home (a route that starts and ends at the robot's home): a ``jointtarget`` ``jhome`` (axis
  values in degrees) and ``MoveAbsJ jhome``, the program's first and last motion.
* the weld instruction: ``weld_template`` (placeholders ``{id}``, ``{target}``, ``{tool}``,
  ``{wobj}``, ``{time}``) after every weld target; the default calls the ``weld_spot`` routine
  above, which waits the weld time: replace it with the gun's own instruction (``SpotL``,
  a servo-gun routine).
* interlock signals (:attr:`RobotProgram.signals`, a station of several robots): outputs
  ``do<n>_<name>`` and inputs ``di<n>_<name>`` (:func:`signal_do`, :func:`signal_di`), declared
  in the controller's I/O configuration as the header's comment block lists them; every output
  the program sets gets ``SetDO ..., 0;`` before the first move, a ``set`` is ``SetDO ..., 1;``
  and a ``wait`` ``WaitDI ..., 1;`` after its target (always ``fine``: RAPID runs them once the
  robot is there) and its weld.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from weldplan.errors import WeldplanError
from weldplan.io.blending import rapid_zone
from weldplan.io.outputset import comment_lines
from weldplan.io.posts.config import abb_confdata
from weldplan.io.posts.program import (
    RobotProgram,
    SignalAction,
    fmt,
    home_names,
    identifier,
    outputs_set,
    signal_notes,
    signals_at,
)

log = logging.getLogger(__name__)

TOOL_NAME = "tWeldplan"
WOBJ_NAME = "wPart"
#: the default spot instruction: a call of the ``weld_spot`` routine the module defines
DEFAULT_WELD_TEMPLATE = 'weld_spot "{id}";'
#: decimals of positions (mm) and quaternion components
POS_DECIMALS = 3
QUAT_DECIMALS = 8
#: reorientation speed (deg/s) and external-axis speeds of every speeddata (ABB's ``v1000``)
V_ORI, V_LEAX, V_REAX = 500, 5000, 1000


def quat_wxyz(R: np.ndarray) -> np.ndarray:
    """``(4,)`` unit quaternion ``[q1, q2, q3, q4] = [w, x, y, z]`` of ``R (3, 3)``, ``w >= 0``."""
    x, y, z, w = Rotation.from_matrix(R).as_quat()
    q = np.array([w, x, y, z])
    return q if q[0] >= 0 else -q


def _pose_text(T: np.ndarray) -> str:
    xyz = ",".join(fmt(v, POS_DECIMALS) for v in T[:3, 3])
    quat = ",".join(fmt(v, QUAT_DECIMALS) for v in quat_wxyz(T[:3, :3]))
    return f"[[{xyz}],[{quat}]]"


def _signal(prefix: str, a: SignalAction) -> str:
    body = "".join(c if (c.isascii() and c.isalnum()) else "_" for c in a.name)
    return f"{prefix}{a.signal}_{body}"[:32]


def signal_do(a: SignalAction) -> str:
    """The digital output that carries ``a``'s signal, e.g. ``do1_Z1_R1_R2`` (number, then the
    interlock's name; <= 32 characters, RAPID's limit). Declare it in the I/O configuration
    (EIO) of the robot that sets it; the header says so."""
    return _signal("do", a)


def signal_di(a: SignalAction) -> str:
    """The digital input that carries ``a``'s signal, e.g. ``di1_Z1_R1_R2``, wired to the
    output :func:`signal_do` of the robot that sets it."""
    return _signal("di", a)


def _eio_note(program: RobotProgram) -> list[str]:
    """The signals this controller's I/O configuration (EIO) must declare, one line."""
    names = dict.fromkeys(
        ("DO " + signal_do(a)) if a.action == "set" else ("DI " + signal_di(a))
        for a in program.signals
    )
    return [f"I/O configuration (EIO) to declare: {', '.join(names)}"] if names else []


def _signal_line(a: SignalAction) -> str:
    """``SetDO`` a ``set`` on, ``WaitDI`` a ``wait``: after a ``fine`` point, where RAPID runs
    the next instruction once the robot is there."""
    return f"SetDO {signal_do(a)}, 1;" if a.action == "set" else f"WaitDI {signal_di(a)}, 1;"


def _home_decls(program: RobotProgram, homes: dict[int, str]) -> list[str]:
    """``CONST jointtarget jhome := [[a1,...,a6],[9E+09 x 6]];`` once per home configuration:
    its axis values in degrees (the URDF's joint values); ``MoveAbsJ jhome`` moves there."""
    out: dict[str, str] = {}
    for k, name in homes.items():
        axes = ",".join(fmt(v, 4) for v in np.degrees(program.targets[k].q))
        out.setdefault(
            name, f"    CONST jointtarget {name} := [[{axes}],"
            "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]; ! home"
        )  # fmt: skip
    return list(out.values())


def speed_name(speed: float) -> tuple[str, int]:
    """The ``speeddata`` name and its TCP speed (mm/s, rounded up) for ``speed`` mm/s."""
    if not (math.isfinite(speed) and speed > 0):
        raise WeldplanError(f"a target's TCP speed must be finite and > 0 mm/s, got {speed}")
    v = int(math.ceil(speed - 1e-9))
    return f"vw{v}", v


def render_rapid(
    program: RobotProgram,
    *,
    max_zone: str = "z50",
    weld_template: str | None = None,
    header: Sequence[str] = (),
) -> str:
    """The RAPID module text of ``program`` (module docstring); ``header``: comment lines after
    the first (what produced it and what was verified).

    ``max_zone``: the largest ``zonedata`` any target may get (the blend radius decides below
    it). ``weld_template``: the spot instruction (default :data:`DEFAULT_WELD_TEMPLATE`).
    """
    rapid_zone(0.0, max_zone)  # validates the name
    template = DEFAULT_WELD_TEMPLATE if weld_template is None else weld_template
    module = identifier(program.name, "weldplan_route")
    tg = program.targets
    conf = abb_confdata(np.array([t.q for t in tg]), np.array([t.flags for t in tg]))
    zones = [
        "fine"
        if (t.kind == "weld" or t.blend <= 0 or t.move == "joint")
        else rapid_zone(t.blend, max_zone)
        for t in tg
    ]
    out = [f"MODULE {module}", f"    ! Generated by weldplan for {program.robot}."]
    out += comment_lines(header, "!", "    ").splitlines()
    note = program.frame_note()
    out += [f"    ! {line}" for line in (*program.notes, *(() if note is None else (note,)))]
    out += [f"    ! {line}" for line in signal_notes(program, signal_do, signal_di)]
    out += [f"    ! {line}" for line in _eio_note(program)]
    at = signals_at(program)  # refuses a signal on a target that is not ``fine``
    uframe, oframe = program.work_object()
    m, cog = program.tool_mass, program.tool_cog
    if not (math.isfinite(m) and m > 0):
        raise WeldplanError(f"tool mass must be a finite number of kg > 0, got {m}")
    out += [
        f"    PERS tooldata {TOOL_NAME} := [TRUE,{_pose_text(program.tool_frame)},"
        f"[{fmt(m, 3)},[{','.join(fmt(v, 1) for v in cog)}],[1,0,0,0],0,0,0]];",
        f'    PERS wobjdata {WOBJ_NAME} := [FALSE,TRUE,"",{_pose_text(uframe)},'
        f"{'[[0,0,0],[1,0,0,0]]' if program.part_pose is None else _pose_text(oframe)}];",
    ]
    speeds = sorted({speed_name(t.speed) for t in tg}, key=lambda s: s[1])
    out += [f"    CONST speeddata {n} := [{v},{V_ORI},{V_LEAX},{V_REAX}];" for n, v in speeds]
    homes = home_names(program, "jhome")
    names = [homes.get(k, f"p{k:04d}") for k in range(len(tg))]
    out += _home_decls(program, homes)
    for k, (name, t, c) in enumerate(zip(names, tg, conf, strict=True)):
        if k in homes:
            continue
        tag = f" ! weld {t.joint_id}" if t.kind == "weld" else f" ! {t.kind}, route row {t.row}"
        out.append(
            f"    CONST robtarget {name} := {_pose_text(program.pose_in_part(t.pose))[:-1]},"
            f"[{','.join(str(int(v)) for v in c)}],"
            f"[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];{tag}"
        )
    out += ["", "    PROC main()", "        ConfJ\\On;", "        ConfL\\On;"]
    out += [f"        SetDO {signal_do(a)}, 0;" for a in outputs_set(program)]
    for k, (name, t, z) in enumerate(zip(names, tg, zones, strict=True)):
        move = "MoveAbsJ" if k in homes else "MoveJ" if t.move == "joint" else "MoveL"
        out.append(
            f"        {move} {name},{speed_name(t.speed)[0]},{z},{TOOL_NAME}\\WObj:={WOBJ_NAME};"
        )
        if t.kind == "weld":
            out.append(
                "        "
                + template.format(
                    id=t.joint_id,
                    target=name,
                    tool=TOOL_NAME,
                    wobj=WOBJ_NAME,
                    time=fmt(program.weld_time, 3),
                )
            )
        out += [f"        {_signal_line(a)}" for a in at.get(k, ())]  # after a fine point
    out.append("    ENDPROC")
    if weld_template is None:
        out += [
            "",
            "    PROC weld_spot(string id)",
            "        ! the spot-weld instruction: replace with the gun's (SpotL, a gun routine)",
            f"        WaitTime {fmt(program.weld_time, 3)};",
            "    ENDPROC",
        ]
    out += ["ENDMODULE", ""]
    return "\n".join(out)
