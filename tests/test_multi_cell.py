"""A station of several robots placed in a cell (weldplan.multi.cell): the part pose, given
bases checked against the part and each other, searched bases kept apart.

The demo part with the shared spot gun on two KUKA KR 150. The frame check: the same cell
expressed with a part pose (the part turned about z and lifted onto a fixture, the bases given
in the cell frame) and without one (the bases and the floor moved into the part frame by hand)
must give the same studies and the same allocation."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import require_shared

ROOT = Path(__file__).resolve().parents[1]
#: the part pose: moved, its lowest point (z 652.7 in the part frame) lifted to 500 mm above the
#: cell's floor (z 0). Not turned: the tool stage's candidate poses start from the planning
#: frame's x axis (weldplan.tool.poses.orient.nominal_frames), so a turned part gets other (equally
#: valid) gun poses, and an exact comparison holds for a moved and lifted part only
POSE = (600.0, -400.0, -152.7, 0.0, 0.0, 0.0)
#: a turned one: a quarter turn about z, lifted the same
TURNED = (1000.0, 500.0, -152.7, 0.0, 0.0, 90.0)
#: (x, y, z mm, yaw deg) in the part frame: behind the demo part facing it, in front facing back
#: (tests/test_multi_plan.py's), on 500 mm pedestals above the floor of the posed cell
PART_BASES = ((448.1, 95.3, 652.7, -7.5), (2450.0, -150.0, 652.7, 180.0))
#: the demo welds of the station
IDS = ("1", "3", "5", "7", "9", "11", "13", "15")


def _to_cell(b, pose=POSE):
    """A part-frame base in the cell frame of ``pose`` (rx = ry = 0), by hand: (x, y) turned
    by rz, then moved; the yaw turned by rz."""
    x, y, z, yaw = b
    c, s = math.cos(math.radians(pose[5])), math.sin(math.radians(pose[5]))
    return (pose[0] + c * x - s * y, pose[1] + s * x + c * y, z + pose[2], yaw + pose[5])


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The demo station (tests/test_multi_plan.py's), its welds limited to IDS."""
    import weldplan
    from weldplan.io.joints import Joints, read_joints
    from weldplan.weld import demo_part

    require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    folder = tmp_path_factory.mktemp("cell")
    st = weldplan.load_station(ROOT / "examples" / "demo_station.toml")
    j = read_joints(demo_part.DEMO_JOINTS)
    k = [j.ids.index(i) for i in IDS]
    sub = Joints(ids=IDS, xyz=np.asarray(j.xyz)[k], directions=np.asarray(j.directions)[k])
    sub.to_csv(folder / "welds.csv")
    part = dataclasses.replace(st.part, mesh=demo_part.DEMO_PART, welds=folder / "welds.csv")
    return dataclasses.replace(st, part=part)


def _with(st, bases, **kw):
    specs = tuple(
        dataclasses.replace(st.robots[0], base=b, search=s or {})
        for b, s in zip(bases, kw.pop("search", (None,) * len(bases)), strict=True)
    )
    return dataclasses.replace(st, robots=specs, **kw)


def _posed(st, bases, pose=POSE, **kw):
    from weldplan.cellframe import PartPose

    pose = PartPose.from_xyzrpy(pose, floor_z=0.0)
    return _with(st, bases, part_pose=pose, **kw)


def _allocate(st):
    """plan_station's steps up to the allocation: the cell, the bases, the studies, the
    allocation report."""
    from weldplan.multi.baselines import allocation_report
    from weldplan.multi.cell import place_robots
    from weldplan.multi.inputs import stack_inputs, study_inputs
    from weldplan.multi.station import _robots, _study
    from weldplan.station.pipeline import cell_stage

    robots = _robots(st)
    cell = cell_stage(st)
    layout = place_robots(cell, st, robots)
    studies, inputs = [], []
    for k, (spec, mounted, robot) in enumerate(layout.robots):
        study = layout.studies[k] or _study(cell, st, k, mounted, robot)
        studies.append(study)
        inputs.append(study_inputs(study, [robot], [spec.settings.weld_time]))
    inp = stack_inputs(inputs, [f"robot{k + 1}" for k in range(len(robots))])
    report = allocation_report(inp.reach, inp.weld_time, inp.cost, rng=0, bound_travel=inp.bound)
    return cell, layout, studies, inp, report


@pytest.mark.slow
def test_a_part_pose_gives_the_allocation_of_the_same_cell_in_the_part_frame(demo):
    """The exact check of the frame handling: bases given in the cell frame of a moved and
    lifted part give what the same bases moved into the part frame give there (about 1 min
    wall on a loaded machine)."""
    cell_c, _, studies_c, inp_c, rep_c = _allocate(_posed(demo, [_to_cell(b) for b in PART_BASES]))
    # the same cell without a pose: the floor (cell z 0) is at -POSE z in the part frame
    cell_p, _, studies_p, inp_p, rep_p = _allocate(_with(demo, PART_BASES, floor_z=-POSE[2]))
    assert cell_c.frame == "cell" and cell_p.frame == "part"
    # the study is in the cell frame: the spots where the pose puts them, the bases as given
    pose = cell_c.part_pose
    for sc, sp in zip(studies_c, studies_p, strict=True):
        xyz_c = np.array([s.position for s in sc.spots])
        xyz_p = np.array([s.position for s in sp.spots])
        assert np.allclose(xyz_c, pose.to_cell(xyz_p), atol=1e-6)
        assert np.allclose(sc.robots[0].base_matrix(), pose.matrix @ sp.robots[0].base_matrix())
    assert np.array_equal(inp_c.reach.ok, inp_p.reach.ok)
    assert inp_c.reach.reasons == inp_p.reach.reasons
    assert inp_c.reach.ok.sum() >= 10  # both robots serve most welds: the check is not vacuous
    assert np.allclose(inp_c.cost, inp_p.cost, atol=1e-6)
    a_c, a_p = rep_c.ours, rep_p.ours
    for r in range(2):
        assert a_c.welds_of(r) == a_p.welds_of(r)
    assert a_c.cycle_time == pytest.approx(a_p.cycle_time, abs=1e-6)
    assert rep_c.bound.value == pytest.approx(rep_p.bound.value, abs=1e-6)
    unreached = [u.weld for u in a_c.unreached]
    assert unreached == [u.weld for u in a_p.unreached] and "15" in unreached
    assert [u.reasons for u in a_c.unreached] == [u.reasons for u in a_p.unreached]


@pytest.mark.slow
def test_a_turned_part_puts_the_studies_and_the_robots_in_one_frame(demo):
    """A quarter turn: every configuration a study found puts the gun's TCP on its spot where
    the pose puts it in the cell, by the forward kinematics of the robot at its cell-frame base
    (an independent check that the robots and the welds share the cell frame)."""
    cell, layout, studies, inp, rep = _allocate(
        _posed(demo, [_to_cell(b, TURNED) for b in PART_BASES], pose=TURNED)
    )
    from weldplan.io.joints import read_joints

    part_xyz = read_joints(demo.part.welds).xyz
    want = np.asarray(part_xyz) @ np.asarray([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]]).T
    want = want + TURNED[:3]
    assert np.allclose(cell.joints.xyz, want, atol=1e-6)
    for k, ((spec, mounted, robot), study) in enumerate(zip(layout.robots, studies, strict=True)):
        assert spec.base == _to_cell(PART_BASES[k], TURNED)
        ok = [s for s in study.spots if s.robots[0].q is not None]
        assert len(ok) >= 5
        tcp = robot.fk(np.array([s.robots[0].q for s in ok])) @ mounted.flange_tcp
        assert np.allclose(tcp[:, :3, 3], [want[IDS.index(s.id)] for s in ok], atol=1e-3)
    served = {w for r in range(2) for w in rep.ours.welds_of(r)}
    assert served == {IDS[i] for i in np.flatnonzero(inp.reach.ok.any(axis=0))}


def test_two_robots_at_one_base_or_closer_than_their_footprints_are_refused(demo):
    """Refused before anything slow: the same base, and bases 1 m apart (a KR 150's base
    link reaches 767 mm from A1, so two of them need 1534 mm)."""
    import weldplan
    from weldplan.errors import InputError

    b = PART_BASES[0]
    with pytest.raises(InputError, match="robots 1 and 2 stand at the same base") as e:
        weldplan.plan(_with(demo, [b, b]), rng=0)
    assert e.value.field == "robot.base" and e.value.path == str(demo.source)
    near = (b[0], b[1] + 1000.0, b[2], 0.0)
    with pytest.raises(InputError, match=r"robots 1 and 2 stand 1000.0 mm apart.* 1535 mm"):
        weldplan.plan(_with(demo, [b, near]), rng=0)


def test_a_given_base_in_the_part_is_refused_saying_which(demo):
    """In the solid (the base link through the part, at a weld), and under the part (the base
    link clear below it, its origin inside the part's footprint on the floor)."""
    from weldplan.errors import InputError
    from weldplan.multi.cell import place_robots
    from weldplan.multi.station import _robots
    from weldplan.station.pipeline import cell_stage

    cell = cell_stage(demo)
    lo, hi = cell.part.bounds
    cases = {
        "stands in the part's solid: its base link 'base_link' meets the part": (
            1400.0, -60.0, 500.0, 0.0,
        ),
        "lies inside the part's footprint on the floor": (
            (lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2] - 400.0, 0.0,
        ),
    }  # fmt: skip
    for words, base in cases.items():
        st = _with(demo, [(-3000.0, 0.0, 0.0, 0.0), base])  # robot 1 far off, clear
        with pytest.raises(InputError, match=f"robot 2's base .*{words}") as e:
            place_robots(cell, st, _robots(st))
        assert e.value.field == "robot.base" and e.value.path == str(demo.source)


def test_the_base_search_keeps_out_of_the_discs_it_is_given():
    """BaseSearch.keep_out: no candidate within a disc, the same grid elsewhere."""
    from weldplan.robot import load_robot
    from weldplan.robot.placement import BaseSearch, candidate_bases

    robot = load_robot(require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf"))
    T = np.tile(np.eye(4), (2, 1, 1))
    T[:, :3, 3] = [[1500.0, 0.0, 800.0], [1600.0, 100.0, 900.0]]
    free = candidate_bases(robot, T, None, BaseSearch(floor_z=0.0))
    disc = (1000.0, 0.0, 1200.0)
    kept = candidate_bases(robot, T, None, BaseSearch(floor_z=0.0, keep_out=(disc,)))
    d = np.hypot(free[:, 0, 3] - disc[0], free[:, 1, 3] - disc[1])
    assert 0 < len(kept) < len(free)
    assert np.array_equal(kept, free[d >= disc[2]])


@pytest.mark.slow
def test_a_searched_base_stands_apart_and_serves_what_its_study_says(demo):
    """Robot 1 given, robot 2 searched on the cell's floor: robot 2 stands at least the two
    footprints from robot 1, serves welds, and a fresh study at the base it took agrees."""
    from weldplan.multi.cell import footprint_radius, place_robots
    from weldplan.multi.station import _robots, _study
    from weldplan.station.pipeline import cell_stage

    st = _posed(demo, [_to_cell(PART_BASES[0]), None])
    robots = _robots(st)
    cell = cell_stage(st)
    layout = place_robots(cell, st, robots)
    (s1, _, r1), (s2, m2, r2) = layout.robots
    assert layout.studies[0] is None and layout.studies[1] is not None
    assert s2.base is not None and not s2.search and s2.base[2] >= 0.0  # on the floor
    apart = math.hypot(s2.base[0] - s1.base[0], s2.base[1] - s1.base[1])
    assert apart >= footprint_radius(r1) + footprint_radius(r2)
    searched = layout.studies[1].reach_matrix()[:, 0]
    assert searched.sum() >= 1
    fresh = _study(cell, st, 1, m2, r2)
    assert np.array_equal(fresh.reach_matrix()[:, 0], searched)
    assert np.allclose(fresh.robots[0].base_matrix(), r2.base)


def test_a_search_region_with_no_base_serving_a_weld_is_refused_by_robot(demo):
    from weldplan.errors import ConfigError
    from weldplan.multi.cell import place_robots
    from weldplan.multi.station import _robots
    from weldplan.station.pipeline import cell_stage

    far = {"line": ((20000.0, 0.0, 652.7), (21000.0, 0.0, 652.7)), "step": 500.0}
    st = _with(demo, [PART_BASES[0], None], search=(None, far))
    with pytest.raises(ConfigError, match="robot 2: no base in its search region") as e:
        place_robots(cell_stage(st), st, _robots(st))
    assert e.value.field == "search"


@pytest.mark.slow
def test_weldplan_plan_keeps_the_part_pose_and_the_searched_base_in_every_robots_plan(demo):
    """The whole station through ``weldplan.plan``: robot 1 given in the cell frame, robot 2
    searched; each robot's plan is in the cell frame with the station's pose, at the base its
    study used, and its program's work object carries the pose (several minutes wall)."""
    import weldplan

    st = _posed(demo, [_to_cell(PART_BASES[0]), None])
    p = weldplan.plan(st, rng=0)
    pose = p.plans[0].cell.part_pose if p.plans[0] is not None else p.plans[1].cell.part_pose
    for r, sub in enumerate(p.plans):
        if sub is None:
            continue
        assert sub.cell.frame == "cell" and sub.station.part_pose is st.part_pose
        assert sub.cell.part_pose.same_as(pose)
        assert np.allclose(sub.robot.robot.base, p.studies[r].robots[0].base_matrix(), atol=1e-9)
        assert np.allclose(sub.program.program.part_pose, pose.matrix)
        assert set(sub.cell.joints.ids) == set(p.allocation.welds_of(r))
    assert p.plans[0].station.robots[0].base == _to_cell(PART_BASES[0])
    assert p.studies[1].robots[0].searched
