"""The baselines an allocation is compared with, and the report that puts them side by side.

Issue 30 asks for three columns and a bound (``weldplan bench station``):

* **one robot**: the fastest single robot that serves every weld some robot serves (``None``
  when none does): what the station would cost without the others;
* **nearest robot**: each weld to the robot, among those that serve it, whose base is nearest
  (mm, part frame; ties: the first robot): the split an engineer draws first;
* **ours**: :func:`weldplan.multi.allocate`;

each robot's share ordered by the same sequencer with the same polish, so the columns differ
only by the assignment; and the :class:`~weldplan.multi.result.LowerBound`
(:func:`weldplan.multi.bound.lower_bound`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from weldplan.multi.allocate import PairCost, allocate, make_allocation, sequence_share
from weldplan.multi.bound import lower_bound
from weldplan.multi.problem import AllocationProblem, AllocationSettings, ReachMap
from weldplan.multi.result import Allocation, AllocationReport, LowerBound
from weldplan.random import RNGLike, as_generator, seed_of


def _ordered(
    problem: AllocationProblem,
    assign: np.ndarray,
    method: str,
    rng: RNGLike,
    kicks: int | None,
    stats: dict,
) -> Allocation:
    gen = as_generator(rng)
    orders = [
        sequence_share(problem, r, np.flatnonzero(assign == r), int(gen.integers(2**31)), kicks)
        for r in range(problem.ok.shape[0])
    ]
    return make_allocation(problem, method, assign, orders, seed_of(rng), stats)


def nearest_robot(
    problem: AllocationProblem, *, rng: RNGLike = None, kicks: int | None = None
) -> Allocation | None:
    """Each served weld to the nearest robot that serves it (module docstring); ``None``
    when the reach map has no bases or no weld positions."""
    rm = problem.reach
    if rm.bases is None or rm.positions is None:
        return None
    d = np.linalg.norm(rm.positions[None, :, :] - rm.bases[:, None, :], axis=2)  # (R, W) mm
    d = np.where(problem.ok, d, np.inf)
    assign = np.where(problem.served, np.argmin(d, axis=0), -1).astype(np.intp)
    return _ordered(problem, assign, "nearest-robot", rng, kicks, {})


def one_robot(
    problem: AllocationProblem, *, rng: RNGLike = None, kicks: int | None = None
) -> Allocation | None:
    """The fastest robot that serves every served weld, welding them all alone; ``None``
    when no robot serves them all. ``stats["robot"]`` names it."""
    ok, served = problem.ok, problem.served
    best = None
    for r in np.flatnonzero((ok | ~served[None, :]).all(axis=1)):
        assign = np.where(served, r, -1).astype(np.intp)
        name = problem.reach.robots[r]
        a = _ordered(problem, assign, "one-robot", rng, kicks, {"robot": name})
        if best is None or a.cycle_time < best.cycle_time:
            best = a
    return best


def allocation_report(
    reach: ReachMap | ArrayLike,
    weld_time: ArrayLike,
    travel: Sequence[ArrayLike] | ArrayLike,
    *,
    rng: RNGLike = None,
    settings: AllocationSettings | None = None,
    bound_travel: Sequence[ArrayLike] | ArrayLike | None = None,
    bound: LowerBound | None = None,
    conflicts: PairCost | None = None,
) -> AllocationReport:
    """Our allocation (:func:`weldplan.multi.allocate`, same arguments), its lower bound and
    the two baselines (module docstring), every order by the same sequencer and polish.

    ``bound_travel``: move times (``R`` matrices ``(W, W)`` s) never above the
    real ones, for the bound only (e.g. :mod:`weldplan.robot.route.legtime`'s ``bound`` over every
    branch while ``travel`` is its ``cost`` on the station branch): the bound is then one of
    the timed cycle, not only of the cycle over ``travel``. Default: ``travel``.

    ``bound``: a :class:`~weldplan.multi.result.LowerBound` already computed (e.g. once over
    the all-branch times while ``travel`` is calibrated round after round,
    :mod:`weldplan.multi.calibrate`); it is then reported as given and ``bound_travel`` is
    not read.

    ``conflicts``: the pairs of welds of two robots that meet (:class:`~weldplan.multi.
    allocate.PairCost`), charged in our allocation's search only (the baselines ignore them)."""
    settings = settings or AllocationSettings()
    problem = AllocationProblem.build(reach, weld_time, travel, settings.closed)
    for_bound = problem
    if bound is None and bound_travel is not None:
        for_bound = AllocationProblem.build(problem.reach, weld_time, bound_travel, settings.closed)
    seed = seed_of(rng)
    gen = as_generator(rng)
    ours = allocate(problem.reach, problem.weld_time, problem.travel, rng=gen, settings=settings,
                    conflicts=conflicts)  # fmt: skip
    if seed is not None:
        from dataclasses import replace

        ours = replace(ours, seed=seed)
    sub = int(gen.integers(2**31))
    return AllocationReport(
        ours=ours,
        bound=bound
        or lower_bound(for_bound, nodes=settings.milp_nodes, seconds=settings.milp_seconds),
        nearest=nearest_robot(problem, rng=sub, kicks=settings.final_kicks),
        one_robot=one_robot(problem, rng=sub, kicks=settings.final_kicks),
    )
