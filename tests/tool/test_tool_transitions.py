"""Transitions with the whole tool (issue 16, items 3 and 4): the swept check, retract/approach,
the independent re-check, the tool-aware order."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from weldplan.tool import Tool, TransitionSettings, WeldPose, WeldPoses
from weldplan.tool.poses import OK, quat_wxyz
from weldplan.tool.transitions import (
    BLOCKED,
    DIRECT,
    SLIDE_LIFTS,
    SweepChecker,
    ToolPath,
    Transition,
    TransitionPlanner,
    interpolate,
    motion_bound,
    outside_sphere,
    plan_transitions,
    tool_leg_costs,
    tool_order,
)
from weldplan.tool.verify import verify_sweeps


def _box(extents, centre) -> trimesh.Trimesh:
    return trimesh.creation.box(extents).apply_translation(centre)


def _tool(*meshes: trimesh.Trimesh, name: str = "t") -> Tool:
    m = trimesh.util.concatenate(list(meshes))
    return Tool(name, np.asarray(m.vertices), np.asarray(m.faces))


def _stick(length: float = 200.0, width: float = 10.0) -> Tool:
    """A square stick behind the TCP (along TCP -z), its tip face at the TCP."""
    return _tool(_box((width, width, length), (0, 0, -length / 2)), name="stick")


def _fork() -> Tool:
    """The stick plus a prong ahead of the TCP (like a C-gun's fixed electrode, 30 mm ahead,
    reached by an arm 100 mm off the axis)."""
    return _tool(
        _box((10, 10, 200), (0, 0, -100)),
        _box((10, 10, 40), (100, 0, 10)),  # arm down the side, beyond the sheet's edge
        _box((110, 10, 10), (50, 0, 35)),  # the lower jaw under the sheet, 30..40 mm ahead
        name="fork",
    )


def _q(R) -> np.ndarray:
    return quat_wxyz(np.asarray(R)[None])[0]


DOWN = np.diag([1.0, -1.0, -1.0])  # TCP +z along world -z: the tool stands above, pointing down
#: the default exits with a 50 mm retract, no SE(3) re-plan
NO_SE3 = TransitionSettings(retract=50.0, se3=False)


def test_outside_sphere_cuts_a_large_triangle_covering_the_sphere():
    # one 1 m triangle whose vertices are all far outside a 20 mm sphere at its middle
    v = np.array([[-500.0, -500, 0], [500, -500, 0], [0, 600, 0]])
    f = np.array([[0, 1, 2]])
    ov, of = outside_sphere(v, f, [0, 0, 0], 20.0)
    tri = ov[of]
    # nothing left deeper than 1 mm inside the sphere, and the area outside is all kept
    cp = trimesh.triangles.closest_point(tri, np.zeros((len(tri), 3)))
    assert np.linalg.norm(cp, axis=1).min() >= 20.0 - 1.0
    area = trimesh.triangles.area(tri).sum()
    full = trimesh.triangles.area(v[f][None, 0]).sum()
    assert full - math.pi * 20.0**2 <= area <= full - math.pi * 19.0**2


def test_translation_past_a_plate_is_free_exactly_above_the_clearance():
    plate = _box((400, 400, 2), (0, 0, -1))
    stick = _stick()
    chk = SweepChecker(plate, stick, clearance=5.0, contact_radius=0.0)
    q = _q(DOWN)
    assert chk.check([-150, 0, 6], q, [150, 0, 6], q).ok  # 6 mm above: 1 mm to spare
    out = chk.check([-150, 0, 40], q, [150, 0, 4], q)  # ends 4 mm above: short by 1 mm
    assert not out.ok and out.blocked_at > 0.5


def test_rotation_sweeps_the_far_end_through_a_wall_that_both_ends_clear():
    # a 500 mm stick, pointing up, turns 160 deg about the world y axis: its far end passes
    # x = +492 where a wall stands at x = 300; both end poses are far from the wall (the end
    # pose's far end is at x = 171)
    wall = _box((10, 1000, 1000), (305, 0, 0))
    stick = _stick(500.0)
    chk = SweepChecker(wall, stick, clearance=5.0, contact_radius=0.0)
    R0 = DOWN
    R1 = Rotation.from_rotvec([0, math.radians(160), 0]).as_matrix() @ DOWN
    p = np.zeros(3)
    for R in (R0, R1):
        assert chk.state_ok(p, _q(R))
    _, mid_R = interpolate(p, _q(R0), p, _q(R1), [0.5])
    np.testing.assert_allclose(mid_R[0] @ [0, 0, -500.0], [492.4, 0, 86.8], atol=0.1)
    out = chk.check(p, _q(R0), p, _q(R1))
    # blocked where the stick is in the wall (FCL's collide on the motion's grid goes first):
    # its far end (500 mm out) past x = 300, i.e. past asin(300 / 500) of the 160 deg both ways
    assert not out.ok and out.min_slack < 0
    edge = math.degrees(math.asin(0.6)) / 160
    assert edge < out.blocked_at < 1 - edge
    _, R_hit = interpolate(p, _q(R0), p, _q(R1), [out.blocked_at])
    assert (R_hit[0] @ [0, 0, -500.0])[0] > 300.0 - 10.0
    # the same turn with the wall beyond the stick's reach is free
    far = SweepChecker(_box((10, 1000, 1000), (520, 0, 0)), stick, 5.0, 0.0)
    assert far.check(p, _q(R0), p, _q(R1)).ok
    assert motion_bound(p, _q(R0), p, _q(R1), stick.reach) == pytest.approx(
        math.radians(160) * stick.reach
    )


def _poses(ids_xyz, R, *, clearance=5.0, radius=20.0) -> WeldPoses:
    q = tuple(float(v) for v in _q(R))
    poses = tuple(WeldPose(i, OK, tuple(map(float, p)), (0.0, 0.0, -1.0), q) for i, p in ids_xyz)
    return WeldPoses(poses, "t", 0.0, {"clearance": clearance, "contact_radius": radius})


def test_retract_is_free_for_a_stick_and_blocked_for_a_fork_that_straddles_the_sheet():
    # a 2 mm sheet whose edge is at x = 60; welds 30 mm from the edge
    sheet = _box((400, 400, 2), (-140, 0, -1))
    poses = _poses([("a", (30, -100, 0)), ("b", (30, 100, 0))], DOWN)
    # TCP at the top face: DOWN makes TCP x = world x, so the fork's jaw runs under the sheet
    path = plan_transitions(sheet, _stick(), poses, NO_SE3)
    (t,) = path.transitions
    assert t.status == DIRECT and t.kinds == ("retract", "move", "approach")
    np.testing.assert_allclose(t.positions[1], [30, -100, 50])
    assert t.length == pytest.approx(50 + 200 + 50)
    v = verify_sweeps(path, poses, sheet, _stick())
    assert v.ok and v.checked == 1, v.describe()
    fork = plan_transitions(
        sheet, _fork(), poses, dataclasses.replace(NO_SE3, side_exit=0.0, slide=False)
    )
    (tf,) = fork.transitions
    assert tf.status == BLOCKED and "retract" in tf.reason
    assert verify_sweeps(fork, poses, sheet, _fork()).blocked == ("a->b",)
    # sideways, the fork's jaw comes off the sheet past its edge (x = 60): towards TCP +x only
    side = plan_transitions(
        sheet, _fork(), poses, dataclasses.replace(NO_SE3, side_exit=120.0, slide=False)
    )
    (ts,) = side.transitions
    assert ts.status == DIRECT and ts.kinds[:3] == ("lift", "exit +x", "retract"), ts.kinds
    assert ts.kinds[-3:] == ("approach", "enter +x", "lift")
    assert ts.positions[2][0] == pytest.approx(30 + 120)
    assert verify_sweeps(side, poses, sheet, _fork()).ok


def test_the_recheck_catches_a_transition_through_the_part():
    sheet = _box((400, 400, 2), (0, 0, -1))
    wall = _box((400, 4, 300), (0, 0, 150))  # a wall between the two welds
    part = trimesh.util.concatenate([sheet, wall])
    poses = _poses([("a", (0, -100, 0)), ("b", (0, 100, 0))], DOWN)
    stick = _stick()
    path = plan_transitions(part, stick, poses, NO_SE3)
    (t,) = path.transitions
    assert t.status == BLOCKED and "move" in t.reason
    forged = ToolPath(
        path.order,
        (Transition(t.from_id, t.to_id, t.positions, t.quaternions, t.kinds, DIRECT),),
        settings=path.settings,
    )
    v = verify_sweeps(forged, poses, part, stick)
    assert not v.ok and "motion 1 (move)" in v.failures[0][1]
    # over the wall (300 mm high) instead: free, and the re-check agrees
    q = t.quaternions[0]
    over = Transition(
        "a", "b",
        [[0, -100, 0], [0, -100, 320], [0, 100, 320], [0, 100, 0]],
        [q, q, q, q], ("retract", "se3", "approach"), DIRECT,
    )  # fmt: skip
    assert verify_sweeps(ToolPath(("a", "b"), (over,)), poses, part, stick).ok


def test_path_json_round_trip():
    sheet = _box((400, 400, 2), (0, 0, -1))
    poses = _poses([("a", (0, -100, 0)), ("b", (0, 100, 0)), ("c", (100, 0, 0))], DOWN)
    path = plan_transitions(sheet, _stick(), poses, dataclasses.replace(NO_SE3, retract=30.0))
    back = ToolPath.from_dict(path.to_dict())
    assert back.order == path.order and back.length == pytest.approx(path.length)
    for a, b in zip(back.transitions, path.transitions, strict=True):
        np.testing.assert_array_equal(a.quaternions, b.quaternions)
        assert (a.status, a.kinds) == (b.status, b.kinds)


def test_tool_order_trades_length_for_rotation_with_the_weight():
    # four welds on a line; b and d are turned 90 deg about the tool axis. In line order the tool
    # turns three times; with a high rotation weight the order groups equal orientations
    spin = Rotation.from_rotvec([0, 0, math.pi / 2]).as_matrix()
    q0 = tuple(map(float, _q(DOWN)))
    q1 = tuple(map(float, _q(DOWN @ spin)))
    xs = {"a": 0.0, "b": 100.0, "c": 200.0, "d": 300.0}
    qs = {"a": q0, "b": q1, "c": q0, "d": q1}
    poses = WeldPoses(
        tuple(WeldPose(i, OK, (xs[i], 0.0, 0.0), (0, 0, -1.0), qs[i]) for i in "abcd"),
        "t", 0.0, {"clearance": 5.0, "contact_radius": 20.0},
    )  # fmt: skip
    cost, length, angle = tool_leg_costs(poses, list("abcd"), 50.0, 0.0)
    assert length[0, 1] == pytest.approx(200.0) and angle[0, 1] == pytest.approx(math.pi / 2)
    order, st = tool_order(poses, 50.0, rot_weight=0.0)
    assert order in (list("abcd"), list("dcba"))
    order, st = tool_order(poses, 50.0, rot_weight=1000.0)
    assert st["tool_order"]["rotation_deg"] == pytest.approx(90.0)
    assert st["point_order"]["rotation_deg"] == pytest.approx(270.0)
    assert st["tool_order"]["cost"] < st["point_order"]["cost"]
    assert {order[0], order[1]} in ({"a", "c"}, {"b", "d"})


def test_a_blocked_move_is_replanned_in_se3_and_the_recheck_agrees():
    pytest.importorskip("ompl")
    sheet = _box((400, 400, 2), (0, 0, -1))
    wall = _box((400, 4, 80), (0, 0, 40))  # between the welds, 80 mm high
    part = trimesh.util.concatenate([sheet, wall])
    poses = _poses([("a", (0, -100, 0)), ("b", (0, 100, 0))], DOWN)
    stick = _stick(100.0)
    # RRT-Connect stops at its first solution; the time is only a cap (a loaded machine is slow)
    path = plan_transitions(part, stick, poses, TransitionSettings(time_s=30.0, seed=1))
    (t,) = path.transitions
    assert t.status == "replanned", t.reason
    assert t.kinds[0] == "retract" and t.kinds[-1] == "approach" and "se3" in t.kinds
    assert "move" in t.reason  # what blocked the direct transition
    # it goes round or over the wall: longer than the straight 300 mm, and its TCP clears the top
    # or the sides of the wall somewhere
    assert t.length > 300.0
    v = verify_sweeps(path, poses, part, stick)
    assert v.ok and v.checked == 1, v.describe()


def test_the_replanned_path_is_not_checked_again_where_the_fast_check_proved_it(monkeypatch):
    """The SE(3) path's motions that the fast check passed during the run are not given to the
    exact check again: the same path and verdict as when every motion is checked again, fewer
    exact samples, and the independent re-check passes it."""
    pytest.importorskip("ompl")
    import weldplan.tool.transitions.se3_replan as se3_replan

    sheet = _box((400, 400, 2), (0, 0, -1))
    wall = _box((400, 4, 80), (0, 0, 40))
    part = trimesh.util.concatenate([sheet, wall])
    poses = _poses([("a", (0, -100, 0)), ("b", (0, 100, 0))], DOWN)
    stick = _stick(100.0)
    settings = TransitionSettings(time_s=30.0, seed=1)
    lean = plan_transitions(part, stick, poses, settings)
    real = se3_replan.se3_path

    def forgetful(*a, **k):
        path, status, _ = real(*a, **k)
        return path, status, set()  # nothing proven: every motion to the exact check

    monkeypatch.setattr(se3_replan, "se3_path", forgetful)
    full = plan_transitions(part, stick, poses, settings)
    (t,), (u,) = lean.transitions, full.transitions
    assert t.status == u.status == "replanned"
    assert np.array_equal(t.positions, u.positions) and np.array_equal(t.quaternions, u.quaternions)
    assert t.samples < u.samples
    v = verify_sweeps(lean, poses, part, stick)
    assert v.ok and v.checked == 1, v.describe()


def test_slide_along_one_flange_where_the_fork_cannot_retract():
    # a 2 mm flange whose free edge is at x = 60; the fork straddles it (jaw 28 mm under it,
    # arm beyond the edge): the axial retract pulls the jaw through the sheet, the slide does not
    sheet = _box((400, 400, 2), (-140, 0, -1))
    poses = _poses([("a", (30, -100, 0)), ("b", (30, 100, 0))], DOWN)
    fork = _fork()
    path = plan_transitions(sheet, fork, poses, NO_SE3)
    (t,) = path.transitions
    assert t.status == DIRECT and t.kinds == ("lift", "slide", "lower") and t.via == "slide"
    lift = SLIDE_LIFTS[0]
    np.testing.assert_allclose(
        t.positions, [[30, -100, 0], [30, -100, lift], [30, 100, lift], [30, 100, 0]]
    )
    assert t.length == pytest.approx(2 * lift + 200.0)
    assert t.rotation == pytest.approx(0.0)
    assert "axial: leaving a: retract" in t.reason  # what was tried first
    assert path.by_via() == {"axial": 0, "slide": 1, "side": 0, "se3": 0, "blocked": 0}
    v = verify_sweeps(path, poses, sheet, fork)
    assert v.ok and v.checked == 1, v.describe()
    # a tool that straddles the sheet slides first: the same path, nothing tried before it
    gun = dataclasses.replace(fork, straddles=True, _cache={})
    (g,) = plan_transitions(sheet, gun, poses, NO_SE3).transitions
    np.testing.assert_array_equal(g.positions, t.positions)
    assert g.via == "slide" and g.reason == ""


def test_a_blocked_transition_lists_every_exit_tried():
    # a rib 60 mm high stands across the flange between the welds: no slide passes it, no 50 mm
    # retract point clears it; every exit is named in the reason
    sheet = _box((400, 400, 2), (-140, 0, -1))
    rib = _box((560, 4, 60), (-60, 0, 30))  # beyond the edge too: no way round it
    part = trimesh.util.concatenate([sheet, rib])
    poses = _poses([("a", (30, -100, 0)), ("b", (30, 100, 0))], DOWN)
    path = plan_transitions(part, _fork(), poses, dataclasses.replace(NO_SE3, side_exit=120.0))
    (t,) = path.transitions
    assert t.status == BLOCKED and t.via == "blocked"
    assert "axial: leaving a: retract: retract blocked" in t.reason
    for lift in SLIDE_LIFTS:
        assert f"lift {lift:g}: slide blocked" in t.reason, t.reason
    assert "side: move blocked" in t.reason, t.reason


def test_a_motion_check_stops_at_its_cap_and_says_so():
    plate = _box((400, 400, 2), (0, 0, -1))
    chk = SweepChecker(plate, _stick(), clearance=5.0, contact_radius=0.0)
    q = _q(DOWN)
    free = chk.check([-150, 0, 6], q, [150, 0, 6], q)
    assert free.ok and free.samples > 5
    capped = chk.check([-150, 0, 6], q, [150, 0, 6], q, cap=5)
    assert not capped.ok and capped.out_of_budget and capped.samples == 5
    assert "budget ran out" in capped.describe()


def test_the_se3_budget_is_a_budget():
    pytest.importorskip("ompl")
    sheet = _box((400, 400, 2), (0, 0, -1))
    wall = _box((400, 4, 80), (0, 0, 40))
    part = trimesh.util.concatenate([sheet, wall])
    poses = _poses([("a", (0, -100, 0)), ("b", (0, 100, 0))], DOWN)
    stick = _stick(100.0)
    budget = TransitionSettings(time_s=60.0, seed=1, se3_samples=10, slide=False)
    tp = TransitionPlanner(part, stick, budget, clearance=5.0, contact_radius=20.0)
    t = tp.plan(poses["a"], poses["b"])
    (run,) = tp.se3_runs
    # the states and motions OMPL asked about took at most the 10 samples (a motion is cut
    # short at what is left); once spent, OMPL is stopped and the transition reported blocked
    assert run["samples"] <= 10 and run["motions"] > 0
    assert t.status == BLOCKED and "refused: budget spent" in t.reason
    # the same seed with room to work solves it, and the counts are reproducible
    roomy = dataclasses.replace(budget, se3_samples=20_000)
    tp2 = TransitionPlanner(part, stick, roomy, clearance=5.0, contact_radius=20.0)
    assert tp2.plan(poses["a"], poses["b"]).status == "replanned"
    assert tp2.se3_runs[0]["samples"] <= 20_000


def test_the_se3_check_budget_starves_and_a_seeded_replan_repeats_exactly():
    pytest.importorskip("ompl")
    sheet = _box((400, 400, 2), (0, 0, -1))
    wall = _box((400, 4, 80), (0, 0, 40))
    part = trimesh.util.concatenate([sheet, wall])
    poses = _poses([("a", (0, -100, 0)), ("b", (0, 100, 0))], DOWN)

    def planner(checks):
        s = TransitionSettings(time_s=60.0, seed=1, slide=False, se3_checks=checks)
        tp = TransitionPlanner(part, _stick(100.0), s, clearance=5.0, contact_radius=20.0)
        return tp, tp.plan(poses["a"], poses["b"])

    tp, t = planner(2)
    assert t.status == BLOCKED and tp.se3_runs[0]["checks"] < 20
    assert not tp.se3_runs[0]["clock"] and "ended by checks" in t.reason
    (tp1, t1), (tp2, t2) = planner(2_000), planner(2_000)
    assert t1.status == t2.status == "replanned"
    np.testing.assert_array_equal(t1.positions, t2.positions)
    assert tp1.se3_runs == tp2.se3_runs and not tp1.se3_runs[0]["clock"]


@pytest.mark.parametrize("gap", [-1.0, 1.0, 3.0, 40.0])
def test_the_recheck_passes_a_move_past_a_post_exactly_when_it_keeps_the_clearance(gap):
    # a 10 mm square stick (cut to 5 mm triangles, so only its tip is in the contact zone)
    # moves 200 mm past a post whose face is 10 + gap mm from its axis, spinning 90 deg about
    # its axis: half-way, turned 45 deg, its corners reach 5 sqrt(2) mm from the axis, so its
    # least slack is gap - 2.07 mm. The coarse grid is bisected near the post down to the
    # verdict the geometry gives, and agrees with a dense grid (4 mm, 8 bisections)
    import weldplan.tool.verify.sweeps as vs

    post = _box((30, 20, 300), (10 + gap + 15, 0, 150))
    v, f = trimesh.remesh.subdivide_to_size(
        _stick().vertices, _stick().faces, max_edge=5.0, max_iter=10
    )
    stick = Tool("stick", np.asarray(v), np.asarray(f))
    spun = _q(DOWN @ Rotation.from_rotvec([0, 0, math.pi / 2]).as_matrix())
    q = _q(DOWN)
    poses = WeldPoses(
        (WeldPose("a", OK, (0.0, -100.0, 50.0), (0.0, 0.0, -1.0), tuple(map(float, q))),
         WeldPose("b", OK, (0.0, 100.0, 50.0), (0.0, 0.0, -1.0), tuple(map(float, spun)))),
        "t", 0.0, {"clearance": 5.0, "contact_radius": 8.0},
    )  # fmt: skip
    move = Transition("a", "b", [[0, -100, 50], [0, 100, 50]], [q, spun], ("move",), DIRECT)
    path = ToolPath(("a", "b"), (move,))
    coarse = verify_sweeps(path, poses, post, stick)
    assert coarse.ok == (gap - 5 * (math.sqrt(2) - 1) > 0), coarse.describe()
    old = vs.MAX_DEPTH
    try:
        vs.MAX_DEPTH = 8
        dense = verify_sweeps(path, poses, post, stick, spacing=4.0)
    finally:
        vs.MAX_DEPTH = old
    assert dense.ok == coarse.ok
    if coarse.ok:
        assert coarse.samples < dense.samples
        assert coarse.min_clearance == pytest.approx(5 + gap - 5 * (math.sqrt(2) - 1), abs=0.3)
