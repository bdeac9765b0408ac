"""The part's distance table: a lower bound everywhere, and the same verdicts as open3d."""

from __future__ import annotations

import numpy as np
import trimesh

from weldplan.geometry.distance import SurfaceDistance
from weldplan.geometry.distbound import DistanceBound


def _part() -> trimesh.Trimesh:
    a = trimesh.creation.box((300.0, 200.0, 4.0))
    b = trimesh.creation.box((4.0, 200.0, 150.0))
    b.apply_translation((150.0, 0.0, 75.0))
    return trimesh.util.concatenate([a, b])


def test_the_bound_never_exceeds_the_exact_distance_and_clear_matches_open3d():
    part = _part()
    dist = SurfaceDistance(part)
    bound = DistanceBound(dist, *part.bounds, max_nodes=20_000)
    assert bound.cell > 5.0  # a coarse table: the bound's slack is exercised
    rng = np.random.default_rng(3)
    P = rng.uniform(part.bounds[0] - 400.0, part.bounds[1] + 400.0, (20_000, 3))
    exact = dist(P)
    low = bound.lower(P)
    assert np.all(low <= exact + 1e-6)
    inside = np.all((P > part.bounds[0] - 150) & (P < part.bounds[1] + 150), axis=1)
    # within the table the bound is tight to twice the distance to the nearest node
    assert np.all(exact[inside] - low[inside] <= bound.cell * np.sqrt(3) + bound.tol + 1e-6)
    need = rng.uniform(0.0, 120.0, len(P))
    np.testing.assert_array_equal(bound.clear(P, need), exact > need)
    # far points are decided by the table or the box alone: open3d is asked for few of them
    assert np.mean(low > need) > 0.5


def test_the_table_is_filled_only_where_it_is_asked():
    part = _part()
    dist = SurfaceDistance(part)
    bound = DistanceBound(dist, *part.bounds, max_nodes=200_000)
    assert not bound._done.any()
    P = part.bounds[0] + np.random.default_rng(1).uniform(0.0, 30.0, (50, 3))
    np.testing.assert_array_equal(bound.clear(P, 10.0), dist(P) > 10.0)
    assert 0 < bound._done.sum() < bound._done.size / 4


def test_the_upper_bound_is_never_below_open3ds_own_distance():
    part = _part()
    dist = SurfaceDistance(part)
    bound = DistanceBound(dist, *part.bounds, max_nodes=20_000)
    rng = np.random.default_rng(4)
    # inside the table, beyond it (the node is clipped to its edge) and on the part itself
    P = np.vstack([
        rng.uniform(part.bounds[0] - 400.0, part.bounds[1] + 400.0, (20_000, 3)),
        trimesh.sample.sample_surface(part, 2_000, seed=2)[0],
    ])  # fmt: skip
    exact = dist(P)
    low, up = bound.bounds(P)
    assert np.all(up >= exact) and np.all(low <= exact + 1e-6)
    inside = np.all((P > part.bounds[0] - 150) & (P < part.bounds[1] + 150), axis=1)
    # within the table it is as tight as the lower one: the way to the nearest node, twice
    assert np.all(up[inside] - exact[inside] <= bound.cell * np.sqrt(3) + 2 * bound.tol + 1e-6)


def test_the_robot_checkers_coarser_table_gives_the_finest_tables_verdicts():
    # RobotCollision's table keeps cells of at least TABLE_CELL_MM: fewer nodes to fill, the
    # same verdicts as the 5 mm table (and open3d), thresholds close to the distances included
    from weldplan.robot.collision.checker import TABLE_CELL_MM

    part = _part()
    dist = SurfaceDistance(part)
    fine = DistanceBound(dist, *part.bounds)
    coarse = DistanceBound(dist, *part.bounds, min_cell=TABLE_CELL_MM)
    assert coarse.cell >= TABLE_CELL_MM > fine.cell and coarse.table.size < fine.table.size / 4
    rng = np.random.default_rng(5)
    P = rng.uniform(part.bounds[0] - 250.0, part.bounds[1] + 250.0, (20_000, 3))
    exact = dist(P)
    need = np.clip(exact + rng.normal(0.0, 3.0, len(P)), 0.0, None)
    np.testing.assert_array_equal(coarse.clear(P, need), fine.clear(P, need))
    np.testing.assert_array_equal(coarse.clear(P, need), exact > need)
