"""Lazy costs that converge (weld/converge.py): with an exact optimistic sequencer the rounds end
on the optimum over the true costs, having planned only some of the legs."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.optim.discrete.costs import cost_matrix
from weldplan.optim.discrete.sequence import solve_sequence
from weldplan.weld.converge import close_gap


def _station(n: int, seed: int):
    rng = np.random.default_rng(seed)
    P = rng.uniform(0.0, 1000.0, size=(n, 2))
    est = cost_matrix(P)  # straight lines: a lower bound of every leg
    detour = rng.uniform(1.0, 2.5, size=(n, n))
    detour = np.triu(detour, 1) + np.triu(detour, 1).T
    blocked = np.triu(rng.random((n, n)) < 0.4, 1)
    blocked = blocked | blocked.T
    true = np.where(blocked, est * detour, est)
    iu, ju = np.triu_indices(n, 1)
    pair_index = -np.ones((n, n), dtype=np.intp)
    pair_index[iu, ju] = pair_index[ju, iu] = np.arange(len(iu))
    known = ~blocked[iu, ju]
    return est, true, pair_index, known, iu, ju


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rounds_end_on_the_optimum_over_true_costs(seed: int) -> None:
    n = 11
    est, true, pair_index, known, iu, ju = _station(n, seed)
    C = est.copy()
    planned: list[int] = []
    n_blocked = int((~known).sum())

    def plan(pairs: list[int]) -> None:
        for p in pairs:
            if not known[p]:
                C[iu[p], ju[p]] = C[ju[p], iu[p]] = true[iu[p], ju[p]]
                known[p] = True
                planned.append(p)

    def known_first():
        # the route of the known legs only (unknown legs unusable): exact over them
        Ck = np.where(known[pair_index] | (pair_index < 0), C, np.inf)
        return solve_sequence(Ck, method="exact")

    seq0 = known_first()
    seq, info = close_gap(
        seq0,
        C,
        known,
        pair_index,
        optimistic=lambda Cb: solve_sequence(Cb, method="exact"),
        plan=plan,
        resequence=known_first,
        near=lambda pairs: [],
        target=0.0,
        max_rounds=100,
    )
    best = solve_sequence(true, method="exact").cost
    assert info.reason == "optimistic order is known"
    assert seq.cost == pytest.approx(best, rel=1e-12)
    o = np.asarray(seq.order)
    assert known[pair_index[o[:-1], o[1:]]].all()
    assert seq0.cost >= best  # the known-first route was no better to start with
    assert 0 < len(planned) < n_blocked  # lazy: some blocked legs never needed planning
    assert info.pairs_planned == len(planned)


def test_target_stops_early_and_the_route_uses_known_legs() -> None:
    n = 11
    est, true, pair_index, known, iu, ju = _station(n, 4)
    C = est.copy()

    def plan(pairs: list[int]) -> None:
        for p in pairs:
            C[iu[p], ju[p]] = C[ju[p], iu[p]] = true[iu[p], ju[p]]
            known[p] = True

    def known_first():
        Ck = np.where(known[pair_index] | (pair_index < 0), C, np.inf)
        return solve_sequence(Ck, method="exact")

    seq, info = close_gap(
        known_first(),
        C,
        known,
        pair_index,
        optimistic=lambda Cb: solve_sequence(Cb, method="exact"),
        plan=plan,
        resequence=known_first,
        near=lambda pairs: [],
        target=10.0,  # any route is within 1000 % of the optimistic order
        max_rounds=100,
    )
    assert info.rounds == 1 and info.pairs_planned == 0
    assert info.reason in ("within target of the optimistic order", "optimistic order is known")
    assert seq.cost <= 11.0 * info.optimistic_cost
