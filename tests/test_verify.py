"""The independent verifier: catches collisions, skipped and repeated joints, bad approaches."""

from __future__ import annotations

import numpy as np
import pytest

from tests.route_fixtures import CLEARANCE, SPOTS, box_part, box_route
from weldplan.geometry.collision import CollisionModel
from weldplan.weld.route import Leg, Route
from weldplan.weld.verify import APPROACH_EXEMPT_MM, approach_pieces, verify_route


@pytest.fixture(scope="module")
def part():
    return box_part()


def _with_leg(route: Route, k: int, points) -> Route:
    legs = list(route.legs)
    legs[k] = Leg(legs[k].from_id, legs[k].to_id, points, legs[k].method)
    return Route(
        route.order, tuple(legs), route.joint_ids, route.joint_xyz, settings=route.settings
    )


def test_good_route_passes(part):
    rep = verify_route(box_route(), part)
    assert rep.ok, rep.describe()
    assert rep.segments_checked == 1 + 2  # middles of the two legs
    assert rep.approach_segments == 4
    assert rep.joints_visited == 3
    assert rep.clearance == CLEARANCE


def test_segment_moved_through_the_part_is_caught(part):
    r = box_route()
    P = r.legs[1].points.copy()
    P[2] = [0.0, 30.0, 10.0]  # the via now sits inside the wall (|y| <= 50)
    rep = verify_route(_with_leg(r, 1, P), part)
    assert not rep.ok
    bad = [(v.leg, v.segment) for v in rep.violations]
    assert bad == [(1, 1), (1, 2)]
    assert "leg 1 (C -> B), segment 1" in rep.describe()


def test_segment_too_close_at_clearance_is_caught(part):
    r = box_route()
    P = r.legs[1].points.copy()
    P[2] = [0.0, 50.0 + 0.5 * CLEARANCE, 10.0]  # passes 2.5 mm from the wall's end
    rep = verify_route(_with_leg(r, 1, P), part)
    assert [(v.leg, v.segment, v.kind) for v in rep.violations][0] == (1, 1, "collision")
    # at a smaller clearance the same route is fine
    assert verify_route(_with_leg(r, 1, P), part, clearance=0.5).ok


def test_skipped_joint_is_caught(part):
    r = box_route()
    skip = Route(("A", "C"), r.legs[:1], r.joint_ids, r.joint_xyz, settings=r.settings)
    rep = verify_route(skip, part)
    assert not rep.ok
    assert [v.kind for v in rep.violations] == ["missing"]
    assert "joint B is never visited" in rep.describe()


def test_repeated_joint_is_caught(part):
    r = box_route()
    back = r.legs[0].reversed()
    again = Route(("A", "C", "A"), (r.legs[0], back), r.joint_ids, r.joint_xyz)
    kinds = sorted(v.kind for v in verify_route(again, part).violations)
    assert kinds == ["duplicate", "missing"]


def test_leg_not_ending_on_its_weld_spot_is_caught(part):
    r = box_route()
    P = r.legs[0].points.copy()
    P[-1] = P[-1] + [1.0, 0.0, 0.0]
    rep = verify_route(_with_leg(r, 0, P), part)
    assert [(v.kind, v.leg) for v in rep.violations] == [("endpoint", 0)]


def test_joints_table_must_match_the_joints_given(part):
    class J:
        ids = ("A", "B", "C")
        xyz = SPOTS + [[0, 0, 0], [0, 0, 0], [0, 2.0, 0]]

    rep = verify_route(box_route(), part, joints=J)
    assert [v.kind for v in rep.violations] == ["joints"]


def test_approach_cone_admits_oblique_descents_and_rejects_grazing(part):
    r = box_route()
    P = r.legs[0].points.copy()
    # oblique approaches onto the floor are fine, however shallow, if the virtual joint is free
    P[1] = SPOTS[0] + [-10.0, 0.0, 10.0]
    assert verify_route(_with_leg(r, 0, P), part).ok
    P[1] = SPOTS[0] + [-40.0, 0.0, 6.0]
    assert verify_route(_with_leg(r, 0, P), part).ok
    # B's approach from a virtual joint beyond the wall skims 1.3 mm over the wall's top edge:
    # a bare segment would pass, the cone (radius 2.8 mm there) does not
    Q = r.legs[1].points.copy()
    Q[-2] = [-30.0, 0.0, 110.0]
    off_spot = Q[-1] + 0.01 * (Q[-2] - Q[-1])  # a bare segment (radius 0) clears the wall
    assert CollisionModel(part).segment_free(off_spot, Q[-2], 0.0)
    rep = verify_route(_with_leg(r, 1, Q), part)
    assert (1, 3) in [(v.leg, v.segment) for v in rep.violations]
    assert "cone" in rep.describe()


def test_approach_pieces_lie_inside_the_cone():
    spot, virt = np.zeros(3), np.array([0.0, 0.0, 20.0])
    A, B, radii = approach_pieces(spot, virt, 5.0, pieces=4)
    assert len(A) == 4
    assert A[0][2] == pytest.approx(APPROACH_EXEMPT_MM)
    np.testing.assert_allclose(B[-1], virt)
    # radius at the near end of each piece, below the cone c * s / L
    np.testing.assert_array_less(radii, 5.0 * A[:, 2] / 20.0 + 1e-12)
    assert np.all(np.diff(radii) > 0)


def test_uses_a_given_collision_model_and_route_clearance(part):
    model = CollisionModel(part)
    r = box_route()
    assert verify_route(r, model).clearance == CLEARANCE
    assert verify_route(r, model, clearance=2.0).clearance == 2.0


def test_leg_without_virtual_joint_is_refused(part):
    r = box_route()
    rep = verify_route(_with_leg(r, 0, [SPOTS[0], SPOTS[2]]), part)
    assert [(v.kind, v.leg) for v in rep.violations] == [("approach", 0)]


def test_report_round_trip(part):
    from weldplan.weld.verify import VerifyReport

    r = box_route()
    P = r.legs[1].points.copy()
    P[2] = [0.0, 30.0, 10.0]
    rep = verify_route(_with_leg(r, 1, P), part)
    assert VerifyReport.from_dict(rep.to_dict()) == rep


def test_spot_declared_its_own_virtual_joint_gets_no_exemption(part):
    r = box_route()
    V = r.virtual_xyz.copy()
    V[0] = SPOTS[0]  # A "in free space": its first segment must be free at full clearance
    r2 = Route(r.order, r.legs, r.joint_ids, r.joint_xyz, virtual_xyz=V, settings=r.settings)
    rep = verify_route(r2, part)
    assert [(v.leg, v.segment, v.kind) for v in rep.violations] == [(0, 0, "collision")]
    assert rep.approach_segments == 3
