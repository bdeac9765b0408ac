"""Several robots, one station: which robot welds which weld (issue 30).

::

    from weldplan.multi import ReachMap, allocate, allocation_report, lower_bound
    reach = ReachMap.from_study(study)              # weldplan.study.check_spots
    report = allocation_report(reach, weld_time, travel, rng=0)
    report.ours.cycle_time, report.bound.value      # s: ours and a proved lower bound
    report.lines()                                  # one robot, nearest robot, ours, bound

:mod:`.problem` (the inputs and the tour shares), :mod:`.allocate` (the min-max MILP start, the
sequencer, the local search), :mod:`.bound` (the lower bound), :mod:`.baselines` (one robot,
nearest robot, the report), :mod:`.result` (the frozen results), :mod:`.schedule`
(interlocks and the station's clock: who moves, welds and waits when).
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
from weldplan.multi.schedule import (
    Activity,
    Interlock,
    ReplayVerdict,
    StationSchedule,
    station_schedule,
)

__all__ = [
    "Activity",
    "Allocation",
    "AllocationProblem",
    "AllocationReport",
    "AllocationSettings",
    "Interlock",
    "LowerBound",
    "ReachMap",
    "ReplayVerdict",
    "RobotShare",
    "StationSchedule",
    "Unreached",
    "allocate",
    "allocation_report",
    "lower_bound",
    "nearest_robot",
    "one_robot",
    "station_schedule",
]
