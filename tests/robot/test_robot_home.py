"""The robot's home (weldplan.robot.route.home; issue 30, item 4): a home that is not a
configuration of the robot is refused naming why; a program whose joint route starts and ends at
home has home as its first and last target (KRL ``PTP XHOME``, RAPID ``MoveAbsJ jhome``), times
the legs to and from it, reads back through our parsers at the axis values given, and passes
ABB's grammar (rapidchecker); an interlock at home is written right after the home move. The
robot is the shared KR 150 with the spot gun on the box route of tests/robot_fixtures.py."""

from __future__ import annotations

import dataclasses
import importlib
import os

import numpy as np
import pytest

from tests.conftest import require_shared
from tests.robot_fixtures import box_joint_route, gun_tcp, shared_robot
from tests.route_fixtures import box_part
from weldplan.errors import ConfigError

#: deg: the KR 150's conventional home
HOME_DEG = (0.0, -90.0, 90.0, 0.0, 0.0, 0.0)


def test_a_home_that_is_not_a_free_configuration_is_refused_saying_why():
    import trimesh

    from weldplan.robot.collision.checker import RobotCollision
    from weldplan.robot.route.home import check_home

    robot = shared_robot()
    Tft, _ = gun_tcp(robot)
    q = check_home(robot, HOME_DEG)
    assert np.allclose(np.degrees(q), HOME_DEG, atol=1e-12)
    with pytest.raises(ConfigError, match="home needs 6 finite joint values") as e:
        check_home(robot, HOME_DEG[:5])
    assert e.value.field == "home"
    with pytest.raises(ConfigError, match=r"home A2 = 0 deg is outside the joint's limits"):
        check_home(robot, (0.0, 0.0, 90.0, 0.0, 0.0, 0.0))  # the KR 150's A2 stops at -5 deg
    # the flange at home, inside a box: the robot at home touches the part
    flange = robot.fk(q[None])[0][:3, 3]
    box = trimesh.creation.box((300.0, 300.0, 300.0))
    box.apply_translation(flange)
    free = RobotCollision(robot, box_part(), None, Tft, contact_radius=20.0)
    assert np.array_equal(check_home(robot, HOME_DEG, free), q)
    hit = RobotCollision(robot, box, None, Tft, contact_radius=20.0)
    with pytest.raises(ConfigError, match=r"at home .* collides: link_\d touches the part"):
        check_home(robot, HOME_DEG, hit)
    # a floor above the base: the lowest link stands in it
    floor = RobotCollision(robot, box_part(), None, Tft, contact_radius=20.0,
                           floor_z=float(robot.base[2, 3]) + 300.0)  # fmt: skip
    with pytest.raises(ConfigError, match="touches floor"):
        check_home(robot, HOME_DEG, floor)


@pytest.fixture(scope="module")
def builds():
    """``(without home, from home)``: the box route's program, and the same joint route with
    home before its first row and after its last."""
    from weldplan.robot.model import urdf_payload
    from weldplan.robot.program import robot_program
    from weldplan.robot.settings import ProgramSettings, ToolOnRobot

    robot = shared_robot()
    Tft, gun = gun_tcp(robot)
    route, Q = box_joint_route(robot, Tft)
    mass, cog = urdf_payload(gun)
    tool = ToolOnRobot(Tft, mass=mass, cog=(robot.mount @ np.r_[cog, 1.0])[:3])
    n, home = len(Q), np.radians(HOME_DEG)
    plain = robot_program(route, Q, robot, tool, part=box_part(),
                          settings=ProgramSettings(weld_time=0.5))  # fmt: skip
    row = np.r_[0, np.arange(n), n - 1]
    exact = np.r_[False, np.ones(n, bool), False]
    homed = robot_program(
        route, np.vstack([home, Q, home]), robot, tool, part=box_part(), row=row, exact=exact,
        settings=ProgramSettings(weld_time=0.5, home=True),
    )  # fmt: skip
    return plain, homed


def test_a_program_from_home_starts_and_ends_there_and_times_both_legs(builds):
    plain, homed = builds
    tg, n = homed.program.targets, int(plain.row.max()) + 1
    assert [t.kind for t in tg[:1] + tg[-1:]] == ["home", "home"]
    assert (tg[0].row, tg[-1].row) == (-1, n) and tg[0].move == tg[-1].move == "joint"
    assert np.allclose(np.degrees(tg[0].q), HOME_DEG) and np.array_equal(tg[0].q, tg[-1].q)
    assert homed.row[0] == -1 and homed.row[-1] == n
    assert np.array_equal(homed.row[1:-1], plain.row)
    # between the homes, the same targets as the program without (its approach and retreat,
    # moves from wherever the robot is, give way to the legs from and to home)
    inner = [(t.kind, t.row, t.joint_id) for t in tg[1:-1]]
    assert inner == [(t.kind, t.row, t.joint_id) for t in plain.program.targets[1:-1]]
    # the timing runs from home to home: both legs are in it, at rest at each end
    T, P = homed.timing, plain.timing
    assert np.allclose(T.q[0], np.radians(HOME_DEG)) and np.allclose(T.q[-1], T.q[0])
    assert T.stops[0] and T.stops[-1] and T.stops[1] and T.stops[-2]
    legs = T.row_times[1] + (T.total - T.row_times[-2] - T.weld_time)
    assert legs > 0 and T.total == pytest.approx(P.total + legs, abs=1e-6)
    assert "from home to home" in " ".join(homed.program.notes)


def _require(module: str):
    try:
        return importlib.import_module(module)
    except ImportError as e:
        if os.environ.get("WELDPLAN_REQUIRE_SHARED") == "1":
            pytest.fail(f"{module} is not installed (WELDPLAN_REQUIRE_SHARED=1): {e}")
        pytest.skip(f"{module} is not installed (the test extra of requirements.lock has it)")


def test_the_posts_write_home_as_axis_values_and_read_them_back(builds):
    from weldplan.io.posts.krl import render_krl
    from weldplan.io.posts.parse import parse_krl, parse_rapid
    from weldplan.io.posts.rapid import render_rapid

    _, homed = builds
    src, dat = render_krl(homed.program)
    k = parse_krl(src, dat)
    assert set(k.axes) == {"XHOME"} and np.allclose(k.axes["XHOME"], HOME_DEG, atol=1e-5)
    assert k.moves[0][:2] == ("PTP", "XHOME") and k.moves[-1][:2] == ("PTP", "XHOME")
    assert all(m[1] in k.points for m in k.moves[1:-1])
    assert len(k.moves) == len(homed.program.targets)
    text = render_rapid(homed.program)
    r = parse_rapid(text)
    assert set(r.joints) == {"jhome"} and np.allclose(r.joints["jhome"], HOME_DEG, atol=1e-4)
    assert r.moves[0][:2] == ("MoveAbsJ", "jhome") and r.moves[-1][:2] == ("MoveAbsJ", "jhome")
    assert len(r.moves) == len(homed.program.targets)
    # the plan's own check of what it writes: FK of every target read back (home: of its axes)
    from weldplan.station.outputs import check_program

    robot = shared_robot()
    assert check_program("krl", {"post": src, "post_dat": dat}, homed.program, robot) < 0.01
    assert check_program("rapid", {"post": text}, homed.program, robot) < 0.01
    _require("rapidchecker.cli")
    from pyparsing import ParseBaseException
    from rapidchecker.cli import check_file
    from rapidchecker.config import CONFIG

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(CONFIG, "indentation_size", 4)
        try:
            errors = [(int(e.lineno), str(e)) for e in check_file(text)]
        except ParseBaseException as e:
            errors = [(int(e.lineno), str(e))]
    assert errors == []


def test_a_robot_waits_at_home_behind_an_interlock(builds):
    from weldplan.io.posts.krl import render_krl
    from weldplan.io.posts.parse import parse_krl, parse_rapid
    from weldplan.io.posts.rapid import render_rapid
    from weldplan.multi.schedule import Interlock

    _, homed = builds
    stops = np.flatnonzero(homed.timing.stops)
    last = int(stops[-1])
    lock = Interlock("Z1", first=0, release_row=last, second=1, wait_row=0, signal=1)
    (_, set_), (_, wait) = lock.actions([homed.row, homed.row])
    assert wait.row == -1 and set_.row == int(homed.row[-1])  # both at a home target
    waiting = dataclasses.replace(homed.program, signals=(wait,))
    k = parse_krl(*render_krl(waiting))
    assert k.signals == [("XHOME", "wait", 1, lock.name)]
    assert parse_rapid(render_rapid(waiting)).signals == [("jhome", "wait", 1, lock.name)]
    src, _ = render_krl(dataclasses.replace(homed.program, signals=(set_,)))
    lines = [ln.strip() for ln in src.splitlines()]
    assert lines[-4:-1] == ["PTP XHOME", "WAIT SEC 0", f"$OUT[1] = TRUE ; {lock.name}"]


def test_the_route_starts_and_ends_at_home_on_legs_an_independent_sampling_finds_free():
    """The box route with the torch from BOX_BASE, home the conventional one: the joint route
    starts and ends at home, the legs' rows are not exact and carry the first and last weld's
    route rows, the welds' rows are those of the route without a home, and every motion of the
    legs is free of the part and the robot itself under a dense FCL sampling of the
    whole torch and every link (200 configurations a motion). A home out of the limits is
    refused before any planning."""
    from tests.robot_helpers import BOX_BASE, TORCH_TCP, down_poses
    from tests.route_fixtures import box_route
    from weldplan.robot import load_robot
    from weldplan.robot.collision import RobotCollision
    from weldplan.robot.route import plan_robot_route
    from weldplan.robot.settings import JointRouteSettings, RobotCell, ToolOnRobot
    from weldplan.tool import arc_torch

    robot = load_robot(require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf"))
    route = box_route()
    poses = down_poses(route)
    tool, cell = ToolOnRobot(TORCH_TCP, arc_torch()), RobotCell(box_part(), base=BOX_BASE)
    plain = plan_robot_route(route, poses, robot, tool=tool, cell=cell, rng=0)
    s = JointRouteSettings(home=tuple(np.radians(HOME_DEG)))
    rr = plan_robot_route(route, poses, robot, tool=tool, cell=cell, settings=s, rng=0)
    a, b = rr.stats["home"]["lead_rows"], rr.stats["home"]["trail_rows"]
    assert a >= 1 and b >= 1 and len(rr.q) == len(plain.q) + a + b
    assert np.allclose(rr.q[0], np.radians(HOME_DEG)) and np.array_equal(rr.q[0], rr.q[-1])
    assert not rr.exact[:a].any() and not rr.exact[-b:].any()
    assert set(rr.row[:a].tolist()) == {0} and set(rr.row[-b:].tolist()) == {plain.row[-1]}
    np.testing.assert_array_equal(rr.q[a : len(rr.q) - b], plain.q)
    assert rr.status == plain.status and rr.stats["collision_free"]
    chk = RobotCollision(robot.with_base(rr.base), box_part(), arc_torch(), TORCH_TCP)
    whole = set(rr.stats["whole_tool_motions"])
    for i in [*range(a), *range(len(rr.q) - b - 1, len(rr.q) - 1)]:  # the legs' motions
        qa, qb = rr.q[i], rr.q[i + 1]
        assert all(chk.state_free(qa + t * (qb - qa), zone=i not in whole)
                   for t in np.linspace(0.0, 1.0, 200))  # fmt: skip
    with pytest.raises(ConfigError, match="home A2"):
        bad = JointRouteSettings(home=(0.0, 0.0, 1.5, 0.0, 0.0, 0.0))
        plan_robot_route(route, poses, robot, tool=tool, cell=cell, settings=bad, rng=0)

