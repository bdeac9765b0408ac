"""Exact planar baselines against the Moving AI optimal lengths and across map formats."""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import require_shared
from weldplan.errors import PlanningError
from weldplan.geometry.obstacles2d import Obstacles2D, grid_to_rectangles
from weldplan.planar.exact import (
    ExactPath,
    MeshFreeSpace,
    VisibilityGraph,
    astar_grid,
    grid_graph,
    grid_lengths,
    mesh_shortest_path_bounded,
    octile,
    read_movingai_map,
    read_scen,
    visibility_shortest_path,
)


def _close_to_scen(length: float, ref: float) -> bool:
    """Scenario files print lengths with 6 significant digits (``508.764`` for
    508.76450...): within 1e-4, or within one unit of the last printed digit."""
    resolution = 10.0 ** (np.floor(np.log10(max(ref, 1e-12))) - 5)
    return abs(length - ref) <= max(1e-4, resolution)


def test_astar_on_small_grids_exact() -> None:
    free = np.ones((5, 5), dtype=bool)
    assert astar_grid(free, (0, 0), (4, 4)).length == pytest.approx(4 * np.sqrt(2))
    assert astar_grid(free, (0, 0), (4, 1)).length == pytest.approx(octile(4, 1))
    # no corner cutting: a wall with a diagonal gap is closed
    wall = np.ones((3, 3), dtype=bool)
    wall[1, 0] = wall[0, 1] = False
    with pytest.raises(PlanningError):
        astar_grid(wall, (0, 0), (2, 2))
    wall[0, 1] = True  # now around through (0, 1) -> (1, 2)? costs 1 + sqrt2 + 1
    r = astar_grid(wall, (0, 0), (2, 2))
    assert r.length == pytest.approx(2 + np.sqrt(2))
    assert ExactPath.from_json(r.to_json()) == r


@pytest.mark.parametrize("name", ["arena", "random512-10-0", "maze512-32-9"])
def test_astar_matches_movingai_lengths_subset(name: str) -> None:
    folder = require_shared("movingai")
    free = read_movingai_map(folder / f"{name}.map")
    sc = read_scen(folder / f"{name}.map.scen")
    # arena: every query; the 512 maps: the short buckets (the long ones are in the slow test
    # and in `weldplan bench planar`)
    idx = np.arange(len(sc.length)) if name == "arena" else np.nonzero(sc.bucket <= 3)[0][::4]
    assert len(idx) > 5
    for k in idx:
        r = astar_grid(free, sc.start[k], sc.goal[k])
        assert _close_to_scen(r.length, sc.length[k]), (k, r.length, sc.length[k])


def test_compiled_grid_search_equals_astar_on_random_grids() -> None:
    rng = np.random.default_rng(7)
    for _ in range(20):
        free = rng.random((12, 9)) > 0.3
        cells = np.argwhere(free)
        S = cells[rng.integers(0, len(cells), 6)]
        T = cells[rng.integers(0, len(cells), 6)]
        L = grid_lengths(free, S, T)
        for s, t, length in zip(S, T, L, strict=True):
            try:
                ref = astar_grid(free, s, t).length
            except PlanningError:
                ref = np.inf
            assert length == pytest.approx(ref, abs=1e-12) or (np.isinf(ref) and np.isinf(length))
    # a limit bounds the work, never a length found within it
    free = np.ones((6, 6), dtype=bool)
    G = grid_graph(free)
    assert grid_lengths(free, [[0, 0]], [[5, 5]], graph=G, limits=[100.0])[0] == pytest.approx(
        5 * np.sqrt(2)
    )
    assert np.isinf(grid_lengths(free, [[0, 0]], [[5, 5]], graph=G, limits=[3.0])[0])


def test_compiled_grid_search_matches_movingai_maze_sample() -> None:
    folder = require_shared("movingai")
    free = read_movingai_map(folder / "maze512-32-9.map")
    sc = read_scen(folder / "maze512-32-9.map.scen")
    k = np.arange(0, len(sc.length), 400)  # 21 queries over every bucket (all 8010: the bench)
    L = grid_lengths(free, sc.start[k], sc.goal[k])
    assert all(_close_to_scen(a, b) for a, b in zip(L, sc.length[k], strict=True))


@pytest.mark.slow
def test_astar_matches_movingai_lengths_sampled_long() -> None:
    folder = require_shared("movingai")
    free = read_movingai_map(folder / "random512-10-0.map")
    sc = read_scen(folder / "random512-10-0.map.scen")
    for k in range(0, len(sc.length), 97):
        r = astar_grid(free, sc.start[k], sc.goal[k])
        assert _close_to_scen(r.length, sc.length[k])


@pytest.mark.slow
def test_visibility_graph_on_mesh_equals_grid_and_bounds_octile() -> None:
    """The arena as a Polyanya mesh and as a Moving AI grid: two descriptions of one free
    space, two visibility graphs, the same any-angle lengths; never longer than the octile
    optimum, and a path never squeezes between cells that touch at a corner."""
    mesh = MeshFreeSpace.read(require_shared("meshmaps", "arena.mesh"))
    free = read_movingai_map(require_shared("movingai", "arena.map"))
    sc = read_scen(require_shared("meshmaps", "arena.mesh.scen"))
    grid_space = Obstacles2D(rectangles=grid_to_rectangles(~free))
    vm = VisibilityGraph(mesh)
    vg = VisibilityGraph(grid_space)
    Lm, Lg = [], []
    for k in range(len(sc.length)):
        s, g = sc.start[k] + 0.5, sc.goal[k] + 0.5
        pm = vm.shortest_path(s, g)
        Lm.append(pm.length)
        Lg.append(vg.shortest_path(s, g).length)
        P = pm.points_array
        assert grid_space.segments_free(P[:-1], P[1:]).all()
    Lm, Lg = np.array(Lm), np.array(Lg)
    np.testing.assert_allclose(Lm, Lg, atol=1e-9)
    assert np.all(Lm <= sc.length + 1e-4)
    assert np.mean(Lm < sc.length - 1e-3) > 0.5  # any-angle is usually strictly shorter


def test_visibility_graph_exact_on_simple_maps() -> None:
    square = Obstacles2D(rectangles=[[1, -1, 3, 1]])
    r = visibility_shortest_path(square, [0, 0], [4, 0])
    assert r.length == pytest.approx(2 * np.sqrt(2) + 2)
    # a circle: true optimum 2 sqrt(d^2 - r^2) + r * (pi - 2 acos(r / d))
    circ = Obstacles2D(circles=[[0.0, 0.0, 1.0]])
    d = 3.0
    exact = 2 * np.sqrt(d * d - 1) + (np.pi - 2 * np.arccos(1 / d))
    r = visibility_shortest_path(circ, [-d, 0], [d, 0])
    assert exact <= r.length <= exact * (1 + 1e-3)
    P = r.points_array
    assert circ.segments_free(P[:-1], P[1:]).all()
    # squeezing between two squares that touch at a corner is not allowed
    pinch = Obstacles2D(rectangles=[[0, 0, 1, 1], [1, 1, 2, 2]])
    r = visibility_shortest_path(pinch, [0.2, 1.8], [1.8, 0.2])
    assert r.length > np.hypot(1.6, 1.6) + 0.1


def test_bounded_mesh_search_equals_the_full_visibility_graph_on_arena() -> None:
    mesh = MeshFreeSpace.read(require_shared("meshmaps", "arena.mesh"))
    sc = read_scen(require_shared("meshmaps", "arena.mesh.scen"))
    vm = VisibilityGraph(mesh)
    for k in range(0, len(sc.length), 5):
        s, g = sc.start[k] + 0.5, sc.goal[k] + 0.5
        full = vm.shortest_path(s, g).length
        bounded = mesh_shortest_path_bounded(mesh, s, g, sc.length[k] + 1e-3)
        assert bounded.length == pytest.approx(full, abs=1e-9)
        P = bounded.points_array
        assert mesh.segments_free(P[:-1], P[1:]).all()
    # a bound below the true length finds nothing
    k = int(np.argmax(sc.length))
    with pytest.raises(PlanningError):
        mesh_shortest_path_bounded(
            mesh,
            sc.start[k] + 0.5,
            sc.goal[k] + 0.5,
            0.99 * vm.shortest_path(sc.start[k] + 0.5, sc.goal[k] + 0.5).length,
        )


def test_aurora_short_queries_lie_between_octile_bounds() -> None:
    """aurora.mesh.scen holds octile grid lengths (not any-angle ones): the any-angle length
    is at most the octile one and at least octile / sqrt(4 - 2 sqrt(2))."""
    mesh = MeshFreeSpace.read(require_shared("meshmaps", "aurora.mesh"))
    sc = read_scen(require_shared("meshmaps", "aurora.mesh.scen"))
    # query 1 is an unobstructed (3, 4) offset: Polyanya's any-angle length would be 5
    assert abs(sc.goal[1] - sc.start[1]).tolist() == [3, 4]
    assert sc.length[1] == pytest.approx(float(octile(3, 4)), abs=1e-5)
    ratio_max = np.sqrt(4 - 2 * np.sqrt(2))
    for k in np.nonzero(sc.bucket <= 3)[0][::3]:
        r = mesh_shortest_path_bounded(
            mesh, sc.start[k] + 0.5, sc.goal[k] + 0.5, sc.length[k] + 1e-3
        )
        assert sc.length[k] / ratio_max - 1e-4 <= r.length <= sc.length[k] + 1e-4
