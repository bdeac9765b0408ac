"""Multi-goal traversal on triangular-mesh maps (paper 002 sec. 3)."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from weldplan.errors import InputError
from weldplan.planar.multigoal import (
    KEY_SCALE,
    RandomKeyTourProblem,
    TourResult,
    available_tours,
    build_tour_graph,
    ground_truth,
    load_tour,
    plan_tour,
    polish_order,
    segments_clear,
    tour_from_dict,
    tour_lengths,
    two_opt_batch,
)


@pytest.fixture(scope="module")
def tour1():
    task = load_tour("tour-1")
    return task, build_tour_graph(task)


def test_shipped_scenarios_load_with_increasing_size():
    names = available_tours()
    assert names[:3] == ["tour-1", "tour-2", "tour-3"]
    sizes = [len(load_tour(n).goals) for n in names[:3]]
    assert sizes == sorted(sizes) and sizes[-1] == 14  # 002 Table 3: 14 targets
    for n in names[:3]:
        t = load_tour(n)
        assert t.max_edge == 10.0  # 002 sec. 2.2: M = 10 m on the 500 m maps
        assert t.scenario.bounds.tolist() == [0, 0, 500, 500]


def test_goal_inside_obstacle_names_the_field():
    data = json.loads(open(load_tour("tour-1").scenario.path).read())
    data["goals"][2] = [150.0, 150.0]  # centre of a circle
    with pytest.raises(InputError, match="inside an obstacle"):
        tour_from_dict(data, path="x.json")
    data["goals"] = []
    with pytest.raises(InputError) as exc:
        tour_from_dict(data, path="x.json")
    assert exc.value.field == "goals"


def test_random_key_decoding_and_lengths():
    rng = np.random.default_rng(0)
    P = rng.uniform(0, 10, size=(6, 2))
    D = np.linalg.norm(P[:, None] - P[None], axis=-1)
    prob = RandomKeyTourProblem(D)
    assert prob.n_var == 5
    np.testing.assert_allclose(prob.upper, KEY_SCALE * 5)
    X = rng.uniform(0, 50, size=(20, 5))
    O = prob.orders(X)
    assert all(sorted(o) == [1, 2, 3, 4, 5] for o in O.tolist())
    f = prob.evaluate(X)
    for o, v in zip(O, f, strict=True):
        seq = [0, *o, 0]
        assert v == pytest.approx(sum(D[a, b] for a, b in itertools.pairwise(seq)))


def test_two_opt_reaches_a_local_optimum_and_never_worsens():
    rng = np.random.default_rng(1)
    P = rng.uniform(0, 10, size=(10, 2))
    D = np.linalg.norm(P[:, None] - P[None], axis=-1)
    O = np.array([rng.permutation(9) + 1 for _ in range(30)])
    O2 = two_opt_batch(D, O)
    assert np.all(tour_lengths(D, O2) <= tour_lengths(D, O) + 1e-12)
    # no single reversal improves any result
    for o in O2:
        seq = [0, *o]
        base = tour_lengths(D, np.array([o]))[0]
        for i in range(1, 9):
            for j in range(i + 1, 10):
                s2 = seq[:i] + seq[i : j + 1][::-1] + seq[j + 1 :]
                assert tour_lengths(D, np.array([s2[1:]]))[0] >= base - 1e-9


def test_polish_order_never_longer_and_reaches_the_optimum(tour1):
    _, g = tour1
    _, opt, _ = ground_truth(g)
    t = g.dist.shape[0] - 1
    rng = np.random.default_rng(2)
    for _ in range(5):
        o = rng.permutation(t) + 1
        before = tour_lengths(g.dist, o[None])[0]
        new, length = polish_order(g.dist, o, rng)
        assert sorted(new.tolist()) == list(range(1, t + 1))
        assert length == pytest.approx(tour_lengths(g.dist, new[None])[0], rel=1e-12)
        assert length <= before + 1e-9
        assert length == pytest.approx(opt, rel=1e-9)  # 8 targets: the ILS finds the optimum


def test_default_polishes_the_optimiser_order_and_keeps_both(tour1):
    task, g = tour1
    kw = dict(graph=g, pop_size=6, max_iter=3, rng=4, smooth=False)
    raw = plan_tour(task, "isma", polish=False, **kw)
    pol = plan_tour(task, "isma", **kw)
    assert not raw.polished and raw.optimizer_length == raw.length
    assert pol.polished and pol.params["polish"]
    # same optimiser run (the polish comes after it), then a tour no longer than it
    assert pol.optimizer_length == raw.length
    assert pol.length <= raw.length + 1e-9
    assert pol.gap == pytest.approx(0.0, abs=1e-9)
    assert raw.gap > 0.01  # a starved ISMA as printed misses the optimum
    assert pol.optimizer_gap == pytest.approx(raw.gap)


def test_ground_truth_is_the_brute_force_optimum(tour1):
    _, g = tour1
    order, length, method = ground_truth(g)
    perms = np.array(list(itertools.permutations(range(1, g.dist.shape[0]))))
    assert method == "exact"
    assert length == pytest.approx(tour_lengths(g.dist, perms).min(), rel=1e-12)
    assert tour_lengths(g.dist, np.array([order]))[0] == pytest.approx(length, rel=1e-12)


def test_isma_tour_visits_every_goal_once_returns_and_is_collision_free(tour1):
    task, g = tour1
    r = plan_tour(task, "isma", graph=g, pop_size=60, max_iter=60, rng=3)
    assert sorted(r.order) == list(range(1, len(task.goals) + 1))
    P = r.points_array
    np.testing.assert_allclose(P[0], task.scenario.start)
    np.testing.assert_allclose(P[-1], task.scenario.start)
    # the smoothed curve passes through every goal (multiplicity-3 control points)
    d = np.linalg.norm(P[:, None] - task.goals[None], axis=-1).min(axis=0)
    assert np.all(d < 1e-6)
    # and in the order chosen
    first_hit = [int(np.argmin(np.linalg.norm(P - task.goals[k - 1], axis=1))) for k in r.order]
    assert first_hit == sorted(first_hit)
    assert r.smoothed and r.collision_free
    assert segments_clear(task.scenario.world, P[:-1], P[1:]).all()
    assert task.scenario.world.clearance(P).min() > -1e-9 * task.scenario.world.scale
    # default: any-angle legs (Polyanya's exact paths, already taut: the spline keeps their
    # corners), and the tour is not shorter than the optimum over the same costs
    assert r.metric == "any-angle" and r.pipeline == "default"
    assert r.polyline_length == pytest.approx(r.length, rel=1e-9)
    assert r.smooth_length <= r.length * (1 + 1e-9)
    assert r.length >= r.optimum - 1e-9 and r.optimum == pytest.approx(r.exact_optimum)
    assert r.gap < 0.02


def test_taut_legs_are_shorter_than_the_mesh_edges_and_collision_free(tour1):
    task, g = tour1
    edge = plan_tour(task, "exact", graph=g, taut=False)
    taut = plan_tour(task, "exact", graph=g, metric="mesh")
    assert edge.metric == taut.metric == "mesh"
    assert edge.order == taut.order and edge.length == taut.length
    assert edge.polyline_length == pytest.approx(edge.length, rel=1e-12)
    assert taut.polyline_length < 0.97 * edge.length  # the zig-zag costs > 3 % here
    assert taut.smooth_length < edge.smooth_length
    assert taut.collision_free and taut.smoothed
    P = taut.points_array
    assert segments_clear(task.scenario.world, P[:-1], P[1:]).all()
    # every goal is still visited, in order
    d = np.linalg.norm(P[:, None] - task.goals[None], axis=-1).min(axis=0)
    assert np.all(d < 1e-6)


def test_same_seed_same_result_and_json_round_trip(tour1):
    task, g = tour1
    a = plan_tour(task, "sma", graph=g, pop_size=20, max_iter=10, rng=5, smooth=False)
    b = plan_tour(task, "sma", graph=g, pop_size=20, max_iter=10, rng=5, smooth=False)
    assert a.order == b.order and a.length == b.length
    c = TourResult.from_json(a.to_json())
    assert c == a


@pytest.mark.slow
def test_starved_budget_does_measurably_worse():
    task = load_tour("tour-3")
    g = build_tour_graph(task)
    _, opt, _ = ground_truth(g)
    full = [
        plan_tour(
            task,
            "isma",
            graph=g,
            optimum=opt,
            rng=s,
            two_opt=True,
            polish=False,
            pop_size=50,
            max_iter=50,
            smooth=False,
        ).gap
        for s in range(2)
    ]
    starved = [
        plan_tour(
            task,
            "isma",
            graph=g,
            optimum=opt,
            rng=s,
            pop_size=4,
            max_iter=2,
            smooth=False,
            polish=False,
        ).gap
        for s in range(3)
    ]
    assert max(full) < 0.02
    assert np.mean(starved) > max(full) + 0.05


def test_cli_planar_tour_prints_table_and_plots(tmp_path, capsys):
    from weldplan.cli import main

    png = tmp_path / "t.png"
    rc = main(
        ["planar", "tour", "tour-1", "--order-by", "sma,exact", "--pop", "20", "--iters", "10",
         "--seed", "1", "--plot", str(png)]
    )  # fmt: skip
    out = capsys.readouterr().out
    assert rc == 0
    assert "exact" in out and "sma" in out and "+0.00 %" in out
    assert png.stat().st_size > 10_000
    rc = main(["planar", "tour", "tour-1", "--order-by", "exact", "--json"])
    rows = json.loads(capsys.readouterr().out)
    assert rc == 0 and rows[0]["algorithm"] == "exact" and rows[0]["collision_free"]
    # as paper 002: the optimiser as printed, the B-spline over the mesh-edge legs
    rc = main(["planar", "tour", "tour-1", "--order-by", "sma", "--pop", "6", "--iters", "3",
               "--seed", "1", "--no-polish", "--no-funnel", "--json"])  # fmt: skip
    (raw,) = json.loads(capsys.readouterr().out)
    assert rc == 0 and not raw["polished"] and raw["length"] == raw["optimizer_length"]
    assert raw["polyline_length"] == pytest.approx(raw["length"])


def test_cli_planar_tour_rejects_unknown_algorithm(capsys):
    from weldplan.cli import main

    assert main(["planar", "tour", "tour-1", "--order-by", "nope"]) == 2
    assert "--order-by" in capsys.readouterr().err


@pytest.mark.slow
def test_bench_tour_writes_tables(tmp_path):
    from weldplan.cli import main

    rc = main(
        ["bench", "tour", "--runs", "1", "--pop", "10", "--iters", "5", "--m-values", "50",
         "--maps", "tour-1,tour-3", "--out", str(tmp_path)]
    )  # fmt: skip
    text = (tmp_path / "tour.md").read_text()
    assert rc == 0
    assert "Table 4" in text and "Table 3" in text and "ISMA memetic" in text
    assert "ISMA as printed" in text and "polish alone" in text and "String pulling" in text
    assert (tmp_path / "tour-tour-3.png").exists() and (tmp_path / "tour-table3.png").exists()
    # the default pipeline beside paper 002 as printed, gaps to the exact any-angle tour
    assert "Any-angle leg costs" in text
    rows = [r.split("|")[1:-1] for r in text.splitlines() if r.startswith("| tour-")]
    aa = {(c[0].strip(), c[2].strip()): c for c in rows if len(c) == 12}
    gap = {k: float(c[5].strip(" %")) for k, c in aa.items()}
    for m in ("tour-1", "tour-3"):
        assert gap[(m, "default")] < gap[(m, "as printed (002)")]
        assert aa[(m, "default")][9].strip() == aa[(m, "default")][10].strip() == "1/1"


def test_navmesh_tour_on_polyanya_arena():
    """Polyanya's arena navmesh as a real multi-goal map: the ISMA tour equals the ground
    truth on 8 targets, and the smoothed path stays in the navmesh."""
    from conftest import require_shared

    from weldplan.planar.exact import MeshFreeSpace
    from weldplan.planar.multigoal import navmesh_tour

    space = MeshFreeSpace.read(require_shared("meshmaps", "arena.mesh"))
    rng = np.random.default_rng(0)
    P = rng.uniform(space.vertices_xy.min(0), space.vertices_xy.max(0), size=(200, 2))
    P = P[space.contains_free(P)][:9]
    task = navmesh_tour(space, P[0], P[1:], label="arena")
    r = plan_tour(task, "isma", pop_size=100, max_iter=100, rng=0)
    assert sorted(r.order) == list(range(1, 9))
    assert r.gap < 0.02
    assert r.collision_free
    Q = r.points_array
    assert space.contains_free(Q).all()
    with pytest.raises(InputError):
        navmesh_tour(space, [-100.0, -100.0], P[1:])


@pytest.mark.slow
def test_navmesh_tour_on_polyanya_aurora():
    """The large aurora navmesh (35k boundary edges): the mesh builds, the tour reaches the
    ground truth, and the Polyanya legs and the smoothed path stay in the navmesh (its exact
    segment check runs through the edge grid instead of all-pairs arrays)."""
    from conftest import require_shared

    from weldplan.planar.exact import MeshFreeSpace
    from weldplan.planar.multigoal import navmesh_tour

    space = MeshFreeSpace.read(require_shared("meshmaps", "aurora.mesh"))
    assert len(space.edge_a) > 30000
    rng = np.random.default_rng(0)
    P = rng.uniform(space.vertices_xy.min(0), space.vertices_xy.max(0), size=(100, 2))
    P = P[space.contains_free(P)][:6]
    task = navmesh_tour(space, P[0], P[1:], label="aurora")
    r = plan_tour(task, "isma", pop_size=40, max_iter=40, rng=0)
    assert sorted(r.order) == list(range(1, 6))
    assert r.gap == pytest.approx(0.0, abs=1e-9)
    # default: Polyanya's legs on the navmesh itself, judged by the independent segment check
    assert r.metric == "any-angle" and r.legs_collision_free
    assert r.collision_free and r.polyline_length == pytest.approx(r.length, rel=1e-9)
    Q = r.points_array
    assert space.contains_free(Q).all()
    assert segments_clear(space, Q[:-1], Q[1:]).all()


def test_house_floorplan_tour():
    """rtb-data's house.mat: 11 named places from the kitchen; ISMA (paper budget) within 2 %
    of the ground truth, smoothed tour inside free cells, and the grid outline check agrees
    with the cells."""
    pytest.importorskip("rtbdata")
    from weldplan.planar.multigoal import SampledGridWorld, house_tour

    task = house_tour()
    assert len(task.goals) == 11
    r = plan_tour(task, "isma", rng=0)
    assert sorted(r.order) == list(range(1, 12))
    assert r.gap < 0.02 and r.smoothed and r.collision_free
    w = task.world
    assert isinstance(w, SampledGridWorld)
    # the final judge is the exact check on the 3,838 grid rectangles (it used to stall there)
    ex = task.exact_world
    assert len(ex.rectangles) == 3838 + 4  # and the map frame
    P = r.points_array
    assert segments_clear(ex, P[:-1], P[1:]).all()
    # a segment straight through a wall is caught
    occ = task.scenario.grid.occupied
    i, j = np.argwhere(occ)[len(np.argwhere(occ)) // 2]
    c = task.scenario.grid.centre(np.array([i, j]))
    assert not w.segments_free(c[None] - [0.3, 0.0], c[None] + [0.3, 0.0])[0]
