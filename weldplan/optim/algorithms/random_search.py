"""Pure random search: the baseline every metaheuristic must beat at equal budget."""

from __future__ import annotations

from typing import ClassVar

from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import random_in_bounds


class RandomSearch(Optimizer):
    """Draw ``pop_size`` points uniformly in the box per iteration; keep nothing but the best.

    The best-so-far is tracked by :class:`~weldplan.optim.core.Context`, so there is no state.
    """

    name: ClassVar[str] = "random"

    def initialize(self, ctx: Context) -> None:
        ctx.evaluate(random_in_bounds(ctx.rng, ctx.lower, ctx.upper, self.pop_size))

    def step(self, ctx: Context) -> None:
        ctx.evaluate(random_in_bounds(ctx.rng, ctx.lower, ctx.upper, self.pop_size))
