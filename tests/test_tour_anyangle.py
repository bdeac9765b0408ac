"""Multi-goal tours over exact any-angle leg costs (Polyanya), the exact optimal tour beside
every answer, and paper 002 as printed one keyword away."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from weldplan.errors import ConfigError
from weldplan.planar.exact import visibility_shortest_path
from weldplan.planar.multigoal import build_tour_graph, load_tour, segments_clear, tour_lengths
from weldplan.planar.tour_anyangle import build_anyangle_graph
from weldplan.planar.tour_planner import ground_truth, plan_tour
from weldplan.planar.tour_settings import TourSettings


@pytest.fixture(scope="module")
def tour1():
    task = load_tour("tour-1")
    return task, build_tour_graph(task), build_anyangle_graph(task)


@pytest.mark.parametrize(
    "name, pairs",
    [("tour-1", [(0, 3), (2, 6), (5, 8)]), ("tour-2", [(0, 11), (3, 7)])],
)
def test_polyanya_legs_equal_the_visibility_graph(name, pairs):
    """An independent any-angle answer (visibility graph + A*, the same circle polygons):
    Polyanya's leg lengths equal it, and its path is that long."""
    task = load_tour(name)
    g = build_anyangle_graph(task)
    sc = task.scenario
    for a, b in pairs:
        vg = visibility_shortest_path(sc.world, task.stops[a], task.stops[b], bounds=sc.bounds)
        assert g.dist[a, b] == pytest.approx(vg.length, rel=1e-9)
        leg = g.leg(a, b)
        assert np.linalg.norm(np.diff(leg, axis=0), axis=1).sum() == pytest.approx(
            g.dist[a, b], rel=1e-12
        )


def test_anyangle_matrix_is_symmetric_shorter_than_mesh_edges_and_its_legs_are_free(tour1):
    task, mesh_g, g = tour1
    k = len(task.stops)
    assert g.n_queries == k * (k - 1) // 2
    np.testing.assert_array_equal(g.dist, g.dist.T)
    assert np.all(np.diag(g.dist) == 0)
    # the mesh-edge paths are feasible any-angle paths: never shorter, here 1-7 % longer
    off = ~np.eye(k, dtype=bool)
    ratio = mesh_g.dist[off] / g.dist[off]
    assert ratio.min() >= 1 - 1e-12 and ratio.max() > 1.01
    # straight line <= leg, and every leg passes the exact obstacle check
    straight = np.linalg.norm(task.stops[:, None] - task.stops[None], axis=-1)
    assert np.all(g.dist >= straight - 1e-9)
    for a, b in itertools.combinations(range(k), 2):
        P = g.leg(a, b)
        np.testing.assert_allclose(P[[0, -1]], task.stops[[a, b]])
        assert segments_clear(task.exact_world, P[:-1], P[1:]).all()
        np.testing.assert_array_equal(g.leg(b, a), P[::-1])


def test_exact_optimum_is_the_brute_force_any_angle_tour(tour1):
    _, _, g = tour1
    order, length, method = ground_truth(g)
    perms = np.array(list(itertools.permutations(range(1, g.dist.shape[0]))))
    assert method == "exact"
    assert length == pytest.approx(tour_lengths(g.dist, perms).min(), rel=1e-12)


def test_default_reaches_the_exact_any_angle_optimum_with_free_legs(tour1):
    task, mesh_g, g = tour1
    r = plan_tour(task, graph=mesh_g, anyangle=g, pop_size=30, max_iter=30, rng=1)
    _, exact, _ = ground_truth(g)
    assert r.pipeline == "default" and r.metric == "any-angle" and r.polished
    assert r.exact_optimum == pytest.approx(exact, rel=1e-12)
    assert r.length == pytest.approx(exact, rel=1e-9)  # 8 targets: the polish reaches it
    assert r.legs_collision_free and r.collision_free
    assert abs(r.exact_gap) < 1e-6
    # stages: the optimiser's own order, then the polish, then the spline; lengths match
    names = [s[0] for s in r.stages]
    assert names == ["order", "polish", "spline"]
    assert r.stages[0][1] == pytest.approx(r.optimizer_length)
    assert r.stages[1][1] == pytest.approx(r.length)
    assert r.stages[2][1] == pytest.approx(r.smooth_length)


def test_as_printed_is_paper_002_and_further_from_the_optimum(tour1):
    task, mesh_g, g = tour1
    kw = dict(graph=mesh_g, anyangle=g, pop_size=30, max_iter=30, rng=1)
    p = plan_tour(task, as_printed=True, **kw)
    d = plan_tour(task, **kw)
    assert p.pipeline == "as-printed" and p.metric == "mesh"
    assert not p.polished and p.optimizer_length == p.length
    # mesh-edge legs: the polyline is the ordering cost itself (no funnel)
    assert p.polyline_length == pytest.approx(p.length, rel=1e-9)
    assert [s[0] for s in p.stages] == ["order", "spline"]
    assert p.exact_optimum == d.exact_optimum
    assert p.exact_gap > 0.01 > d.exact_gap
    assert p.collision_free
    # the same flags one at a time give the same as-printed run
    q = plan_tour(task, polish=False, taut=False, **kw)
    assert q.pipeline == "as-printed" and q.order == p.order and q.length == p.length


def test_contradictory_settings_are_config_errors_naming_the_field(tour1):
    task, mesh_g, g = tour1
    with pytest.raises(ConfigError, match="taut") as info:
        plan_tour(task, anyangle=g, metric="any-angle", taut=False, pop_size=4, max_iter=2)
    assert info.value.field == "taut"
    with pytest.raises(ConfigError, match="metric"):
        plan_tour(task, anyangle=g, metric="octile", pop_size=4, max_iter=2)
    with pytest.raises(ConfigError, match="as_printed") as info:
        TourSettings(as_printed=True, metric="any-angle")
    assert info.value.field == "metric"


def test_a_settings_object_and_its_keywords_plan_the_same_tour(tour1):
    task, mesh_g, g = tour1
    st = TourSettings(metric="mesh", pop_size=20, max_iter=15, polish=False)
    a = plan_tour(task, "sma", st, graph=mesh_g, anyangle=g, rng=2, smooth=False)
    b = plan_tour(task, "sma", graph=mesh_g, anyangle=g, rng=2, metric="mesh", pop_size=20,
                  max_iter=15, polish=False, smooth=False)  # fmt: skip
    assert a.order == b.order and a.length == b.length and a.params == b.params
    assert a.metric == "mesh" and a.pipeline == "custom" and not a.polished
    assert a.params["max_iter"] == 15 and a.params["pop_size"] == 20


def test_cli_tour_default_and_as_printed_summaries(capsys):
    from weldplan.cli import main

    args = ["planar", "tour", "tour-1", "--pop", "20", "--iters", "10", "--seed", "2"]
    assert main([*args, "--order-by", "isma"]) == 0
    out = capsys.readouterr().out
    assert "pipeline   default" in out and "exact optimum" in out
    assert "polish" in out and "spline" in out
    assert main([*args, "--order-by", "isma", "--as-printed"]) == 0
    out = capsys.readouterr().out
    assert "pipeline   as printed" in out and "\npolish " not in out
    assert main([*args, "--order-by", "isma", "--as-printed", "--metric", "any-angle"]) == 2
