"""Triangular-mesh maps (paper 002, sec. 2): matrices, graph, shortest paths against the
visibility graph, paper 002's rule for M, Polyanya meshes."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from conftest import require_shared

from weldplan.geometry.obstacles2d import Obstacles2D
from weldplan.planar.exact import (
    MeshFreeSpace,
    VisibilityGraph,
    read_scen,
    visibility_shortest_path,
)
from weldplan.planar.meshmap import max_edge_rule, triangulate_map, triangulate_navmesh
from weldplan.planar.scenarios import load_scenario


def test_square_obstacle_exact_detour():
    # one 4 x 4 square in a 10 x 10 map; start and goal on either side: the shortest path goes
    # around a corner, length 2 * hypot(3, 2) + ... computed by the visibility graph
    obs = Obstacles2D(rectangles=[[3.0, 3.0, 7.0, 7.0]])
    s, g = np.array([1.0, 5.0]), np.array([9.0, 5.0])
    exact = 2 * np.hypot(2.0, 2.0) + 4.0  # (1,5)->(3,7)->(7,7)->(9,5)
    tm = triangulate_map(obs, [0, 0, 10, 10], 0.5, points=[s, g])
    pts, L = tm.shortest_path(*tm.terminals)
    assert L >= exact - 1e-9
    assert L <= 1.08 * exact
    np.testing.assert_allclose(pts[0], s)
    np.testing.assert_allclose(pts[-1], g)
    assert obs.segments_free(pts[:-1], pts[1:]).all()


def test_matrices_are_consistent():
    sc = load_scenario("map20-1")
    tm = triangulate_map(sc.obstacles, sc.bounds, 1.0, points=[sc.start, sc.goal])
    assert tm.cells.shape[1] == 3 and tm.cells.max() < tm.n_nodes
    # every edge (T, S) is a side of some cell and D is its length
    sides = np.concatenate([tm.cells[:, [0, 1]], tm.cells[:, [1, 2]], tm.cells[:, [2, 0]]])
    sides = {tuple(e) for e in np.sort(sides, axis=1).tolist()}
    edges = set(zip(tm.edge_t.tolist(), tm.edge_s.tolist(), strict=True))
    assert edges == sides
    np.testing.assert_allclose(
        tm.edge_d, np.linalg.norm(tm.nodes[tm.edge_t] - tm.nodes[tm.edge_s], axis=1)
    )
    # every triangle is free space, every node inside the map
    cen = tm.nodes[tm.cells].mean(axis=1)
    assert not sc.obstacles.contains(cen).any()
    assert (tm.nodes >= sc.bounds[:2] - 1e-9).all() and (tm.nodes <= sc.bounds[2:] + 1e-9).all()
    np.testing.assert_allclose(tm.nodes[tm.terminals], [sc.start, sc.goal])
    # Triangle bounds the area; the longest edges stay close to M
    assert tm.longest_edge <= 1.5


def test_networkx_graph_agrees_with_dijkstra():
    sc = load_scenario("circles-1")
    tm = triangulate_map(sc.obstacles, sc.bounds, 2.0, points=[sc.start, sc.goal])
    a, b = (int(v) for v in tm.terminals)
    _, L = tm.shortest_path(a, b)
    assert nx.shortest_path_length(tm.graph, a, b, weight="weight") == pytest.approx(L, rel=1e-12)
    assert tm.graph.number_of_edges() == len(tm.edge_d)


@pytest.mark.parametrize("name", ["circles-1", "map20-1", "map20-3", "building100"])
def test_mesh_paths_bracket_the_visibility_graph(name):
    """Mesh paths are feasible and never shorter than the any-angle optimum; with M well under
    the map size they stay within 8 % of it."""
    sc = load_scenario(name)
    M = 0.05 * float(sc.bounds[2] - sc.bounds[0])
    tm = triangulate_map(sc.obstacles, sc.bounds, M, points=[sc.start, sc.goal])
    pts, L = tm.shortest_path(*tm.terminals)
    vis = visibility_shortest_path(sc.world, sc.start, sc.goal, bounds=sc.bounds)
    assert L >= vis.length * (1 - 1e-9)
    assert L <= 1.08 * vis.length
    assert sc.world.segments_free(pts[:-1], pts[1:]).all()


def test_finer_mesh_is_closer_to_optimum_than_coarse():
    sc = load_scenario("circles-1")
    vis = visibility_shortest_path(sc.world, sc.start, sc.goal, bounds=sc.bounds).length
    out = []
    for M in (8.0, 0.5):
        tm = triangulate_map(sc.obstacles, sc.bounds, M, points=[sc.start, sc.goal])
        out.append(tm.shortest_path(*tm.terminals)[1] / vis)
    assert out[1] < out[0]


def test_max_edge_rule_quarter_of_smallest_gap():
    obs = Obstacles2D(rectangles=[[0, 0, 2, 2], [6, 0, 8, 2], [0, 10, 2, 12]])
    assert max_edge_rule(obs) == pytest.approx(1.0)  # gap 4 between the first two
    touching = Obstacles2D(rectangles=[[0, 0, 2, 2], [2, 0, 4, 2]])
    assert max_edge_rule(touching) == np.inf


def test_point_in_obstacle_is_an_error():
    from weldplan.errors import PlanningError

    obs = Obstacles2D(rectangles=[[3.0, 3.0, 7.0, 7.0]])
    with pytest.raises(PlanningError):
        triangulate_map(obs, [0, 0, 10, 10], 1.0, points=[[5.0, 5.0]])


def test_polyanya_arena_mesh_paths():
    """Polyanya's arena navmesh as a triangular-mesh map: paths are never shorter than the
    any-angle optimum in the navmesh (its visibility graph), stay within 10 % of it, and never
    beat the 8-connected lengths of the .scen file by more than the any-angle gain allows."""
    space = MeshFreeSpace.read(require_shared("meshmaps", "arena.mesh"))
    scen = read_scen(require_shared("meshmaps", "arena.mesh.scen"))
    sel = np.linspace(0, len(scen.length) - 1, 8).astype(int)
    S = scen.start[sel].astype(float)
    G = scen.goal[sel].astype(float)
    tm = triangulate_navmesh(space, 2.0, points=np.concatenate([S, G]))
    n = len(sel)
    dist, _ = tm.distances(tm.terminals[:n], tm.terminals[n:])
    L = np.diag(dist)
    vg = VisibilityGraph(space)
    opt = np.array([vg.shortest_path(s, g).length for s, g in zip(S, G, strict=True)])
    assert np.all(L >= opt * (1 - 1e-9))
    assert np.all(L <= opt * 1.10 + 1e-9)
    # octile (.scen) lengths are at most 8.3 % above any-angle ones
    assert np.all(L >= scen.length[sel] / 1.083)


# ------------------------------------------------------------------------------ string pulling
def _taut(tm, a, b):
    dist, pred = tm.distances([a], [b])
    nodes = tm.path_nodes(pred[0], int(b))
    return tm.funnel(nodes), float(dist[0, 0])


def _length(P):
    return float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())


def test_funnel_square_detour_is_the_exact_optimum():
    obs = Obstacles2D(rectangles=[[3.0, 3.0, 7.0, 7.0]])
    s, g = np.array([1.0, 5.0]), np.array([9.0, 5.0])
    tm = triangulate_map(obs, [0, 0, 10, 10], 0.5, points=[s, g])
    F, L = _taut(tm, *tm.terminals)
    exact = 2 * np.hypot(2.0, 2.0) + 4.0  # (1,5)->(3,7)->(7,7)->(9,5) or its mirror
    assert _length(F) == pytest.approx(exact, abs=1e-6)
    assert L > exact + 0.1  # the edge path zig-zags
    np.testing.assert_allclose(F[[0, -1]], [s, g])
    assert len(F) == 4  # bends only at the two corners
    assert obs.segments_free(F[:-1], F[1:]).all()


@pytest.mark.parametrize("name", ["map20-1", "building100"])
def test_funnel_equals_the_visibility_graph_on_polygon_maps(name):
    """Maps of rectangles (exact outlines in the mesh): the mesh path goes around the obstacles
    on the optimal sides, so the taut path is the any-angle optimum."""
    sc = load_scenario(name)
    M = 0.05 * float(sc.bounds[2] - sc.bounds[0])
    tm = triangulate_map(sc.obstacles, sc.bounds, M, points=[sc.start, sc.goal])
    F, L = _taut(tm, *tm.terminals)
    vis = visibility_shortest_path(sc.world, sc.start, sc.goal, bounds=sc.bounds)
    assert _length(F) == pytest.approx(vis.length, abs=1e-6)
    assert _length(F) < L - 1e-3
    assert sc.world.segments_free(F[:-1], F[1:]).all()


@pytest.mark.parametrize("name", ["circles-1", "map20-3"])
def test_funnel_never_longer_than_the_mesh_path_and_never_beats_the_optimum(name):
    sc = load_scenario(name)
    M = 0.05 * float(sc.bounds[2] - sc.bounds[0])
    tm = triangulate_map(sc.obstacles, sc.bounds, M, points=[sc.start, sc.goal])
    F, L = _taut(tm, *tm.terminals)
    vis = visibility_shortest_path(sc.world, sc.start, sc.goal, bounds=sc.bounds).length
    # circles are circumscribed polygons in the mesh: slightly longer than around the circle
    assert vis * (1 - 1e-9) <= _length(F) <= min(L, 1.002 * vis)
    rng = np.random.default_rng(0)
    for a, b in rng.integers(0, tm.n_nodes, size=(20, 2)).tolist():
        F, L = _taut(tm, a, b)
        np.testing.assert_allclose(F[[0, -1]], tm.nodes[[a, b]])
        assert _length(F) <= L + 1e-9
        assert _length(F) >= np.linalg.norm(tm.nodes[a] - tm.nodes[b]) - 1e-9
        assert sc.world.segments_free(F[:-1], F[1:]).all()


def test_funnel_keeps_a_pinch_point():
    # two squares touching at (5, 5): the only way from the top left to the bottom right
    obs = Obstacles2D(rectangles=[[0.0, 0.0, 5.0, 5.0], [5.0, 5.0, 10.0, 10.0]])
    tm = triangulate_map(obs, [0, 0, 10, 10], 1.0, points=[[1.0, 9.0], [9.0, 1.0]])
    F, _ = _taut(tm, *tm.terminals)
    assert _length(F) == pytest.approx(2 * np.hypot(4.0, 4.0), abs=1e-9)
    assert np.min(np.linalg.norm(F - [5.0, 5.0], axis=1)) < 1e-12


def test_navmesh_edge_index_agrees_with_all_pairs():
    """MeshFreeSpace answers through a grid of its boundary edges; on arena the answers equal
    the all-pairs ray casting and crossing tests."""
    from weldplan.geometry.obstacles2d import point_segment_distance

    space = MeshFreeSpace.read(require_shared("meshmaps", "arena.mesh"))
    a, b = space.edge_a, space.edge_b
    rng = np.random.default_rng(3)
    lo, hi = space.vertices_xy.min(0), space.vertices_xy.max(0)
    P = np.concatenate([rng.uniform(lo - 2, hi + 2, size=(500, 2)), 0.5 * (a + b)[:50]])
    py = P[:, None, 1]
    cond = (a[:, 1] > py) != (b[:, 1] > py)
    dy = np.where(b[:, 1] == a[:, 1], 1.0, b[:, 1] - a[:, 1])
    xint = a[:, 0] + (py - a[:, 1]) * (b[:, 0] - a[:, 0]) / dy
    inside = (np.sum(cond & (P[:, None, 0] < xint), axis=1) % 2 == 1) | (
        point_segment_distance(P[:, None], a, b).min(axis=1) <= 1e-9 * space.scale
    )
    np.testing.assert_array_equal(space.contains_free(P), inside)
    # segments: a proper crossing of a boundary edge means not free
    A = rng.uniform(lo, hi, size=(300, 2))
    B = A + rng.normal(size=(300, 2)) * 8.0
    d, e = B - A, b - a
    den = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]
    w = a[None] - A[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[..., 0] * e[None, :, 1] - w[..., 1] * e[None, :, 0]) / den
        u = (w[..., 0] * d[:, None, 1] - w[..., 1] * d[:, None, 0]) / den
    crosses = np.any((den != 0) & (t > 1e-6) & (t < 1 - 1e-6) & (u > 1e-6) & (u < 1 - 1e-6), 1)
    free = space.segments_free(A, B)
    assert not np.any(free & crosses)
    both_in = space.contains_free(A) & space.contains_free(B)
    np.testing.assert_array_equal(free[~crosses], both_in[~crosses])
