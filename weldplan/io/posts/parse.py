"""Readers of exactly what :mod:`.rapid` and :mod:`.krl` write: a small line grammar each.

They exist so that tests (and a user who wants to check a program before loading it) can take
an emitted program back to numbers: tool, work object / base, every target's pose and
configuration, every move with its speed and zone. A line outside the grammar is an
:class:`~weldplan.errors.InputError` naming the line, never skipped.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from weldplan.errors import InputError

_NUM = r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?"
_POSE = rf"\[\[({_NUM}),({_NUM}),({_NUM})\],\[({_NUM}),({_NUM}),({_NUM}),({_NUM})\]\]"


def _match(rules: list[tuple[str, re.Pattern[str]]], line: str) -> tuple[str, tuple] | None:
    """The first rule matching ``line``: ``(kind, groups)``, else None."""
    for kind, rx in rules:
        m = rx.match(line)
        if m:
            return kind, m.groups()
    return None


def _pose_wxyz(vals: list[str]) -> NDArray[np.float64]:
    x, y, z, w, qx, qy, qz = (float(v) for v in vals)
    T = np.eye(4)
    T[:3, :3] = Rotation.from_quat([qx, qy, qz, w]).as_matrix()
    T[:3, 3] = [x, y, z]
    return T


@dataclass
class RapidModule:
    """A parsed RAPID module: frames (4, 4) mm, targets, moves in order."""

    name: str = ""
    tool: NDArray[np.float64] = field(default_factory=lambda: np.eye(4))
    tool_mass: float = float("nan")
    tool_cog: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    #: the work object: user frame @ object frame (the part frame in the robot's world)
    wobj: NDArray[np.float64] = field(default_factory=lambda: np.eye(4))
    uframe: NDArray[np.float64] = field(default_factory=lambda: np.eye(4))
    oframe: NDArray[np.float64] = field(default_factory=lambda: np.eye(4))
    speeds: dict[str, float] = field(default_factory=dict)
    targets: dict[str, tuple[NDArray[np.float64], tuple[int, int, int, int]]] = field(
        default_factory=dict
    )
    moves: list[tuple[str, str, str, str]] = field(default_factory=list)  # instr, target, v, zone
    #: ``jointtarget`` name -> ``(6,)`` axis values, deg (the home: ``MoveAbsJ``)
    joints: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    welds: list[tuple[str, str]] = field(default_factory=list)  # (after target, instruction)
    weld_time: float | None = None
    #: ``(after target, "set" | "wait", signal number, signal name)`` in program order
    signals: list[tuple[str, str, int, str]] = field(default_factory=list)
    #: ``(signal number, signal name)`` of the outputs switched off before the first move
    resets: list[tuple[int, str]] = field(default_factory=list)
    #: each target's comment (``weld <id>``, ``<kind>, route row <row>``), by target name
    tags: dict[str, str] = field(default_factory=dict)
    #: the line (1-based) of each move and of each signal, parallel to :attr:`moves` and
    #: :attr:`signals`: what a check of the program names
    move_lines: list[int] = field(default_factory=list)
    signal_lines: list[int] = field(default_factory=list)


_RAPID = [
    ("module", re.compile(r"^MODULE (\w+)$")),
    ("comment", re.compile(r"^!.*$")),
    ("blank", re.compile(r"^$")),
    (
        "tool",
        re.compile(
            rf"^PERS tooldata \w+ := \[TRUE,{_POSE},\[({_NUM}),\[({_NUM}),({_NUM}),({_NUM})\],"
            r"\[1,0,0,0\],0,0,0\]\];$"
        ),
    ),
    (
        "wobj",
        re.compile(rf'^PERS wobjdata \w+ := \[FALSE,TRUE,"",{_POSE},{_POSE}\];$'),
    ),
    ("speed", re.compile(rf"^CONST speeddata (\w+) := \[({_NUM}),{_NUM},{_NUM},{_NUM}\];$")),
    (
        "target",
        re.compile(
            rf"^CONST robtarget (\w+) := {_POSE[:-2]},\[(-?\d+),(-?\d+),(-?\d+),(\d+)\],"
            r"\[9E\+09,9E\+09,9E\+09,9E\+09,9E\+09,9E\+09\]\];(?: ! (.*))?$"
        ),
    ),
    (
        "joints",
        re.compile(
            rf"^CONST jointtarget (\w+) := \[\[({_NUM}),({_NUM}),({_NUM}),({_NUM}),({_NUM}),"
            rf"({_NUM})\],\[9E\+09,9E\+09,9E\+09,9E\+09,9E\+09,9E\+09\]\];(?: !.*)?$"
        ),
    ),
    ("proc", re.compile(r"^PROC \w+\((?:string id)?\)$")),
    ("conf", re.compile(r"^Conf[JL]\\On;$")),
    ("move", re.compile(r"^(MoveJ|MoveL|MoveAbsJ) (\w+),(\w+),(\w+),\w+\\WObj:=\w+;$")),
    ("waittime", re.compile(rf"^WaitTime ({_NUM});$")),
    ("setdo", re.compile(r"^SetDO (do(\d+)_\w+), ([01]);$")),
    ("waitdi", re.compile(r"^WaitDI (di(\d+)_\w+), 1;$")),
    ("end", re.compile(r"^(ENDPROC|ENDMODULE)$")),
]


def parse_rapid(text: str, *, path: str = "<rapid>") -> RapidModule:
    """Parse a module written by :func:`~weldplan.io.posts.rapid.render_rapid`.

    A line after a move that matches no other rule is taken as the weld instruction of the
    target before it (the user's template); anywhere else it is an error.
    """
    mod = RapidModule()
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        hit = _match(_RAPID, line)
        if hit is None:
            if mod.moves:
                mod.welds.append((mod.moves[-1][1], line))
                continue
            raise InputError(f"not a line weldplan writes: {line[:60]!r}", path=path, line=lineno)
        kind, g = hit
        if kind == "module":
            mod.name = g[0]
        elif kind == "tool":
            mod.tool = _pose_wxyz(list(g[:7]))
            mod.tool_mass = float(g[7])
            mod.tool_cog = np.array([float(v) for v in g[8:11]])
        elif kind == "wobj":
            mod.uframe, mod.oframe = _pose_wxyz(list(g[:7])), _pose_wxyz(list(g[7:14]))
            mod.wobj = mod.uframe @ mod.oframe
        elif kind == "speed":
            mod.speeds[g[0]] = float(g[1])
        elif kind == "target":
            mod.targets[g[0]] = (_pose_wxyz(list(g[1:8])), tuple(int(v) for v in g[8:12]))  # type: ignore[misc]
            if g[12] is not None:
                mod.tags[g[0]] = g[12]
        elif kind == "joints":
            mod.joints[g[0]] = np.array([float(v) for v in g[1:7]])
        elif kind == "move":
            known = mod.joints if g[0] == "MoveAbsJ" else mod.targets
            if g[1] not in known or g[2] not in mod.speeds:
                raise InputError(f"undeclared target or speed in {line!r}", path=path, line=lineno)
            mod.moves.append(g)  # type: ignore[arg-type]
            mod.move_lines.append(lineno)
        elif kind == "waittime":
            mod.weld_time = float(g[0])
        elif kind in ("setdo", "waitdi"):
            _rapid_signal(mod, kind, g, path, lineno)
    return mod


def _rapid_signal(mod: RapidModule, kind: str, g: tuple, path: str, lineno: int) -> None:
    """A ``SetDO`` (0 before the first move: a reset; 1 after a target: a set) or a ``WaitDI``
    after a target."""
    name, number = g[0], int(g[1])
    interlock = name.split("_", 1)[1]  # do<n>_<name>, di<n>_<name>
    if kind == "setdo" and g[2] == "0":
        if mod.moves:
            raise InputError(f"{name} switched off after a move", path=path, line=lineno)
        mod.resets.append((number, interlock))
        return
    if not mod.moves:
        raise InputError(f"a signal before the first move: {name}", path=path, line=lineno)
    action = "set" if kind == "setdo" else "wait"
    mod.signals.append((mod.moves[-1][1], action, number, interlock))
    mod.signal_lines.append(lineno)


@dataclass
class KrlProgram:
    """A parsed KRL ``.src`` + ``.dat``: frames (4, 4) mm, points, moves in order."""

    name: str = ""
    tool: NDArray[np.float64] = field(default_factory=lambda: np.eye(4))
    base: NDArray[np.float64] = field(default_factory=lambda: np.eye(4))
    load_mass: float = float("nan")
    load_cog: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    points: dict[str, tuple[NDArray[np.float64], int, int]] = field(default_factory=dict)
    #: ``E6AXIS`` name -> ``(6,)`` axis values, deg (the home, ``XHOME``: ``PTP`` only)
    axes: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    moves: list[tuple[str, str, float, float]] = field(
        default_factory=list
    )  # instr, point, vel m/s, cdis (0: exact)
    welds: list[tuple[str, str]] = field(default_factory=list)
    #: ``(after point, "set" | "wait", signal number, interlock name)`` in program order
    signals: list[tuple[str, str, int, str]] = field(default_factory=list)
    #: ``(signal number, interlock name)`` of the outputs switched off before the first move
    resets: list[tuple[int, str]] = field(default_factory=list)
    #: each point's comment in the ``.dat`` (``weld <id>``, ``<kind>, route row <row>``)
    tags: dict[str, str] = field(default_factory=dict)
    #: the ``.src`` line (1-based) of each move and of each signal, parallel to :attr:`moves`
    #: and :attr:`signals`: what a check of the program names
    move_lines: list[int] = field(default_factory=list)
    signal_lines: list[int] = field(default_factory=list)


_FRAME = rf"\{{X ({_NUM}), Y ({_NUM}), Z ({_NUM}), A ({_NUM}), B ({_NUM}), C ({_NUM})"


def krl_frame(vals: list[str]) -> NDArray[np.float64]:
    """``(4, 4)`` of ``X, Y, Z`` mm and ``A, B, C`` degrees (``Rz(A) Ry(B) Rx(C)``)."""
    x, y, z, a, b, c = (float(v) for v in vals)
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("ZYX", [a, b, c], degrees=True).as_matrix()
    T[:3, 3] = [x, y, z]
    return T


def parse_krl(src: str, dat: str, *, path: str = "<krl>") -> KrlProgram:
    """Parse a ``(src, dat)`` pair written by :func:`~weldplan.io.posts.krl.render_krl`."""
    prog = KrlProgram()
    frames: dict[str, NDArray[np.float64]] = {}
    dat_rules = [
        ("defdat", re.compile(r"^DEFDAT (\w+)$")),
        ("skip", re.compile(r"^(;.*|ENDDAT|)$")),
        ("frame", re.compile(rf"^DECL FRAME (\w+)={_FRAME}\}}$")),
        (
            "e6axis",
            re.compile(
                rf"^DECL E6AXIS (\w+)=\{{A1 ({_NUM}), A2 ({_NUM}), A3 ({_NUM}), A4 ({_NUM}), "
                rf"A5 ({_NUM}), A6 ({_NUM}), E1 0\.0, E2 0\.0, E3 0\.0, E4 0\.0, E5 0\.0, "
                r"E6 0\.0\}(?: ;.*)?$"
            ),
        ),
        (
            "e6pos",
            re.compile(
                rf"^DECL E6POS (\w+)={_FRAME}, S (\d+), T (\d+), E1 0\.0, E2 0\.0, E3 0\.0, "
                r"E4 0\.0, E5 0\.0, E6 0\.0\}(?: ; (.*))?$"
            ),
        ),
    ]
    for lineno, raw in enumerate(dat.splitlines(), start=1):
        line = raw.strip()
        hit = _match(dat_rules, line)
        if hit is None:
            raise InputError(
                f"not a line weldplan writes: {line[:60]!r}", path=f"{path}.dat", line=lineno
            )
        kind, g = hit
        if kind == "defdat":
            prog.name = g[0]
        elif kind == "frame":
            frames[g[0]] = krl_frame(list(g[1:7]))
        elif kind == "e6pos":
            prog.points[g[0]] = (krl_frame(list(g[1:7])), int(g[7]), int(g[8]))
            if g[9] is not None:
                prog.tags[g[0]] = g[9]
        elif kind == "e6axis":
            prog.axes[g[0]] = np.array([float(v) for v in g[1:7]])
    vel, cdis = float("nan"), 0.0
    src_rules = [
        ("def", re.compile(r"^DEF (\w+)\(\)$")),
        ("skip", re.compile(r"^(;.*|END|)$")),
        ("tool", re.compile(r"^\$TOOL = (\w+)$")),
        ("base", re.compile(r"^\$BASE = (\w+)$")),
        ("mass", re.compile(rf"^\$LOAD\.M = ({_NUM})$")),
        (
            "cog",
            re.compile(
                rf"^\$LOAD\.CM = \{{X ({_NUM}), Y ({_NUM}), Z ({_NUM}), A 0\.0, B 0\.0, C 0\.0\}}$"
            ),
        ),
        ("velaxis", re.compile(r"^\$VEL_AXIS\[\d\] = \d+$")),
        ("vel", re.compile(rf"^\$VEL\.CP = ({_NUM})$")),
        ("cdis", re.compile(rf"^\$APO\.CDIS = ({_NUM})$")),
        ("move", re.compile(r"^(PTP|LIN) (\w+)( C_DIS)?$")),
        ("out", re.compile(r"^\$OUT\[(\d+)\] = (TRUE|FALSE) ; (\w+)$")),
        ("advance", re.compile(r"^WAIT SEC 0$")),
        ("waitin", re.compile(r"^WAIT FOR \$IN\[(\d+)\] ; (\w+)$")),
    ]
    last = ""
    for lineno, raw in enumerate(src.splitlines(), start=1):
        line, prev = raw.strip(), last
        last = line
        hit = _match(src_rules, line)
        if hit is None:
            if prog.moves:
                prog.welds.append((prog.moves[-1][1], line))
                continue
            raise InputError(
                f"not a line weldplan writes: {line[:60]!r}", path=f"{path}.src", line=lineno
            )
        kind, g = hit
        if kind in ("tool", "base"):
            if g[0] not in frames:
                raise InputError(f"undeclared frame {g[0]}", path=f"{path}.src", line=lineno)
            setattr(prog, kind, frames[g[0]])
        elif kind == "mass":
            prog.load_mass = float(g[0])
        elif kind == "cog":
            prog.load_cog = np.array([float(v) for v in g])
        elif kind == "vel":
            vel = float(g[0])
        elif kind == "cdis":
            cdis = float(g[0])
        elif kind == "move":
            if g[1] not in prog.points and not (g[0] == "PTP" and g[1] in prog.axes):
                raise InputError(f"undeclared point {g[1]}", path=f"{path}.src", line=lineno)
            prog.moves.append((g[0], g[1], vel, cdis if g[2] else 0.0))
            prog.move_lines.append(lineno)
        elif kind == "def" and prog.name and g[0] != prog.name:
            raise InputError(f"DEF {g[0]} but DEFDAT {prog.name}", path=f"{path}.src", line=lineno)
        elif kind in ("out", "waitin"):
            _krl_signal(prog, g, prev, f"{path}.src", lineno)
    return prog


def _krl_signal(prog: KrlProgram, g: tuple, prev: str, path: str, lineno: int) -> None:
    """``$OUT[n] = FALSE`` before the first move (a reset), ``$OUT[n] = TRUE`` after a point
    and right after ``WAIT SEC 0`` (the advance-run stop that makes it switch at the point),
    ``WAIT FOR $IN[n]`` after a point."""
    if len(g) == 2:  # WAIT FOR $IN[n] ; name
        if not prog.moves:
            raise InputError("WAIT FOR $IN before the first move", path=path, line=lineno)
        prog.signals.append((prog.moves[-1][1], "wait", int(g[0]), g[1]))
        prog.signal_lines.append(lineno)
        return
    number, on, name = int(g[0]), g[1] == "TRUE", g[2]
    if not on:
        if prog.moves:
            raise InputError(f"$OUT[{number}] switched off after a move", path=path, line=lineno)
        prog.resets.append((number, name))
        return
    if not prog.moves or prev != "WAIT SEC 0":
        raise InputError(
            f"$OUT[{number}] = TRUE without WAIT SEC 0 after a point before it", path=path,
            line=lineno,
        )  # fmt: skip
    prog.signals.append((prog.moves[-1][1], "set", number, name))
    prog.signal_lines.append(lineno)
