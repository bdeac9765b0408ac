"""Work budgets of OMPL runs: checks counted, turned into OMPL's termination condition.

A run of :mod:`weldplan.motion.sampling` is budgeted by the calls its caller's validity
callables receive (``max_checks``), not by the clock, so that a seeded run stops after the same
check on any machine and at any load (../shared/DESIGN.md, reproducibility). The condition is a
plain ``PlannerTerminationCondition(fn)``, without an evaluation period: OMPL evaluates it in the
planner's own thread between its steps (OMPL's "Planner Termination Conditions" page: only the
variants given an ``interval`` / ``period`` spawn a thread that polls), and the wall-clock
limit ORed with it, ``timedPlannerTerminationCondition(duration)``, has no thread either. A
step in progress finishes first, so a run may make a few checks more than its budget.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


class Checks:
    """Counts the calls the caller's validity callables receive, against ``limit`` (``None``:
    counted, never spent), and remembers whether the caller's own ``stop`` ended the run."""

    def __init__(self, limit: int | None, stop: Callable[[], bool] | None = None) -> None:
        self.limit = None if limit is None else int(limit)
        self.stop = stop
        self.n = 0
        self.stopped = False

    def spent(self) -> bool:
        return self.limit is not None and self.n >= self.limit

    def state(self, f: Callable[..., bool]) -> Callable[..., bool]:
        """``f`` counted (any signature: R^n states, SE(3) position and quaternion, motions)."""

        def counted(*args: Any) -> bool:
            self.n += 1
            return bool(f(*args))

        return counted

    def motion(self, f: Callable[..., bool] | None) -> Callable[..., bool] | None:
        return None if f is None else self.state(f)

    def done(self) -> bool:
        """OMPL's termination function: the budget spent, or the caller's ``stop()`` true."""
        if self.spent():
            return True
        if self.stop is not None and self.stop():
            self.stopped = True
        return self.stopped

    def termination(self, ob: Any, time_s: float) -> Any:
        """``ss.solve``'s argument: ``time_s`` alone when there is nothing to count against,
        else the budget ORed with the wall-clock limit (both evaluated in the planner's
        thread: module docstring)."""
        if self.stop is None and self.limit is None:
            return float(time_s)
        return ob.plannerOrTerminationCondition(
            ob.timedPlannerTerminationCondition(float(time_s)),
            ob.PlannerTerminationCondition(self.done),
        )

    def ended(self, solved: bool, used: int, late: bool) -> str:
        """What ended a run (:attr:`~weldplan.motion.sampling.SampledPath.ended`) that had made
        ``used`` checks when OMPL returned; the work budget is named before the clock when both
        are spent."""
        if solved:
            return "solved"
        if self.limit is not None and used >= self.limit:
            return "checks"
        if self.stopped:
            return "stop"
        return "clock" if late else "planner"
