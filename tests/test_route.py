"""Route: invariants, JSON round trip, thin wrappers."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.route_fixtures import SPOTS, box_part, box_route
from weldplan.io.export import read_route, write_csv, write_json, write_post
from weldplan.weld.route import Leg, Route, polyline_length


def test_lengths_are_sums_of_segments():
    r = box_route()
    A, B, C = SPOTS
    # A -> vA -> vC -> C: 10 + 60 + 10; C -> vC -> (0, 62, 10) -> vB -> B
    leg2 = 10 + np.hypot(40, 2) + np.hypot(40, 62) + 10
    assert r.legs[0].length == pytest.approx(80.0)
    assert r.legs[1].length == pytest.approx(leg2)
    assert r.length == pytest.approx(80.0 + leg2)
    assert r.leg_lengths.sum() == pytest.approx(r.length)
    assert polyline_length(r.waypoints()) == pytest.approx(r.length)
    assert r.gap == pytest.approx(r.length / r.lower_bound - 1)


def test_waypoints_share_weld_spots_once():
    r = box_route()
    W = r.waypoints()
    assert len(W) == 4 + 5 - 1
    np.testing.assert_array_equal(W[0], SPOTS[0])
    np.testing.assert_array_equal(W[3], SPOTS[2])
    np.testing.assert_array_equal(W[-1], SPOTS[1])


def test_json_round_trip_is_exact():
    r = box_route(directions=True)
    r2 = Route.from_json(r.to_json())
    assert r2 == r
    assert r2.order == r.order and r2.seed == 7
    for a, b in zip(r.legs, r2.legs, strict=True):
        np.testing.assert_array_equal(a.points, b.points)
        assert (a.from_id, a.to_id, a.method, a.length) == (b.from_id, b.to_id, b.method, b.length)
    np.testing.assert_array_equal(r2.directions, r.directions)
    assert r2.settings == r.settings and r2.stats == r.stats


def test_json_writes_nan_as_null_and_reads_it_back():
    r = box_route()
    r = Route(r.order, r.legs, r.joint_ids, r.joint_xyz, stats={"x": float("nan")})
    d = json.loads(r.to_json())
    assert d["lower_bound"] is None and d["stats"]["x"] is None
    assert np.isnan(Route.from_json(r.to_json()).lower_bound)


def test_arrays_are_read_only():
    r = box_route()
    with pytest.raises(ValueError):
        r.legs[0].points[0, 0] = 1.0
    with pytest.raises(ValueError):
        r.joint_xyz[0, 0] = 1.0


def test_legs_must_follow_the_order():
    r = box_route()
    with pytest.raises(ValueError, match="leg 0"):
        Route(("C", "A", "B"), r.legs, r.joint_ids, r.joint_xyz)
    with pytest.raises(ValueError, match="k - 1 legs"):
        Route(("A", "C", "B"), r.legs[:1], r.joint_ids, r.joint_xyz)


def test_reversed_leg():
    leg = box_route().legs[1]
    back = leg.reversed()
    assert (back.from_id, back.to_id) == ("B", "C")
    np.testing.assert_array_equal(back.points, leg.points[::-1])
    assert back.length == leg.length


def test_leg_needs_two_points():
    with pytest.raises(ValueError):
        Leg("A", "B", np.zeros((1, 3)))


def test_wrong_format_is_refused():
    d = json.loads(box_route().to_json())
    d["format"] = "something-else"
    with pytest.raises(ValueError, match="not a weldplan route"):
        Route.from_dict(d)


def test_export_functions_write_files(tmp_path):
    r = box_route()
    write_csv(r, tmp_path / "r.csv")
    write_json(r, tmp_path / "r.json")
    write_post(r, tmp_path / "r.mod", "rapid", part=box_part())
    assert read_route(tmp_path / "r.json") == r
    assert (tmp_path / "r.csv").read_text().startswith("step,kind,joint_id")
    assert "MODULE" in (tmp_path / "r.mod").read_text()


def test_summary_and_table():
    r = box_route()
    s = r.summary()
    assert s["joints"] == 3 and s["legs"] == 2 and s["order"] == "A-C-B"
    t = r.table()
    assert [row["from"] for row in t] == ["A", "C"] and t[1]["vias"] == 3


def test_inner_length_leaves_out_the_approaches():
    r = box_route()
    # four approach segments of 10 mm (A down, C up and down, B down)
    assert r.approach_length == pytest.approx(40.0)
    assert r.inner_length == pytest.approx(r.length - 40.0)
    assert r.approach_flags(0) == (True, True)
    V = r.virtual_xyz.copy()
    V[0] = SPOTS[0]  # A declared its own virtual joint: no approach at A
    r2 = Route(r.order, r.legs, r.joint_ids, r.joint_xyz, virtual_xyz=V)
    assert r2.approach_flags(0) == (False, True)
    assert r2.approach_length == pytest.approx(30.0)
