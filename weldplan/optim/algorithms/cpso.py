"""CPSO: PSO with logistic-map chaotic initialisation (003's baseline)."""

from __future__ import annotations

from typing import ClassVar, Literal

from weldplan.optim.algorithms.pso import C_003, PSO, W_003
from weldplan.optim.operators import LOGISTIC_MU


class CPSO(PSO):
    """003's CPSO: the initial swarm from the logistic map ``x <- mu x (1 - x)``, ``mu = 4``
    (003 eq. 4), then PSO with constant ``w = 0.7`` and ``c1 = c2 = 1.49445`` (003 section 4:
    "otherwise, the w is adapted as a constant 0.7")."""

    name: ClassVar[str] = "cpso"

    def __init__(
        self,
        pop_size: int = 30,
        w_start: float = W_003,
        w_end: float = W_003,
        c1: float = C_003,
        c2: float = C_003,
        v_max: float = 0.2,
        init: Literal["uniform", "logistic"] = "logistic",
        mu: float = LOGISTIC_MU,
    ) -> None:
        super().__init__(pop_size, w_start, w_end, c1, c2, v_max, init, mu)
