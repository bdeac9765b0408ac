"""Small helpers shared by the algorithm files (schedules), kept out of the Optimizer base."""

from __future__ import annotations

from weldplan.optim.core import Context


def iteration_fraction(ctx: Context) -> float:
    """``t / T`` for the iteration now running, in ``(0, 1]``, for any kind of budget.

    Papers write schedules with a 1-based iteration counter ``t = 1..T`` (SMA's
    ``a = arctanh(1 - t/T)`` is infinite at ``t = 0``). With an iteration budget this is
    ``(ctx.iteration + 1) / max_iter``; with an evaluation or time budget it is the fraction of
    that budget already used (``ctx.progress``, positive once the initial population is
    evaluated); the larger of the two when several budgets are given.
    """
    f = ctx.progress
    if ctx.max_iter:
        f = max(f, (ctx.iteration + 1) / ctx.max_iter)
    return min(f, 1.0)
