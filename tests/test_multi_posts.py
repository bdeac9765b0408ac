"""Interlock signals in the programs (issue 30, item 4): an :class:`Interlock` between two
robots becomes a ``set`` in one program and a ``wait`` in the other; both posts write them
(KRL ``$OUT`` / ``WAIT FOR $IN``, RAPID ``SetDO`` / ``WaitDI``), our readers take them back to
the same actions, and ABB RAPID's grammar (rapidchecker, a third-party checker) accepts the
module. The program is the shared KR 150 with the spot gun on the box route of
tests/robot_fixtures.py; the interlock rows are stop rows of its timed route."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tests.robot_fixtures import box_joint_route, gun_tcp, shared_robot
from tests.route_fixtures import box_part
from weldplan.errors import InputError, PlanningError
from weldplan.io.posts.krl import render_krl
from weldplan.io.posts.parse import parse_krl, parse_rapid
from weldplan.io.posts.program import SignalAction
from weldplan.io.posts.rapid import render_rapid
from weldplan.multi.schedule import Interlock


@pytest.fixture(scope="module")
def build():
    from weldplan.robot.model import urdf_payload
    from weldplan.robot.program import robot_program
    from weldplan.robot.settings import ProgramSettings, ToolOnRobot

    robot = shared_robot()
    Tft, gun = gun_tcp(robot)
    route, Q = box_joint_route(robot, Tft)
    mass, cog = urdf_payload(gun)
    tool = ToolOnRobot(Tft, mass=mass, cog=(robot.mount @ np.r_[cog, 1.0])[:3])
    return robot_program(
        route, Q, robot, tool, part=box_part(), settings=ProgramSettings(weld_time=0.5)
    )


def _programs(build):
    """Two programs of the same route standing for robots 1 and 2, tied by two interlocks:
    robot 2 waits at its first stop for robot 1's second stop (signal 1), and robot 1 waits at
    its last stop for robot 2's second stop (signal 2)."""
    stops = np.flatnonzero(build.timing.stops)
    assert len(stops) >= 3
    locks = (
        Interlock("Z1", first=0, release_row=int(stops[1]), second=1, wait_row=int(stops[0]),
                  signal=1),
        Interlock("Z2", first=1, release_row=int(stops[1]), second=0, wait_row=int(stops[-1]),
                  signal=2),
    )  # fmt: skip
    acts: dict[int, list[SignalAction]] = {0: [], 1: []}
    for lock in locks:
        for robot, action in lock.actions([build.row, build.row]):
            peer = f"robot{(lock.second if robot == lock.first else lock.first) + 1}"
            acts[robot].append(dataclasses.replace(action, peer=peer))
    progs = [
        dataclasses.replace(build.program, signals=tuple(sorted(acts[r], key=_order(build))))
        for r in (0, 1)
    ]
    return progs, locks


def _order(build):
    rows = [t.row for t in build.program.targets]
    return lambda a: rows.index(a.row)


def _read_back(actions_by_point, program):
    """``(route row, action, signal, name)`` of parsed ``(point, action, n, name)`` tuples, the
    point named by its index in the program (``XP0003`` / ``p0003``)."""
    out = []
    for point, action, n, name in actions_by_point:
        k = int(point.lstrip("XPp"))
        out.append((program.targets[k].row, action, n, name))
    return out


def _expected(program):
    return [(a.row, a.action, a.signal, a.name) for a in program.signals]


def test_interlock_rows_land_on_exact_stops_of_both_programs(build):
    progs, locks = _programs(build)
    for prog in progs:
        by_row = {t.row: t for t in prog.targets if t.kind == "weld"}
        for a in prog.signals:  # the stop rows of this route are its welds
            assert a.row in by_row
    assert [a.action for a in progs[0].signals] == ["set", "wait"]
    assert {a.name for a in progs[1].signals} == {lk.name for lk in locks}


def test_krl_writes_the_signals_and_our_reader_takes_them_back(build):
    progs, _ = _programs(build)
    for prog in progs:
        src, dat = render_krl(prog)
        back = parse_krl(src, dat)
        assert _read_back(back.signals, prog) == _expected(prog)
        sets = sorted({(a.signal, a.name) for a in prog.signals if a.action == "set"})
        assert back.resets == sets
        lines = [ln.strip() for ln in src.splitlines()]
        first_move = next(k for k, ln in enumerate(lines) if ln.startswith(("PTP", "LIN")))
        for n, name in sets:
            k = lines.index(f"$OUT[{n}] = TRUE ; {name}")
            assert lines[k - 1] == "WAIT SEC 0"  # the advance-run stop
            assert lines.index(f"$OUT[{n}] = FALSE ; {name}") < first_move
        for a in prog.signals:  # the header lists each signal with its wiring
            assert any(f"signal {a.signal} {a.name}:" in ln and "wiring" in ln for ln in lines)


def test_krl_signal_after_the_weld_instruction_before_the_next_move(build):
    progs, _ = _programs(build)
    src, _ = render_krl(progs[1])
    lines = [ln.strip() for ln in src.splitlines()]
    k = next(i for i, ln in enumerate(lines) if ln.startswith("WAIT FOR $IN[1]"))
    assert lines[k - 1].startswith("WAIT SEC 0.500 ; spot")  # the weld's dwell
    assert lines[k + 1].startswith(("LIN", "PTP", "$VEL", "$APO"))


def test_rapid_writes_the_signals_and_our_reader_takes_them_back(build):
    progs, _ = _programs(build)
    for prog in progs:
        text = render_rapid(prog)
        mod = parse_rapid(text)
        assert _read_back(mod.signals, prog) == _expected(prog)
        sets = sorted({(a.signal, a.name) for a in prog.signals if a.action == "set"})
        assert mod.resets == sets
        eio = [ln for ln in text.splitlines() if "I/O configuration (EIO) to declare" in ln]
        want = {
            f"{'DO do' if a.action == 'set' else 'DI di'}{a.signal}_{a.name}" for a in prog.signals
        }
        assert len(eio) == 1 and set(eio[0].split(": ", 1)[1].split(", ")) == want
        zone = {name: z for _, name, _, z in mod.moves}
        for point, *_ in mod.signals:  # a signal only after a fine point
            assert zone[point] == "fine"


def test_rapid_with_signals_passes_the_rapid_grammar(build, monkeypatch):
    """rapidchecker (PyPI; not a dependency of weldplan: install it to run this) parses the
    module with its RAPID grammar; our modules indent by 4."""
    rc = pytest.importorskip("rapidchecker.check")
    from rapidchecker.config import CONFIG

    monkeypatch.setattr(CONFIG, "indentation_size", 4)
    progs, _ = _programs(build)
    for prog in progs:
        assert rc.check_format(render_rapid(prog)) == []
    assert rc.check_format(render_rapid(build.program)) == []


def test_a_signal_on_a_blended_target_or_off_the_targets_is_refused(build):
    blended = next(t for t in build.program.targets if t.kind == "via" and t.blend > 0)
    rows = {t.row for t in build.program.targets}
    for row, what in ((blended.row, "not an exact stop"), (max(rows) + 5, "no target")):
        prog = dataclasses.replace(
            build.program, signals=(SignalAction(row, "set", 1, "Z1_R1_R2"),)
        )
        for render in (render_rapid, lambda p: render_krl(p)[0]):
            with pytest.raises(PlanningError, match=what):
                render(prog)


def test_krl_reader_refuses_an_output_set_without_the_advance_run_stop(build):
    progs, _ = _programs(build)
    src, dat = render_krl(progs[0])
    bad = src.replace("  WAIT SEC 0\n", "", 1)
    with pytest.raises(InputError, match="WAIT SEC 0"):
        parse_krl(bad, dat)


def test_a_program_without_signals_writes_none(build):
    src, dat = render_krl(build.program)
    assert "$OUT" not in src and "$IN" not in src and "Interlock" not in src
    text = render_rapid(build.program)
    assert "SetDO" not in text and "WaitDI" not in text
    assert parse_rapid(text).signals == [] and parse_krl(src, dat).signals == []
