"""The allocation's leg times against the timed programs: measure, calibrate, iterate.

The allocation (:func:`weldplan.multi.allocate`) minimises the station cycle over a *model* of
each robot's leg times (:mod:`weldplan.multi.inputs`), known before any robot is planned. The
robots' programs are then planned and timed (:func:`weldplan.robot.program.time_route`), and a
planned leg is slower than its model: the gun leaves and reaches each weld along its approach,
the joint path follows the gun's transition (or an OMPL detour) rather than a straight joint
line, and the robot stops where no blend fits. This module closes that loop as Spensieri et al.
do for the min-max multiple generalised TSP ("Optimal robot placement for tasks execution",
IEEE T-ASE 13(3), 2016: allocate and sequence over estimated times, plan the paths, put the
planned times back, repeat; Åblad et al., IEEE T-ASE 2022, iterate the same way):

1. :func:`timed_legs`: per planned robot, the welds in the order its program welds them and
   the timed motion between each two (from the end of one weld's dwell to the arrival at the
   next), the time before its first weld and after its last;
2. :func:`calibrated_travel`: the allocation's move times with every planned leg replaced by
   its timed value, both ways (a rest-to-rest motion under symmetric velocity and acceleration
   limits takes as long backwards: the reversed time law is admissible), and, per robot, every
   leg not planned yet scaled by the median ratio of timed to model time over the legs timed
   so far (:func:`leg_scales`: the model's systematic part, the transfer's stops and path
   shape, carried to the legs the robot has not flown yet);
3. :func:`allocate_and_plan`: allocate, plan every robot's share, calibrate, and again while
   the station's timed cycle (the slowest robot's timed program) drops, within a budget of
   rounds (:attr:`~weldplan.multi.problem.AllocationSettings.rounds`); the best round is kept
   (a later round that planned nothing new and times the same is taken for its report: its
   model is the calibrated one).
   Each round's allocation is seeded with the same seed, and a robot whose share is a set of
   welds it has planned before is not planned again (its plan sequences the share itself: the
   earlier plan is kept), so the loop is deterministic.

The lower bound printed beside the answer is computed once, over the all-branch rest-to-rest
bounds (:func:`weldplan.robot.route.legtime.rest_to_rest_bound`), never over calibrated times:
a timed leg is an upper value of what that leg can take, not a bound of it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import ConfigError

log = logging.getLogger(__name__)

#: a round's timed cycle must drop by more than this (s) to count as better
EPS_S = 1e-6


@dataclass(frozen=True, eq=False)
class TimedLegs:
    """One robot's timed program read as legs between welds (:func:`timed_legs`).

    Attributes
    ----------
    robot
        The robot's index in the station.
    welds
        ``(n,) int``: reach-map weld indices in the order the program welds them.
    legs
        ``(n - 1,)`` s: the motion from the end of each weld's dwell to the arrival at the
        next (no dwell in it).
    head, tail
        s: the motion before the first weld, after the last one's dwell.
    weld_time
        s a weld.
    """

    robot: int
    welds: NDArray[np.intp]
    legs: NDArray[np.float64]
    head: float
    tail: float
    weld_time: float

    @property
    def total(self) -> float:
        """s: the program's cycle (head, legs, dwells, tail)."""
        return self.head + float(self.legs.sum()) + self.weld_time * len(self.welds) + self.tail


def timed_legs(robot: int, build: Any, welds: Sequence[str]) -> TimedLegs:
    """The legs of robot ``robot``'s :class:`~weldplan.robot.program.ProgramBuild` ``build``
    over the reach map's weld ids ``welds`` (module docstring, step 1)."""
    tm = build.timing
    ids = build.weld_ids_by_row()  # every row standing on a weld, its dwell row among them
    rows = np.array([w for w in np.asarray(tm.weld_rows).tolist() if w in ids], dtype=np.intp)
    pos = {str(w): i for i, w in enumerate(welds)}
    order = np.array([pos[str(ids[int(k)])] for k in rows], dtype=np.intp)
    arrive = np.asarray(tm.row_times, dtype=np.float64)[rows]
    wt = float(tm.weld_time)
    if not len(rows):
        return TimedLegs(robot, order, np.zeros(0), float(tm.total), 0.0, wt)
    return TimedLegs(
        robot,
        order,
        np.diff(arrive) - wt,
        float(arrive[0]),
        float(tm.total) - float(arrive[-1]) - wt,
        wt,
    )


def leg_scales(
    model: NDArray[np.float64], known: NDArray[np.bool_], timed: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``(R,)``: per robot the median of timed over model time over its timed legs whose model
    time is > 0: how much slower than its model it flies a leg. A robot with no timed leg
    takes the median of the others' (robots of one station are alike more often than not), 1
    when no robot has one."""
    R = len(model)
    scale, has = np.ones(R), np.zeros(R, bool)
    for r in range(R):
        m = known[r] & (model[r] > 0)
        if m.any():
            scale[r], has[r] = float(np.median(timed[r][m] / model[r][m])), True
    if has.any():
        scale[~has] = float(np.median(scale[has]))
    return scale


def calibrated_travel(
    model: NDArray[np.float64],
    planned: Sequence[TimedLegs],
    known: NDArray[np.bool_] | None = None,
    timed: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.float64]]:
    """Move times calibrated by the timed legs (module docstring, step 2).

    Parameters
    ----------
    model
        ``(R, W, W)`` s: the leg-time model (never changed).
    planned
        The :class:`TimedLegs` of this round's planned robots.
    known, timed
        ``(R, W, W)``: the legs timed in earlier rounds and their times (``None``: none).

    Returns
    -------
    travel, known, timed
        ``(R, W, W)`` s: the calibrated move times; the legs timed so far (this round's and
        the earlier ones, the latest time winning) and their times.
    """
    model = np.asarray(model, dtype=np.float64)
    known = np.zeros(model.shape, bool) if known is None else known.copy()
    timed = np.zeros(model.shape) if timed is None else timed.copy()
    for tl in planned:
        if not 0 <= tl.robot < len(model):
            raise ConfigError(f"no robot {tl.robot} in the station", field="robot")
        a, b = tl.welds[:-1], tl.welds[1:]
        known[tl.robot, a, b] = known[tl.robot, b, a] = True
        timed[tl.robot, a, b] = timed[tl.robot, b, a] = tl.legs
    scale = leg_scales(model, known, timed)
    travel = np.where(known, timed, model * scale[:, None, None])
    return travel, known, timed


@dataclass(frozen=True)
class CalibrationRound:
    """One round of :func:`allocate_and_plan`.

    Attributes
    ----------
    model_cycle
        s: the allocation's cycle over the move times it was given this round.
    timed_cycle
        s: the slowest robot's timed program (no interlock waits yet).
    timed
        s per robot: its timed program (0: idle).
    planned
        The robots planned this round (the others kept their plan of an earlier round).
    """

    model_cycle: float
    timed_cycle: float
    timed: tuple[float, ...]
    planned: tuple[int, ...]

    def to_dict(self) -> dict[str, Any]:
        return {"model_cycle": self.model_cycle, "timed_cycle": self.timed_cycle,
                "timed": list(self.timed), "planned": list(self.planned)}  # fmt: skip


@dataclass(frozen=True, eq=False)
class Calibrated:
    """What :func:`allocate_and_plan` returns: the best round's report and plans, every
    round's figures, and the first round's report (over the uncalibrated model)."""

    report: Any
    plans: tuple[Any, ...]
    rounds: tuple[CalibrationRound, ...]
    first: Any
    best: int


def allocate_and_plan(
    allocate_once: Callable[[NDArray[np.float64]], Any],
    plan_shares: Callable[[dict[int, tuple[str, ...]]], dict[int, Any]],
    model: NDArray[np.float64],
    rounds: int,
) -> Calibrated:
    """Allocate, plan, calibrate, again while the timed cycle drops (module docstring, step 3).

    Parameters
    ----------
    allocate_once
        ``travel (R, W, W) s -> AllocationReport``: one allocation (same seed every call).
    plan_shares
        ``{robot: weld ids in order} -> {robot: Plan}``: the round's new shares planned (in
        turn or side by side: :func:`weldplan.multi.shares.plan_shares`).
    model
        ``(R, W, W)`` s: the leg-time model of the first round.
    rounds
        The most allocations (>= 1; 1: allocate and plan once, no calibration).
    """
    if not (isinstance(rounds, int) and rounds >= 1):
        raise ConfigError(f"must be an integer >= 1, got {rounds!r}", field="rounds")
    travel = np.asarray(model, dtype=np.float64)
    known = timed = None
    cache: dict[tuple[int, tuple[str, ...]], Any] = {}
    out: list[CalibrationRound] = []
    best: tuple[float, Any, tuple[Any, ...], int] | None = None
    first = None
    for k in range(rounds):
        report = allocate_once(travel)
        first = first or report
        shares = {r: report.ours.welds_of(r) for r in range(len(report.ours.robots))}
        # the robot's plan sequences its share itself: a share planned before is kept
        keys = {r: (r, tuple(sorted(ids))) for r, ids in shares.items() if ids}
        todo = {r: shares[r] for r, key in keys.items() if key not in cache}
        if todo:
            for r, p in plan_shares(todo).items():
                cache[keys[r]] = p
        fresh = sorted(todo)
        plans = [cache[keys[r]] if r in keys else None for r in range(len(shares))]
        legs = [timed_legs(r, p.program, report.ours.welds) for r, p in enumerate(plans) if p]
        times = [0.0 if p is None else float(p.program.timing.total) for p in plans]
        out.append(CalibrationRound(report.ours.cycle_time, max(times), tuple(times), tuple(fresh)))
        log.info("round %d: model cycle %.3f s, timed cycle %.3f s (robots %s planned)",
                 k + 1, report.ours.cycle_time, max(times), fresh)  # fmt: skip
        if best is not None and max(times) >= best[0] - EPS_S:
            if not fresh and max(times) <= best[0] + EPS_S:
                # the plans of the best round again: keep this round's calibrated report
                best = (best[0], report, tuple(plans), k)
            break  # no better than the best round: stop
        best = (max(times), report, tuple(plans), k)
        travel, known, timed = calibrated_travel(model, legs, known, timed)
    assert best is not None
    return Calibrated(best[1], best[2], tuple(out), first, best[3])
