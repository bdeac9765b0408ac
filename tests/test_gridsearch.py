"""The exact lattice search against a brute-force Dijkstra, and the grid ant colony's invariants."""

from __future__ import annotations

import heapq
import itertools
import math

import numpy as np
import pytest

from weldplan.geometry.gridsearch import (
    lattice_distance,
    neighbour_offsets,
    pad_free,
    shortest_grid_path,
)
from weldplan.optim.discrete.aco_grid import AntColonyParams, ant_colony_grid


def brute_dijkstra(free: np.ndarray, s, g, moves, corner_cutting: bool = True) -> float:
    """Textbook Dijkstra over an explicit adjacency dict (no padding, no heuristic)."""
    nodes = [tuple(int(v) for v in x) for x in np.argwhere(free)]
    node_set = set(nodes)

    def box_free(u, mv) -> bool:
        # every voxel of the box spanned by the move
        ranges = [range(min(0, m), max(0, m) + 1) for m in mv]
        return all(
            (u[0] + a, u[1] + b, u[2] + c) in node_set for a in ranges[0] for b in ranges[1]
            for c in ranges[2]
        )  # fmt: skip

    adj = {
        u: [
            (v, math.sqrt(sum(m * m for m in mv)))
            for mv in moves
            if (v := (u[0] + mv[0], u[1] + mv[1], u[2] + mv[2])) in node_set
            and (corner_cutting or box_free(u, mv))
        ]
        for u in nodes
    }
    dist = {tuple(s): 0.0}
    heap = [(0.0, tuple(s))]
    done = set()
    while heap:
        d, u = heapq.heappop(heap)
        if u in done:
            continue
        done.add(u)
        if u == tuple(g):
            return d
        for v, c in adj[u]:
            if d + c < dist.get(v, math.inf):
                dist[v] = d + c
                heapq.heappush(heap, (d + c, v))
    return math.inf


def random_free(rng: np.random.Generator, shape=(9, 8, 7), p_obstacle=0.3) -> np.ndarray:
    return rng.random(shape) > p_obstacle


def _path_is_valid(free, path, moves) -> None:
    assert free[tuple(path.T)].all()
    steps = {tuple(m) for m in moves.tolist()}
    for a, b in itertools.pairwise(path.tolist()):
        assert tuple(np.subtract(b, a)) in steps


@pytest.mark.parametrize(("connectivity", "corner_cutting"), [(6, True), (26, True), (26, False)])
@pytest.mark.parametrize("seed", range(6))
def test_astar_equals_brute_force_dijkstra(
    connectivity: int, corner_cutting: bool, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    free = random_free(rng, p_obstacle=0.3 if corner_cutting else 0.15)
    cells = np.argwhere(free)
    s, g = cells[rng.choice(len(cells), 2, replace=False)]
    moves = neighbour_offsets(connectivity)
    expected = brute_dijkstra(free, s, g, moves.tolist(), corner_cutting)
    r = shortest_grid_path(
        free, s, g, connectivity=connectivity, pitch=5.0, corner_cutting=corner_cutting
    )
    if math.isinf(expected):
        assert not r.success and r.path is None and "not reachable" in r.reason
        return
    assert r.success
    assert r.length == pytest.approx(5.0 * expected, abs=1e-9)
    assert np.array_equal(r.path[0], s) and np.array_equal(r.path[-1], g)
    _path_is_valid(free, r.path, moves)
    seg = np.linalg.norm(np.diff(r.path, axis=0), axis=1).sum()
    assert 5.0 * seg == pytest.approx(r.length)


def test_lattice_distance_is_the_empty_grid_optimum() -> None:
    free = np.ones((7, 6, 5), dtype=bool)
    rng = np.random.default_rng(3)
    for _ in range(10):
        a, b = rng.integers(0, 5, (2, 3))
        for conn in (6, 26):
            r = shortest_grid_path(free, a, b, connectivity=conn)
            assert r.length == pytest.approx(float(lattice_distance(a, b, conn)))


def test_blocked_edges_are_avoided() -> None:
    free = np.ones((5, 3, 1), dtype=bool)
    pg = pad_free(free)
    s, g = np.array([0, 1, 0]), np.array([4, 1, 0])
    direct = shortest_grid_path(pg, s, g, connectivity=6)
    assert direct.length == 4
    flat = pg.flat(direct.path)
    r = shortest_grid_path(pg, s, g, connectivity=6, blocked_edges=[(int(flat[1]), int(flat[2]))])
    assert r.length == 6
    assert not any(
        {int(a), int(b)} == {int(flat[1]), int(flat[2])}
        for a, b in itertools.pairwise(pg.flat(r.path))
    )


@pytest.mark.parametrize("connectivity", [6, 26])
@pytest.mark.parametrize("seed", range(4))
def test_forbidden_voxels_are_obstacles_to_the_search(connectivity: int, seed: int) -> None:
    # with corner cutting allowed, forbidding voxels is the same as making them obstacles
    rng = np.random.default_rng(10 + seed)
    free = random_free(rng, p_obstacle=0.2)
    cells = np.argwhere(free)
    s, g = cells[rng.choice(len(cells), 2, replace=False)]
    ban = free & (rng.random(free.shape) < 0.2)
    ban[tuple(s)] = ban[tuple(g)] = False
    moves = neighbour_offsets(connectivity)
    expected = brute_dijkstra(free & ~ban, s, g, moves.tolist())
    pg = pad_free(free)
    r = shortest_grid_path(
        pg, s, g, connectivity=connectivity, pitch=5.0, forbidden=pg.flat(np.argwhere(ban))
    )
    if math.isinf(expected):
        assert not r.success
        return
    assert r.length == pytest.approx(5.0 * expected, abs=1e-9)
    assert not ban[tuple(r.path.T)].any()
    # the forbidden set is the call's own: the same grid searched again without it is unchanged
    plain = shortest_grid_path(pg, s, g, connectivity=connectivity, pitch=5.0)
    assert plain.length == pytest.approx(5.0 * brute_dijkstra(free, s, g, moves.tolist()))
    with pytest.raises(ValueError, match="forbidden"):
        shortest_grid_path(pg, s, g, connectivity=connectivity, forbidden=[int(pg.flat(s))])


def test_expansion_cap_stops_the_search_deterministically() -> None:
    free, s, g = wall_grid()
    full = shortest_grid_path(free, s, g, connectivity=26)
    assert full.success
    same = shortest_grid_path(free, s, g, connectivity=26, max_expansions=full.expansions)
    assert same.length == full.length and same.expansions == full.expansions
    short = shortest_grid_path(free, s, g, connectivity=26, max_expansions=full.expansions - 1)
    assert not short.success and short.reason == "expansion cap reached"
    assert short.expansions == full.expansions - 1


def test_start_on_obstacle_is_an_error() -> None:
    free = np.ones((3, 3, 3), dtype=bool)
    free[1, 1, 1] = False
    with pytest.raises(ValueError, match="start"):
        shortest_grid_path(free, (1, 1, 1), (0, 0, 0))


# ---------------------------------------------------------------------------------- ant colony


def wall_grid() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A 20 x 12 x 12 box with a wall x = 10 leaving a gap near y = 11 (ants must detour)."""
    free = np.ones((20, 12, 12), dtype=bool)
    free[10, :10, :] = False
    return free, np.array([2, 3, 6]), np.array([17, 3, 6])


def test_colony_routes_are_valid_walks() -> None:
    free, s, g = wall_grid()
    r = ant_colony_grid(free, s, g, params=AntColonyParams(n_iterations=5, n_ants=8), rng=0)
    assert r.success
    assert np.array_equal(r.path[0], s) and np.array_equal(r.path[-1], g)
    _path_is_valid(free, r.path, neighbour_offsets(6))
    # tabu list: no voxel twice
    assert len({tuple(p) for p in r.path.tolist()}) == len(r.path)
    assert r.length == len(r.path) - 1
    assert r.iterations == 5 and r.ants == 40
    assert len(r.best_history) == 5
    assert all(a >= b for a, b in itertools.pairwise(r.best_history))
    # never shorter than the exact 6-connected optimum
    assert r.length >= shortest_grid_path(free, s, g, connectivity=6).length


def test_colony_same_seed_same_route_and_seeds_differ() -> None:
    free, s, g = wall_grid()
    prm = AntColonyParams(n_iterations=4, n_ants=6)
    a = ant_colony_grid(free, s, g, params=prm, rng=11)
    b = ant_colony_grid(free, s, g, params=prm, rng=11)
    assert np.array_equal(a.path, b.path) and a.iteration_mean == b.iteration_mean
    others = [ant_colony_grid(free, s, g, params=prm, rng=k).iteration_mean for k in range(5)]
    assert len(set(others)) > 1


def test_colony_dead_end_is_infinite() -> None:
    # a 1-voxel-wide corridor with the nest in the middle: ants walking away from the food die
    free = np.zeros((9, 1, 1), dtype=bool)
    free[:, 0, 0] = True
    prm = AntColonyParams(n_iterations=3, n_ants=20, beta=0.0)
    r = ant_colony_grid(free, (4, 0, 0), (8, 0, 0), params=prm, rng=1)
    assert r.success and r.length == 4
    assert 0 < r.dead_ends < 60
    assert any(math.isfinite(m) for m in r.iteration_mean)


def test_colony_unreachable_food_fails_cleanly() -> None:
    free = np.ones((6, 6, 6), dtype=bool)
    free[3, :, :] = False
    prm = AntColonyParams(n_iterations=2, n_ants=3)
    r = ant_colony_grid(free, (0, 0, 0), (5, 5, 5), params=prm, rng=0)
    assert not r.success and r.path is None and math.isinf(r.length)
    assert "no ant reached" in r.reason and r.dead_ends == 6


def test_starved_colony_does_worse() -> None:
    free, s, g = wall_grid()
    starved = [
        ant_colony_grid(free, s, g, params=AntColonyParams(n_iterations=2, n_ants=2), rng=k).length
        for k in range(5)
    ]
    fed = [
        ant_colony_grid(
            free, s, g, params=AntColonyParams(n_iterations=12, n_ants=12), rng=k
        ).length
        for k in range(5)
    ]
    assert np.mean(fed) < 0.9 * np.mean(starved)


def test_colony_deadline_stops_it() -> None:
    free, s, g = wall_grid()
    r = ant_colony_grid(
        free, s, g, params=AntColonyParams(n_iterations=10_000, n_ants=5), rng=0, deadline=0.0
    )
    assert r.iterations == 0 and not r.success and "time budget" in r.reason


def test_params_round_trip_and_validation() -> None:
    p = AntColonyParams(n_iterations=7, beta=3.0)
    assert AntColonyParams.from_dict(p.to_dict()) == p
    assert AntColonyParams() == AntColonyParams(1.0, 11.0, 0.9, 5.0, 50, 50, 0.5)
    with pytest.raises(ValueError):
        AntColonyParams(rho=1.5)


def test_no_corner_cutting_goes_round_the_edge() -> None:
    # a single obstacle voxel beside the diagonal move (0,0,0) -> (1,1,0)
    free = np.ones((2, 2, 1), dtype=bool)
    free[1, 0, 0] = False
    cut = shortest_grid_path(free, (0, 0, 0), (1, 1, 0), connectivity=26)
    assert cut.length == pytest.approx(math.sqrt(2))
    no_cut = shortest_grid_path(free, (0, 0, 0), (1, 1, 0), connectivity=26, corner_cutting=False)
    assert no_cut.length == pytest.approx(2.0)
