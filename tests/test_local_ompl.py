"""OMPL torch paths on a cell (weldplan.weld.local_ompl) and ``--planner ompl`` end to end.

The box station of route_fixtures: a 2 mm wall (x in [-1, 1], |y| <= 50, z in [0, 60]) on a
floor, tip radius 5 mm. Between the virtual joints A (-40, 0, 5) and B (40, 0, 5) the shortest
path stays in the plane z = 5 and wraps one end of the wall: the expanded wall's corner is a
circle of radius 5 about (-1, +-50), so the path is tangent, arc, 2 mm across, arc, tangent.
(Over the top is longer: at least 2 hypot(40, 60) = 144.2 mm.)
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

pytest.importorskip("ompl")

from route_fixtures import box_part  # noqa: E402

from weldplan.errors import ConfigError  # noqa: E402
from weldplan.geometry.collision import CollisionModel  # noqa: E402
from weldplan.io.joints import Joints  # noqa: E402
from weldplan.weld.cell import build_cell  # noqa: E402
from weldplan.weld.local_ompl import TorchChecks, plan_pair_ompl  # noqa: E402
from weldplan.weld.pipeline import PlanConfig, plan_route  # noqa: E402
from weldplan.weld.verify import verify_route  # noqa: E402

SPOTS = np.array([[-40.0, 0.0, 0.0], [40.0, 0.0, 0.0], [-40.0, 60.0, 0.0], [40.0, -30.0, 0.0]])


@pytest.fixture(scope="module")
def cell():
    joints = Joints(ids=("A", "B", "C", "D"), xyz=SPOTS, directions=None)
    return build_cell(box_part(), joints)


def wrap_length(a: np.ndarray, b: np.ndarray, r: float = 5.0) -> float:
    """Exact shortest planar path from a to b (same z, y = 0) around the wall end at y = 50."""
    total = 2.0  # across the 2 mm wall top of the expanded corner, at y = 50 + r
    for p, cx in ((a, -1.0), (b, 1.0)):
        v = p[:2] - np.array([cx, 50.0])
        d = float(np.linalg.norm(v))
        tangent = math.sqrt(d * d - r * r)
        # angle at the centre from the tangent point to the top of the circle (0, 1)
        to_p = math.atan2(abs(v[0]), -v[1])  # angle between (0, 1) and v, measured outwards
        arc = math.pi - to_p - math.acos(r / d)
        total += tangent + r * arc
    return total


def test_wrap_length_formula_against_brute_force():
    # A -> a point P(t) of the left corner circle that A sees -> arc over the top, minimised
    # over t (the minimum is the tangent point); the right side mirrors it
    r, c = 5.0, np.array([-1.0, 50.0])
    t = np.linspace(np.pi / 2, 3 * np.pi / 2, 400_001)
    P = c + r * np.c_[np.cos(t), np.sin(t)]
    A = np.array([-40.0, 0.0])
    visible = np.einsum("ij,ij->i", P - c, A - P) >= 0  # the segment A-P stays outside the disc
    side = np.where(visible, np.linalg.norm(P - A, axis=1) + r * (t - np.pi / 2), np.inf)
    brute = 2.0 * side.min() + 2.0
    assert wrap_length(np.array([-40.0, 0.0, 5.0]), np.array([40.0, 0.0, 5.0])) == pytest.approx(
        brute, abs=1e-6
    )


def test_bitstar_wraps_the_wall_never_shorter_than_exact(cell):
    vA, vB = cell.virtual_xyz[0], cell.virtual_xyz[1]
    assert vA[2] == pytest.approx(vB[2]) and vA[1] == vB[1] == 0.0
    exact = wrap_length(vA, vB)
    checks = TorchChecks(cell)
    lp = plan_pair_ompl(cell, 0, 1, time_s=1.0, rng=4, checks=checks)
    assert lp.success, lp.reason
    assert lp.method == "ompl" and not lp.fast_path
    assert lp.collision_checks > 0 and checks.motions > 0
    assert lp.inner_length >= exact - 1e-6
    # loose: the optimum grazes the floor (z = 5 is exactly the clearance), which sampling only
    # approaches, and 1 s on a busy machine is a few thousand checks in a 385 x 395 x 305 mm box
    assert lp.inner_length <= exact * 1.10
    # the path leaves and ends on the real joints, through the virtual joints
    np.testing.assert_array_equal(lp.points[0], SPOTS[0])
    np.testing.assert_array_equal(lp.points[-1], SPOTS[1])
    # an independent FCL model of the part agrees the inner path is free
    inner = lp.points[1:-1]
    judge = CollisionModel(cell.part)
    assert judge.segments_free(inner[:-1], inner[1:], cell.clearance, method="fcl").all()


def test_free_pair_takes_the_straight_segment(cell):
    lp = plan_pair_ompl(cell, 0, 2, time_s=0.1, rng=1)
    assert lp.success and lp.fast_path
    assert lp.inner_length == pytest.approx(60.0)


def test_planner_ompl_routes_verify(cell):
    route = plan_route(cell, config=PlanConfig(planner="ompl", local_time_budget=1.0), rng=0)
    assert "ompl" in {leg.method for leg in route.legs}
    assert verify_route(route, cell.part).ok
    assert route.settings["planner"] == "ompl"


def test_planner_ompl_without_ompl_is_a_config_error(cell, monkeypatch):
    for name in ("ompl", "ompl.base", "ompl.geometric", "ompl.util"):
        monkeypatch.setitem(sys.modules, name, None)
    with pytest.raises(ConfigError, match="weldplan\\[ompl\\]"):
        plan_route(cell, config=PlanConfig(planner="ompl"))
