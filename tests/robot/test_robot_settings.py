"""The robot stages' settings objects (weldplan/robot/settings.py): validated once when built, a
bad field named in a one-line ConfigError, the tool on the flange kept as given, and the
station's RobotSettings mapped onto them in one place (station/robotstage.py)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.robot_helpers import TORCH_TCP
from weldplan.errors import ConfigError
from weldplan.motion.roadmap import RoadmapSettings
from weldplan.robot.placement import BaseSearch, base_pose
from weldplan.robot.settings import (
    ROADMAP,
    JointRouteSettings,
    PlacementSettings,
    ProgramSettings,
    RobotCell,
    ToolOnRobot,
)


@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: PlacementSettings(singular_deg=90.0), "singular_deg"),
        (lambda: PlacementSettings(singular_deg=-1.0), "singular_deg"),
        (lambda: PlacementSettings(flip_penalty=float("nan")), "flip_penalty"),
        (lambda: PlacementSettings(top=0), "top"),
        (lambda: PlacementSettings(top=2.5), "top"),
        (lambda: PlacementSettings(joins={"milestones": 40}), "joins"),
        (lambda: PlacementSettings(trial="yes"), "trial"),
        (lambda: JointRouteSettings(singular_deg=95.0), "singular_deg"),
        (lambda: JointRouteSettings(search_top=0), "top"),
        (lambda: JointRouteSettings(contact_radius=-1.0), "contact_radius"),
        (lambda: JointRouteSettings(replan="yes"), "replan"),
        (lambda: JointRouteSettings(check_collision=1), "check_collision"),
        (lambda: JointRouteSettings(planner="rrt-star-ish"), "planner"),
        (lambda: JointRouteSettings(replan_time_s=0.0), "replan_time_s"),
        (lambda: JointRouteSettings(roadmap=40), "joins"),
        (lambda: ProgramSettings(moves="spline"), "moves"),
        (lambda: ProgramSettings(line_tolerance=-0.1), "line_tolerance"),
        (lambda: ProgramSettings(weld_time=float("inf")), "weld_time"),
        (lambda: ProgramSettings(clearance=-5.0), "clearance"),
        (lambda: ProgramSettings(tolerance=0.0), "tolerance"),
        (lambda: ProgramSettings(tcp_speed=0.0), "tcp_speed"),
        (lambda: ProgramSettings(name=""), "name"),
        (lambda: ToolOnRobot(np.eye(3)), "flange_tcp"),
        (lambda: ToolOnRobot(np.diag([2.0, 1.0, 1.0, 1.0])), "flange_tcp"),
        (lambda: ToolOnRobot(np.diag([-1.0, 1.0, 1.0, 1.0])), "flange_tcp"),  # a mirror
        (lambda: ToolOnRobot(np.full((4, 4), np.nan)), "flange_tcp"),
        (lambda: ToolOnRobot(TORCH_TCP, mass=2.0), "mass"),
        (lambda: ToolOnRobot(TORCH_TCP, mass=-2.0, cog=np.zeros(3)), "mass"),
        (lambda: ToolOnRobot(TORCH_TCP, mass=2.0, cog=np.zeros(2)), "cog"),
        (lambda: RobotCell(base=np.eye(3)), "base"),
        (lambda: RobotCell(search={"floor_z": 0.0}), "search"),
        (lambda: RobotCell(floor_z=float("nan")), "floor_z"),
    ],
)
def test_a_bad_field_is_refused_when_built_by_name(make, field):
    with pytest.raises(ConfigError) as ei:
        make()
    assert ei.value.field == field
    assert "\n" not in str(ei.value)


def test_the_route_settings_hand_the_roadmap_to_the_base_search_only_with_detours():
    assert JointRouteSettings().placement == PlacementSettings()
    s = JointRouteSettings(singular_deg=7.0, flip_penalty=3.0, search_top=2, roadmap=ROADMAP)
    assert s.placement == PlacementSettings(7.0, 3.0, 2, ROADMAP)
    assert JointRouteSettings(roadmap=ROADMAP, replan=False).placement.joins is None
    assert isinstance(ROADMAP, RoadmapSettings)


def test_the_tool_on_the_robot_keeps_a_read_only_copy_of_what_it_was_given():
    F = TORCH_TCP.copy()
    cog = np.array([0.0, 0.0, 100.0])
    tool = ToolOnRobot(F, mass=3, cog=cog)
    F[2, 3] = 0.0
    cog[2] = 0.0
    assert tool.flange_tcp[2, 3] == 425.0 and tool.cog[2] == 100.0
    assert tool.mass == 3.0 and isinstance(tool.mass, float)
    with pytest.raises(ValueError):
        tool.flange_tcp[0, 3] = 1.0
    assert ToolOnRobot(TORCH_TCP).mass is None and ToolOnRobot(TORCH_TCP).tool is None


def test_a_cell_takes_a_given_base_or_a_search_and_a_floor():
    B = base_pose(-1800.0, 0.0, -700.0, 30.0)
    cell = RobotCell(None, base=B, floor_z=-10)
    np.testing.assert_array_equal(cell.base, B)
    assert cell.floor_z == -10.0 and cell.search is None
    assert RobotCell(search=BaseSearch()).base is None


def test_a_program_needs_the_tools_load():
    from tests.route_fixtures import box_route
    from weldplan.robot.program import robot_program

    with pytest.raises(ConfigError) as ei:
        robot_program(box_route(), np.zeros((3, 6)), None, ToolOnRobot(TORCH_TCP), part=None)
    assert ei.value.field == "mass"


def test_a_collision_check_without_a_part_is_refused_before_any_work():
    from tests.route_fixtures import box_route
    from weldplan.robot.route import plan_robot_route

    with pytest.raises(ConfigError) as ei:
        plan_robot_route(box_route(), None, None, tool=ToolOnRobot(TORCH_TCP))
    assert ei.value.field == "part"


def test_the_station_maps_its_robot_settings_onto_the_stages_in_one_place():
    from weldplan.station.mount import MountedTool
    from weldplan.station.robotstage import program_settings, route_settings, tool_on_robot
    from weldplan.station.settings import RobotSettings

    rs = RobotSettings(weld_time=0.7, tcp_speed=800.0, moves="joint", roadmap=True)
    assert program_settings(rs, "cell_1") == ProgramSettings(
        moves="joint", weld_time=0.7, tcp_speed=800.0, name="cell_1"
    )
    assert route_settings(rs.roadmap) == JointRouteSettings(roadmap=ROADMAP)
    assert route_settings(False) == JointRouteSettings()

    mounted = MountedTool(None, "torch", flange_tcp=TORCH_TCP, mass=4.0, cog=np.zeros(3))
    on = tool_on_robot(mounted)
    np.testing.assert_array_equal(on.flange_tcp, TORCH_TCP)
    assert (on.tool, on.mass) == ("torch", 4.0)
