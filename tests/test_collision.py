"""The collision judge against analytic cases: segments past a box and a sphere, just inside and
just outside the clearance, with both the fast path and pure fcl."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import trimesh
from conftest import require_shared
from hypothesis import given, settings
from hypothesis import strategies as st

from weldplan.geometry.collision import CollisionModel
from weldplan.io.mesh import load_part

METHODS = ["auto", "fcl"]
R = 5.0  # torch-tip radius (mm)
EPS = 0.05  # "just" inside / outside (mm); fcl's GJK is accurate well below this


@pytest.fixture(scope="module")
def box_model() -> CollisionModel:
    """The cube [-50, 50]^3: distances to it are exact and analytic."""
    return CollisionModel(trimesh.creation.box(extents=(100, 100, 100)))


@pytest.fixture(scope="module")
def sphere_model() -> tuple[CollisionModel, float, float]:
    """An icosphere of radius 40 and the radius of its largest inscribed sphere."""
    mesh = trimesh.creation.icosphere(subdivisions=3, radius=40.0)
    inner = float(np.min(np.abs(np.sum(mesh.face_normals * mesh.triangles[:, 0], axis=1))))
    return CollisionModel(mesh), 40.0, inner


def box_distance(P: np.ndarray) -> np.ndarray:
    """Distance from points outside the cube [-50, 50]^3 to it."""
    return np.linalg.norm(np.maximum(np.abs(P) - 50.0, 0.0), axis=-1)


@pytest.mark.parametrize("method", METHODS)
def test_segments_parallel_to_a_face_just_outside_and_inside(box_model, method):
    # along the top face at height 50 + R +- EPS, running well past both edges
    A = np.array([[-120.0, 0.0, 50 + R + EPS], [-120.0, 0.0, 50 + R - EPS]])
    B = A * [-1, 1, 1]
    got = box_model.segments_free(A, B, R, method=method)
    np.testing.assert_array_equal(got, [True, False])


@pytest.mark.parametrize("method", METHODS)
def test_segments_past_an_edge_and_a_corner(box_model, method):
    # the line x = 50 + h / sqrt2, z = 50 + h / sqrt2 passes the edge (x = z = 50) at distance h
    cases = []
    for h, free in ((R + EPS, True), (R - EPS, False)):
        o = 50 + h / np.sqrt(2)
        cases.append(([o, -200, o], [o, 200, o], free))
        # and past the corner (50, 50, 50) at distance h, along (1, -1, 0)
        c = 50 + h / np.sqrt(3)
        u = np.array([1.0, -1.0, 0.0]) / np.sqrt(2)
        p = np.array([c, c, c])
        cases.append((p - 150 * u, p + 150 * u, free))
    A = np.array([c[0] for c in cases], dtype=float)
    B = np.array([c[1] for c in cases], dtype=float)
    # the corner segments pass at h from the corner: check the analytic minimum distance
    t = np.linspace(0, 1, 20001)[:, None]
    for a, b, (_, _, free) in zip(A, B, cases, strict=True):
        dmin = box_distance(a + t * (b - a)).min()
        assert (dmin >= R) == free
    np.testing.assert_array_equal(
        box_model.segments_free(A, B, R, method=method), [c[2] for c in cases]
    )


@pytest.mark.parametrize("method", METHODS)
def test_segments_through_stopping_short_and_zero_length(box_model, method):
    A = np.array(
        [
            [-200, 0, 0],  # straight through the box
            [-200, 0, 0],  # stops R + EPS before the face x = -50
            [-200, 0, 0],  # stops R - EPS before it
            [0, 0, 50 + R + EPS],  # a point (sphere) just outside
            [0, 0, 50 + R - EPS],  # a point just inside
            [0, 0, 0],  # a point inside the solid: closest surface 50 mm away, so free
        ],
        dtype=float,
    )
    B = A.copy()
    B[0] = [200, 0, 0]
    B[1] = [-50 - R - EPS, 0, 0]
    B[2] = [-50 - R + EPS, 0, 0]
    got = box_model.segments_free(A, B, R, method=method)
    # a mesh is a surface: the torch tip deep inside a closed solid touches no triangle
    np.testing.assert_array_equal(got, [False, True, False, True, False, True])


@pytest.mark.parametrize("method", METHODS)
def test_segments_past_a_sphere(sphere_model, method):
    model, radius, inner = sphere_model
    # tangent lines at distance h from the centre: free when h >= radius + R (the facets lie
    # inside the sphere), colliding when h < inner + R (the facets reach out to inner)
    free_h = radius + R + EPS
    hit_h = inner + R - EPS
    A = np.array([[-300, free_h, 0], [-300, 0, hit_h], [-300, hit_h / 2**0.5, hit_h / 2**0.5]])
    B = A * [-1, 1, 1]
    np.testing.assert_array_equal(model.segments_free(A, B, R, method=method), [True, False, False])


def test_fast_path_agrees_with_fcl_on_random_segments(box_model, sphere_model):
    rng = np.random.default_rng(7)
    parts = [box_model.mesh, sphere_model[0].mesh.copy()]
    parts[1].apply_translation([120, 0, 0])
    model = CollisionModel(trimesh.util.concatenate(parts))
    A = rng.uniform([-70, -70, -70], [180, 70, 70], (1500, 3))
    B = A + rng.normal(size=(1500, 3)) * rng.uniform(5, 60, (1500, 1))
    fast = model.segments_free(A, B, R)
    slow = model.segments_free(A, B, R, method="fcl")
    # exclude near-ties, where the exact answer is within round-off of the radius
    t = np.linspace(0, 1, 201)[:, None, None]
    d = model.clearance((A + t * (B - A)).reshape(-1, 3)).reshape(201, -1).min(axis=0)
    clear = np.abs(d - R) > 0.05
    np.testing.assert_array_equal(fast[clear], slow[clear])
    assert 0.2 < fast.mean() < 0.8  # both outcomes are exercised


@settings(max_examples=60, deadline=None)
@given(
    a=st.tuples(*[st.floats(-120, 120)] * 3),
    b=st.tuples(*[st.floats(-120, 120)] * 3),
)
def test_segment_checks_are_symmetric(box_model, a, b):
    assert box_model.segment_free(a, b, R) == box_model.segment_free(b, a, R)


def test_clearance_of_points_is_the_analytic_distance(box_model):
    rng = np.random.default_rng(3)
    P = rng.uniform(-150, 150, (500, 3))
    P = P[np.any(np.abs(P) > 50, axis=1)]
    np.testing.assert_allclose(box_model.clearance(P), box_distance(P), atol=1e-3)
    np.testing.assert_allclose(
        box_model.clearance(P[:20], method="fcl"), box_distance(P[:20]), atol=1e-3
    )


def test_path_free_and_pickling(box_model):
    around = np.array([[-60, -60, 0], [-60, 60, 0], [60, 60, 0]], dtype=float) * 1.2
    through = np.array([[-80, 0, 0], [80, 0, 0]], dtype=float)
    assert box_model.path_free(around, R)
    assert not box_model.path_free(through, R)
    clone = pickle.loads(pickle.dumps(box_model))
    assert clone.path_free(around, R) and not clone.path_free(through, R)


def test_car2_fast_path_agrees_with_fcl():
    mesh = load_part(require_shared("bodies", "car2.obj"), length=4500)
    model = CollisionModel(mesh)
    rng = np.random.default_rng(0)
    n = 400
    S, _ = trimesh.sample.sample_surface(mesh, n, seed=1)
    u = rng.normal(size=(n, 3))
    v = rng.normal(size=(n, 3))
    A = S + u / np.linalg.norm(u, axis=1, keepdims=True) * rng.uniform(5, 50, (n, 1))
    B = A + v / np.linalg.norm(v, axis=1, keepdims=True) * rng.uniform(50, 300, (n, 1))
    np.testing.assert_array_equal(
        model.segments_free(A, B, R), model.segments_free(A, B, R, method="fcl")
    )


@pytest.mark.parametrize("method", ["auto", "fcl"])
def test_segments_with_non_finite_ends_or_radius_are_refused(box_model, method):
    """A NaN compares false with every distance: today such a segment comes back free."""
    from weldplan.errors import InputError

    nan = float("nan")
    A = np.array([[0.0, 0.0, 50.0], [nan, 0.0, 50.0]])
    B = np.array([[10.0, 0.0, 50.0], [10.0, 0.0, 50.0]])
    with pytest.raises(InputError, match="1 segments have a NaN or infinite end"):
        box_model.segments_free(A, B, 1.0, method=method)
    with pytest.raises(InputError):
        box_model.segment_free([0.0, float("inf"), 0.0], [0.0, 0.0, 0.0], 1.0)
    with pytest.raises(InputError):
        box_model.path_free([[0.0, 0.0, 50.0], [nan, nan, nan]], 1.0, method=method)
    for radius in (nan, -1.0, float("inf")):
        with pytest.raises(InputError, match="radius"):
            box_model.segments_free(A[:1], B[:1], radius, method=method)
