"""ParaPA's multimodal planning (003 4.3-4.4): k distinct collision-free paths, eq. 17's
crossings, Algorithm 2's reverse planning, determinism, and the CLI."""

from __future__ import annotations

import math

import numpy as np
import pytest

from weldplan.cli import main
from weldplan.errors import WeldplanError
from weldplan.optim.core import Context
from weldplan.planar.encodings import SegmentPathProblem
from weldplan.planar.multimodal import (
    MultimodalParaPA,
    MultimodalResult,
    class_differs,
    crossing_cross,
    infeasible_segments,
    path_crossings,
    plan_multimodal,
    reference_points,
    reverse_repair,
    swept_angles,
)
from weldplan.planar.scenarios import load_scenario, scenario_from_dict
from weldplan.planar.solve import solve

MAPS_20 = [f"map20-{i}" for i in range(1, 8)]


def _box_problem() -> SegmentPathProblem:
    """A 20 x 20 map with one square in the middle; 6 inner nodes in the rotated frame."""
    sc = scenario_from_dict(
        {
            "name": "box",
            "bounds": [0, 0, 20, 20],
            "start": [0.5, 0.5],
            "goal": [19.5, 19.5],
            "nodes": 6,
            "encoding": "segments",
            "obstacles": [{"type": "rectangle", "min": [8, 8], "max": [12, 12]}],
        }
    )
    return SegmentPathProblem(sc)


#: collision-free round the box on the upper-left side / the lower-right side
UPPER = np.array([2.6, 4.7, 5.9, 5.9, 4.7, 2.6])
LOWER = -UPPER


# ------------------------------------------------------------------------ geometry helpers
def _winding_by_ray(loop: np.ndarray, q: np.ndarray) -> int:
    """Independent winding number: signed crossings of the closed loop with the ray from
    ``q`` towards +x (an edge going up counts +1, down -1)."""
    w = 0
    for a, b in zip(loop, np.roll(loop, -1, axis=0), strict=True):
        if (a[1] <= q[1]) != (b[1] <= q[1]):
            x = a[0] + (q[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
            if x > q[0]:
                w += 1 if b[1] > a[1] else -1
    return w


@pytest.mark.parametrize("name", MAPS_20)
def test_reference_points_lie_inside_their_obstacles(name: str) -> None:
    o = load_scenario(name).obstacles
    q = reference_points(o)
    assert len(q) == o.n_obstacles
    assert np.all(o.contains(q))


def test_box_paths_on_either_side_are_distinct_and_on_one_side_are_not() -> None:
    pr = _box_problem()
    P = pr.decode(np.stack([UPPER, LOWER, 0.5 * UPPER + 0.8]))
    assert pr.success(np.stack([UPPER, LOWER, 0.5 * UPPER + 0.8])).all()
    s = swept_angles(P, reference_points(pr.scenario.obstacles))
    assert class_differs(s[0], s[1])
    assert not class_differs(s[0], s[2])
    # the sweep difference is 2 pi times the winding number of the loop, checked by a ray
    loop = np.concatenate([P[0], P[1][::-1]])
    w = _winding_by_ray(loop, np.array([10.0, 10.0]))
    assert abs(w) == 1
    assert (s[0, 0] - s[1, 0]) / (2 * math.pi) == pytest.approx(w, abs=1e-9)


def test_path_crossings_match_a_brute_force_count() -> None:
    shapely = pytest.importorskip("shapely.geometry")
    rng = np.random.default_rng(5)
    s, g = np.array([0.0, 0.0]), np.array([10.0, 0.0])
    A = np.concatenate(
        [np.tile(s, (4, 1, 1)), rng.uniform(0, 10, (4, 5, 2)) - [0, 5], np.tile(g, (4, 1, 1))], 1
    )
    B = np.concatenate(
        [np.tile(s, (3, 1, 1)), rng.uniform(0, 10, (3, 4, 2)) - [0, 5], np.tile(g, (3, 1, 1))], 1
    )
    got = path_crossings(A, B)
    for i in range(len(A)):
        for e in range(len(B)):
            n = sum(
                shapely.LineString(A[i, a : a + 2]).intersects(shapely.LineString(B[e, b : b + 2]))
                for a in range(A.shape[1] - 1)
                for b in range(B.shape[1] - 1)
            )
            assert got[i, e] == n - 2  # the pairs touching at the shared start and goal
    same = path_crossings(A[:1], A[:1])[0, 0]
    assert same >= A.shape[1] - 1  # an identical path overlaps every segment


def test_crossing_cross_follows_the_parapa_contract() -> None:
    """``cross(candidates (m, n), elites (E, n)) -> (m,)``, lower is better, inputs untouched:
    a copy of an elite scores worse than a path round the other side of the box."""
    pr = _box_problem()
    cross = crossing_cross(pr)
    cand = np.stack([UPPER, LOWER, 0.9 * UPPER])
    elites = np.stack([UPPER, 0.8 * UPPER])
    before = (cand.copy(), elites.copy())
    c = cross(cand, elites)
    assert c.shape == (3,) and c.dtype == np.float64
    np.testing.assert_array_equal(cand, before[0])
    np.testing.assert_array_equal(elites, before[1])
    assert c[1] == 0 and c[0] > c[1]


# ------------------------------------------------------------------------ reverse planning
def test_reverse_repair_fixes_one_infeasible_segment_from_the_memory() -> None:
    pr = _box_problem()
    nectar = LOWER.copy()
    nectar[2] = 2.0  # node 3 pulled onto the box side: segment 3 cuts the box
    bad = infeasible_segments(pr, nectar[None])[0]
    assert bad.sum() == 1 and bad[3]
    straight = np.zeros(6)  # through the box: its prefix is infeasible, so it is skipped
    assert infeasible_segments(pr, straight[None])[0][:4].any()
    out = reverse_repair(pr, nectar, np.stack([straight, UPPER]))
    assert out is not None
    assert pr.success(out[None])[0]
    # the nodes of S_1 .. S_4 come from the memory, the rest stays
    np.testing.assert_array_equal(out[:4], UPPER[:4])
    np.testing.assert_array_equal(out[4:], nectar[4:])


def test_reverse_repair_declines_what_algorithm_2_does_not_cover() -> None:
    pr = _box_problem()
    nectar = LOWER.copy()
    nectar[2] = 2.0
    straight = np.zeros(6)
    assert reverse_repair(pr, nectar, straight[None]) is None  # no memory with a free prefix
    assert infeasible_segments(pr, straight[None])[0].sum() > 2
    assert reverse_repair(pr, straight, UPPER[None]) is None  # more than two bad segments
    assert reverse_repair(pr, UPPER, LOWER[None]) is None  # nothing to repair


def test_abandoned_host_is_repaired_from_its_swarms_memory() -> None:
    pr = _box_problem()
    opt = MultimodalParaPA(pr, 2, n_swarms=2, pop_size=10)
    ctx = Context(pr, np.random.default_rng(0), max_iter=5, max_evals=None, time_budget=None)
    opt.initialize(ctx)
    opt.P[1, 0] = UPPER
    opt.Pf[1, 0] = pr.evaluate(UPPER[None])[0]
    nectar = LOWER.copy()
    nectar[2] = 2.0
    new = opt._respawn(ctx, np.array([1, 1]), np.stack([nectar, np.zeros(6)]))
    assert opt.repairs == 1 and opt.random_respawns == 1
    assert pr.success(new[:1])[0]
    np.testing.assert_array_equal(new[0, :4], UPPER[:4])


# ------------------------------------------------------------------------ whole runs
RUN = {"iterations": 80, "pop_per_swarm": 30}


@pytest.mark.slow
@pytest.mark.parametrize("name", ["map20-1", "map20-2", "map20-3"])
def test_k_paths_are_collision_free_and_pairwise_distinct(name: str) -> None:
    sc = load_scenario(name)
    refs = reference_points(sc.obstacles)
    for seed in (0, 1):
        r = plan_multimodal(sc, 3, rng=seed, with_optimum=False, **RUN)
        assert len(r.paths) == 3 and r.n_success == 3 and r.all_distinct, (name, seed, r)
        paths = [r.path_array(i) for i in range(3)]
        for p in paths:  # independent checks: exact segment test, ray-cast winding numbers
            assert sc.world.path_hits(p) == 0
            assert np.allclose(p[0], sc.start) and np.allclose(p[-1], sc.goal)
        for i in range(3):
            for j in range(i + 1, 3):
                loop = np.concatenate([paths[i], paths[j][::-1]])
                assert any(_winding_by_ray(loop, q) != 0 for q in refs), (name, seed, i, j)
        assert list(r.lengths) == sorted(r.lengths)  # greedy by length among distinct ones


@pytest.mark.slow
def test_same_seed_same_paths_and_json_round_trip() -> None:
    sc = load_scenario("map20-1")
    a = plan_multimodal(sc, 2, rng=7, with_optimum=False, iterations=30, pop_per_swarm=20)
    b = plan_multimodal(sc, 2, rng=7, with_optimum=False, iterations=30, pop_per_swarm=20)
    c = plan_multimodal(sc, 2, rng=8, with_optimum=False, iterations=30, pop_per_swarm=20)
    assert a.paths == b.paths and a.lengths == b.lengths and a.n_eval == b.n_eval
    assert a.paths != c.paths
    back = MultimodalResult.from_json(a.to_json())
    assert back.paths == a.paths and back.distinct == a.distinct and back.swarm == a.swarm
    assert back.crossings == a.crossings and back.success == a.success


@pytest.mark.slow
def test_k1_matches_single_best_parapa_and_a_starved_budget_does_worse() -> None:
    """k = 1 (no class penalty) against ParaPA with the same particles and iterations."""
    sc = load_scenario("map20-1")
    multi, single, starved = [], [], []
    for seed in range(3):
        r = plan_multimodal(sc, 1, rng=seed, with_optimum=False, **RUN)
        s = solve(
            sc, "parapa", pop_size=120, max_iter=80, rng=seed, with_optimum=False, as_printed=True
        )
        t = plan_multimodal(sc, 1, rng=seed, with_optimum=False, iterations=3, pop_per_swarm=30)
        multi.append(r.lengths[0] if r.success[0] else np.inf)
        single.append(s.length if s.success else np.inf)
        starved.append(t.lengths[0] if t.success[0] else np.inf)
    assert np.median(multi) <= 1.01 * np.median(single)
    assert np.median(multi) < np.median(starved)


def test_bad_k_names_the_option(capsys) -> None:
    sc = load_scenario("map20-1")
    with pytest.raises(WeldplanError, match="--k"):
        plan_multimodal(sc, 0)
    with pytest.raises(WeldplanError, match="--k"):
        plan_multimodal(sc, 5, n_swarms=4)
    assert main(["planar", "multimodal", "map20-1", "--k", "0"]) == 2
    assert "--k" in capsys.readouterr().err
    assert main(["planar", "multimodal", "map20-1", "--k", "4", "--swarms", "3"]) == 2
    assert "--k" in capsys.readouterr().err


@pytest.mark.slow
def test_cli_prints_the_paths_and_writes_the_plot(tmp_path, capsys) -> None:
    png = tmp_path / "mm.png"
    rc = main(
        ["planar", "multimodal", "map20-3", "--k", "2", "--seed", "1", "--iterations", "40"]
        + ["--pop", "20", "--plot", str(png)]
    )
    out = capsys.readouterr().out
    assert "path 1" in out and "path 2" in out and "paths 1-2" in out and "gap" in out
    assert rc in (0, 1)  # 1 when a path collides or two coincide: reported, not hidden
    assert png.stat().st_size > 1000
