"""The joint vertex optimisation (weldplan.weld.taut) against exact answers: closest points on a
box and a disc, shortest paths around a cylinder (3D) and a disc (2D) at the clearance."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from weldplan.geometry.collision import CollisionModel
from weldplan.geometry.obstacles2d import Obstacles2D
from weldplan.geometry.pathcore import polyline_length
from weldplan.geometry.planar_obstacle import PlanarObstacle
from weldplan.weld import taut
from weldplan.weld.refine import refine_path

R = 5.0  # mm clearance


def around(radius: float, d: float) -> float:
    """Shortest path between two points ``d`` either side of the centre of a disc of
    ``radius`` (in its plane), outside the disc: tangent, arc, tangent (exact)."""
    return 2.0 * math.sqrt(d * d - radius * radius) + radius * (
        math.pi - 2.0 * math.acos(radius / d)
    )


@pytest.fixture(scope="module")
def cylinder() -> CollisionModel:
    """A cylinder of radius 30 mm, 200 mm high, about the z axis (a 128-sided prism)."""
    return CollisionModel(trimesh.creation.cylinder(radius=30.0, height=200.0, sections=128))


@pytest.fixture
def disc() -> PlanarObstacle:
    return PlanarObstacle(Obstacles2D(circles=np.array([[0.0, 0.0, 1.0]])))


def fcl(model: CollisionModel):
    return lambda A, B, r: model.segments_free(A, B, r, method="fcl")


def test_closest_points_on_a_box_are_exact() -> None:
    box = CollisionModel(trimesh.creation.box(extents=(100.0, 100.0, 100.0)))
    X = np.array([[0.0, 0.0, 80.0], [70.0, 0.0, 10.0], [60.0, 60.0, 60.0]])
    want = np.array([[0.0, 0.0, 50.0], [50.0, 0.0, 10.0], [50.0, 50.0, 50.0]])
    C, D = taut.closest_points(box, X)
    assert np.allclose(C, want, atol=1e-3)
    assert np.allclose(D, [30.0, 20.0, math.sqrt(300.0)], atol=1e-3)


def test_closest_points_without_the_method_use_the_distance_gradient(disc) -> None:
    # PlanarObstacle has only distance(): c = x - d grad d, by central differences
    assert not hasattr(disc, "closest_points")
    X = np.array([[3.0, 0.0], [0.0, -2.0], [1.5, 1.5]])
    C, D = taut.closest_points(disc, X)
    want = X / np.linalg.norm(X, axis=1, keepdims=True)
    assert np.allclose(C, want, atol=1e-6)
    assert np.allclose(D, np.linalg.norm(X, axis=1) - 1.0, atol=1e-9)


def test_shortest_path_around_a_cylinder(cylinder: CollisionModel) -> None:
    # in the plane z = 0, around the prism grown by R: between the disc of its inscribed
    # radius and the disc of its circumscribed radius, both grown by R
    P = np.array([[-100.0, 0, 0], [-100, 60, 0], [100, 60, 0], [100, 0, 0]])
    assert cylinder.path_free(P, R, method="fcl")
    lo = around(30.0 * math.cos(math.pi / 128) + R, 100.0)
    hi = around(30.0 + R, 100.0)
    joint = refine_path(P, cylinder, R, check=fcl(cylinder), final_check=fcl(cylinder))
    sweeps = refine_path(P, cylinder, R, check=fcl(cylinder), final_check=fcl(cylinder), taut=False)
    assert joint.refined, joint.status
    assert lo - 1e-6 <= joint.length <= hi * 1.001, (joint.length, lo, hi)
    assert joint.length < sweeps.length
    assert cylinder.path_free(joint.points, R, method="fcl")


def test_shortest_path_around_a_disc_in_2d(disc: PlanarObstacle) -> None:
    P = np.array([[-3.0, 0.0], [-3.0, 2.0], [3.0, 2.0], [3.0, 0.0]])
    c = 0.2
    best = around(1.0 + c, 3.0)
    joint = refine_path(P, disc, c)
    sweeps = refine_path(P, disc, c, taut=False)
    assert best - 1e-9 <= joint.length <= best * 1.003, (joint.length, best)
    assert joint.length < sweeps.length
    assert disc.segments_free(joint.points[:-1], joint.points[1:], c).all()


def test_tauten_keeps_the_ends_never_lengthens_and_checks_what_it_changes(
    cylinder: CollisionModel,
) -> None:
    P = np.array([[-100.0, 0, 0], [-100, 60, 0], [0, 60, 0], [100, 60, 0], [100, 0, 0]])
    asked: list[np.ndarray] = []

    def free(A, B):
        asked.append(np.concatenate([A, B], axis=1))
        return cylinder.segments_free(A, B, R + 0.01, method="fcl")

    W, rounds = taut.tauten_path(P, cylinder, R, free, margin=0.01)
    assert rounds >= 1
    assert np.array_equal(W[0], P[0]) and np.array_equal(W[-1], P[-1])
    assert polyline_length(W) < polyline_length(P)
    # every segment of the result was asked about, or is a piece of an input segment
    seen = np.concatenate(asked)
    for a, b in zip(W[:-1], W[1:], strict=True):
        hit = np.all(np.isclose(seen, np.concatenate([a, b])[None]), axis=1).any()
        assert hit or cylinder.segment_free(a, b, R)
    assert cylinder.path_free(W, R, method="fcl")


def test_a_straight_free_path_stays_put(cylinder: CollisionModel) -> None:
    P = np.array([[-100.0, 0, 150], [0, 0, 150], [100, 0, 150]])
    W, _ = taut.tauten_path(P, cylinder, R, fcl_free(cylinder))
    assert polyline_length(W) == pytest.approx(200.0)


def test_the_current_path_satisfies_its_planes(cylinder: CollisionModel) -> None:
    # each round starts feasible: the planes through the contacts hold at the current vertices
    P = np.array([[-100.0, 0, 0], [-100, 37, 0], [0, 37, 0], [100, 37, 0], [100, 0, 0]])
    V = taut._densify(P, cylinder, R)
    K, C = taut._contacts(V, cylinder, R, taut.SAMPLE_STEP * R)
    assert len(K) > 0
    (rows, cols, vals), h = taut._planes(V, K, C, R, np.inf)
    x = V[1:-1].ravel()
    Gx = np.bincount(rows, weights=vals * x[cols], minlength=len(h))
    assert np.all(Gx >= h - 1e-9)


def fcl_free(model: CollisionModel):
    return lambda A, B: model.segments_free(A, B, R, method="fcl")
