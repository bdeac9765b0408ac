"""plan_route: lazy pair planning is exact, executors do not change the route, failures are clear.

Fast properties run on a small box cell (a floor and a wall, grids by the exact box distance of
tests/_boxcell.py); the demo cell checks the whole pipeline against Held-Karp and the paper.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from types import SimpleNamespace

import numpy as np
import pytest

from weldplan.errors import PlanningError, WeldplanError
from weldplan.weld import pairtasks, pipeline
from weldplan.weld.pipeline import PlanConfig, plan_route, straight_lower_bound
from weldplan.weld.verify import verify_route

IDS = tuple("ABCDEF")
XYZ = np.array([[-40, 0, 0], [40, 0, 0], [-40, 60, 0], [40, -30, 0], [-60, -30, 0], [30, 40, 0.0]])


@pytest.fixture(scope="module")
def cell():
    from tests._boxcell import box_cell

    boxes = [
        (np.array([-100.0, -100.0, -2.0]), np.array([100.0, 100.0, 0.0])),  # floor
        (np.array([-1.0, -50.0, 0.0]), np.array([1.0, 50.0, 60.0])),  # wall at x = 0
    ]
    bc = box_cell(boxes, np.array([-100.0, -100.0, -10.0]), np.array([100.0, 100.0, 100.0]))
    vidx = np.array([bc.virtual(p) for p in XYZ])
    return SimpleNamespace(
        part=bc.collision.mesh,
        joints=SimpleNamespace(ids=IDS, xyz=XYZ, directions=None),
        grid=bc.grid,
        collision=bc.collision,
        virtual_index=vidx,
        virtual_xyz=bc.grid.index_to_world(vidx),
        clearance=5.0,
        pitch=5.0,
    )


def _legs(route):
    return [(g.from_id, g.to_id, g.points.tobytes()) for g in route.legs]


def test_route_visits_every_joint_and_verifies(cell):
    r = plan_route(cell, rng=0)
    assert sorted(r.order) == sorted(IDS)
    assert verify_route(r, cell.part).ok
    assert r.lower_bound <= r.length
    # the measure between virtual joints has its own bound, over the virtual joints
    V = np.asarray(cell.virtual_xyz, dtype=float)
    assert r.stats["bound_virtual"] == pytest.approx(straight_lower_bound(V)[0])
    assert r.stats["bound_virtual"] <= r.inner_length * (1 + 1e-12)
    assert r.stats["pairs"] == 15
    assert r.stats["pairs_straight"] + r.stats["pairs_blocked"] == 15
    assert r.stats["pairs_blocked"] > 0  # the wall blocks the pairs across it
    assert r.settings["clearance"] == 5.0 and r.seed == 0
    for leg in r.legs:
        np.testing.assert_array_equal(leg.points[0], XYZ[IDS.index(leg.from_id)])
        np.testing.assert_array_equal(leg.points[-1], XYZ[IDS.index(leg.to_id)])


def test_lazy_exact_pipeline_is_the_optimum_over_all_pairs(cell):
    """Lazy planning (estimates = straight lower bounds) loses nothing with an exact sequencer."""
    from weldplan.optim.discrete.sequence import solve_sequence
    from weldplan.weld.local import plan_pair

    lazy = plan_route(cell, config=PlanConfig(planner="exact", sequencer="exact"))
    full = plan_route(cell, config=PlanConfig(planner="exact", sequencer="exact", pairs="all"))
    assert full.stats["pairs_planned"] == full.stats["pairs_blocked"]
    assert lazy.stats["pairs_planned"] < full.stats["pairs_planned"]
    # brute force: every pair planned by hand, Held-Karp over the full matrix
    n = len(IDS)
    C = np.zeros((n, n))
    V = cell.virtual_xyz
    for i in range(n):
        for j in range(i + 1, n):
            if cell.collision.segment_free(V[i], V[j], 5.0):
                c = sum(np.linalg.norm(d) for d in (XYZ[i] - V[i], V[i] - V[j], V[j] - XYZ[j]))
            else:
                c = plan_pair(cell, i, j, method="exact").length
            C[i, j] = C[j, i] = c
    best = solve_sequence(C, method="exact").cost
    assert lazy.length == pytest.approx(best, rel=1e-9)
    assert full.length == pytest.approx(best, rel=1e-9)
    # the bound over the planned legs: below the all-pairs optimum, and equal to it here
    for route in (lazy, full):
        assert route.stats["bound_planned_method"] == "held-karp"
        assert route.stats["bound_planned"] <= best * (1 + 1e-12)
        assert route.stats["bound_planned"] == pytest.approx(best, rel=1e-9)


def test_bound_of_planned_legs_on_a_larger_cell_is_a_1tree_bound_below_the_route(cell):
    """Above 16 joints the bound over the planned legs is Held-Karp's 1-tree bound: below the
    route and below the exact optimum over the all-pairs costs, above the spanning tree."""
    from scipy.sparse.csgraph import minimum_spanning_tree

    small = plan_route(cell, config=PlanConfig(planner="exact", sequencer="exact"))
    exact = small.stats["bound_planned"]
    try:
        pipeline.LOWER_BOUND_EXACT_MAX, old = 2, pipeline.LOWER_BOUND_EXACT_MAX
        r = plan_route(cell, config=PlanConfig(planner="exact", sequencer="pso"), rng=0)
    finally:
        pipeline.LOWER_BOUND_EXACT_MAX = old
    assert r.stats["bound_planned_method"] == "1-tree"
    assert r.stats["bound_planned"] <= exact * (1 + 1e-9) <= r.length * (1 + 1e-9)
    P = np.asarray(XYZ, dtype=float)
    assert (
        r.stats["bound_planned"]
        > minimum_spanning_tree(np.linalg.norm(P[:, None] - P[None], axis=-1)).sum()
    )


def test_a_spent_refinement_cap_is_named_and_marks_the_route_not_reproducible(cell):
    from weldplan.station.summary import clock_caps

    free = plan_route(cell, config=PlanConfig(pairs="all"), rng=0)
    assert free.stats["clock_stops"] == {
        "refine_pairs": [], "lower_bound": False, "bound_planned": False,
    }  # fmt: skip
    assert clock_caps(free) == []
    # a zero CPU cap: every refinement that has rounds to run is stopped by it
    starved = plan_route(cell, config=PlanConfig(pairs="all", aco={"refine_budget": 0.0}), rng=0)
    refined = sorted(k for k, v in starved.stats["local_paths"].items() if v["method"] == "exact")
    pairs = starved.stats["clock_stops"]["refine_pairs"]
    assert pairs and set(pairs) <= set(refined)
    assert clock_caps(starved) == [
        f"{len(pairs)} local path refinement(s) stopped by their CPU cap ("
        + ", ".join(pairs[:5]) + (", ..." if len(pairs) > 5 else "") + ")"
    ]  # fmt: skip


def test_same_seed_same_route_and_executor_does_not_matter(cell):
    cfg = PlanConfig(pairs="all", aco={"n_iterations": 3, "n_ants": 4})
    a = plan_route(cell, config=cfg, rng=3)
    b = plan_route(cell, config=cfg, rng=3)
    with ThreadPoolExecutor(2) as ex:
        c = plan_route(cell, config=cfg, rng=3, executor=ex)
    assert a.order == b.order == c.order
    assert _legs(a) == _legs(b) == _legs(c)


def test_progress_reports_each_stage(cell):
    seen = []
    plan_route(cell, rng=0, progress=lambda s, d, t: seen.append((s, d, t)))
    stages = {s for s, _, _ in seen}
    assert {"straight", "sequence"} <= stages
    assert all(0 <= d <= t for _, d, t in seen)


def test_lower_bound_is_held_karp_over_straight_distances():
    lb, how = straight_lower_bound(XYZ)
    assert how == "held-karp"
    import itertools

    D = np.linalg.norm(XYZ[:, None] - XYZ[None], axis=-1)
    brute = min(
        sum(D[p[k], p[k + 1]] for k in range(len(p) - 1))
        for p in itertools.permutations(range(len(XYZ)))
    )
    assert lb == pytest.approx(brute)
    many = np.random.default_rng(0).uniform(0, 100, (20, 3))
    lb20, how20 = straight_lower_bound(many)
    D20 = np.linalg.norm(many[:, None] - many[None], axis=-1)
    from scipy.sparse.csgraph import minimum_spanning_tree

    from weldplan.optim.discrete.sequence import solve_sequence

    # the 1-tree bound: above the spanning tree, never above an actual open path
    assert how20 == "1-tree" and minimum_spanning_tree(D20).sum() < lb20
    assert lb20 <= solve_sequence(D20, method="exact").cost + 1e-9
    assert straight_lower_bound(XYZ[:1]) == (0.0, "trivial")


def test_failed_local_paths_give_a_planning_error_naming_pairs(cell, monkeypatch):
    blocked = SimpleNamespace(**vars(cell))
    blocked.collision = SimpleNamespace(segments_free=lambda A, B, r: np.zeros(len(A), dtype=bool))

    def fail_for_A(cell_, i, j, *a):
        from weldplan.weld.local import LocalPath

        if 0 in (i, j):
            return LocalPath(np.zeros((0, 3)), np.inf, np.inf, "so-aco", False, reason="dead end")
        P = np.array([XYZ[i], cell.virtual_xyz[i], cell.virtual_xyz[j], XYZ[j]])
        return LocalPath(
            P, float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum()), 0.0, "so-aco", True
        )

    monkeypatch.setattr(pairtasks, "_plan_pair_task", fail_for_A)
    with pytest.raises(PlanningError, match="A-B"):
        plan_route(blocked, config=PlanConfig(pairs="all"), rng=0)


def test_config_validation_and_round_trip():
    with pytest.raises(WeldplanError, match="unknown planner"):
        PlanConfig(planner="astar")
    with pytest.raises(WeldplanError, match="clearance"):
        PlanConfig(clearance=-1)
    cfg = PlanConfig(sequencer="pso", aco={"n_iterations": 5, "n_ants": 5})
    assert PlanConfig.from_dict(cfg.to_dict()) == cfg


# ---------------------------------------------------------------------------- the demo cell
@pytest.fixture(scope="module")
def demo():
    cell_mod = pytest.importorskip("weldplan.weld.cell")
    return cell_mod.demo_cell()


@pytest.mark.slow
def test_demo_so_aco_pso_within_2_percent_of_exact_held_karp(demo):
    fast = plan_route(demo, config=PlanConfig(planner="so-aco", sequencer="pso"), rng=0)
    exact = plan_route(demo, config=PlanConfig(planner="exact", sequencer="exact"))
    assert verify_route(fast, demo.part, joints=demo.joints).ok
    assert verify_route(exact, demo.part, joints=demo.joints).ok
    assert fast.lower_bound == pytest.approx(595.10, abs=0.01)  # DESIGN.md, Held-Karp
    # both planners' legs go through the same refinement, which stops when a round gains less
    # than 1e-4 of the length (weldplan.weld.taut): refined legs agree to that, not to rounding
    assert exact.lower_bound <= exact.length <= fast.length * (1 + 1e-4)
    assert fast.length <= 1.02 * exact.length


@pytest.mark.slow
def test_demo_starved_sequencer_does_worse(demo):
    good = plan_route(demo, config=PlanConfig(planner="exact", sequencer="exact"))
    starved = plan_route(
        demo,
        config=PlanConfig(
            planner="exact",
            sequencer="pso",
            polish=False,
            pso={"iterations": 1, "particles": 2},
        ),
        rng=0,
    )
    assert starved.length > 1.05 * good.length


@pytest.mark.slow
def test_demo_verifier_catches_a_detour_cut_through_the_panel(demo):
    from weldplan.weld.route import Leg, Route

    r = plan_route(demo, config=PlanConfig(planner="exact", sequencer="exact"))
    k = next(k for k, g in enumerate(r.legs) if g.method != "straight")
    g = r.legs[k]
    cut = Leg(g.from_id, g.to_id, g.points[[0, 1, -2, -1]], g.method)  # the blocked straight line
    legs = list(r.legs)
    legs[k] = cut
    bad = Route(r.order, tuple(legs), r.joint_ids, r.joint_xyz, r.directions, r.virtual_xyz)
    rep = verify_route(bad, demo.part, joints=demo.joints)
    assert [(v.leg, v.segment) for v in rep.violations] == [(k, 1)]
    short = Route(r.order[:-1], r.legs[:-1], r.joint_ids, r.joint_xyz, r.directions, r.virtual_xyz)
    rep = verify_route(short, demo.part, joints=demo.joints)
    assert [v.kind for v in rep.violations] == ["missing"]


def test_process_pool_gives_the_serial_route(cell):
    from concurrent.futures import ProcessPoolExecutor

    cfg = PlanConfig(pairs="all", aco={"n_iterations": 3, "n_ants": 4})
    serial = plan_route(cell, config=cfg, rng=5)
    with ProcessPoolExecutor(2) as ex:
        pooled = plan_route(cell, config=cfg, rng=5, executor=ex)
    assert _legs(pooled) == _legs(serial)


def test_joints_in_separate_regions_are_named_as_groups(cell, monkeypatch):
    blocked = SimpleNamespace(**vars(cell))
    blocked.collision = SimpleNamespace(segments_free=lambda A, B, r: np.zeros(len(A), dtype=bool))
    from weldplan.weld.local import LocalPath

    def two_sides(cell_, i, j, *a):
        if (i < 3) != (j < 3):  # {A, B, C} cannot reach {D, E, F}
            return LocalPath(np.zeros((0, 3)), np.inf, np.inf, "so-aco", False, reason="walled")
        P = np.array([XYZ[i], cell.virtual_xyz[i], cell.virtual_xyz[j], XYZ[j]])
        L = float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())
        return LocalPath(P, L, 0.0, "so-aco", True)

    monkeypatch.setattr(pairtasks, "_plan_pair_task", two_sides)
    with pytest.raises(PlanningError, match=r"2 groups .*\{A, B, C\} \{D, E, F\}"):
        plan_route(blocked, config=PlanConfig(pairs="all"), rng=0)
