"""KUKA KRL post: a ``.src`` program and its ``.dat`` data list, with real TOOL, BASE, load,
Status/Turn, approximation and speeds.

Layout of what :func:`render_krl` writes (and :func:`weldplan.io.posts.parse.parse_krl` reads
back)::

    <name>.dat                                        <name>.src
    DEFDAT <name>                                     DEF <name>()
      ; comments                                        ; comments
      DECL FRAME WP_TOOL={X .., Y .., Z .., A .., B .., C ..}
      DECL FRAME WP_BASE={X .., ...}                    $TOOL = WP_TOOL
      DECL E6POS XP0000={X .., Y .., Z .., A .., B .., C .., S 2, T 35, E1 0.0, ..., E6 0.0}
      ...                                               $BASE = WP_BASE
    ENDDAT                                              $LOAD.M = 2.002
                                                        $LOAD.CM = {X .., Y .., Z .., A 0, B 0, C 0}
                                                        PTP XP0000
                                                        $VEL.CP = 1.25
                                                        LIN XP0001
                                                        WAIT SEC 0.5 ; spot 15   (weld template)
                                                        $APO.CDIS = 5
                                                        LIN XP0002 C_DIS
                                                        ...
                                                      END

* ``WP_TOOL``: the TCP in ``$FLANGE`` (mm; ``A, B, C`` = Z-Y-X Euler angles in degrees,
  ``R = Rz(A) Ry(B) Rx(C)``); ``WP_BASE``: the part frame in ``$WORLD`` (= ``$ROBROOT``):
  the planning frame in the robot base times the part pose in it
  (:attr:`RobotProgram.part_pose`, identity without one).
* ``E6POS``: the TCP pose in the part frame with ``S`` (Status) and ``T`` (Turn) of the target's
  joint values (:mod:`weldplan.io.posts.config`), external axes 0.
* approximation: ``C_DIS`` only where the target's allowed blend radius (rounded down to 0.1 mm,
  :func:`weldplan.io.blending.krl_cdis`) is positive, with its own ``$APO.CDIS``; exact stops
  otherwise, at welds always.
* speeds: ``$VEL.CP`` (m/s) = the target's TCP speed, written when it changes; a ``PTP`` runs at
  ``$VEL_AXIS`` 100 % (the URDF velocities the cycle time assumes).
* the weld instruction: ``weld_template`` (placeholders ``{id}``, ``{target}``, ``{time}``),
  by default ``WAIT SEC <weld time>`` with a comment: replace with the gun's instruction.
* home (a route that starts and ends at the robot's home): its axis values declared once as
  ``DECL E6AXIS XHOME`` and moved to by ``PTP XHOME``, the program's first and last motion.
* interlock signals (:attr:`RobotProgram.signals`, a station of several robots): every output
  the program sets is switched off before the first move (``$OUT[n] = FALSE``); a ``set``
  follows its (exact-stop) target and weld as ``WAIT SEC 0`` (an advance-run stop, so the
  output switches when the robot is really there) and ``$OUT[n] = TRUE``; a ``wait`` as
  ``WAIT FOR $IN[n]`` before the motion that leaves the target. Each line ends with
  ``; <interlock name>``, and the header lists every signal with its wiring.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence

import numpy as np

from weldplan.errors import WeldplanError
from weldplan.io.blending import krl_cdis
from weldplan.io.outputset import comment_lines
from weldplan.io.posts.config import kuka_status, kuka_turn
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

DEFAULT_WELD_TEMPLATE = "WAIT SEC {time} ; spot {id}: replace with the gun's weld instruction"
POS_DECIMALS = 3
ANGLE_DECIMALS = 5
#: ``cos B`` below which a pose is at gimbal lock for the A, B, C angles (:func:`abc_deg`; B
#: within 2e-4 deg of +-90)
GIMBAL_COS = 1e-6


def abc_deg(R: np.ndarray) -> np.ndarray:
    """``(3,)`` KUKA ``A, B, C`` in degrees: ``R = Rz(A) @ Ry(B) @ Rx(C)`` (``R (3, 3)`` a
    rotation).

    ``B = atan2(-R[2, 0], hypot(R[0, 0], R[1, 0]))`` in [-90, 90]; ``A = atan2(R[1, 0],
    R[0, 0])`` and ``C = atan2(R[2, 1], R[2, 2])``. At gimbal lock (``B = +-90`` deg, ``cos B``
    below :data:`GIMBAL_COS`) ``A`` and ``C`` turn about the same axis and only their sum (B =
    -90) or difference (B = 90) is defined: ``C`` is 0 and ``A = atan2(-R[0, 1], R[1, 1])``,
    exact for ``R = Rz(A) Ry(B)`` at any ``B`` (scipy's ``as_euler`` makes the same choice but
    warns "Gimbal lock detected" on stderr).
    """
    R = np.asarray(R, dtype=np.float64).reshape(3, 3)
    cb = math.hypot(R[0, 0], R[1, 0])
    b = math.atan2(-R[2, 0], cb)
    if cb < GIMBAL_COS:
        a, c = math.atan2(-R[0, 1], R[1, 1]), 0.0
    else:
        a, c = math.atan2(R[1, 0], R[0, 0]), math.atan2(R[2, 1], R[2, 2])
    return np.degrees([a, b, c])


def frame_text(T: np.ndarray) -> str:
    """``{X .., Y .., Z .., A .., B .., C ..}`` of a ``(4, 4)`` pose (mm, degrees)."""
    vals = list(T[:3, 3]) + list(abc_deg(T[:3, :3]))
    decs = [POS_DECIMALS] * 3 + [ANGLE_DECIMALS] * 3
    return (
        "{"
        + ", ".join(f"{n} {fmt(v, d)}" for n, v, d in zip("XYZABC", vals, decs, strict=True))
        + "}"
    )


def render_krl(
    program: RobotProgram,
    *,
    max_cdis: float = 50.0,
    weld_template: str | None = None,
    header: Sequence[str] = (),
) -> tuple[str, str]:
    """``(src, dat)`` texts of ``program`` (module docstring). ``max_cdis`` mm caps
    ``$APO.CDIS``; ``header``: comment lines of both after the first (what produced them and
    what was verified)."""
    krl_cdis(0.0, max_cdis)  # validates it
    template = DEFAULT_WELD_TEMPLATE if weld_template is None else weld_template
    name = identifier(program.name, "weldplan_route")
    tg = program.targets
    Q = np.array([t.q for t in tg])
    status = kuka_status(np.array([t.flags for t in tg]))
    turn = kuka_turn(Q)
    m = program.tool_mass
    if not (math.isfinite(m) and m > 0):
        raise WeldplanError(f"tool mass must be a finite number of kg > 0, got {m}")
    head = [f"  ; Generated by weldplan for {program.robot}."]
    head += comment_lines(header, ";", "  ").splitlines()
    note = program.frame_note()
    head += [f"  ; {line}" for line in (*program.notes, *(() if note is None else (note,)))]
    head += [f"  ; {line}" for line in signal_notes(program, _out, _in)]
    at = signals_at(program)  # refuses a signal on a blended target
    uframe, oframe = program.work_object()
    dat = [f"DEFDAT {name}", *head]
    dat += [
        f"  DECL FRAME WP_TOOL={frame_text(program.tool_frame)}",
        f"  DECL FRAME WP_BASE={frame_text(uframe @ oframe)}",
    ]
    homes = home_names(program, "XHOME")
    names = [homes.get(k, f"XP{k:04d}") for k in range(len(tg))]
    dat += _home_decls(program, homes)
    for k, (n, t, s, tu) in enumerate(zip(names, tg, status, turn, strict=True)):
        if k in homes:
            continue
        e6 = frame_text(program.pose_in_part(t.pose))[:-1] + f", S {int(s)}, T {int(tu)}"
        e6 += ", E1 0.0, E2 0.0, E3 0.0, E4 0.0, E5 0.0, E6 0.0}"
        tag = f" ; weld {t.joint_id}" if t.kind == "weld" else f" ; {t.kind}, route row {t.row}"
        dat.append(f"  DECL E6POS {n}={e6}{tag}")
    dat += ["ENDDAT", ""]

    cog = program.tool_cog
    src = [f"DEF {name}()", *head]
    src += [
        "  $TOOL = WP_TOOL",
        "  $BASE = WP_BASE",
        f"  $LOAD.M = {fmt(m, 3)}",
        "  $LOAD.CM = {"
        + ", ".join(f"{a} {fmt(v, 1)}" for a, v in zip("XYZ", cog, strict=True))
        + ", A 0.0, B 0.0, C 0.0}",
    ]
    src += [f"  $VEL_AXIS[{i}] = 100" for i in range(1, 7)]
    src += [f"  {_out(a)} = FALSE ; {a.name}" for a in outputs_set(program)]
    vel, cdis = None, None
    for k, (n, t) in enumerate(zip(names, tg, strict=True)):
        cd = 0.0 if t.kind == "weld" or t.move == "joint" else krl_cdis(t.blend, max_cdis)
        if t.move == "joint":
            src.append(f"  PTP {n}")
        else:
            v = fmt(max(t.speed, 1e-3) / 1000.0, 4)
            if v != vel:
                src.append(f"  $VEL.CP = {v}")
                vel = v
            if cd > 0 and cd != cdis:
                src.append(f"  $APO.CDIS = {cd:g}")
                cdis = cd
            src.append(f"  LIN {n}" + (" C_DIS" if cd > 0 else ""))
        if t.kind == "weld":
            src.append(
                "  " + template.format(id=t.joint_id, target=n, time=fmt(program.weld_time, 3))
            )
        src += [line for a in at.get(k, ()) for line in _signal_lines(a)]
    src += ["END", ""]
    return "\n".join(src), "\n".join(dat)


def _home_decls(program: RobotProgram, homes: dict[int, str]) -> list[str]:
    """``DECL E6AXIS XHOME={A1 .., ..., A6 .., E1 0.0, ...}`` once per home configuration: its
    axis values in degrees (the URDF's joint values, the controller's axes as the posts' Status
    and Turn take them), as KUKA declares ``XHOME``; ``PTP XHOME`` moves there."""
    out: dict[str, str] = {}
    for k, name in homes.items():
        deg = np.degrees(program.targets[k].q)
        axes = ", ".join(f"A{i + 1} {fmt(v, ANGLE_DECIMALS)}" for i, v in enumerate(deg))
        out.setdefault(
            name, f"  DECL E6AXIS {name}={{{axes}, E1 0.0, E2 0.0, E3 0.0, E4 0.0, E5 0.0, E6 0.0}}"
            " ; home"
        )  # fmt: skip
    return list(out.values())


def _out(a: SignalAction) -> str:
    return f"$OUT[{a.signal}]"


def _in(a: SignalAction) -> str:
    return f"$IN[{a.signal}]"


def _signal_lines(a: SignalAction) -> list[str]:
    """A ``set``: ``WAIT SEC 0`` (an advance-run stop: the output switches when the robot is
    at rest at the target, not when the interpreter reads ahead), then the output on. A
    ``wait``: ``WAIT FOR`` the input (itself an advance-run stop) before the next motion."""
    if a.action == "set":
        return ["  WAIT SEC 0", f"  {_out(a)} = TRUE ; {a.name}"]
    return [f"  WAIT FOR {_in(a)} ; {a.name}"]
