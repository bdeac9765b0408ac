"""Paper 001 sec. 3 building blocks: expansion circles, collision probabilities, eq. 15."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.planar.multirobot import (
    collision_probability,
    expansion_zone,
    local_choice,
    obstacle_zones,
    score,
)


def test_expansion_zone_of_a_rectangle():
    z = expansion_zone([[0, 0], [4, 0], [4, 3], [0, 3]])
    assert z.d_max == pytest.approx(5.0)  # the diagonal
    assert z.center == pytest.approx((2.0, 1.5))
    assert z.radii == pytest.approx((2.5, 3.0, 3.5))


def test_collision_probabilities_by_ring():
    z = expansion_zone([[0, 0], [4, 0], [4, 3], [0, 3]])
    c = np.array(z.center)
    pts = [c, c + [0, 2.4], c + [0, 2.8], c + [0, 3.2], c + [0, 3.6]]
    np.testing.assert_allclose(collision_probability([z], pts), [1.0, 0.85, 0.65, 0.45, 0.0])


def test_score_eq15():
    assert score(10.0, 5.0) == 98
    assert score(10.0, 3.0) == 96  # ceil(3.33) = 4
    np.testing.assert_array_equal(score([10.0, 10.0], [10.0, 20.0]), [99, 99])
    with pytest.raises(ValueError):
        score(1.0, 0.0)


def test_local_choice_weighs_progress_by_collision_probability():
    here, goal, start = (5, 5), (10, 5), (0, 5)
    cells = [(6, 5), (6, 6), (5, 5)]
    # without risk: the paper's rule, the cell closest to the goal
    assert local_choice(here, goal, start, cells, 0.0) == 0
    # (6, 5) in the 0.85 ring: expected 0.15 * 4 + 0.85 * 5 = 4.85 > |(10, 5) - (6, 6)| = 4.12
    assert local_choice(here, goal, start, cells, [0.85, 0.0, 0.0]) == 1
    # a 0.45 ring costs less: 0.55 * 4 + 0.45 * 5 = 4.45 > 4.12, still the safer cell
    assert local_choice(here, goal, start, cells, [0.45, 0.0, 0.0]) == 1
    # equal expected distance (4 from the goal): the higher eq. 15 score wins,
    # 100 - ceil(10 / 6) = 98 for (6, 5) against 100 - ceil(10 / 10.77) = 99 for (10, 9)
    assert local_choice(here, goal, start, [(6, 5), (10, 9)], 0.0) == 1
    rng = np.random.default_rng(0)
    for _ in range(50):  # p = 0: exactly the nearest cell to the goal
        C = rng.integers(0, 20, size=(9, 2))
        k = local_choice(C[0], (19, 19), (0, 0), C, 0.0)
        d = np.linalg.norm(C - [19, 19], axis=1)
        assert d[k] == d.min()


def test_obstacle_zones_of_a_grid_scenario():
    from weldplan.planar.scenarios import load_scenario

    sc = load_scenario("grid20")
    zones = obstacle_zones(sc.obstacles)
    assert len(zones) == len(sc.obstacles.rectangles)
    # every occupied cell centre has probability 1, and free cells next to walls are in a ring
    ij = np.argwhere(sc.grid.occupied)
    np.testing.assert_array_equal(collision_probability(zones, sc.grid.centre(ij)), 1.0)
    p = collision_probability(zones, sc.grid.centre(np.argwhere(~sc.grid.occupied)))
    assert set(np.unique(p)) <= {0.0, 0.45, 0.65, 0.85} and (p > 0).any()


def _check_moves(sc, run):
    free = ~sc.grid.occupied
    for path in run.paths:
        P = np.array(path)
        assert free[P[:, 0], P[:, 1]].all()
        d = np.diff(P, axis=0)
        assert np.abs(d).max() <= 1
        for a, m in zip(P[:-1], d, strict=True):
            if m[0] and m[1]:  # no corner cutting
                assert free[a[0] + m[0], a[1]] and free[a[0], a[1] + m[1]]


@pytest.mark.slow
def test_paper_three_robot_case_with_hafsa():
    from weldplan.planar.multirobot import PAPER_GOALS, PAPER_STARTS, simulate_robots
    from weldplan.planar.scenarios import load_scenario

    sc = load_scenario("grid20")
    run = simulate_robots(sc, algorithm="hafsa", rng=0)
    assert run.all_arrived
    assert min(run.min_distance) > run.safety
    for k in range(3):
        assert run.paths[k][0] == PAPER_STARTS[k] and run.paths[k][-1] == PAPER_GOALS[k]
    _check_moves(sc, run)


def test_head_on_robots_replan_and_keep_distance():
    from weldplan.planar.multirobot import simulate_robots
    from weldplan.planar.scenarios import load_scenario

    sc = load_scenario("grid20")
    run = simulate_robots(sc, starts=[(1, 1), (10, 1)], goals=[(10, 1), (1, 1)], algorithm="astar")
    assert run.all_arrived
    assert sum(run.replans) >= 1
    assert min(run.min_distance) > run.safety
    _check_moves(sc, run)


def test_cli_planar_robots_writes_png_and_gif(tmp_path, capsys):
    from weldplan.cli import main

    png, gif = tmp_path / "r.png", tmp_path / "r.gif"
    rc = main(["planar", "robots", "grid20", "--global-planner", "astar", "--plot", str(png),
               "--gif", str(gif)])  # fmt: skip
    out = capsys.readouterr().out
    assert rc == 0
    assert out.count("arrives at step") == 3 and "> safety radius" in out
    assert png.stat().st_size > 10_000 and gif.read_bytes()[:3] == b"GIF"
