"""The collision world (weldplan.geometry.world): named bodies and the allowed pairs kept as data,
on its own and as the registry of the robot's checks (the shared KUKA KR 150 with the shared spot
gun): every body listed, the chain's pairs allowed as the URDF joins them, the other pairs
checked, and a folded arm reported by the self check with the two bodies' names."""

from __future__ import annotations

import fcl
import numpy as np
import pytest
import trimesh

from tests.conftest import require_shared
from tests.robot_helpers import make_plate
from weldplan.geometry.world import CollisionWorld, Exemption, WorldBody

#: the gun folded back into the upper arm (link_2): elbow folded, wrist bent 100 deg
FOLDED = np.radians([0.0, -60.0, 155.0, 30.0, 100.0, -90.0])
#: an ordinary configuration: arm up, forearm forward, gun down in front
HOME = np.radians([0.0, -90.0, 90.0, 0.0, 30.0, 0.0])
#: a part far from the robot: nothing the robot does reaches it
FAR_PART = make_plate([9000.0, 9000.0, 0.0], 2, size=100.0)


def _box(name: str, kind: str, frame: int | None = None) -> WorldBody:
    m = trimesh.creation.box((10.0, 10.0, 10.0))
    obj = fcl.CollisionObject(fcl.Box(10.0, 10.0, 10.0), fcl.Transform())
    return WorldBody(name, kind, obj, frame, "" if frame is None else f"l{frame}", "box", m)


def _at(x: float) -> np.ndarray:
    T = np.eye(4)
    T[0, 3] = x
    return T


# ---------------------------------------------------------------------------- the world alone
def test_pairs_to_check_are_the_pairs_not_allowed_with_the_later_frame_first():
    bodies = [_box("a", "link", 0), _box("b", "link", 1), _box("t", "tool", 1), _box("p", "part")]
    world = CollisionWorld.of(
        bodies, {("a", "b"): Exemption("adjacent", "joint j1"), ("t", "b"): "tool-flange"}
    )
    assert world.allowed("b", "a") == "adjacent" and world.allowed("b", "t") == "tool-flange"
    assert world.allowed("a", "t") is None and world.zone("a", "t") is None
    # every pair of 4 bodies but the 2 allowed, in body order, the later frame first; the part is
    # fixed (before every frame)
    assert world.pairs_to_check() == (("t", "a"), ("a", "p"), ("b", "p"), ("t", "p"))
    assert world.pairs_to_check(["link", "tool"]) == (("t", "a"),)
    text = world.describe()
    assert "b/a: adjacent (joint j1)" in text and "t/b: tool-flange" in text
    assert "pairs checked: 4 of 6" in text


def test_contacts_name_the_touching_pairs_and_skip_the_allowed_ones():
    bodies = [_box("a", "link", 0), _box("b", "link", 1), _box("c", "link", 2)]
    world = CollisionWorld.of(bodies, {("a", "b"): "adjacent"})
    # a and b overlap (allowed: not reported), c overlaps b only
    assert world.contacts({"a": _at(0.0), "b": _at(5.0), "c": _at(12.0)}) == (("c", "b"),)
    assert world.contacts({"c": _at(40.0)}) == ()


@pytest.mark.parametrize(
    "bodies, allowed, words",
    [
        ([("a", "link"), ("a", "tool")], {}, "two bodies"),
        ([("a", "robot")], {}, "kind"),
        ([("a", "link"), ("b", "link")], {("a", "x"): "adjacent"}, "not two bodies"),
        ([("a", "link"), ("b", "link")], {("a", "a"): "adjacent"}, "not two bodies"),
        ([("a", "link"), ("b", "link")], {("a", "b"): "close"}, "reason"),
    ],
)
def test_a_malformed_world_is_refused(bodies, allowed, words):
    with pytest.raises(ValueError, match=words):
        CollisionWorld.of([_box(n, k, 0) for n, k in bodies], allowed)
    with pytest.raises(ValueError, match=words):  # made directly: the same checks
        CollisionWorld(tuple(_box(n, k, 0) for n, k in bodies), allowed)
    world = CollisionWorld.of([_box("a", "link", 0)])
    with pytest.raises(ValueError, match="no body 'z'"):
        world.allowed("a", "z")


# ---------------------------------------------------------------------------- the robot's world
@pytest.fixture(scope="module")
def urdf():
    return require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")


@pytest.fixture(scope="module")
def gun_checker(urdf):
    """The gun on the KUKA (base at the origin on the floor z = 0), the part far away."""
    from weldplan.robot import load_robot
    from weldplan.robot.collision import RobotCollision
    from weldplan.robot.route import tool_flange_tcp
    from weldplan.tool import shared_spot_gun
    from weldplan.tool.model import SHARED_GUN_DIR

    require_shared("tools", "spot_welding_gun")
    robot = load_robot(urdf)
    F = tool_flange_tcp(robot, SHARED_GUN_DIR / "spot_welding_gun.urdf", "nozzle_tip")
    return RobotCollision(robot, FAR_PART, shared_spot_gun(), F, floor_z=0.0)


def _urdf_links_and_joints(urdf):
    """The URDF's links that carry a collision mesh, and its revolute joints as (name, parent,
    child), read with ElementTree here (not weldplan's reader)."""
    import xml.etree.ElementTree as ET

    root = ET.parse(urdf).getroot()
    links = [lk.get("name") for lk in root.iter("link") if lk.find("collision") is not None]
    joints = [
        (j.get("name"), j.find("parent").get("link"), j.find("child").get("link"))
        for j in root.iter("joint")
        if j.get("type") == "revolute"
    ]
    return links, joints


def test_the_world_lists_every_link_the_tool_the_part_and_the_floor(gun_checker, urdf):
    world = gun_checker.world
    links, joints = _urdf_links_and_joints(urdf)
    assert len(links) == 7 and len(joints) == 6
    assert [b.name for b in world.of_kind("link")] == links
    assert [b.name for b in world.bodies if b.kind != "link"] == ["tool", "part", "floor"]
    assert world.body("tool").link == "link_6" and world.body("part").frame is None
    # the self check reads its bodies from the world: the same objects
    assert [b.data for b in world.of_kind("link", "tool")] == gun_checker.selfcheck.bodies
    text = world.describe()
    for name in links + ["tool", "part", "floor"]:
        assert f"\n  {name} " in text


def test_links_a_urdf_joint_joins_are_allowed_as_adjacent_and_no_other_link_pair(gun_checker, urdf):
    world = gun_checker.world
    links, joints = _urdf_links_and_joints(urdf)
    joined = {frozenset((p, c)): name for name, p, c in joints}
    for i, a in enumerate(links):
        for b in links[i + 1 :]:
            key = frozenset((a, b))
            if key in joined:
                assert world.allowed(a, b) == "adjacent"
                assert joined[key] in world.allowed_pairs[key].note  # the joint named
            else:
                assert world.allowed(a, b) is None, (a, b)
    # the tool is mounted on the flange link (the last joint's child) and adjacent to its parent
    _, parent, flange = joints[-1]
    assert world.allowed("tool", flange) == "tool-flange"
    assert world.allowed("tool", parent) == "adjacent"
    assert world.allowed(links[0], "floor") == "on the floor"
    assert world.allowed(links[1], "floor") is None
    # the tool touches the part at a weld: checked, with its contact zone exempt
    assert world.allowed("tool", "part") is None and world.zone("tool", "part") == "contact zone"
    robot_pairs = world.pairs_to_check(["link", "tool"])
    assert len(robot_pairs) == 28 - 6 - 2 and ("tool", "link_2") in robot_pairs


def test_a_folded_arm_is_reported_with_the_two_bodies_of_the_world(gun_checker):
    chk = gun_checker
    world = chk.world
    assert chk.states_blocked(np.stack([HOME, FOLDED])) == [None, "tool/link_2"]
    a, b = chk.states_blocked(FOLDED[None])[0].split("/")
    assert world.body(a).kind == "tool" and world.body(b).kind == "link"
    assert world.allowed(a, b) is None
    # the world's own query (FCL collide on every checked pair, no broad phase) agrees
    F = chk.robot.link_frames(FOLDED)[0]
    poses = {x.name: F[x.frame] for x in world.of_kind("link", "tool")}
    assert ("tool", "link_2") in world.contacts(poses, ["link", "tool"])
    poses = {x.name: chk.robot.link_frames(HOME)[0][x.frame] for x in world.of_kind("link", "tool")}
    assert world.contacts(poses, ["link", "tool"]) == ()


def _robot_copy(tmp_path, urdf, srdf: str):
    """A copy of the shared KUKA's URDF (its meshes and OPW file linked) with ``srdf`` beside it."""
    from weldplan.robot import load_robot

    d = tmp_path / "kuka"
    d.mkdir(parents=True)
    for f in ("collision", "opw_parameters.yaml"):
        (d / f).symlink_to(urdf.parent / f)
    (d / urdf.name).write_text(urdf.read_text(encoding="utf-8"), encoding="utf-8")
    (d / urdf.with_suffix(".srdf").name).write_text(srdf, encoding="utf-8")
    return load_robot(d / urdf.name)


def test_pairs_an_srdf_disables_are_allowed_and_a_wrong_link_is_refused(tmp_path, urdf):
    from weldplan.errors import InputError
    from weldplan.robot.collision import RobotCollision

    srdf = """<robot name="kr150">
  <!-- <disable_collisions link1="link_1" link2="link_3" reason="commented out"/> -->
  <disable_collisions link1="link_2" link2="link_4" reason="Never"/>
  <disable_collisions link1="link_5" link2="link_6" reason="Adjacent"/>
</robot>
"""
    world = RobotCollision(_robot_copy(tmp_path, urdf, srdf), FAR_PART).world
    assert world.allowed("link_2", "link_4") == "disabled"
    assert "line 3: Never" in world.allowed_pairs[frozenset(("link_2", "link_4"))].note
    assert world.allowed("link_1", "link_3") is None  # a comment disables nothing
    assert world.allowed("link_5", "link_6") == "adjacent"  # the chain's reason comes first
    assert ("link_4", "link_2") not in world.pairs_to_check()
    bad = srdf.replace('link2="link_4"', 'link2="link_9"')
    with pytest.raises(InputError, match=r"kr150r3100_2\.srdf.*line 3.*link2.*'link_9'"):
        _ = RobotCollision(_robot_copy(tmp_path / "b", urdf, bad), FAR_PART).world


def test_the_tool_stage_registers_its_tool_and_part_in_a_world():
    """SweepChecker's world: its own FCL objects, the one pair checked with the contact zone
    exempt; the world's query agrees with FCL on a pose through the plate and one above it."""
    from weldplan.tool import arc_torch
    from weldplan.tool.transitions import SweepChecker

    plate = make_plate([0.0, 0.0, 0.0], 2, size=200.0)
    chk = SweepChecker(plate, arc_torch(), clearance=5.0, contact_radius=20.0)
    world = chk.world
    assert world.names == ("part", "tool") and world.body("tool").obj is chk._model("tool")
    assert world.allowed("tool", "part") is None and world.zone("tool", "part") == "contact zone"
    assert world.pairs_to_check() == (("tool", "part"),)
    assert "tool/part: contact zone (a sphere of 20 mm" in world.describe()
    down = np.diag([1.0, -1.0, -1.0, 1.0])  # TCP z down: the torch above the TCP
    below, above = down.copy(), down.copy()
    below[2, 3], above[2, 3] = -50.0, 50.0  # the TCP 50 mm under the plate: the torch through it
    assert world.contacts({"tool": below, "part": np.eye(4)}) == (("tool", "part"),)
    assert world.contacts({"tool": above}) == ()
