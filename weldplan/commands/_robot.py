"""The robot options of ``plan`` and ``demo`` (issue 17).

They fill the station's robot (:class:`~weldplan.station.model.RobotSpec`: ``--robot``,
``--opw``, ``--robot-base``) and the robot stage's settings
(:class:`~weldplan.station.model.RobotSettings`); the stages are
:mod:`weldplan.station.robotstage`'s, the program's round-trip check
:func:`weldplan.station.outputs.check_program`'s.
"""

from __future__ import annotations

import argparse

from weldplan.commands._settings_args import add_settings_options
from weldplan.commands._types import number_type
from weldplan.station.model import DEFAULT_WELD_TIME, RobotSettings
from weldplan.station.outputs import CHECK_DEG, CHECK_MM, check_program
from weldplan.station.summary import order_rows as _order_rows

#: what scripts and tests import from here
__all__ = [
    "CHECK_DEG", "CHECK_MM", "DEFAULT_WELD_TIME", "_order_rows", "add_robot_arguments",
    "check_program",
]  # fmt: skip


def add_robot_arguments(p: argparse.ArgumentParser) -> None:
    """``--robot`` with its base and load, and the robot stage's options
    (:class:`RobotSettings`' fields)."""
    g = p.add_argument_group("robot: the arm, its base, the tool's load (station file: [[robot]])")
    g.add_argument("--robot", metavar="URDF", help="6-axis robot (URDF with limits; OPW beside it)")
    g.add_argument(
        "--opw", metavar="F", help="OPW parameters (default: opw_parameters.yaml beside)"
    )
    g.add_argument(
        "--robot-base",
        metavar="X,Y,Z,YAW",
        help="robot base in the cell frame (the part frame without --up/--part-pose; mm, degrees "
        "about +z); default: searched on the floor",
    )
    g.add_argument(
        "--floor-z",
        metavar="MM",
        type=number_type("height in mm", -1e6, 1e6),
        help="the cell's floor height, mm, in the cell frame (the part frame without --up/"
        "--part-pose; with them default 0): the base search stands the robot on it and no link "
        "nor the tool may reach below it (without a part pose, default: no floor known, not "
        "checked, the search stands the robot at the part's lowest point; station file: "
        "floor_z)",
    )
    g.add_argument(
        "--tool-mass",
        metavar="KG",
        type=number_type("mass in kg", 0.0, 5000.0, lo_open=True),
        help="tool mass for the programs (default: the tool URDF's <inertial> masses; station "
        "file: [robot.tool] mass)",
    )
    s = p.add_argument_group(
        "robot stage: the joint-space route, its cycle time, the program (with --robot; "
        "station file: [[robot]])"
    )
    add_settings_options(s, RobotSettings, "[[robot]]")
