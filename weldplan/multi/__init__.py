"""Several robots, one station: which robot welds which weld (issue 30).

::

    from weldplan.multi import ReachMap, allocate, allocation_report, lower_bound
    reach = ReachMap.from_study(study)              # weldplan.study.check_spots
    report = allocation_report(reach, weld_time, travel, rng=0)
    report.ours.cycle_time, report.bound.value      # s: ours and a proved lower bound
    report.lines()                                  # one robot, nearest robot, ours, bound

:mod:`.problem` (the inputs and the tour shares), :mod:`.allocate` (the min-max MILP start, the
sequencer, the local search), :mod:`.bound` (the lower bound), :mod:`.baselines` (one robot,
nearest robot, the report), :mod:`.result` (the frozen results). Robot-robot interference is
not handled yet: an allocation says which robot welds which weld and in which order, not when.
"""

from weldplan.multi.allocate import allocate
from weldplan.multi.baselines import allocation_report, nearest_robot, one_robot
from weldplan.multi.bound import lower_bound
from weldplan.multi.problem import AllocationProblem, AllocationSettings, ReachMap
from weldplan.multi.result import (
    Allocation,
    AllocationReport,
    LowerBound,
    RobotShare,
    Unreached,
)

__all__ = [
    "Allocation",
    "AllocationProblem",
    "AllocationReport",
    "AllocationSettings",
    "LowerBound",
    "ReachMap",
    "RobotShare",
    "Unreached",
    "allocate",
    "allocation_report",
    "lower_bound",
    "nearest_robot",
    "one_robot",
]
