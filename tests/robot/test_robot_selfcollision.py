"""The robot against itself and the floor (weldplan.robot.collision.selfcollision), with the shared
KUKA KR 150 and the shared spot gun: the allowed collision matrix, the gun folded into the arm,
links below the floor, and the planner's checks on ordinary configurations."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from tests.conftest import require_shared
from tests.robot_helpers import make_plate
from weldplan.robot import load_robot
from weldplan.robot.collision import RobotCollision, cell_floor, hit_words
from weldplan.robot.placement import BaseSearch

#: an ordinary configuration: arm up, forearm forward, gun down in front
HOME = np.radians([0.0, -90.0, 90.0, 0.0, 30.0, 0.0])
#: the gun folded back into the upper arm (link_2): elbow folded, wrist bent 100 deg
FOLDED = np.radians([0.0, -60.0, 155.0, 30.0, 100.0, -90.0])
#: the arm reaching down in front of a base standing on the floor: link_4 below it
DOWN = np.radians([0.0, -30.0, 120.0, 0.0, 90.0, 0.0])
#: a part far from the robot: every hit below is the robot's own or the floor's
FAR_PART = make_plate([9000.0, 9000.0, 0.0], 2, size=100.0)


@pytest.fixture(scope="module")
def robot():
    d = require_shared("robots", "kuka_kr150r3100_2")
    return load_robot(d / "kr150r3100_2.urdf")


@pytest.fixture(scope="module")
def gun_checker(robot):
    """The gun on the KUKA (base at the origin on the floor z = 0), the part far away."""
    from weldplan.robot.route import tool_flange_tcp
    from weldplan.tool import shared_spot_gun
    from weldplan.tool.model import SHARED_GUN_DIR

    require_shared("tools", "spot_welding_gun")
    F = tool_flange_tcp(robot, SHARED_GUN_DIR / "spot_welding_gun.urdf", "nozzle_tip")
    return RobotCollision(robot, FAR_PART, shared_spot_gun(), F, floor_z=0.0)


def test_allowed_collision_matrix_excludes_adjacent_links_only(gun_checker):
    acm = gun_checker.selfcheck.acm
    chain = ["base_link", "link_1", "link_2", "link_3", "link_4", "link_5", "link_6"]
    for a, b in zip(chain[:-1], chain[1:], strict=True):
        assert acm.allowed(a, b) == "adjacent"
    # the gun rides on link_6 through the fixed mount: mounted on link_6, adjacent to link_5
    assert acm.allowed("tool", "link_6") == "tool-flange"
    assert acm.allowed("tool", "link_5") == "adjacent"
    # on this robot no other pair touches at the zero pose or at every sample: all checked
    assert len(acm.reasons) == 8 and len(acm.checked) == 28 - 8
    for b in ("base_link", "link_1", "link_2", "link_3", "link_4"):
        assert acm.allowed("tool", b) is None
    assert acm.allowed("link_2", "base_link") is None and acm.allowed("link_6", "link_4") is None
    # the body on the later link comes first in a checked pair
    frames = [body.frame for body in gun_checker.selfcheck.bodies]
    assert all(frames[i] >= frames[j] for i, j in acm.checked)


def test_zero_pose_contact_is_allowed(robot):
    """A tool that reaches back through the wrist into link_4 at the zero pose: that pair is
    allowed ("zero pose"), as MoveIt's setup assistant's default-collision rule; link_3 is not."""
    from weldplan.tool.model import Tool

    box = trimesh.creation.box((60.0, 60.0, 500.0))  # TCP frame: along the flange axis
    box.apply_translation([0.0, 0.0, -250.0 + 100.0])  # from 100 mm out to 400 mm back
    tool = Tool("stub", box.vertices, box.faces)
    F = np.eye(4)
    F[2, 3] = 100.0
    acm = RobotCollision(robot, FAR_PART, tool, F).selfcheck.acm
    assert acm.allowed("tool", "link_4") == "zero pose"
    assert acm.allowed("tool", "link_3") is None


def test_gun_folded_into_the_upper_arm_is_refused(gun_checker):
    chk = gun_checker
    assert chk.state_free(HOME)
    assert not chk.state_free(FOLDED)
    assert chk.states_blocked(np.stack([HOME, FOLDED])) == [None, "tool/link_2"]
    # the links alone are free there: it is the gun
    assert chk.states_blocked(FOLDED[None], tool=False) == [None]
    # the motion into it is refused, and so is a motion whose ends are free but which turns A4
    # through the fold
    hits = chk.path_hits(np.stack([HOME, FOLDED]))
    assert len(hits) == 1 and hits[0].body.startswith("tool/") and 0.0 < hits[0].t <= 1.0
    qa, qb = FOLDED.copy(), FOLDED.copy()
    qa[3], qb[3] = np.radians(60.0), np.radians(-90.0)
    assert chk.state_free(qa) and chk.state_free(qb)
    hits = chk.path_hits(np.stack([qa, qb]))
    assert len(hits) == 1 and hits[0].body == "tool/link_2" and 0.0 < hits[0].t < 0.5
    assert not chk.motion_free(qa, qb) and not chk.motion_free(qa, qb, zone=True)
    assert hit_words("tool/link_2") == "tool/link_2 collide (self-collision)"


def test_a_link_below_the_floor_is_refused(robot, gun_checker):
    chk = gun_checker
    assert chk.states_blocked(DOWN[None], tool=False) == ["link_4/floor"]
    hits = chk.path_hits(np.stack([HOME, DOWN]))
    assert len(hits) == 1 and hits[0].body.endswith("/floor") and 0.0 < hits[0].t <= 1.0
    # the same robot on a pedestal 1.5 m high: the floor is far below, nothing touches
    high = chk.with_robot(robot.with_base(_lifted(1500.0)))
    assert high.state_free(DOWN) and high.path_hits(np.stack([HOME, DOWN])) == []
    # no floor known: not checked
    from weldplan.tool import shared_spot_gun

    free = RobotCollision(robot, FAR_PART, shared_spot_gun(), chk.flange_tcp)
    assert free.state_free(DOWN) and free.path_hits(np.stack([HOME, DOWN])) == []


def test_a_long_motion_through_the_floor_is_blocked_and_a_turn_of_a1_costs_no_floor_call(
    robot, gun_checker
):
    """A wide motion whose gun dips 130 mm below the floor half-way (both ends clear) is
    blocked: before, its bound on the gun's motion (27 m, A1 turning 265 deg) raised the floor
    box past its own side, and the check found nothing below it. A turn of A1 alone (an upright
    base) moves no point up or down: proven clear of the floor at once."""
    from weldplan.robot.collision import selfcollision as sc

    chk = gun_checker
    qa = np.radians([-170.0, -41.2, 56.9, -330.1, 54.8, -338.8])
    qb = np.radians([95.4, -70.8, 147.6, -303.7, 85.3, -303.3])
    assert chk.state_free(qa) and chk.state_free(qb)
    hits = chk.path_hits(np.stack([qa, qb]))
    assert [h.body for h in hits] == ["tool/floor"] and 0.3 < hits[0].t < 0.9
    Q = qa + np.linspace(0.0, 1.0, 50)[:, None] * (qb - qa)
    assert "tool/floor" in chk.states_blocked(Q)  # the judge agrees: below the floor
    calls = []
    orig = sc.SelfCheck._height

    def counted(self, b, F):
        calls.append(b)
        return orig(self, b, F)

    sc.SelfCheck._height = counted
    try:
        turned = HOME.copy()
        turned[0] += np.radians(180.0)
        assert chk.path_hits(np.stack([HOME, turned])) == []
    finally:
        sc.SelfCheck._height = orig
    assert len(calls) <= 7  # one height a body at most: no bisection


def test_ordinary_motions_pass_and_free_verdicts_hold_under_dense_sampling(gun_checker):
    """Random motions about the ordinary pose, and A4 sweeps through the fold with random
    offsets: what path_hits calls free, 200 state checks along the motion find free; both
    verdicts occur."""
    chk = gun_checker
    rng = np.random.default_rng(3)
    sweep_a, sweep_b = FOLDED.copy(), FOLDED.copy()
    sweep_a[3], sweep_b[3] = np.radians(60.0), np.radians(-90.0)
    motions = [(HOME + rng.normal(0, 0.35, 6), HOME + rng.normal(0, 0.35, 6)) for _ in range(6)]
    motions += [(sweep_a + rng.normal(0, 0.1, 6), sweep_b + rng.normal(0, 0.1, 6)) for _ in "abcd"]
    n_free = n_blocked = 0
    for qa, qb in motions:
        if not (chk.state_free(qa) and chk.state_free(qb)):
            continue
        if chk.path_hits(np.stack([qa, qb])):
            n_blocked += 1
            continue
        n_free += 1
        Q = qa + np.linspace(0.0, 1.0, 200)[:, None] * (qb - qa)
        assert chk.states_blocked(Q) == [None] * len(Q)
    assert n_free >= 3 and n_blocked >= 1


def test_a_floor_is_known_only_when_given():
    assert cell_floor(BaseSearch(floor_z=-10.0), None) == -10.0
    # the search's default (the part's lowest point) is where it stands the base, not a floor
    assert cell_floor(BaseSearch(), None) is None
    assert cell_floor(BaseSearch(floor_z=-10.0), np.eye(4)) is None  # a given base
    assert cell_floor(None, None) is None
    assert cell_floor(BaseSearch(floor_z=0.0, line=((0, 0, 0), (1, 0, 0))), None) is None


def _lifted(z: float) -> np.ndarray:
    B = np.eye(4)
    B[2, 3] = z
    return B


def test_plan_robot_route_keeps_the_links_above_a_given_floor(robot):
    """The box scene (base 0.7 m below the box): a floor 100 mm below the box's floor plate
    cuts through link_1, so no weld is served, and the details name the pair; a floor 100 mm
    below the base (a pedestal) changes nothing, and the route records the floor it was checked
    against for verify --robot."""
    from tests.robot_helpers import BOX_BASE, TORCH_TCP, down_poses
    from tests.route_fixtures import box_part, box_route
    from weldplan.robot.program import RobotCheck
    from weldplan.robot.route import plan_robot_route
    from weldplan.robot.settings import JointRouteSettings, RobotCell, ToolOnRobot
    from weldplan.tool import arc_torch

    route = box_route()
    kw = dict(tool=ToolOnRobot(TORCH_TCP, arc_torch()), settings=JointRouteSettings(replan=False))

    def on(floor_z):
        return RobotCell(box_part(), base=BOX_BASE, floor_z=floor_z)

    rr = plan_robot_route(route, down_poses(route), robot, cell=on(-100.0), **kw)
    assert rr.status == ("collision",) * 3 and not rr.stats["collision_free"]
    assert all(d.startswith("link_1/floor collide (the floor) at the weld pose") for d in rr.detail)
    assert "link_1/floor" in {h["body"] for h in rr.stats["hits"]}
    rr = plan_robot_route(route, down_poses(route), robot, cell=on(-800.0), **kw)
    bare = plan_robot_route(route, down_poses(route), robot, cell=on(None), **kw)
    assert rr.stats["floor_z"] == -800.0 and bare.stats["floor_z"] is None
    assert rr.status == bare.status and rr.stats["hits"] == bare.stats["hits"]  # the wall graze
    assert (
        "above the floor at z -800 mm" in RobotCheck(True, 0.0, 0.0, (), (), 3, -800.0).describe()
    )
    assert "no floor known" in RobotCheck(True, 0.0, 0.0, (), (), 3).describe()
