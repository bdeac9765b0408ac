"""The one collision vocabulary (weldplan.geometry.checker): the checkers satisfy the protocol,
the conservative advancement meets an analytic first contact, and the checkers' last valid
parameter agrees with a fine sampling of python-fcl's distance on the demo part."""

from __future__ import annotations

import math
from pathlib import Path

import fcl
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from weldplan.geometry.checker import (
    Advance,
    CheckVerdict,
    PointChecker,
    StateChecker,
    advance,
)
from weldplan.geometry.collision import CollisionModel
from weldplan.io.joints import read_joints
from weldplan.io.mesh import load_part
from weldplan.tool.model import arc_torch, bvh
from weldplan.tool.transitions import SweepChecker, ToolStateChecker, interpolate

DEMO = Path(__file__).resolve().parents[1] / "assets" / "demo"

#: the analytic case: a cube of half side H about the origin, a sphere of radius R
H, R = 50.0, 10.0


@pytest.fixture(scope="module")
def demo_part():
    return load_part(DEMO / "part.stl")


@pytest.fixture(scope="module")
def demo_weld():
    """``(spot (3,) mm, approach normal (3,))`` of the demo's weld 3."""
    j = read_joints(DEMO / "joints.csv")
    k = list(j.ids).index("3")
    n = np.asarray(j.directions[k], dtype=np.float64)
    return np.asarray(j.xyz[k], dtype=np.float64), n / np.linalg.norm(n)


def _cube_distance(a: np.ndarray, b: np.ndarray):
    """``distance(t)``: python-fcl's distance of the sphere at ``a + t (b - a)`` to the cube."""
    cube = fcl.CollisionObject(fcl.Box(2 * H, 2 * H, 2 * H), fcl.Transform())
    ball = fcl.CollisionObject(fcl.Sphere(R), fcl.Transform())

    def distance(t: float) -> float:
        ball.setTransform(fcl.Transform(a + t * (b - a)))
        return float(fcl.distance(ball, cube, fcl.DistanceRequest(), fcl.DistanceResult()))

    return distance


def test_advancement_stops_at_the_analytic_first_contact():
    # the centre crosses x = -(H + R) at t* = 140 / 400 = 0.35, at y = 41, z = 0: on the face
    a, b = np.array([-200.0, 20.0, 0.0]), np.array([200.0, 80.0, 0.0])
    gap = 1e-6
    run = advance(_cube_distance(a, b), float(np.linalg.norm(b - a)), gap=gap, max_steps=200)
    assert isinstance(run, Advance) and not run.free
    assert run.t <= 0.35 and 0.35 - run.t < 1e-6
    assert run.distance <= gap


def test_advancement_past_the_cube_is_free_and_keeps_an_analytic_gap():
    # the centre passes at y = H + R + 5 beside the face: 5 mm from the cube all along x in [-H, H]
    a, b = np.array([-200.0, H + R + 5.0, 0.0]), np.array([200.0, H + R + 5.0, 0.0])
    L = float(np.linalg.norm(b - a))
    run = advance(_cube_distance(a, b), L, gap=4.0, max_steps=1000)
    assert run.free and run.t == 1.0
    # asked for 6 mm it is blocked before the sphere comes within 6 mm of the cube's edge at
    # x = -H, y = H (the distance sqrt((x + H)^2 + 15^2) - R is 6 mm at x + H = -sqrt(16^2 - 15^2))
    first = (-H - math.sqrt(16.0**2 - 15.0**2) + 200.0) / 400.0
    run = advance(_cube_distance(a, b), L, gap=6.0, max_steps=1000)
    assert not run.free and run.t <= first and first - run.t < 1e-6
    # backwards, from the end: the mirror image
    back = advance(_cube_distance(a, b), L, gap=6.0, start=1.0, stop=0.0, max_steps=1000)
    assert not back.free and back.t >= 1.0 - first and back.t - (1.0 - first) < 1e-6


def test_advancement_rules_are_parameters():
    d = _cube_distance(np.array([-200.0, 0.0, 0.0]), np.array([-100.0, 0.0, 0.0]))
    # 40..140 mm of distance over a 100 mm motion: the rest is covered from the first sample
    covered = advance(d, 100.0, until_covered=True)
    assert covered.free and covered.steps == 1 and covered.t == 0.0
    assert covered.left == pytest.approx(140.0 - 100.0)
    measured = advance(d, 100.0)
    assert measured.free and measured.t == 1.0 and measured.left == pytest.approx(40.0)
    # a blocking rule of the caller's, and a probe that finds a contact ahead
    assert not advance(d, 100.0, blocked=lambda t, s: s < 100.0).free
    probed = advance(d, 100.0, probe=lambda step, t: True)
    assert not probed.free and probed.steps == 1
    capped = advance(d, 100.0, max_steps=1)
    assert not capped.free and capped.t > 0.0  # the next step's place, not measured


def _pose(spot, n, along):
    """The TCP ``along`` mm out of the part on the weld's normal, its +z into the part."""
    rot = Rotation.align_vectors([-n], [[0.0, 0.0, 1.0]])[0]
    return spot + along * n, np.roll(rot.as_quat(), 1)


def _fcl_slack(part, tool, clearance):
    """The whole tool's python-fcl distance to the whole part, less the clearance, from models
    built here (none of the checker's)."""
    p_obj = fcl.CollisionObject(bvh(part.vertices, part.faces), fcl.Transform())
    t_obj = fcl.CollisionObject(bvh(tool.vertices, tool.faces), fcl.Transform())

    def slack(pos, rot) -> float:
        t_obj.setTransform(fcl.Transform(rot, pos))
        d = fcl.distance(t_obj, p_obj, fcl.DistanceRequest(), fcl.DistanceResult())
        return float(d) - clearance

    return slack


def test_tool_check_motion_agrees_with_sampled_fcl_distances(demo_part, demo_weld):
    tool = arc_torch()
    chk = SweepChecker(demo_part, tool, clearance=5.0, contact_radius=0.0)
    sc = ToolStateChecker(chk)
    spot, n = demo_weld
    a, b = _pose(spot, n, 150.0), _pose(spot, n, -20.0)  # into the sheet
    t = sc.check_motion(a, b)
    assert 0.0 < t < 1.0
    s = np.linspace(0.0, 1.0, 1701)
    P, Rs = interpolate(a[0], a[1], b[0], b[1], s)
    slack = _fcl_slack(demo_part, tool, 5.0)
    v = np.array([slack(p, r) for p, r in zip(P, Rs, strict=True)])
    assert np.all(v[s <= t] >= -1e-6)  # free where it says so
    first_bad = s[np.argmax(v < 0)]
    assert v.min() < 0 and t <= first_bad
    # it stopped where the slack fell below the checker's least step, not earlier
    pos, rot = interpolate(a[0], a[1], b[0], b[1], [t])
    assert slack(pos[0], rot[0]) < chk.min_step + 1e-6
    # a motion that stays clear is free, and its states are valid with their clearance
    c, d = _pose(spot, n, 150.0), _pose(spot, n, 120.0)
    assert sc.check_motion(c, d) == 1.0
    assert sc.is_valid(c) and not sc.is_valid(b)
    rot_c = Rotation.from_quat(np.roll(c[1], -1)).as_matrix()
    assert sc.clearance(c) == pytest.approx(slack(c[0], rot_c) + 5.0)


def test_point_check_motion_agrees_with_sampled_fcl_distances(demo_part, demo_weld):
    model = CollisionModel(demo_part)
    pc = PointChecker(model, 5.0)
    spot, n = demo_weld
    a, b = spot + 60.0 * n, spot - 30.0 * n
    t = pc.check_motion(a, b)
    s = np.linspace(0.0, 1.0, 2001)
    d = model.clearance(a + s[:, None] * (b - a), method="fcl")
    assert 0.0 < t < 1.0
    assert np.all(d[s < t] > 5.0 - 1e-6)
    assert t <= s[np.argmax(d <= 5.0)]
    assert pc.check_motion(a, spot + 40.0 * n) == 1.0
    assert pc.is_valid(a) and not pc.is_valid(spot)


def test_point_check_motion_agrees_with_fcl_capsules(demo_part, demo_weld):
    # random segments about a weld: a motion shown wholly free is a free capsule (python-fcl),
    # a capsule that touches is never shown wholly free
    model = CollisionModel(demo_part)
    pc = PointChecker(model, 5.0)
    spot, _ = demo_weld
    rng = np.random.default_rng(3)
    A = spot + rng.uniform(-60.0, 60.0, (40, 3))
    B = spot + rng.uniform(-60.0, 60.0, (40, 3))
    free = model.segments_free(A, B, 5.0, method="fcl")
    t = np.array([pc.check_motion(a, b) for a, b in zip(A, B, strict=True)])
    assert free.any() and not free.all()
    assert np.all(t[~free] < 1.0)
    # CA may stop short on a grazing segment (none of these), never pass a touching one
    assert np.all(t[free] == 1.0)


def test_both_checkers_satisfy_the_protocol(demo_part):
    chk = SweepChecker(demo_part, arc_torch(), clearance=5.0, contact_radius=0.0)
    assert isinstance(ToolStateChecker(chk), StateChecker)
    assert isinstance(PointChecker(CollisionModel(demo_part), 5.0), StateChecker)
    assert not isinstance(chk, StateChecker)  # the planner's own API: the adapter is the one


def test_robot_checker_satisfies_the_protocol_and_agrees_with_sampled_states():
    from tests.robot_fixtures import box_joint_route, gun_tcp, shared_robot
    from tests.route_fixtures import box_part
    from weldplan.robot.collision import MIN_GAP_MM, RobotCollision

    robot = shared_robot()
    Tft, _ = gun_tcp(robot)
    _, Q = box_joint_route(robot, Tft)
    part = box_part()
    rc = RobotCollision(robot, part)
    assert isinstance(rc, StateChecker)
    qa = Q[0]
    qb = Q[0].copy()
    qb[1] += 0.6  # the shoulder forward: the arm swings down through the box
    t = rc.check_motion(qa, qb)
    ts = np.linspace(0.0, 1.0, 241)
    valid = np.array([rc.is_valid(qa + x * (qb - qa)) for x in ts])
    assert valid[0] and not valid.all()
    assert 0.0 < t < 1.0 and np.all(valid[ts < t])  # free before t
    # blocked at t: a body within the gap there, or (the probe ahead) a contact after it
    near = rc.clearance(qa + t * (qb - qa)) <= MIN_GAP_MM + 1e-6
    assert near or not valid[ts > t].all()
    assert rc.check_motion(qa, qa) == 1.0 and rc.clearance(qa) > MIN_GAP_MM


def test_every_report_exposes_one_verdict():
    from weldplan.robot.program import RobotCheck
    from weldplan.station.recheck import CheckResult, Verdict
    from weldplan.tool.verify import (
        PoseCheck,
        PosesVerification,
        RoutePosesCheck,
        SweepsVerification,
    )
    from weldplan.weld.verify import VerifyReport, Violation

    bad_seg = Violation("segment", "collides", leg=2, segment=4, from_id="3", to_id="7")
    reports = {
        "route": VerifyReport(False, (bad_seg,), 5.0, 30, 4, 15),
        "tool pose": PoseCheck(True, distance=6.5),
        "tool poses": PosesVerification(False, 4, (("7", "too near"),), 5.2),
        "tool transitions": SweepsVerification(True, 3, 40, ("1->2",), (), 5.5),
        "robot route": RobotCheck(False, 0.0, 0.0, (3,), ((5, "link_2/floor", 0.0),), 9),
    }
    v = {k: r.verdict for k, r in reports.items()}
    assert all(isinstance(x, CheckVerdict) for x in v.values())
    assert [x.ok for x in v.values()] == [r.ok for r in reports.values()]
    assert v["route"].failures[0].place == "leg 2 (3 -> 7), segment 4"
    assert v["route"].failures[0].cause == "collides" and v["route"].checked == 30
    assert v["tool pose"].min_clearance == 6.5 and v["tool pose"].checked == 1
    assert str(v["tool poses"].failures[0]) == "weld 7: too near"
    assert v["tool transitions"].left_out == ("1->2",) and v["tool transitions"].ok
    assert [f.place for f in v["robot route"].failures] == ["row 3", "motion 5"]
    assert "floor" in v["robot route"].failures[1].cause
    from weldplan.tool.transitions.sweep import SweepCheck

    blocked = SweepCheck(False, 12, -0.5, 0.25, 80.0, False, 0.5).verdict
    assert blocked.failures[0].place == "25 %" and "blocked at 25 %" in blocked.failures[0].cause
    assert SweepCheck(True, 9, 3.0).verdict.ok
    rp = RoutePosesCheck(True, 4, 3, ("D",), (), 5.1)
    assert rp.verdict.left_out == ("D",) and rp.verdict.checked == 3
    # the station's verdict collects them, a check without a report (the part pose) included
    results = (
        CheckResult("part pose", True, "as planned"),
        CheckResult("tool poses", rp.ok, rp.describe(), rp.missing, rp),
    )
    got = Verdict(results).verdicts
    assert [x.what for x in got] == ["part pose", "tool poses"]
    assert got[1] is not None and got[1].min_clearance == 5.1
    assert "1 failure(s) of 4: weld 7: too near" in v["tool poses"].describe()
