"""Our robot programs parsed back by parsers we did not write (the standard in DESIGN.md).

* ABB RAPID modules: `rapidchecker` (PyPI, AGPL-3.0; a pyparsing grammar of RAPID plus layout
  checks), run as its command line runs it (:func:`rapidchecker.cli.check_file`: the grammar,
  the indentation, trailing spaces, empty lines, the final newline), indentation 4 as our posts
  write.

KUKA KRL has no parser on PyPI or in Debian (the public ANTLR grammar is not packaged), so KRL is
checked by our own round trip (tests/test_posts.py) only.

The programs are those of the post tests: the point-tip route's RAPID posts (weldplan.io.export,
on the box route of tests/route_fixtures.py, with and without a smooth leg; and the demo cell's,
slow), and the robot posts (weldplan.io.posts, the shared KR 150 with the spot gun on the box
route as in tests/test_posts.py): plain, with a part pose, with interlock signals. A broken edit
of each kind of file is rejected, at the line edited, so these tests can fail.

The parser comes with the test extra of requirements.lock; a test skips when it is not
installed, and fails instead under ``WELDPLAN_REQUIRE_SHARED=1`` (CI), as tests/conftest.py
does for the shared data.
"""

from __future__ import annotations

import dataclasses
import importlib
import os
import re
from pathlib import Path

import numpy as np
import pytest

from tests.route_fixtures import box_part, box_route

pytestmark = [  # the parsers' own deprecations, not ours
    pytest.mark.filterwarnings("ignore::pyparsing.PyparsingDeprecationWarning"),
]

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "assets" / "demo"


def _require(module: str):
    """Import ``module`` (a parser of the test extra); skip when absent, fail under CI's flag."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        msg = f"{module} is not installed (the test extra of requirements.lock has it): {e}"
        if os.environ.get("WELDPLAN_REQUIRE_SHARED") == "1":
            pytest.fail(msg + " (WELDPLAN_REQUIRE_SHARED=1)")
        pytest.skip(msg)


@pytest.fixture(scope="module")
def rapid_errors():
    """``text -> [(line, message)]``: what rapidchecker's command line reports for a module."""
    _require("rapidchecker.cli")
    from pyparsing import ParseBaseException
    from rapidchecker.cli import check_file
    from rapidchecker.config import CONFIG

    def errors(text: str) -> list[tuple[int, str]]:
        try:
            return [(int(e.lineno), str(e)) for e in check_file(text)]
        except ParseBaseException as e:  # check_file lets a fatal or non-syntax error through
            return [(int(e.lineno), str(e))]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(CONFIG, "indentation_size", 4)
        yield errors


@pytest.fixture(scope="module")
def route_programs():
    """``{name: text}``: the point-tip route's RAPID module, of the box route and of its
    smoothed version (the smooth leg as dense ``MoveL`` moves)."""
    from weldplan.geometry.collision import CollisionModel
    from weldplan.io.export import render_post
    from weldplan.weld.smoothing import smooth_route

    model = CollisionModel(box_part())
    smooth = smooth_route(box_route(), model, spacing=5.0)
    return {
        "route.mod": render_post(box_route(), "rapid", model),
        "route_smooth.mod": render_post(smooth, "rapid", model),
    }


@pytest.fixture(scope="module")
def robot_programs():
    """``{name: RobotProgram}``: the robot post's program of tests/test_posts.py (shared KR 150,
    spot gun, box route), that program with a part pose, and with two interlock signals (an
    output set after its first weld, an input awaited at its last)."""
    from tests.robot_fixtures import box_joint_route, gun_tcp, shared_robot
    from weldplan.cellframe import PartPose
    from weldplan.io.posts.program import SignalAction
    from weldplan.robot.model import urdf_payload
    from weldplan.robot.program import robot_program
    from weldplan.robot.settings import ProgramSettings, ToolOnRobot

    robot = shared_robot()
    Tft, gun = gun_tcp(robot)
    route, Q = box_joint_route(robot, Tft)
    mass, cog = urdf_payload(gun)
    tool = ToolOnRobot(Tft, mass=mass, cog=(robot.mount @ np.r_[cog, 1.0])[:3])
    plain = robot_program(
        route, Q, robot, tool, part=box_part(), settings=ProgramSettings(weld_time=0.5)
    ).program
    welds = [t.row for t in plain.targets if t.kind == "weld"]
    signals = (
        SignalAction(welds[0], "set", 1, "Z1_R1_R2", "robot2"),
        SignalAction(welds[-1], "wait", 2, "Z2_R2_R1", "robot2"),
    )
    pose = PartPose.from_xyzrpy([350.0, -120.0, 80.0, 5.0, -10.0, 30.0]).matrix
    return {
        "plain": plain,
        "part_pose": dataclasses.replace(plain, part_pose=pose),
        "interlocks": dataclasses.replace(plain, signals=signals),
    }


ROUTE_RAPID = ["route.mod", pytest.param("route_smooth.mod", marks=pytest.mark.slow)]
ROBOT = ["plain", "part_pose", "interlocks"]


@pytest.mark.parametrize("name", ROUTE_RAPID)
def test_route_rapid_modules_pass_rapidchecker(route_programs, rapid_errors, name):
    assert rapid_errors(route_programs[name]) == []


@pytest.mark.parametrize("name", ROBOT)
def test_robot_rapid_modules_pass_rapidchecker(robot_programs, rapid_errors, name):
    from weldplan.io.posts.rapid import render_rapid

    text = render_rapid(robot_programs[name])
    if name == "interlocks":
        assert "SetDO do1_Z1_R1_R2, 1;" in text and "WaitDI di2_Z2_R2_R1, 1;" in text
    assert rapid_errors(text) == []


def _edit(text: str, pattern: str, repl: str) -> tuple[str, int]:
    """``text`` with the first match of the regular expression ``pattern`` (multiline)
    replaced, and the 1-based line the match starts on."""
    m = re.search(pattern, text, flags=re.MULTILINE)
    assert m is not None, pattern
    return text[: m.start()] + m.expand(repl) + text[m.end() :], text.count("\n", 0, m.start()) + 1


#: ``(what, pattern, replacement)``: broken edits of the route's RAPID module
RAPID_EDITS = [
    ("no ENDMODULE", r"^ENDMODULE\n", ""),
    ("no ENDPROC", r"^\s+ENDPROC\n", ""),
    ("a move without its ';'", r"^(\s+MoveL [^;\n]+);", r"\1"),
    ("a move without the ',' after its target", r"^(\s+MoveL \w+),", r"\1 "),
    ("a robtarget with a bracket left open", r"^(\s+CONST robtarget \w+:=\[\[[^\]]*)\]", r"\1"),
]


def _at_the_edit(errors, line, n_lines, what):
    """The first error is on the edited line or the next (where the missing token was due); a
    missing end line is found at the end of the file."""
    assert errors, f"not rejected: {what}"
    first = errors[0][0]
    if what.startswith("no END"):
        assert first >= n_lines - 1, (what, errors)
    else:
        assert first in (line, line + 1), (what, line, errors)


@pytest.mark.parametrize("edit", RAPID_EDITS, ids=[e[0] for e in RAPID_EDITS])
def test_rapidchecker_rejects_a_broken_module(route_programs, rapid_errors, edit):
    what, pattern, repl = edit
    bad, line = _edit(route_programs["route.mod"], pattern, repl)
    errors = rapid_errors(bad)
    if what == "no ENDMODULE":  # rapidchecker reports the module as a whole, at its line 1
        assert errors and errors[0][0] == 1, errors
    else:
        _at_the_edit(errors, line, bad.count("\n"), what)


@pytest.mark.slow
def test_the_demo_cells_rapid_module_passes_rapidchecker(tmp_path, monkeypatch, rapid_errors):
    """The RAPID module ``weldplan demo --post rapid`` writes (its header included)."""
    from tests.cli_helpers import run_cli

    monkeypatch.chdir(tmp_path)
    argv = ["demo", "--no-html", "--quiet", "--json", "route.json", "--post", "rapid"]
    assert run_cli([*argv, "--post-file", "demo.mod"]) == 0
    text = (tmp_path / "demo.mod").read_text(encoding="utf-8")
    assert text.count("MoveL ") > 30
    assert rapid_errors(text) == []
