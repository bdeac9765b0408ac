"""The interlock signals of a saved station's programs, read back and held against its schedule.

``weldplan verify STATION_JSON`` re-checks each robot's program as written (KRL ``.src`` +
``.dat``, RAPID ``.mod``): the program is parsed back by the posts' own round-trip grammar
(:mod:`weldplan.io.posts.parse`; a line outside it is a failure naming the file and the line),
and its signals must be exactly its side of the schedule's interlocks
(:class:`~weldplan.multi.schedule.Interlock`):

- robot ``first`` sets the output ``signal`` once at rest at ``release_row`` (KRL ``WAIT SEC 0``
  then ``$OUT[n] = TRUE``, RAPID ``SetDO``), robot ``second`` waits on the input ``signal`` at
  ``wait_row`` before it leaves (KRL ``WAIT FOR $IN[n]``, RAPID ``WaitDI``); each after the
  target that stands for that row's route row (the station JSON records the route row of each
  timed row): the weld target of the weld the schedule records on that route row, else the last
  target of the route row, as the posts place them;
- the same signal number and interlock name on both sides, no signal the schedule does not
  hold, and every output the program sets switched off before its first move.

An edited program that drops a wait, moves a set to another target or renumbers a signal
fails, naming the file and the line (of the signal, or of the move to the target a missing one
belongs after). This reads what :mod:`weldplan.multi.station` ``with_signals`` wrote, through
files only; it shares none of its code.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from weldplan.errors import InputError
from weldplan.station.recheck import CheckResult

#: a non-weld target's comment: ``<kind>, route row <row>``
_ROUTE_ROW = re.compile(r", route row (\d+)$")


@dataclass(frozen=True)
class Program:
    """A robot's program as parsed back: its file (the ``.src`` of a KRL pair), its language,
    its targets' comments and moves (target names, in order, with their lines), its signals
    ``(after target, action, number, name)`` with their lines, and the outputs it switches off
    at its start."""

    path: Path
    language: str
    tags: dict[str, str]
    moves: tuple[tuple[str, int], ...]
    signals: tuple[tuple[tuple[str, str, int, str], int], ...]
    resets: frozenset[int]

    def write(self, action: str, signal: int, name: str) -> str:
        """How this language writes a signal action (for messages)."""
        if self.language == "krl":
            return f"$OUT[{signal}] = TRUE" if action == "set" else f"WAIT FOR $IN[{signal}]"
        return f"SetDO do{signal}_{name}" if action == "set" else f"WaitDI di{signal}_{name}"

    def line_of(self, target: str) -> int:
        """The line of the (last) move to ``target`` (0: none)."""
        return max((ln for t, ln in self.moves if t == target), default=0)


def read_program(files: tuple[Path, ...]) -> Program:
    """Parse a saved robot's program: two files, a KRL ``.src`` and ``.dat``; one, RAPID.

    Raises :class:`~weldplan.errors.InputError` naming the file and the line when a line is
    not one the posts write, or a file cannot be read."""
    from weldplan.io.posts.parse import parse_krl, parse_rapid

    texts = []
    for f in files:
        try:
            texts.append(f.read_text(encoding="utf-8"))
        except OSError as exc:
            raise InputError(f"cannot read it: {exc.strerror}", path=f) from None
    if len(files) == 2:
        src = files[0]
        p: Any = parse_krl(texts[0], texts[1], path=str(src.with_suffix("")))
        lang = "krl"
    else:
        src = files[0]
        p, lang = parse_rapid(texts[0], path=str(src)), "rapid"
    return Program(
        src, lang, dict(p.tags),
        tuple((m[1], ln) for m, ln in zip(p.moves, p.move_lines, strict=True)),
        tuple(zip(p.signals, p.signal_lines, strict=True)),
        frozenset(n for n, _ in p.resets),
    )  # fmt: skip


def expected_signals(saved: Any, k: int) -> list[tuple[int, str, int, str]]:
    """Robot ``k``'s side of the schedule's interlocks: ``(timed row, action, signal, name)``,
    ``"set"`` at each ``release_row`` it releases, ``"wait"`` at each ``wait_row`` it waits at."""
    out = []
    for lock in saved.schedule.interlocks:
        if lock.first == k:
            out.append((lock.release_row, "set", lock.signal, lock.name))
        if lock.second == k:
            out.append((lock.wait_row, "wait", lock.signal, lock.name))
    return out


def row_targets(saved: Any, k: int, program: Program, rows: set[int]) -> dict[int, str]:
    """``{timed row: the program's target}`` for the stop ``rows`` of robot ``k`` (module
    docstring); a row with no such target is left out.

    A timed row stands for a route row (the station JSON's ``rows``; a plan saved without
    them: the trajectory CSV's ``step`` at the arrival, which a stop reached without motion
    does not have). Its target is the weld target of the weld the schedule records on that
    route row, else the last target of the route row; the first and the last timed rows of a
    robot with a home are its home target (KRL ``XHOME``, RAPID ``jhome``: the program's first
    and last move, to one untagged target), where it waits before it leaves and releases after
    it is back."""
    s = saved.schedule
    route = _route_row(saved, k)
    home = _home_target(program)
    last = max((a.row for a in s.of(k)), default=-1)
    by_weld: dict[str, str] = {}
    by_row: dict[int, str] = {}
    for name, _ in program.moves:  # the last target of each weld and route row, in order
        tag = program.tags.get(name, "")
        m = _ROUTE_ROW.search(tag)
        if tag.startswith("weld "):
            by_weld[tag[5:]] = name
        elif m:
            by_row[int(m.group(1))] = name
    welds = {route(a.row): a.label for a in s.of(k) if a.kind == "weld" and a.label}
    out = {}
    for r in sorted(rows):
        R = route(r)
        if home is not None and r in (0, last):
            out[r] = home
        elif welds.get(R) in by_weld:
            out[r] = by_weld[welds[R]]
        elif R in by_row:
            out[r] = by_row[R]
    return out


def _home_target(program: Program) -> str | None:
    """The program's home target: its first and last move go to it and it is no weld's or
    route row's (untagged); ``None`` for a program without a home."""
    if not program.moves:
        return None
    first, last = program.moves[0][0], program.moves[-1][0]
    return first if first == last and not program.tags.get(first) else None


def _route_row(saved: Any, k: int) -> Any:
    """Robot ``k``'s ``timed row -> route row`` (``-1``: not known), from the station JSON's
    ``rows``, else from its trajectory CSV (:func:`row_targets`)."""
    from weldplan.multi.filetiming import _trajectory_rows, file_timing

    robot = saved.robots[k]
    if robot.rows is not None:
        rows = robot.rows
        return lambda r: rows[r] if 0 <= r < len(rows) else -1
    timing = file_timing(saved.schedule, k, robot.trajectory)
    step = [int(r[1]) for r in _trajectory_rows(robot.trajectory)[1:]]

    def from_csv(r: int) -> int:
        if not (r < len(timing.stops) and timing.stops[r]):
            return -1
        return step[int(np.argmin(np.abs(timing.t - timing.row_times[r])))]

    return from_csv


def signals_check(saved: Any, k: int) -> CheckResult | None:
    """Robot ``k``'s program against the schedule (module docstring); ``None`` when no
    program was written (``--post`` not given) or the robot is idle."""
    robot = saved.robots[k]
    name = f"{robot.name} signals"
    if not robot.program or saved.schedule is None:
        return None
    try:
        prog = read_program(robot.program)
        want = expected_signals(saved, k)
        at = row_targets(saved, k, prog, {r for r, *_ in want}) if want else {}
    except InputError as exc:
        return CheckResult(name, False, f"cannot read the program: {exc}")
    problems = []
    lost = [w for w in want if w[0] not in at]
    problems += [f"{prog.path.name}: no target stands for timed row {r} ({n})" for r, *_, n in lost]
    expect = Counter((at[r], a, n, nm) for r, a, n, nm in want if r in at)
    found = Counter(sig for sig, _ in prog.signals)
    for sig, count in (expect - found).items():
        problems.append(_missing(prog, sig, count))
    for sig, line in prog.signals:
        if found[sig] > expect[sig]:
            found[sig] -= 1
            problems.append(_extra(prog, sig, line))
    sets = {n for _, a, n, _ in want if a == "set"}
    for n in sorted(sets - prog.resets):
        problems.append(f"{prog.path.name}: output {n} is set but not switched off at the start")
    if problems:
        more = f" (and {len(problems) - 3} more)" if len(problems) > 3 else ""
        return CheckResult(name, False, "; ".join(problems[:3]) + more)
    n_set = sum(a == "set" for _, a, _, _ in want)
    text = (
        f"{prog.path.name}: exactly its {len(want)} interlock signal(s) of the schedule "
        f"({n_set} set, {len(want) - n_set} wait), each after its row's target, parsed back"
    )
    return CheckResult(name, True, text)


def _missing(prog: Program, sig: tuple[str, str, int, str], count: int) -> str:
    target, action, n, lock = sig
    tag = prog.tags.get(target, "")
    what = "waits for" if action == "wait" else "sets"
    times = "" if count == 1 else f" ({count} times)"
    return (
        f"{prog.path.name}, line {prog.line_of(target)}: no {prog.write(action, n, lock)} "
        f"after {target} ({tag}){times}: the schedule's {lock} says this robot {what} signal "
        f"{n} there"
    )


def _extra(prog: Program, sig: tuple[str, str, int, str], line: int) -> str:
    target, action, n, lock = sig
    tag = prog.tags.get(target, "")
    return (
        f"{prog.path.name}, line {line}: {prog.write(action, n, lock)} ({lock}) after {target} "
        f"({tag}) is not in the schedule"
    )
