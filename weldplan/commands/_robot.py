"""The robot options of ``plan`` and ``demo`` (issue 17).

They fill the station's robot (:class:`~weldplan.station.model.RobotSpec`: ``--robot``,
``--opw``, ``--robot-base``) and the robot stage's settings
(:class:`~weldplan.station.model.RobotSettings`); the stages are
:mod:`weldplan.station.robotstage`'s, the program's round-trip check
:func:`weldplan.station.outputs.check_program`'s.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from weldplan.station.model import DEFAULT_WELD_TIME, RobotSettings
from weldplan.station.outputs import CHECK_DEG, CHECK_MM, check_program
from weldplan.station.summary import order_rows as _order_rows

#: what scripts and tests import from here
__all__ = [
    "CHECK_DEG", "CHECK_MM", "DEFAULT_WELD_TIME", "_order_rows", "add_robot_arguments",
    "check_program",
]  # fmt: skip


def _number(kind: str, lo: float, hi: float, lo_open: bool = False):
    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        ok = math.isfinite(v) and (v > lo if lo_open else v >= lo) and v <= hi
        if not ok:
            rng = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
            raise argparse.ArgumentTypeError(f"must be a {kind} in {rng}, got {text!r}")
        return v

    return parse


def add_robot_arguments(p: argparse.ArgumentParser) -> None:
    """``--robot`` and the options of the robot stage."""
    g = p.add_argument_group("robot (a joint-space route, its cycle time, programs)")
    _add_robot_model_arguments(g)
    _add_robot_stage_arguments(g)
    g.add_argument(
        "--tool-mass",
        metavar="KG",
        type=_number("mass in kg", 0.0, 5000.0, lo_open=True),
        help="tool mass for the programs (default: the tool URDF's <inertial> masses)",
    )
    g.add_argument("--trajectory", metavar="F", help="write the timed joint trajectory as CSV")
    g.add_argument(
        "--robot-html",
        metavar="F",
        help="write a 3D page of the robot, tool and part animated along the timed trajectory",
    )


def _add_robot_model_arguments(g: Any) -> None:
    """``--robot``, ``--opw``, ``--robot-base``, ``--floor-z``."""
    g.add_argument("--robot", metavar="URDF", help="6-axis robot (URDF with limits; OPW beside it)")
    g.add_argument(
        "--opw", metavar="F", help="OPW parameters (default: opw_parameters.yaml beside)"
    )
    g.add_argument(
        "--robot-base",
        metavar="X,Y,Z,YAW",
        help="robot base in the part frame (mm, degrees about +z); default: searched on the floor",
    )
    g.add_argument(
        "--floor-z",
        metavar="MM",
        type=_number("height in mm", -1e6, 1e6),
        help="the cell's floor height in the part frame: the base search stands the robot on it "
        "(default: the part's lowest point) and no link nor the tool may reach below it "
        "(default: no floor known, not checked)",
    )


def _add_robot_stage_arguments(g: Any) -> None:
    """The fields of :class:`~weldplan.station.model.RobotSettings` (their defaults)."""
    d = RobotSettings()
    g.add_argument(
        "--roadmap",
        action="store_true",
        default=d.roadmap,
        help="judge a searched base by the welds one joint-space roadmap (OMPL PRM) joins, and "
        "ask it before OMPL for a blocked leg (off by default: slower, same answers measured)",
    )
    g.add_argument(
        "--weld-time",
        metavar="S",
        type=_number("number of s", 0.0, 3600.0),
        default=d.weld_time,
        help=f"seconds per spot in the cycle time (default {d.weld_time:g})",
    )
    g.add_argument(
        "--acc-scale",
        metavar="F",
        type=_number("fraction", 0.0, 1.0, lo_open=True),
        default=d.acc_scale,
        help="scale of the robot's joint accelerations (default 1: each joint reaches its URDF "
        "velocity in 0.5 s)",
    )
    g.add_argument(
        "--vel-scale",
        metavar="F",
        type=_number("fraction", 0.0, 1.0, lo_open=True),
        default=d.vel_scale,
        help="scale of the URDF joint velocity limits (default 1)",
    )
    g.add_argument(
        "--tcp-speed",
        metavar="MM/S",
        type=_number("speed in mm/s", 0.0, 1e5, lo_open=True),
        default=d.tcp_speed,
        help="constant TCP speed the cycle time is compared with (default 1000)",
    )
    _add_program_arguments(g, d)


def _add_program_arguments(g: Any, d: RobotSettings) -> None:
    """``--moves`` and ``--cost``."""
    g.add_argument(
        "--moves",
        choices=("linear", "joint"),
        default=d.moves,
        help="program moves between route rows: linear (blended where verified) or joint "
        "(exact stops, the checked joint path itself); default linear",
    )
    g.add_argument(
        "--cost",
        choices=("length", "time"),
        default=d.cost,
        help="what the sequencer minimises: route length (default) or the robot's cycle time "
        "(rest-to-rest bounds between the welds' IK configurations; needs --robot)",
    )
