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


@pytest.mark.slow
def test_pipeline_closes_the_gap_on_a_car2_station() -> None:
    """17 car2 joints (above Held-Karp's discovery size): the default sequencer (nn + polish) with
    candidates ends within its target of the optimistic order, never below the proved bound,
    and no worse than the all-pairs route by more than the target."""
    from pathlib import Path

    from conftest import require_shared

    from weldplan.io.joints import Joints, read_joints
    from weldplan.io.mesh import load_part
    from weldplan.weld.cell import build_cell
    from weldplan.weld.pipeline import PlanConfig, plan_route
    from weldplan.weld.synthetic import CAR2_LENGTH_MM

    part = load_part(require_shared("bodies", "car2.obj"), length=CAR2_LENGTH_MM)
    root = Path(__file__).resolve().parents[1]
    j = read_joints(root / "assets" / "car2" / "car2_synthetic_50.csv")
    pick = np.sort(np.argsort(np.linalg.norm(j.xyz - j.xyz[0], axis=1))[:17])
    joints = Joints(
        ids=tuple(j.ids[k] for k in pick), xyz=j.xyz[pick], directions=j.directions[pick]
    )
    cell = build_cell(part, joints)
    cfg = PlanConfig(planner="exact", candidates=2)
    route = plan_route(cell, config=cfg, rng=0)
    s = route.stats
    assert s["sequence_method"] == "nn+polish"
    g = s["gap_rounds"]
    assert g is not None and g["rounds"] >= 1
    assert s["bound_planned"] <= route.length + 1e-6
    assert s["gap_planned"] == pytest.approx(s["sequence_cost"] / s["bound_planned"] - 1.0)
    slack = (s.get("sequence_engine") or {}).get("optimality_loss_bound", 0.0)  # fast-tsp only
    assert s["sequence_cost"] <= (1.0 + cfg.gap_target) * g["optimistic_cost"] + slack + 1e-6
    full = plan_route(cell, config=PlanConfig(planner="exact", pairs="all"), rng=0)
    assert full.stats["gap_rounds"] is None  # all pairs known: nothing to close
    assert route.length <= (1.0 + cfg.gap_target) * full.length + 2 * slack


def test_the_summary_names_the_gap_rounds() -> None:
    """The CLI's sequencer row says what the converging rounds did (nothing when none ran)."""
    from weldplan.commands._planning import _gap_rounds

    g = {"rounds": 3, "pairs_planned": 368, "reason": "within target of the optimistic order"}
    assert _gap_rounds(g) == (
        "; 3 gap round(s) planned 368 more pair(s) (within target of the optimistic order)"
    )
    assert _gap_rounds(None) == ""
