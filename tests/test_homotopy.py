"""The second-class stage of the exact local planner (weldplan.weld.homotopy), against closed-form
shortest lengths on a part where A*'s lattice metric picks the longer side of an obstacle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _boxcell import box_cell
from test_local import analytic_clearance

from weldplan.geometry.collision import CollisionModel
from weldplan.geometry.gridsearch import pad_free, shortest_grid_path
from weldplan.weld.homotopy import CLASS_GAIN, corridor, second_class_wins
from weldplan.weld.local import LocalParams, plan_local_path, polyline_length

CLEARANCE = 5.0
S = np.array([0.0, 0.0, 0.0])
G = np.array([200.0, 0.0, 0.0])
#: a "T" standing across the straight line S -> G (z from -300 to 300 mm: the problem is planar)
BAR = (np.array([40.0, 25.0, -300.0]), np.array([160.0, 35.0, 300.0]))
STEM = (np.array([95.0, -45.0, -300.0]), np.array([105.0, 35.0, 300.0]))


def around(corners: list[tuple[float, float]], side: float, r: float = CLEARANCE) -> float:
    """Closed-form shortest length (mm) from S to G in the plane z = 0 around the box corners
    ``corners`` (left to right, the path wraps each one by a circle of radius ``r``) on the
    side ``+1`` (above) or ``-1`` (below): tangent segments, arcs and the straight runs between
    corners at the same height."""
    (x0, y0), (x1, y1) = corners[0], corners[-1]
    assert y0 == y1
    d0 = math.hypot(x0 - S[0], y0 - S[1])
    d1 = math.hypot(G[0] - x1, y1 - G[1])
    # the tangent from S leaves at angle phi above the horizontal (on the wrapped side), and the
    # path turns through phi on the arc before running along the face
    phi0 = math.atan2(side * (y0 - S[1]), x0 - S[0]) + math.asin(r / d0)
    phi1 = math.atan2(side * (y1 - G[1]), G[0] - x1) + math.asin(r / d1)
    tangents = math.sqrt(d0 * d0 - r * r) + math.sqrt(d1 * d1 - r * r)
    return tangents + r * (phi0 + phi1) + (x1 - x0)


#: over the bar (its top corners) and under the stem (its bottom corners)
TOP = around([(40.0, 35.0), (160.0, 35.0)], +1)
BOTTOM = around([(95.0, -45.0), (105.0, -45.0)], -1)


@pytest.fixture(scope="module")
def tcell():
    return box_cell([BAR, STEM], [-20.0, -80.0, -10.0], [220.0, 70.0, 10.0])


def plan(tcell, **params):
    s, g = tcell.virtual(S), tcell.virtual(G)
    assert np.allclose(tcell.grid.index_to_world(s), S)
    assert np.allclose(tcell.grid.index_to_world(g), G)
    return plan_local_path(tcell.grid, tcell.collision, S, G, s, g, method="exact", params=params)


def test_closed_form_lengths_of_the_two_classes() -> None:
    # below the stem is the shorter class in the plane, by about 4 %
    assert BOTTOM == pytest.approx(224.90, abs=0.01)
    assert TOP == pytest.approx(233.96, abs=0.01)


def test_astar_takes_the_longer_class_and_the_second_class_stage_finds_the_shorter(tcell):
    one = plan(tcell, refine=True, second_class=False)
    both = plan(tcell, refine=True)
    assert one.success and both.success
    # on the 26-connected lattice the top is shorter (its runs are axis and diagonal moves,
    # exact on the lattice; the bottom's are near (2, 1), 8 % long), so A* goes over the top
    # and the refinement converges to the top's continuous optimum
    assert one.classes == 1 and not one.second_class
    assert one.inner_length == pytest.approx(TOP, rel=3e-3)
    # the second route, outside the first's corridor, goes under the stem and refines to the
    # bottom's optimum, which is kept
    assert both.classes == 2 and both.second_class
    assert both.evaluations > one.evaluations  # the second A* ran
    assert both.inner_length == pytest.approx(BOTTOM, rel=3e-3)
    assert both.inner_length < one.inner_length
    assert both.inner_length <= both.so_length
    assert float(both.points[1:-1, 1].min()) < -45.0  # it passes under the stem
    # verified by an FCL model rebuilt from the mesh and by the boxes' exact distance
    inner = both.points
    judge = CollisionModel(tcell.collision.mesh.copy())
    assert judge.path_free(inner, CLEARANCE, method="fcl")
    assert analytic_clearance(tcell, inner, step=0.05) >= CLEARANCE - 1e-6
    assert both.inner_length == pytest.approx(polyline_length(inner))


def test_the_stage_needs_the_refinement_and_is_deterministic(tcell):
    plain = plan(tcell)  # refine off: the exact baseline as before, one route
    assert plain.classes == 1 and not plain.second_class and not plain.refined
    a, b = plan(tcell, refine=True), plan(tcell, refine=True)
    assert np.array_equal(a.points, b.points)


def test_a_zero_slack_trigger_still_refines_a_shorter_grid_path(tcell):
    # the bottom's grid path is already shorter than the top's after the secondary
    # optimisation, so the trigger fires even without slack
    lp = plan(tcell, refine=True, class_slack=0.0)
    assert lp.second_class and lp.inner_length == pytest.approx(BOTTOM, rel=3e-3)


def test_corridor_keeps_the_ends_open_and_closes_the_route() -> None:
    pg = pad_free(np.ones((30, 15, 3), dtype=bool))
    route = np.array([[x, 7, 1] for x in range(30)])
    ban = corridor(pg, route, radius=10.0, pitch=5.0)  # 2 voxels
    banned = pg.index(ban)
    d_end = np.minimum(
        np.linalg.norm(banned - route[0], axis=1), np.linalg.norm(banned - route[-1], axis=1)
    )
    assert (d_end > 4.0).all()  # within radius + 2 voxels of an end stays open
    off = banned[:, 1:] - [7, 1]
    assert (np.hypot(off[:, 0], off[:, 1]) <= 2.0).all()  # within the radius of the route
    # every voxel within the radius of the route and farther than radius + 2 from its ends
    mid = np.array([[x, y, z] for x in range(5, 25) for y in range(5, 10) for z in range(3)])
    mid = mid[np.hypot(mid[:, 1] - 7, mid[:, 2] - 1) <= 2.0]
    assert set(map(int, pg.flat(mid))) <= set(map(int, ban))
    # A* outside the corridor leaves the straight route by more than its radius
    r = shortest_grid_path(pg, route[0], route[-1], forbidden=ban)
    assert r.success and np.hypot(r.path[:, 1] - 7, r.path[:, 2] - 1).max() > 2.0
    # in a tube no wider than the corridor no route is left
    narrow = pad_free(np.ones((30, 5, 1), dtype=bool))
    tube = np.array([[x, 2, 0] for x in range(30)])
    r = shortest_grid_path(narrow, tube[0], tube[-1], forbidden=corridor(narrow, tube, 10.0, 5.0))
    assert not r.success


def test_trigger_and_parameters() -> None:
    assert second_class_wins(100.0, 104.9, 0.05)
    assert not second_class_wins(100.0, 105.1, 0.05)
    assert not second_class_wins(100.0, math.inf, 0.05)
    assert LocalParams().second_class is True
    for bad in ({"class_radius": 0.0}, {"class_slack": -0.1}, {"class_radius": math.nan}):
        with pytest.raises(ValueError):
            LocalParams.coerce(bad)


def test_a_path_near_its_straight_segment_skips_the_second_search() -> None:
    # a box 4.9 mm from the straight line S -> G blocks it at the 5 mm clearance by 0.1 mm; the
    # refined path is within 0.1 % (CLASS_GAIN) of the straight segment, a lower bound of every
    # class, so the second search is not run
    cell = box_cell(
        [(np.array([90.0, 4.9, -300.0]), np.array([110.0, 30.0, 300.0]))],
        [-20.0, -80.0, -10.0],
        [220.0, 70.0, 10.0],
    )
    lp = plan(cell, refine=True)
    assert lp.success and lp.refined
    assert 200.0 < lp.inner_length <= (1.0 + CLASS_GAIN) * 200.0
    assert lp.classes == 1 and not lp.second_class
    # no second A* ran: the same expansions as with the stage off
    assert lp.evaluations == plan(cell, refine=True, second_class=False).evaluations
    assert analytic_clearance(cell, lp.points, step=0.05) >= CLEARANCE - 1e-6
