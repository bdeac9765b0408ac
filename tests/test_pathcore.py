"""The path core in R^n: polyline helpers, the 2D adapter, refinement and smooth paths on maps."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from weldplan.geometry.obstacles2d import Obstacles2D
from weldplan.geometry.pathcore import (
    PathObstacle,
    arc_lengths,
    at_fractions,
    point_at,
    polyline_length,
    resample_count,
    resample_even,
    split_segments,
)
from weldplan.geometry.pathmetrics import path_length
from weldplan.geometry.planar_obstacle import PlanarObstacle, segment_segment_distance
from weldplan.geometry.smooth import smooth_path
from weldplan.weld.refine import refine_path

coords = st.floats(-100, 100, allow_nan=False).map(lambda v: round(v * 64) / 64)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(coords, coords, coords), min_size=2, max_size=8), st.floats(0.5, 30))
def test_split_keeps_vertices_length_and_step(pts, step) -> None:
    P = np.array(pts)
    S = split_segments(P, step)
    assert polyline_length(S) == pytest.approx(polyline_length(P), abs=1e-9)
    assert polyline_length(P) == pytest.approx(float(path_length(P)), abs=1e-9)
    assert np.all(np.linalg.norm(np.diff(S, axis=0), axis=1) <= step + 1e-9)
    # the ends survive bit for bit
    assert np.array_equal(S[0], P[0]) and np.array_equal(S[-1], P[-1])


def test_point_at_and_resample() -> None:
    P = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]])
    assert arc_lengths(P).tolist() == [0.0, 3.0, 7.0]
    Q = point_at(P, [0.0, 1.5, 3.0, 5.0, 7.0, 9.0])
    assert np.allclose(Q, [[0, 0], [1.5, 0], [3, 0], [3, 2], [3, 4], [3, 4]])
    R = resample_count(P, 8)
    assert len(R) == 8 and np.allclose(np.diff(arc_lengths(R)), 1.0)


def test_segment_segment_distance() -> None:
    A, B = np.array([0.0, 0.0]), np.array([2.0, 0.0])
    assert segment_segment_distance(A, B, np.array([1.0, -1.0]), np.array([1.0, 1.0])) == 0.0
    assert segment_segment_distance(A, B, np.array([3.0, 1.0]), np.array([5.0, 1.0])) == (
        pytest.approx(math.sqrt(2.0))
    )
    assert segment_segment_distance(A, B, np.array([1.0, 0.5]), np.array([1.0, 3.0])) == (
        pytest.approx(0.5)
    )


@pytest.fixture
def circle() -> PlanarObstacle:
    return PlanarObstacle(Obstacles2D(circles=np.array([[0.0, 0.0, 1.0]])))


@pytest.fixture
def square() -> PlanarObstacle:
    return PlanarObstacle(Obstacles2D(rectangles=np.array([[-1.0, -1.0, 1.0, 1.0]])))


def test_adapter_is_a_path_obstacle(circle: PlanarObstacle) -> None:
    assert isinstance(circle, PathObstacle)
    assert circle.distance(np.array([[3.0, 0.0]])) == pytest.approx([2.0])


@pytest.mark.parametrize("which", ["circle", "square"])
def test_swept_disc_check_matches_dense_sampling(which, circle, square) -> None:
    obs = {"circle": circle, "square": square}[which]
    rng = np.random.default_rng(3)
    A = rng.uniform(-3, 3, (400, 2))
    B = rng.uniform(-3, 3, (400, 2))
    r = 0.3
    got = obs.segments_free(A, B, r)
    t = np.linspace(0, 1, 2001)[None, :, None]
    d = obs.distance((A[:, None] + t * (B - A)[:, None]).reshape(-1, 2)).reshape(400, -1)
    brute = d.min(axis=1) >= r
    # dense sampling can only miss a touch, by at most (segment length / 2000) mm
    unsure = np.abs(d.min(axis=1) - r) < 0.01
    assert np.array_equal(got[~unsure], brute[~unsure])
    assert got.sum() > 20 and (~got).sum() > 20


def around_the_circle(c: float) -> float:
    """Shortest path from (-3, 0) to (3, 0) outside the disc of radius 1 + c (exact)."""
    R, D = 1.0 + c, 3.0
    return 2.0 * math.sqrt(D * D - R * R) + R * (math.pi - 2.0 * math.acos(R / D))


def test_refine_on_a_planar_map_reaches_the_exact_optimum(circle: PlanarObstacle) -> None:
    P = np.array([[-3.0, 0.0], [-3.0, 2.0], [3.0, 2.0], [3.0, 0.0]])
    c = 0.2
    assert circle.segments_free(P[:-1], P[1:], c).all()
    r = refine_path(P, circle, c)
    best = around_the_circle(c)
    assert r.refined, r.status
    assert best - 1e-9 <= r.length <= best * 1.005, (r.length, best)
    assert circle.segments_free(r.points[:-1], r.points[1:], c).all()


def test_smooth_path_keeps_the_clearance_and_measures_curvature(circle: PlanarObstacle) -> None:
    P = np.array([[-3.0, 0.0], [-3.0, 2.0], [3.0, 2.0], [3.0, 0.0]])
    c = 0.2
    r = refine_path(P, circle, c, margin=0.05)
    sm = smooth_path(r.points, circle, c, max_deviation=0.005)
    assert sm.free, sm.status
    assert sm.min_clearance >= c
    assert sm.max_deviation <= 0.005
    # the curve goes around a disc of radius 1.2 at most 0.05 + 0.005 away: it bends at least
    # as sharply as a circle a little wider, and passes through the refined polyline's vertices
    assert sm.max_curvature > 1.0 / 2.0
    W = sm.waypoints()
    assert np.allclose(W[[0, -1]], P[[0, -1]])
    assert circle.segments_free(W[:-1], W[1:], c).all()


def test_smooth_path_of_a_circle_has_its_curvature() -> None:
    empty = PlanarObstacle(Obstacles2D())
    th = np.linspace(0.0, math.pi, 25)
    P = 50.0 * np.stack([np.cos(th), np.sin(th)], axis=1)
    sm = smooth_path(P, empty, 1.0)
    assert sm.free
    assert sm.length == pytest.approx(50.0 * math.pi, rel=1e-3)
    k = sm.spline
    mid = np.asarray(k.derivative(1)(0.5)), np.asarray(k.derivative(2)(0.5))
    from weldplan.geometry.smooth import curvature

    assert curvature(mid[0][None], mid[1][None])[0] == pytest.approx(1.0 / 50.0, rel=0.01)


def test_a_curve_that_cuts_into_an_obstacle_is_reported() -> None:
    # the curve through a left turn at (0, 0) passes it heading (1, 1): before the vertex it
    # dips to y = -0.289 (at x = -0.98), toward a disc below that the polyline keeps clear of
    # (0.64 from its centre, 0.2 + 0.25 needed)
    disc = PlanarObstacle(Obstacles2D(circles=np.array([[-0.98, -0.64, 0.2]])))
    P = np.array([[-3.0, 0.0], [0.0, 0.0], [0.0, 3.0]])
    assert disc.segments_free(P[:-1], P[1:], 0.25).all()
    sm = smooth_path(P, disc, 0.25)
    assert not sm.free and "leaves the clearance" in sm.status
    # and the report is sound: dense samples of the curve confirm it
    u = np.linspace(0.0, 1.0, 20001)
    assert disc.distance(np.asarray(sm.spline(u))).min() < 0.25


@given(st.lists(st.tuples(coords, coords), min_size=2, max_size=12), st.integers(2, 40))
def test_at_fractions_and_resample_even_are_the_planar_formulas_bit_for_bit(pts, n) -> None:
    # the copies these replaced (planar/homology, planar/encodings, planar/solve), verbatim
    P = np.array(pts, dtype=float)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
    t = np.linspace(0.0, s[-1], n)
    old = np.stack([np.interp(t, s, P[:, 0]), np.interp(t, s, P[:, 1])], axis=1)
    assert np.array_equal(resample_even(P, n), old)
    q = np.random.default_rng(n).uniform(0.0, 1.0, (3, 5))
    at = q * s[-1]
    old = np.stack([np.interp(at, s, P[:, 0]), np.interp(at, s, P[:, 1])], -1)
    assert np.array_equal(at_fractions(P, q), old)
    assert np.array_equal(at_fractions(P, [0.0, 1.0]), P[[0, -1]])


def test_resample_even_spaces_points_evenly_in_3d() -> None:
    P = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 12.0]])
    R = resample_even(P, 20)
    assert np.array_equal(R[[0, -1]], P[[0, -1]])
    assert np.allclose(np.diff(arc_lengths(R)), 1.0)
