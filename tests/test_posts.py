"""Robot posts (weldplan.io.posts): emitted RAPID / KRL parsed back and re-solved by FK.

The robot is the shared KUKA KR 150 R3100-2 (URDF FK, not the OPW formulas), the tool the shared
spot gun, the route the box route of route_fixtures (tests/robot_fixtures.py makes the joint
route by IK). Tolerances: 0.01 mm and 0.01 deg, the issue's targets.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.robot_fixtures import box_joint_route, gun_tcp, shared_robot
from tests.route_fixtures import box_part
from weldplan.errors import InputError, PlanningError
from weldplan.io.blending import RAPID_ZONES
from weldplan.io.posts.krl import render_krl
from weldplan.io.posts.parse import parse_krl, parse_rapid
from weldplan.io.posts.rapid import render_rapid
from weldplan.robot import ELBOW, SHOULDER, WRIST
from weldplan.robot.settings import ProgramSettings, ToolOnRobot

MM, DEG = 0.01, 0.01


def _angle_deg(Ra, Rb):
    c = (np.trace(Ra.T @ Rb) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


@pytest.fixture(scope="module")
def build():
    from weldplan.robot.model import urdf_payload
    from weldplan.robot.program import robot_program

    robot = shared_robot()
    Tft, gun = gun_tcp(robot)
    route, Q = box_joint_route(robot, Tft)
    mass, cog = urdf_payload(gun)
    b = robot_program(
        route,
        Q,
        robot,
        ToolOnRobot(Tft, mass=mass, cog=(robot.mount @ np.r_[cog, 1.0])[:3]),
        part=box_part(),
        settings=ProgramSettings(weld_time=0.5),
    )
    return robot, Tft, Q, b


def _check_fk(robot, q, T_base_tcp, tool):
    """The FK flange pose (base frame) against the program's TCP pose composed with its tool."""
    T_fk = np.linalg.inv(robot.base) @ robot.fk(q)[0]
    T_prog = T_base_tcp @ np.linalg.inv(tool)
    assert np.linalg.norm(T_fk[:3, 3] - T_prog[:3, 3]) <= MM
    assert _angle_deg(T_fk[:3, :3], T_prog[:3, :3]) <= DEG


def test_rapid_round_trip_fk_confdata_zones_speeds(build):
    from tests.route_fixtures import box_route
    from weldplan.io.export import route_rows

    robot, Tft, Q, b = build
    rows = np.array([[r["x"], r["y"], r["z"]] for r in route_rows(box_route(directions=True))])
    prog = b.program
    mod = parse_rapid(render_rapid(prog))
    assert mod.tool_mass == pytest.approx(2.002)
    assert len(mod.moves) == len(prog.targets)
    for (instr, name, speed, zone), t in zip(mod.moves, prog.targets, strict=True):
        T_wobj_tcp, conf = mod.targets[name]
        _check_fk(robot, Q[t.row], mod.wobj @ T_wobj_tcp, mod.tool)
        # and the pose the joint route was solved for (IK target: the route row, TCP down)
        np.testing.assert_allclose(T_wobj_tcp[:3, 3], rows[t.row], atol=MM)
        assert _angle_deg(T_wobj_tcp[:3, :3], np.diag([1.0, -1.0, -1.0])) <= DEG
        q = Q[t.row]
        # confdata from the joint values, independently of the post
        quad = [int(np.floor(np.degrees(q[j]) / 90.0)) for j in (0, 3, 5)]
        assert list(conf[:3]) == quad
        br = int(robot.branch_of(q)[0])
        assert bool(conf[3] & 4) == bool(br & SHOULDER)
        assert bool(conf[3] & 2) == bool(br & ELBOW)
        assert bool(conf[3] & 1) == bool(br & WRIST)
        assert mod.speeds[speed] >= t.speed - 1e-9
        if t.kind == "weld" or t.move == "joint":
            assert zone == "fine"
        if zone != "fine":
            assert RAPID_ZONES[zone] <= t.blend
        assert instr == ("MoveJ" if t.move == "joint" else "MoveL")
    assert [m[0] for m in mod.moves][0] == "MoveJ"
    assert len(mod.welds) == 3 and all("weld_spot" in w for _, w in mod.welds)
    assert mod.weld_time == pytest.approx(0.5)


def test_krl_round_trip_fk_status_turn(build):
    robot, Tft, Q, b = build
    src, dat = render_krl(b.program)
    prog = parse_krl(src, dat)
    assert prog.load_mass == pytest.approx(2.002)
    for (instr, name, vel, cdis), t in zip(prog.moves, b.program.targets, strict=True):
        T, status, turn = prog.points[name]
        _check_fk(robot, Q[t.row], prog.base @ T, prog.tool)
        q = Q[t.row]
        assert turn == sum(1 << i for i in range(6) if q[i] < 0)
        br = int(robot.branch_of(q)[0])
        assert bool(status & 1) == bool(br & SHOULDER)
        assert bool(status & 2) == (not br & ELBOW)
        assert bool(status & 4) == bool(br & WRIST)
        if t.kind == "weld":
            assert cdis == 0.0
        assert cdis <= t.blend + 1e-9
        if instr == "LIN":
            assert vel * 1000.0 == pytest.approx(t.speed, abs=0.06)
    assert prog.moves[0][0] == "PTP" and {m[0] for m in prog.moves[1:]} == {"LIN"}


def test_targets_sit_on_the_route_and_timing_matches_the_program(build):
    robot, Tft, Q, b = build
    tt = b.timing
    assert tt.total == pytest.approx(tt.motion_time + 3 * 0.5)
    # exact stops of the timing are the program's fine points (welds included)
    for t in b.program.targets[1:-1]:
        fine = t.kind == "weld" or t.blend < RAPID_ZONES["z0"]
        assert bool(tt.stops[t.row]) == fine or t.row in (0, len(Q) - 1)
    assert b.tcp_deviation < 5.0  # the joint-space timing stays near the Cartesian lines
    assert b.constant_speed_time > 0


def test_a_joint_route_off_the_route_is_refused(build):
    from weldplan.robot.program import robot_program

    robot, Tft, Q, b = build
    from tests.route_fixtures import box_route

    Q2 = Q.copy()
    Q2[3, 0] += 0.01  # 0.57 deg of A1: about 20 mm at the TCP
    with pytest.raises(PlanningError, match="route row 3"):
        robot_program(
            box_route(directions=True),
            Q2,
            robot,
            ToolOnRobot(Tft, mass=1.0, cog=np.zeros(3)),
            part=box_part(),
        )


def test_a_user_weld_template_and_a_foreign_line():
    text = "MODULE m\n    bogus line\nENDMODULE\n"
    with pytest.raises(InputError) as e:
        parse_rapid(text, path="x.mod")
    assert e.value.line == 2


def test_user_weld_template(build):
    _, _, _, b = build
    text = render_rapid(b.program, weld_template="SpotL {target},vmax,gun1,{tool};")
    mod = parse_rapid(text)
    assert [w for _, w in mod.welds][0].startswith("SpotL p0001,vmax,gun1,tWeldplan")
    assert "PROC weld_spot" not in text


def test_joint_moves_stop_everywhere_and_a_replanned_via_is_a_joint_move(build):
    from tests.route_fixtures import box_route
    from weldplan.robot.program import robot_program

    robot, Tft, Q, _ = build
    # a joint-space via between route rows 2 and 3, as a re-planned leg would have it
    mid = 0.5 * (Q[2] + Q[3])
    Qv = np.vstack([Q[:3], mid, Q[3:]])
    row = np.array([0, 1, 2, 2, 3, 4, 5, 6, 7])
    exact = np.array([True, True, True, False, True, True, True, True, True])
    tool = ToolOnRobot(Tft, mass=2.0, cog=np.zeros(3))
    common = dict(part=box_part(), row=row, exact=exact)
    lin = robot_program(
        box_route(directions=True), Qv, robot, tool, settings=ProgramSettings(weld_time=0.5),
        **common,
    )  # fmt: skip
    via = [t for t in lin.program.targets if t.kind == "via" and not np.allclose(t.q, Q[t.row])]
    assert len(via) == 1 and via[0].move == "joint" and via[0].blend == 0.0
    mod = parse_rapid(render_rapid(lin.program))
    for (_, name, _, _), t in zip(mod.moves, lin.program.targets, strict=True):
        _check_fk(robot, t.q, mod.wobj @ mod.targets[name][0], mod.tool)
    jnt = robot_program(
        box_route(directions=True), Qv, robot, tool,
        settings=ProgramSettings(moves="joint", weld_time=0.5), **common,
    )  # fmt: skip
    assert {t.move for t in jnt.program.targets} == {"joint"}
    assert all(t.blend == 0.0 for t in jnt.program.targets)
    assert np.all(jnt.timing.stops) and jnt.timing.total > lin.timing.total


def test_trajectory_csv_replays_the_timing(build):
    import csv
    import io

    from weldplan.io.trajectory import trajectory_csv_text

    robot, _, Q, b = build
    rows = list(csv.reader(io.StringIO(trajectory_csv_text(b.timing))))
    assert rows[0] == ["t", "step", *robot.joint_names]
    data = np.array([[float(v) for v in r] for r in rows[1:]])
    assert np.all(np.diff(data[:, 0]) >= 0) and data[-1, 0] == pytest.approx(
        b.timing.total, abs=1e-4
    )
    for r, t in enumerate(b.timing.row_times):  # every waypoint is a row of the CSV
        k = int(np.argmin(np.abs(data[:, 0] - t) + np.abs(data[:, 2:] - Q[r]).sum(axis=1)))
        np.testing.assert_allclose(data[k, 2:], Q[r], atol=1e-7)
        assert data[k, 1] == r


def test_a_weld_the_robot_cannot_serve_is_passed_without_welding(build):
    from tests.route_fixtures import box_route
    from weldplan.robot.program import robot_program

    robot, Tft, Q, _ = build
    Qs = Q.copy()
    Qs[3] = 0.5 * (Q[2] + Q[4])  # weld C interpolated across, as the robot route does it
    exact = np.ones(len(Q), bool)
    exact[3] = False
    b = robot_program(
        box_route(directions=True), Qs, robot, ToolOnRobot(Tft, mass=2.0, cog=np.zeros(3)),
        exact=exact, part=box_part(), settings=ProgramSettings(weld_time=0.5),
    )  # fmt: skip
    assert b.skipped == ("C",)
    assert [t.joint_id for t in b.program.targets if t.kind == "weld"] == ["A", "B"]
    # no target stands for C: the robot moves from row 2 straight on to row 4 (the same joint
    # path), C named in the header only
    assert 3 not in {t.row for t in b.program.targets}
    assert b.row.tolist() == [0, 1, 2, 4, 5, 6, 7]
    assert b.timing.total == pytest.approx(b.timing.motion_time + 2 * 0.5)
    text = render_rapid(b.program)
    assert "Not welded (the robot cannot serve them; no target moves to them): C." in text
    assert "route row 3" not in text
    mod = parse_rapid(text)
    assert len(mod.welds) == 2 and len(mod.moves) == len(b.program.targets) == 7 + 2
    for (_, name, _, _), t in zip(mod.moves, b.program.targets, strict=True):
        _check_fk(robot, t.q, mod.wobj @ mod.targets[name][0], mod.tool)


def test_welds_after_the_last_served_one_are_named_not_moved_to(build):
    """A robot route that ends at its last served weld (no way off it) holds that configuration
    for the route's later rows; the program stops there and names the welds it leaves out, in
    both posts, with no move to them."""
    from tests.route_fixtures import box_route
    from weldplan.io.export import route_rows
    from weldplan.io.trajectory import trajectory_csv_text
    from weldplan.robot.program import robot_program

    robot, Tft, Q, _ = build
    route = box_route(directions=True)
    rows = route_rows(route)
    assert [r["joint_id"] for r in rows if r["kind"] == "weld"] == ["A", "C", "B"]
    last = 3  # C, the last served weld: B (row 7) and the vias before it are held at C
    Qh = Q.copy()
    Qh[last + 1 :] = Q[last]
    exact = np.arange(len(Q)) <= last
    b = robot_program(
        route, Qh, robot, ToolOnRobot(Tft, mass=2.0, cog=np.zeros(3)), exact=exact,
        part=box_part(), settings=ProgramSettings(weld_time=0.5),
    )  # fmt: skip
    assert b.skipped == ("B",) and b.row.tolist() == list(range(last + 1))
    assert max(t.row for t in b.program.targets) == last
    assert len({tuple(np.round(t.q, 9)) for t in b.program.targets[1:]}) == last + 1
    src, dat = render_krl(b.program)
    prog = parse_krl(src, dat)
    assert len(prog.welds) == 2 and len(prog.moves) == last + 1 + 2
    assert "no target moves to them): B." in src and "no target moves to them): B." in dat
    assert "weld B" not in dat and "route row 7" not in dat
    mod = parse_rapid(render_rapid(b.program))
    assert len(mod.moves) == last + 1 + 2
    steps = {int(r.split(",")[1]) for r in trajectory_csv_text(b.timing, b.row).splitlines()[1:]}
    assert steps == set(range(last + 1))


def test_joint_line_deviation_is_the_sagitta_of_an_axis_1_turn(build):
    from weldplan.robot.program import joint_line_deviation

    robot, Tft, Q, _ = build
    qa = Q[0].copy()
    qb = qa.copy()
    qb[0] += np.radians(20.0)
    p = (robot.fk(qa)[0] @ Tft)[:3, 3]
    axis_xy = robot.base[:2, 3]  # A1 turns about the base's vertical axis
    r = float(np.linalg.norm(p[:2] - axis_xy))
    got = joint_line_deviation(robot, Tft, qa[None], qb[None])[0]
    assert got == pytest.approx(r * (1 - np.cos(np.radians(10.0))), rel=1e-9)
    assert joint_line_deviation(robot, Tft, qa[None], qa[None])[0] == 0.0


@pytest.mark.parametrize("abc", [(30.0, 90.0, 0.0), (-120.0, -90.0, 45.0), (10.0, 89.99999999, 5.0),
                                 (170.0, 20.0, -35.0), (0.0, 0.0, 180.0)])  # fmt: skip
def test_krl_abc_angles_rebuild_the_rotation_without_a_gimbal_lock_warning(abc):
    import warnings

    from scipy.spatial.transform import Rotation

    from weldplan.io.posts.krl import abc_deg

    R = Rotation.from_euler("ZYX", abc, degrees=True).as_matrix()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # scipy's "Gimbal lock detected" would fail here
        got = abc_deg(R)
    a, b, c = np.radians(got)
    Rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    Ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    Rx = np.array([[1, 0, 0], [0, np.cos(c), -np.sin(c)], [0, np.sin(c), np.cos(c)]])
    assert np.abs(Rz @ Ry @ Rx - R).max() < 1e-9
    assert -90.0 <= got[1] <= 90.0
    if abs(abc[1]) < 89.0:  # away from the lock the angles are the ones given
        np.testing.assert_allclose(got, abc, atol=1e-9)
