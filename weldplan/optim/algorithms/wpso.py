"""WPSO: PSO with the inertia weight falling linearly from 0.9 to 0.1 (003's baseline)."""

from __future__ import annotations

from typing import ClassVar, Literal

from weldplan.optim.algorithms.pso import C_003, PSO
from weldplan.optim.operators import LOGISTIC_MU


class WPSO(PSO):
    """PSO with ``w = 0.9 - 0.8 t / T`` (003 eq. 7) and ``c1 = c2 = 1.49445`` (003 section 4).

    003 section 4 prints "w is linearly changed from 0.1 to 0.9", while its eq. 7 decreases w
    from ``w_max`` to ``w_min``; we follow eq. 7 (0.9 -> 0.1), as the issue does.
    """

    name: ClassVar[str] = "wpso"

    def __init__(
        self,
        pop_size: int = 30,
        w_start: float = 0.9,
        w_end: float = 0.1,
        c1: float = C_003,
        c2: float = C_003,
        v_max: float = 0.2,
        init: Literal["uniform", "logistic"] = "uniform",
        mu: float = LOGISTIC_MU,
    ) -> None:
        super().__init__(pop_size, w_start, w_end, c1, c2, v_max, init, mu)
