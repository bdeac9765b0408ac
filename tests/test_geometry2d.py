"""The planar geometry core against shapely (an independent implementation) and properties."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from weldplan.geometry.obstacles2d import (
    Obstacles2D,
    grid_to_rectangles,
    polygon_is_simple,
)
from weldplan.geometry.pathmetrics import measure, path_length, smoothness, turning_angles
from weldplan.geometry.splines import bspline_path, cubic_spline_path, interp_spline_path

shapely = pytest.importorskip("shapely")
from shapely.geometry import LineString, Point, Polygon, box  # noqa: E402

CONCAVE = np.array([[0, 0], [4, 0], [4, 4], [2, 1.5], [0, 4]], dtype=float)  # an arrowhead


def _random_map(rng: np.random.Generator) -> tuple[Obstacles2D, list]:
    circles = np.column_stack([rng.uniform(0, 10, (3, 2)), rng.uniform(0.3, 2, 3)])
    lo = rng.uniform(0, 9, (3, 2))
    rects = np.column_stack([lo, lo + rng.uniform(0.2, 3, (3, 2))])
    poly = CONCAVE * rng.uniform(0.5, 1.5) + rng.uniform(0, 6, 2)
    obs = Obstacles2D(circles=circles, rectangles=rects, polygons=(poly,))
    shapes = [Point(c[:2]).buffer(c[2], quad_segs=256) for c in circles]
    shapes += [box(*r) for r in rects]
    shapes += [Polygon(poly)]
    return obs, shapes


@pytest.mark.parametrize("seed", range(5))
def test_inside_length_and_hits_match_shapely(seed: int) -> None:
    rng = np.random.default_rng(seed)
    obs, shapes = _random_map(rng)
    A = rng.uniform(-1, 11, (200, 2))
    B = rng.uniform(-1, 11, (200, 2))
    per = obs.inside_length(A, B, per_obstacle=True)
    ref = np.array(
        [
            [LineString([a, b]).intersection(s).length for s in shapes]
            for a, b in zip(A, B, strict=True)
        ]
    )
    # circles are 1024-gons in shapely: relative chord error below 1e-4
    np.testing.assert_allclose(per[:, :3], ref[:, :3], atol=2e-3)
    np.testing.assert_allclose(per[:, 3:], ref[:, 3:], atol=1e-9)
    hit = obs.segments_hit(A, B)
    ref_hit = ref.sum(axis=1) > 1e-6
    clear = np.abs(ref.sum(axis=1) - 1e-6) > 5e-3  # away from the tolerance boundary
    assert np.array_equal(hit[clear], ref_hit[clear])


@pytest.mark.parametrize("seed", range(3))
def test_signed_distance_matches_shapely(seed: int) -> None:
    rng = np.random.default_rng(seed)
    obs, shapes = _random_map(rng)
    P = rng.uniform(-1, 11, (300, 2))
    sd = obs.signed_distance(P)
    for k, s in enumerate(shapes):
        ref = np.array(
            [s.exterior.distance(Point(p)) * (-1 if s.contains(Point(p)) else 1) for p in P]
        )
        np.testing.assert_allclose(sd[:, k], ref, atol=2e-3 if k < 3 else 1e-9)


def test_segments_are_symmetric_and_batched() -> None:
    rng = np.random.default_rng(7)
    obs, _ = _random_map(rng)
    A = rng.uniform(0, 10, (5, 7, 2))
    B = rng.uniform(0, 10, (5, 7, 2))
    np.testing.assert_allclose(obs.inside_length(A, B), obs.inside_length(B, A), atol=1e-12)
    assert np.array_equal(obs.segments_hit(A, B), obs.segments_hit(B, A))
    flat = obs.inside_length(A.reshape(-1, 2), B.reshape(-1, 2)).reshape(5, 7)
    np.testing.assert_allclose(obs.inside_length(A, B), flat)


def test_grazing_a_vertex_is_free_but_squeezing_through_a_pinch_is_not() -> None:
    obs = Obstacles2D(rectangles=[[0, 0, 1, 1], [1, 1, 2, 2]])
    assert obs.pinch_points().tolist() == [[1.0, 1.0]]
    # along the shared corner diagonal, between the two squares: a squeeze
    assert obs.segments_hit(np.array([0.0, 2.0]), np.array([2.0, 0.0]))
    # touching one square's corner from outside: free
    single = Obstacles2D(rectangles=[[0, 0, 1, 1]])
    assert not single.segments_hit(np.array([0.0, 2.0]), np.array([2.0, 0.0]))
    assert not single.segments_hit(np.array([-1.0, 1.0]), np.array([3.0, 1.0]))  # along an edge
    assert single.segments_hit(np.array([-1.0, 0.5]), np.array([3.0, 0.5]))


def test_grid_to_rectangles_covers_exactly_the_occupied_cells() -> None:
    rng = np.random.default_rng(3)
    occ = rng.random((13, 9)) < 0.3
    rects = grid_to_rectangles(occ, origin=(2.0, -1.0), cell=0.5)
    centres = np.stack(np.meshgrid(np.arange(13), np.arange(9), indexing="ij"), -1) * 0.5
    centres = centres + np.array([2.0, -1.0]) + 0.25
    obs = Obstacles2D(rectangles=rects)
    assert np.array_equal(obs.contains(centres), occ)
    assert np.isclose(
        np.sum((rects[:, 2] - rects[:, 0]) * (rects[:, 3] - rects[:, 1])), occ.sum() * 0.25
    )


def test_polygon_simplicity() -> None:
    assert polygon_is_simple(CONCAVE)
    assert not polygon_is_simple([[0, 0], [2, 2], [2, 0], [0, 2]])  # bow tie
    assert not polygon_is_simple([[0, 0], [1, 0], [2, 0]])  # no area
    assert not polygon_is_simple([[0, 0], [4, 0], [4, 4], [2, -1], [0, 4]])  # edge crosses


coords = st.floats(-50, 50, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(coords, coords), min_size=2, max_size=8), st.integers(5, 200))
def test_spline_endpoints_and_length_properties(nodes: list, n: int) -> None:
    N = np.array(nodes)
    for path in (cubic_spline_path(N, n), bspline_path(N, n), interp_spline_path(N, n)):
        assert path.shape == (n, 2)
        assert np.array_equal(path[0], N[0]) and np.array_equal(path[-1], N[-1])
        L = path_length(path)
        assert np.isclose(L, np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
        assert L >= np.linalg.norm(N[-1] - N[0]) - 1e-9  # never shorter than the chord


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(coords, coords, coords), min_size=3, max_size=10))
@example([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 0.0, 2.721642901584495e-39)])  # rounding-only
def test_metrics_are_dimension_agnostic_and_invariant(points: list) -> None:
    P = np.array(points)
    R = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    Q = P @ R.T + 5.0
    assert np.isclose(path_length(P), path_length(Q))
    np.testing.assert_allclose(turning_angles(P), turning_angles(Q), atol=1e-6)
    assert np.all((turning_angles(P) >= 0) & (turning_angles(P) <= np.pi))


def test_spline_passes_through_nodes_and_batches() -> None:
    rng = np.random.default_rng(1)
    N = rng.uniform(0, 10, (6, 5, 2))
    P = cubic_spline_path(N, 101)  # nodes at t = 0, .25, .5, .75, 1 -> samples 0, 25, ...
    np.testing.assert_allclose(P[:, ::25], N, atol=1e-12)
    np.testing.assert_allclose(P[2], cubic_spline_path(N[2], 101))


def test_measure_straight_and_colliding_paths() -> None:
    obs = Obstacles2D(circles=[[5.0, 0.0, 1.0]])
    straight = np.array([[0.0, 0.0], [10.0, 0.0]])
    m = measure(straight, obs)
    assert m.length == 10 and m.smoothness == 0 and m.collisions == 1 and not m.success
    assert m.min_clearance == pytest.approx(4.0)  # at the end points; inner points not sampled
    around = np.array([[0.0, 0.0], [5.0, 2.0], [10.0, 0.0]])
    m2 = measure(around, obs)
    assert m2.success and np.isclose(m2.smoothness, 2 * np.arctan2(2, 5))
    assert type(m2).from_json(m2.to_json()) == m2
    assert np.isclose(smoothness(around), m2.smoothness)


def test_many_touching_grid_rectangles_sparse_equals_dense() -> None:
    """A random occupancy grid as ~1,000 touching rectangles (the house floorplan has 3,838):
    the sparse rectangle clipping (bounding-box pairs) sums to the dense per-rectangle one,
    a corridor between two occupied cells that share a side is blocked, and a diagonal touch
    is a pinch point."""
    from weldplan.geometry.obstacles2d import grid_to_rectangles

    rng = np.random.default_rng(7)
    occ = rng.random((60, 60)) < 0.35
    occ[10, 10] = occ[11, 11] = True  # a diagonal touch at (11, 11) ...
    occ[10, 11] = occ[11, 10] = False  # ... with both other cells free
    occ[20, 20] = occ[20, 21] = True  # two cells sharing the side y = 21 between them
    obs = Obstacles2D(rectangles=grid_to_rectangles(occ, (0.0, 0.0), 1.0))
    assert len(obs.rectangles) > 500
    A = rng.uniform(0, 60, size=(400, 2))
    B = A + rng.normal(size=(400, 2)) * 4.0
    B[::2, 1] = A[::2, 1]  # axis-parallel segments, often along cell sides
    dense = obs.inside_length(A, B, per_obstacle=True).sum(axis=-1)
    np.testing.assert_allclose(obs.inside_length(A, B), dense, rtol=1e-12, atol=1e-12)
    assert not obs.segments_free([[20.2, 21.0]], [[20.8, 21.0]])[0]  # along the shared side
    assert [11.0, 11.0] in obs.pinch_points().tolist()
    assert not obs.segments_free([[10.5, 11.5]], [[11.5, 10.5]])[0]  # through the pinch
