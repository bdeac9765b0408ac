"""What a robot post writes: targets with pose, joints, move type, blend and speed; tool; frames.

A :class:`RobotProgram` is language-neutral; :mod:`.rapid` and :mod:`.krl` only format it.
Building one from a planned route is :func:`weldplan.robot.program.robot_program`.

Frames (mm, radians inside, degrees in the programs):

* ``part_frame``: the planning frame (the cell frame when the part was placed by a part pose,
  :mod:`weldplan.cellframe`, else the part frame) in the robot's base frame (ABB world = robot
  base, KUKA ``$ROBROOT``; the program sets no other world);
* ``part_pose``: the part frame in the planning frame (the part pose), or ``None`` (the same
  frame). The posts write the work object as both (ABB ``wobjdata``: user frame
  ``part_frame``, object frame ``part_pose``; KUKA ``BASE_DATA``: their product), and every
  target in the part frame, so the welds keep the coordinates they were given in;
* ``tool_frame``: the TCP in the controller's flange frame (ABB ``tool0``, KUKA ``$FLANGE``,
  the URDF's ``tool0``: z out of the flange);
* a target's ``pose``: the TCP in the planning frame. Forward kinematics closes the loop:
  ``part_frame @ pose == fk_tool0(q) @ tool_frame`` (tests check it through the parsers).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import PlanningError

#: move types a target may have
MOVES = ("joint", "linear")
#: target kinds (``approach`` and ``retreat`` frame the route: the first and last virtual joints;
#: ``home``: the robot's home, the first and last target of a route that starts and ends there)
KINDS = ("approach", "weld", "via", "retreat", "home")
#: what a :class:`SignalAction` does
SIGNAL_ACTIONS = ("set", "wait")


@dataclass(frozen=True)
class SignalAction:
    """One interlock signal at a stop target of a station's program (issue 30, item 4;
    :class:`weldplan.multi.schedule.Interlock` makes them in pairs).

    ``"set"``: once the robot is at rest at route row ``row`` (after its weld there, if any),
    it switches its output ``signal`` on: "I am clear". ``"wait"``: at rest at row ``row``, the
    robot waits for its input ``signal`` to be on before it moves to its next target. KRL
    writes ``$OUT[signal] = TRUE`` / ``WAIT FOR $IN[signal]``, RAPID ``SetDO`` / ``WaitDI``;
    every output a program sets is switched off at the program's start.

    Attributes
    ----------
    row
        The route row of the (stop) target it follows.
    action
        One of :data:`SIGNAL_ACTIONS`.
    signal
        I/O number, >= 1.
    name
        The interlock's name (e.g. ``Z1_R1_R2``), for the program's comment or signal name.
    peer
        The other robot's name: the one that waits on a ``"set"``, the one that sets a
        ``"wait"`` (the header's wiring line; ``""``: not known).
    """

    row: int
    action: str
    signal: int
    name: str
    peer: str = ""

    def __post_init__(self) -> None:
        if self.action not in SIGNAL_ACTIONS or self.signal < 1:
            raise ValueError(f"bad signal action {self.action!r} on signal {self.signal}")


@dataclass(frozen=True, eq=False)
class Target:
    """One programmed point.

    Attributes
    ----------
    kind
        One of :data:`KINDS`.
    row
        The route row (:func:`weldplan.io.export.route_rows`) it stands for.
    joint_id
        The weld joint's id on weld targets, else ``""``.
    pose
        ``(4, 4)`` TCP pose in the part frame, mm.
    q
        ``(6,)`` joint values, rad (URDF convention).
    flags
        ``(3,) bool`` arm flags (:func:`weldplan.io.posts.config.arm_flags`).
    move
        How the robot gets here: ``"joint"`` or ``"linear"`` (:data:`MOVES`).
    blend
        Allowed blend radius at this point, mm (0: exact stop; :mod:`weldplan.io.blending`).
    speed
        TCP speed of the move to this target, mm/s.
    """

    kind: str
    row: int
    joint_id: str
    pose: NDArray[np.float64]
    q: NDArray[np.float64]
    flags: NDArray[np.bool_]
    move: str
    blend: float
    speed: float

    def __post_init__(self) -> None:
        if self.kind not in KINDS or self.move not in MOVES:
            raise ValueError(f"bad target kind {self.kind!r} or move {self.move!r}")


@dataclass(frozen=True, eq=False)
class RobotProgram:
    """Everything a post writes (module docstring for the frames).

    Attributes
    ----------
    name
        Program / module name (sanitised by the posts).
    robot
        The robot's name (URDF).
    joint_names
        ``(6,)`` URDF joint names.
    targets
        In program order.
    tool_frame
        ``(4, 4)`` TCP in the flange frame, mm.
    tool_mass
        kg.
    tool_cog
        ``(3,)`` centre of gravity of the tool in the flange frame, mm.
    part_frame
        ``(4, 4)`` planning frame in the robot base frame, mm.
    weld_time
        s per spot (the default weld instruction waits that long).
    notes
        Header comment lines (how zones, speeds and the cycle time were obtained).
    part_pose
        ``(4, 4)`` part frame in the planning frame, mm (:class:`weldplan.cellframe.PartPose`
        ``.matrix``), or ``None`` when the part frame is the planning frame.
    signals
        Interlock signals at stop targets (:class:`SignalAction`), in program order; empty
        for a robot alone in its station.
    """

    name: str
    robot: str
    joint_names: tuple[str, ...]
    targets: tuple[Target, ...]
    tool_frame: NDArray[np.float64]
    tool_mass: float
    tool_cog: NDArray[np.float64]
    part_frame: NDArray[np.float64]
    weld_time: float = 0.0
    notes: tuple[str, ...] = field(default_factory=tuple)
    part_pose: NDArray[np.float64] | None = None
    signals: tuple[SignalAction, ...] = ()

    def work_object(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(user frame, object frame)`` ``(4, 4)`` mm: :attr:`part_frame` and the part pose
        (the identity without one); a target's pose in the part frame is
        ``inv(object frame) @ pose``."""
        obj = np.eye(4) if self.part_pose is None else np.asarray(self.part_pose, dtype=float)
        return np.asarray(self.part_frame, dtype=float), obj

    def pose_in_part(self, pose: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(4, 4)``: a target's pose (planning frame) in the part frame (mm)."""
        return pose if self.part_pose is None else np.linalg.solve(self.part_pose, pose)

    def frame_note(self) -> str | None:
        """The header line that says which frame the targets are in (``None`` without a part
        pose: the planning frame is the part's)."""
        if self.part_pose is None:
            return None
        return (
            "Frames: the targets are in the part frame (the coordinates of the welds as given); "
            "the work object / BASE is the part pose in the cell times the cell in the robot base."
        )


def is_exact_stop(target: Target) -> bool:
    """True when both posts stop exactly at ``target`` (RAPID ``fine``, KRL no ``C_DIS``): a
    weld, a joint move, or no blend allowed."""
    return target.kind == "weld" or target.move == "joint" or target.blend <= 0


def signals_at(program: RobotProgram) -> dict[int, tuple[SignalAction, ...]]:
    """``{target index: its signal actions}``, in program order: each action after the target
    of its route row (its weld target, else the last target of the row).

    Raises
    ------
    PlanningError
        A signal on a route row with no target, or on a target the robot does not stop at
        exactly (an interlock row is a stop row of the timed route, so the robot is at rest
        there: a blended target would switch the signal while the robot still moves).
    """
    last = {t.row: k for k, t in enumerate(program.targets)}
    last |= {t.row: k for k, t in enumerate(program.targets) if t.kind == "weld"}
    out: dict[int, list[SignalAction]] = {}
    for a in program.signals:
        k = last.get(a.row)
        if k is None:
            raise PlanningError(f"signal {a.signal} ({a.name}): no target at route row {a.row}")
        if not is_exact_stop(program.targets[k]):
            raise PlanningError(
                f"signal {a.signal} ({a.name}): the target at route row {a.row} is blended, "
                "not an exact stop"
            )
        out.setdefault(k, []).append(a)
    return {k: tuple(v) for k, v in out.items()}


def outputs_set(program: RobotProgram) -> tuple[SignalAction, ...]:
    """The first ``"set"`` action of each output the program sets, by signal number: what the
    program switches off at its start."""
    first: dict[int, SignalAction] = {}
    for a in program.signals:
        if a.action == "set":
            first.setdefault(a.signal, a)
    return tuple(first[n] for n in sorted(first))


def signal_notes(
    program: RobotProgram,
    out_name: Callable[[SignalAction], str],
    in_name: Callable[[SignalAction], str],
) -> list[str]:
    """The header block that lists each signal: number, name, who sets it, who waits on it,
    and the wiring. ``out_name`` / ``in_name``: how the language names the output / the input
    that carries an action's signal (KRL ``$OUT[1]``, RAPID ``do1_Z1_R1_R2``)."""
    if not program.signals:
        return []
    lines = [
        "Interlock signals: wire each output to the input of the same number on the robot "
        "that waits on it; every output this program sets is switched off at its start."
    ]
    for a in program.signals:
        peer = a.peer or "the other robot"
        o, i = out_name(a), in_name(a)
        if a.action == "set":
            lines.append(
                f"signal {a.signal} {a.name}: set by this robot at rest at route row {a.row}, "
                f"{peer} waits on it; wiring: this robot {o} -> {peer} {i}"
            )
        else:
            lines.append(
                f"signal {a.signal} {a.name}: this robot waits on it at rest at route row "
                f"{a.row}, {peer} sets it; wiring: {peer} {o} -> this robot {i}"
            )
    return lines


def home_names(program: RobotProgram, prefix: str) -> dict[int, str]:
    """``{target index: name}`` of the program's ``home`` targets, written as axis values
    (KRL ``E6AXIS``, RAPID ``jointtarget``) rather than poses: ``prefix`` for the first home
    configuration (``XHOME``, ``jhome``), ``prefix2``... for another; the same configuration
    (the start and the end) shares one name."""
    names: dict[int, str] = {}
    seen: list[tuple[NDArray[np.float64], str]] = []
    for k, t in enumerate(program.targets):
        if t.kind != "home":
            continue
        name = next((n for q, n in seen if np.array_equal(q, t.q)), None)
        if name is None:
            name = prefix if not seen else f"{prefix}{len(seen) + 1}"
            seen.append((np.asarray(t.q), name))
        names[k] = name
    return names


def identifier(text: str, default: str) -> str:
    """A robot-language identifier: letters, digits, underscores, a letter first, <= 24 chars."""
    s = "".join(c if (c.isascii() and c.isalnum()) else "_" for c in text)
    if not s or not s[0].isalpha():
        s = default
    return s[:24]


def fmt(v: float, decimals: int) -> str:
    """Fixed-point text without a negative zero."""
    return f"{round(float(v), decimals) + 0.0:.{decimals}f}"
