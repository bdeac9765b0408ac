"""The fault suite's independent oracle against exact answers, so that its 'ok' means something."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from tests.faults.harness import closed_box, sheet, wall_plate
from tests.faults.oracle import (
    Triangles,
    blend_curve,
    capsule_free,
    check_route,
    inside_closed,
    point_distance,
    winding_numbers,
)


def _tri(m: trimesh.Trimesh) -> Triangles:
    return Triangles(np.asarray(m.vertices, float), np.asarray(m.faces))


@pytest.mark.parametrize(("h", "free"), [(5.01, True), (4.99, False), (-5.01, True), (0.0, False)])
@pytest.mark.parametrize("direction", [[1, 0, 0], [1, 1, 0], [0, 0, 0]])
def test_capsule_against_a_sheet_at_exact_heights(h, free, direction):
    """A capsule of radius 5 at height h over the sheet z = 0 (any horizontal direction, or a
    sphere when the segment has no length) touches it exactly when |h| < 5."""
    a = np.array([-20.0, -5.0, h])
    b = a + 30.0 * np.asarray(direction, float)
    assert capsule_free(_tri(sheet()), a, b, 5.0) is free


def test_point_distance_is_exact_to_faces_edges_and_vertices():
    t = _tri(closed_box(40.0))  # x, y in [-20, 20], z in [0, 40]
    assert point_distance(t, [0, 0, 47.0]) == pytest.approx(7.0, abs=1e-9)
    assert point_distance(t, [23.0, 24.0, 20.0]) == pytest.approx(5.0, abs=1e-9)  # edge
    assert point_distance(t, [21.0, 22.0, 42.0]) == pytest.approx(3.0, abs=1e-9)  # vertex
    assert point_distance(t, [0, 0, 20.0]) == pytest.approx(20.0, abs=1e-9)  # inside: unsigned


def test_winding_number_inside_outside_and_open_parts():
    box = closed_box(40.0)
    w = winding_numbers(np.asarray(box.triangles), np.array([[0, 0, 20.0], [0, 0, 60.0]]))
    np.testing.assert_allclose(w, [1.0, 0.0], atol=1e-9)
    flipped = np.asarray(box.triangles)[:, ::-1]  # inward normals: still inside
    assert winding_numbers(flipped, np.array([[5.0, 5.0, 5.0]]))[0] == pytest.approx(1.0)
    assert inside_closed(_tri(box), [[0, 0, 20.0], [30.0, 0, 20.0]]).tolist() == [True, False]
    assert _tri(sheet()).closed == []
    # the wall plate: the plate and the wall are two closed components
    assert len(_tri(wall_plate()).closed) == 2


def _route(points, order=("A", "B")):
    return {"order": list(order), "legs": [{"from": order[0], "to": order[1], "points": points}]}


SPOT_A, SPOT_B = [-20.0, 0.0, 0.0], [20.0, 0.0, 0.0]
JOINTS = {"A": np.array(SPOT_A), "B": np.array(SPOT_B)}


def test_check_route_accepts_a_clear_route_with_approach_cones():
    pts = [SPOT_A, [-20, 0, 10.0], [20, 0, 10.0], SPOT_B]
    assert check_route(_route(pts), _tri(sheet()), JOINTS, 5.0) == []


@pytest.mark.parametrize(
    ("points", "what"),
    [
        ([SPOT_A, [-20, 0, 4.0], [20, 0, 4.0], SPOT_B], "touches"),  # 4 mm up: inside clearance
        ([SPOT_A, [-20, 0, 10.0], [20, 0, 10.0], [20, 0, 1.0]], "does not end"),
        ([SPOT_A, [-20, 0, 10.0], [1e300, 0, 10.0], SPOT_B], "non-finite"),
        ([SPOT_A, [-20, 0, 10.0], [np.nan, 0, 10.0], SPOT_B], "non-finite"),
        # an approach sliding along the surface leaves its cone
        ([SPOT_A, [-10, 0, 0.5], [-10, 0, 10.0], [20, 0, 10.0], SPOT_B], "touches"),
    ],
)
def test_check_route_rejects(points, what):
    problems = check_route(_route(points), _tri(sheet()), JOINTS, 5.0)
    assert any(what in p for p in problems), problems


def test_check_route_rejects_a_leg_inside_a_closed_solid_that_touches_no_face():
    box = closed_box(80.0)  # x, y in [-40, 40], z in [0, 80]; spots on its top face
    spots = {"A": np.array([-20.0, 0, 80.0]), "B": np.array([20.0, 0, 80.0])}
    inside = [[-20.0, 0, 80.0], [-20.0, 0, 70.0], [20.0, 0, 70.0], [20.0, 0, 80.0]]
    problems = check_route(_route(inside), _tri(box), spots, 5.0)
    assert problems and all("inside a closed component" in p for p in problems), problems
    outside = [[-20.0, 0, 80.0], [-20.0, 0, 90.0], [20.0, 0, 90.0], [20.0, 0, 80.0]]
    assert check_route(_route(outside), _tri(box), spots, 5.0) == []


def test_check_route_wants_every_joint_once():
    pts = [SPOT_A, [-20, 0, 10.0], [20, 0, 10.0], SPOT_B]
    joints = {**JOINTS, "C": np.array([0.0, 30.0, 0.0])}
    assert any("every joint" in p for p in check_route(_route(pts), _tri(sheet()), joints, 5.0))


def test_blend_curve_stays_within_the_zone_and_joins_the_segments():
    prev, corner, nxt = np.array([0.0, 0, 0]), np.array([10.0, 0, 0]), np.array([10.0, 10, 0])
    c = blend_curve(prev, corner, nxt, 3.0, samples=33)
    np.testing.assert_allclose(c[0], [7.0, 0, 0])
    np.testing.assert_allclose(c[-1], [10.0, 3.0, 0])
    assert np.all(np.linalg.norm(c - corner, axis=1) <= 3.0 + 1e-12)
    # it cuts the corner: its midpoint is the Bezier midpoint (E + 2P + X) / 4
    np.testing.assert_allclose(c[16], [9.25, 0.75, 0.0])
