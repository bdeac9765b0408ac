"""The plan as a saved, re-loadable, re-checkable result (issue 28, item 2).

``Plan.save`` -> ``weldplan.load_plan`` -> ``SavedPlan.save`` gives the same bytes; the loaded plan
holds the weld poses, the tool path and the robot route typed; ``Plan.verify`` and
``SavedPlan.verify`` run the independent re-checks and return one verdict that names the first
failure; route JSON files written before the typed tool section still load and re-save unchanged.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import weldplan
from tests.conftest import ROOT, require_shared
from tests.route_fixtures import box_route, write_box_station
from weldplan.errors import EXIT_PARTIAL, InputError
from weldplan.robot.program import ToolRoute
from weldplan.robot.route import RobotRoute
from weldplan.station.recheck import CheckResult, RobotFiles, Verdict
from weldplan.station.saved import load_plan
from weldplan.tool.poses import WeldPoses
from weldplan.tool.transitions import ToolPath

DATA = Path(__file__).resolve().parent / "data"
#: route JSON files written by weldplan before ToolRoute (commit 6bc50f8): the box of
#: tests.route_fixtures with the bent arc torch, without and with the KR 150 at a given base
OLD_TORCH = DATA / "route_box_torch_v1.json"
OLD_ROBOT = DATA / "route_box_kr150_v1.json"
TORCH = "\n[[robot]]\n[robot.tool]\nbuiltin = 'arc_torch'\nbend_angle = 22\nmass = 3\n"


@pytest.fixture(scope="module")
def torch_plan(tmp_path_factory):
    """The box with the bent arc torch (no robot), planned once (about 10 s on 2 cores)."""
    tmp = tmp_path_factory.mktemp("torch")
    _, mesh, joints = write_box_station(tmp)
    toml = tmp / "station.toml"
    toml.write_text(
        f'clearance = 5.0\n[part]\nmesh = "{mesh.name}"\nwelds = "{joints.name}"\n'
        f"[cell]\nmargin = 50\n{TORCH}"
    )
    return tmp, mesh, weldplan.plan(weldplan.load_station(toml), rng=0)


def test_save_load_save_gives_the_same_file_and_typed_results(torch_plan):
    tmp, mesh, plan = torch_plan
    first = plan.save(tmp / "a.json")
    assert (tmp / "a.timings.json").exists()
    saved = load_plan(first, mesh=mesh)
    saved.save(tmp / "b.json")
    assert (tmp / "b.json").read_bytes() == first.read_bytes()
    assert isinstance(saved.poses, WeldPoses) and isinstance(saved.tool_path, ToolPath)
    assert saved.robot_route is None
    # the same poses and path as planned, re-read from the file (its measured times apart)
    planned = json.loads(json.dumps(plan.poses.poses.to_dict()))
    assert saved.poses.to_dict()["poses"] == planned["poses"]
    assert saved.tool_path.order == plan.transitions.path.order
    assert saved.route.order == plan.route.order
    np.testing.assert_array_equal(saved.route.waypoints(), plan.route.waypoints())


def test_plan_verify_and_the_loaded_plan_verify_agree(torch_plan):
    tmp, mesh, plan = torch_plan
    v = plan.verify()
    assert isinstance(v, Verdict) and v.ok and v.exit_code == 0, v.describe()
    names = [c.name for c in v.checks]
    assert names == ["part pose", "route", "tool poses", "tool transitions"]
    assert v.not_run == ()  # no robot: nothing carried for it, nothing said
    path = plan.save(tmp / "v.json")
    w = load_plan(path, mesh=mesh).verify(tool=plan.tool)
    assert [c.name for c in w.checks] == names and w.ok
    assert [c.text for c in w.checks[1:]] == [c.text for c in v.checks[1:]]
    # without a tool the route alone is checked, and the verdict says what was not
    u = load_plan(path, mesh=mesh).verify()
    assert [c.name for c in u.checks] == ["part pose", "route"] and u.ok
    assert ("tool poses", "no tool given") in u.not_run


def test_a_tampered_pose_fails_and_is_named_first(torch_plan):
    tmp, mesh, plan = torch_plan
    d = json.loads(plan.save(tmp / "t.json").read_text())
    p = d["tool"]["poses"]["poses"][0]
    p["quaternion"] = [0.5**0.5, 0.0, 0.5**0.5, 0.0]  # the torch laid along the floor
    (tmp / "t.json").write_text(json.dumps(d))
    v = load_plan(tmp / "t.json", mesh=mesh).verify(tool=plan.tool)
    assert not v.ok and v.exit_code == 1
    assert [c.name for c in v.failures] == ["tool poses"]
    assert f"weld {p['id']}" in v.describe() and v.describe().startswith("tool poses failed")
    assert ("tool transitions", "an earlier check failed") in v.not_run


def test_a_route_moved_into_the_part_fails_the_route_check(torch_plan):
    tmp, mesh, plan = torch_plan
    d = json.loads(plan.save(tmp / "m.json").read_text())
    leg = max(d["legs"], key=lambda g: len(g["points"]))
    leg["points"][len(leg["points"]) // 2] = [0.0, 30.0, 10.0]  # inside the box's wall
    (tmp / "m.json").write_text(json.dumps(d))
    v = load_plan(tmp / "m.json", mesh=mesh).verify(tool=plan.tool)
    assert [c.name for c in v.failures] == ["route"]
    assert {n for n, _ in v.not_run} == {"tool poses", "tool transitions"}


def test_verdict_exit_codes_and_lookup():
    ok = CheckResult("route", True, "route ok")
    part = CheckResult("tool poses", True, "3 / 4", left_out=("D",))
    bad = CheckResult("tool transitions", False, "1 transition failure(s)")
    assert Verdict((ok,)).exit_code == 0
    assert Verdict((ok, part)).exit_code == EXIT_PARTIAL and Verdict((ok, part)).partial
    v = Verdict((ok, part, bad))
    assert v.exit_code == 1 and not v.partial and v["tool transitions"] is bad
    assert v.describe() == "tool transitions failed: 1 transition failure(s)"
    with pytest.raises(KeyError, match="robot route"):
        v["robot route"]


def test_a_point_tip_route_loads_with_an_empty_tool_section(tmp_path):
    from weldplan.station.saved import save_route

    path = save_route(box_route(), tmp_path / "p.json")
    saved = load_plan(path)
    assert saved.tool_route.is_empty and saved.poses is None and saved.part is None
    saved.save(tmp_path / "q.json")
    assert (tmp_path / "q.json").read_bytes() == path.read_bytes()
    with pytest.raises(InputError, match="no part"):
        saved.verify()


@pytest.mark.parametrize("old", [OLD_TORCH, OLD_ROBOT], ids=["torch", "kr150"])
def test_route_files_written_before_the_typed_section_load_and_resave_unchanged(old, tmp_path):
    saved = load_plan(old)
    assert isinstance(saved.poses, WeldPoses) and isinstance(saved.tool_path, ToolPath)
    saved.save(tmp_path / "new.json")
    assert (tmp_path / "new.json").read_text() == old.read_text()
    tr = ToolRoute.from_json(json.dumps(json.loads(old.read_text())["tool"]))
    assert tr.to_dict() == json.loads(old.read_text())["tool"]
    if old is OLD_ROBOT:
        rr = saved.robot_route
        assert isinstance(rr, RobotRoute) and list(rr.status) == ["ok"] * 4
        follows = saved.tool_route.robot.follows
        assert follows is not None and len(follows.quaternions) == len(follows.route.waypoints())


def test_the_old_robot_file_re_checks_by_fk_and_fcl(tmp_path):
    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    from weldplan.station.model import ToolSpec
    from weldplan.station.mount import load_tool_spec

    _, mesh, _ = write_box_station(tmp_path)
    tool = load_tool_spec(ToolSpec(builtin="arc_torch", params={"bend_angle": 22}))
    v = load_plan(OLD_ROBOT, mesh=mesh).verify(tool=tool, robot=RobotFiles(urdf))
    assert v.ok and v.exit_code == 0, v.describe()
    assert v["robot route"].report.fk_mm <= 0.01 and v["robot route"].report.rows > 0


@pytest.mark.slow
def test_the_demo_with_the_gun_and_the_kr150_saves_loads_and_verifies(tmp_path):
    """examples/demo_station.toml (the gun on the KR 150, its base searched): plan -> save ->
    load -> save gives the same file, and both verdicts pass with the robot route checked."""
    require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    plan = weldplan.plan(weldplan.load_station(ROOT / "examples" / "demo_station.toml"), rng=0)
    v = plan.verify()
    assert v.ok, v.describe()
    assert [c.name for c in v.checks][-1] == "robot route"
    path = plan.save(tmp_path / "demo.json")
    saved = load_plan(path, mesh=ROOT / "assets" / "demo" / "part.stl")
    saved.save(tmp_path / "again.json")
    assert (tmp_path / "again.json").read_bytes() == path.read_bytes()
    assert isinstance(saved.robot_route, RobotRoute)
    w = saved.verify(tool=plan.tool)
    assert w.ok and [c.name for c in w.checks] == [c.name for c in v.checks], w.describe()
    assert w.exit_code == (EXIT_PARTIAL if plan.partial() else 0)


def test_a_plan_with_a_part_pose_verifies_in_the_cell_frame_and_refuses_another_pose(tmp_path):
    """The box stood up (its y to the cell's z, 350 mm above the floor), point-tip only: the
    saved route lies in the cell frame and is checked against the mesh placed by the pose it
    records; a pose given that differs is bad input."""
    from weldplan.cellframe import PartPose, parse_part_pose
    from weldplan.station.saved import PartFiles

    _, mesh, joints = write_box_station(tmp_path)
    toml = tmp_path / "station.toml"
    toml.write_text(
        f'clearance = 5.0\n[part]\nmesh = "{mesh.name}"\nwelds = "{joints.name}"\n'
        'up = "y"\nfixture_z = 350\n[cell]\nmargin = 50\n'
    )
    plan = weldplan.plan(weldplan.load_station(toml), rng=0)
    v = plan.verify()
    assert v.ok and v["part pose"].text.startswith("part pose"), v.describe()
    path = plan.save(tmp_path / "posed.json")
    saved = load_plan(path, mesh=mesh, part=PartFiles(joints=joints))
    assert isinstance(saved.part_pose, PartPose) and saved.part_pose.same_as(plan.cell.part_pose)
    # the part placed in the cell: the route's weld spots are the placed joints
    np.testing.assert_allclose(saved.joints.xyz, saved.route.joint_xyz, atol=1e-9)
    w = saved.verify()
    assert w.ok and [c.name for c in w.checks] == ["part pose", "route"], w.describe()
    other = parse_part_pose("0,0,100,0,0,0")
    with pytest.raises(InputError, match="planned with part pose"):
        load_plan(path, mesh=mesh, part=PartFiles(part_pose=other))


def test_an_unreadable_tool_section_is_bad_input_naming_the_file_and_field(tmp_path):
    d = json.loads(OLD_TORCH.read_text())
    d["tool"]["transitions"]["transitions"][0] = {"no": "transition"}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(d))
    with pytest.raises(InputError) as e:
        load_plan(bad)
    assert "bad.json" in str(e.value) and "tool" in str(e.value)
    assert "\n" not in str(e.value)


def test_the_tool_layer_reads_the_tool_stage_keys_as_the_tool_route_does():
    """ToolSection (weldplan.tool, below the robot's layer) reads the provenance, the poses and
    the transitions as ToolRoute does, keeps the robot's section as read, and a re-check of a
    route whose tool section is unreadable is bad input naming the file and the field."""
    import dataclasses

    from weldplan.tool.poses import route_poses, route_tool_path
    from weldplan.tool.section import ToolSection
    from weldplan.tool.verify import check_tool_provenance
    from weldplan.weld.route import Route

    d = json.loads(OLD_ROBOT.read_text())
    section, full = ToolSection.from_dict(d["tool"]), ToolRoute.from_dict(d["tool"])
    assert section.poses.to_dict() == full.poses.to_dict() == d["tool"]["poses"]
    assert section.transitions.to_dict() == full.transitions.to_dict()
    assert section.transitions.to_dict() == d["tool"]["transitions"]
    assert dict(section.provenance) == d["tool"]["provenance"] and list(section.rest) == ["robot"]
    route = Route.from_dict(d)
    assert route_poses(route).to_dict() == d["tool"]["poses"]
    assert route_tool_path(route).to_dict() == d["tool"]["transitions"]
    assert ToolSection.of(dataclasses.replace(route, tool={})).poses is None
    bad = dataclasses.replace(route, tool={**route.tool, "poses": {"poses": [{"id": "a"}]}})
    with pytest.raises(InputError, match="unreadable tool section") as e:
        check_tool_provenance(bad, dict(section.provenance), "bad.json")
    assert e.value.field == "tool" and "bad.json" in str(e.value)


def test_a_route_reads_its_tool_section_once_and_a_new_route_reads_its_own():
    """ToolSection.of and ToolRoute.of parse a route's section once (Route.tool_view), share
    the poses and the transitions, leave the route's JSON as it was, and a route made from it
    (dataclasses.replace) reads its own section; an unreadable robot section is bad input
    naming the file and the field, for the robot's check and for the re-check's plan of checks,
    each time it is read (nothing cached)."""
    import dataclasses

    from weldplan.robot.program import saved_robot_route
    from weldplan.station.recheck import recheck
    from weldplan.tool.section import ToolSection
    from weldplan.weld.route import Route

    text = OLD_ROBOT.read_text()
    route = Route.from_json(text)
    section, full = ToolSection.of(route), ToolRoute.of(route)
    assert ToolSection.of(route) is section and ToolRoute.of(route) is full
    assert full.poses is section.poses and full.transitions is section.transitions
    assert full.robot.to_dict() == json.loads(text)["tool"]["robot"]
    assert Route.from_json(route.to_json()) == route and "_tool_views" not in route.to_json()
    bare = dataclasses.replace(route, tool={})
    assert ToolSection.of(bare).poses is None and ToolRoute.of(bare).robot is None
    assert ToolRoute.of(route) is full and saved_robot_route(route) is full.robot
    bad = dataclasses.replace(route, tool={**route.tool, "robot": {"q": [[0.0]]}})
    assert ToolSection.of(bad).poses is not None  # the tool stage's part still reads
    for _ in range(2):
        with pytest.raises(InputError, match="robot route is not valid") as e:
            saved_robot_route(bad, "bad.json")
        assert e.value.field == "tool.robot" and "bad.json" in str(e.value)
    with pytest.raises(InputError, match="robot route is not valid") as e:
        recheck(bad, None, path="bad.json")
    assert "bad.json" in str(e.value)


def test_the_tool_stage_writes_its_section_typed_with_the_same_bytes():
    """ToolSection.to_dict gives back the section it read, key for key and in order (so a
    route written through ToolSection.on has the JSON bytes it had when the tool stage built
    the dict itself), an empty section writes nothing, and the tool stage's writer
    (station.toolstage.with_tool) lays the section over the route's."""
    from weldplan.station.toolstage import PosesResult, TransitionsResult, with_tool
    from weldplan.tool.section import ToolSection
    from weldplan.weld.route import Route

    d = json.loads(OLD_ROBOT.read_text())
    section = ToolSection.from_dict(d["tool"])
    assert json.dumps(section.to_dict()) == json.dumps(d["tool"])
    route = Route.from_dict(d)
    assert section.on(route).to_json() == route.to_json()
    assert ToolSection().to_dict() == {} and ToolSection().on(route).tool == {}
    stage = {k: d["tool"][k] for k in ("provenance", "poses", "transitions")}
    poses = PosesResult(section.poses, None)
    path = TransitionsResult(section.transitions, None)
    assert json.dumps(with_tool(route, d["tool"]["provenance"], poses, path).tool) == json.dumps(
        stage
    )
    no_path = with_tool(route, d["tool"]["provenance"], poses, None).tool
    assert list(no_path) == ["provenance", "poses"]
