"""The weld feasibility study (``weldplan check-spots``): per spot, the surface it sits on, the
stack it joins, whether each gun closes on it and whether each robot reaches it.

::

    from weldplan.study import check_spots, load_study_tool, StudyRobot
    study = check_spots(part, spots, [load_study_tool(gun_urdf, tcp="nozzle_tip")],
                        [StudyRobot("kr150", robot, searched=True)])
    study.reach_matrix()          # (spots, robots) bool: the allocation's input

The names are loaded on first use (PEP 562), so reading a study's results
(:mod:`weldplan.study.result`, as the viewer does) does not load the planners. See
:mod:`weldplan.study.feasibility` and docs/check-spots.md.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from weldplan.lazy import lazy_exports

if TYPE_CHECKING:  # the same names, for type checkers and readers
    from weldplan.study.feasibility import (
        StudyRobot,
        StudySettings,
        StudyTool,
        check_spots,
        load_study_tool,
    )
    from weldplan.study.result import FeasibilityStudy, GunVerdict, RobotVerdict, SpotVerdict

#: exported name -> the module of this package that defines it
_EXPORTS = {
    "FeasibilityStudy": "result",
    "GunVerdict": "result",
    "RobotVerdict": "result",
    "SpotVerdict": "result",
    "StudyRobot": "feasibility",
    "StudySettings": "feasibility",
    "StudyTool": "feasibility",
    "check_spots": "feasibility",
    "load_study_tool": "feasibility",
}

__all__ = [
    "FeasibilityStudy",
    "GunVerdict",
    "RobotVerdict",
    "SpotVerdict",
    "StudyRobot",
    "StudySettings",
    "StudyTool",
    "check_spots",
    "load_study_tool",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
