"""A blocked transition re-orders the welds (weldplan.tool.transitions.reorder, tool_order's
forbid)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import trimesh

from weldplan.io.joints import Joints
from weldplan.tool import OrderSettings, TransitionSettings, arc_torch, plan_weld_poses
from weldplan.tool.poses import OK, WeldPose, WeldPoses
from weldplan.tool.transitions import (
    order_cost,
    plan_ordered_transitions,
    tool_leg_costs,
    tool_order,
)

DOWN = (0.0, 1.0, 0.0, 0.0)  # TCP z along -z (qw, qx, qy, qz: 180 deg about x)


def _scattered_poses(n: int) -> WeldPoses:
    rng = np.random.default_rng(5)
    xy = rng.uniform(0, 400, size=(n, 2))
    ids = [chr(ord("a") + k) for k in range(n)]
    welds = zip(ids, xy, strict=True)
    return WeldPoses(
        tuple(WeldPose(i, OK, (x, y, 0.0), (0, 0, -1.0), DOWN) for i, (x, y) in welds),
        "t", 0.0, {"clearance": 5.0, "contact_radius": 20.0},
    )  # fmt: skip


def test_tool_order_with_forbidden_pairs_is_the_best_order_that_avoids_them():
    poses = _scattered_poses(6)
    ids = [p.id for p in poses.poses]
    cost, _, _ = tool_leg_costs(poses, ids, 50.0, 200.0)
    free, _ = tool_order(poses, 50.0, 200.0, rng=0)
    forbid = {(free[1], free[2]), (free[3], free[4])}
    order, st = tool_order(poses, 50.0, 200.0, rng=0, forbid=forbid)
    pairs = set(itertools.pairwise(order))
    assert not pairs & (forbid | {(b, a) for a, b in forbid})
    k = {w: n for n, w in enumerate(ids)}

    def ok(p):
        return not any({(p[m], p[m + 1]), (p[m + 1], p[m])} & forbid for m in range(len(p) - 1))

    best = min(order_cost(cost, [k[w] for w in p]) for p in itertools.permutations(ids) if ok(p))
    assert st["tool_order"]["cost"] == pytest.approx(best)  # exact: 6 welds, no penalty in it
    assert st["forbidden_pairs"] == 2 and st["forbidden_used"] == 0


def test_fast_tsp_avoids_forbidden_pairs_above_the_exact_size():
    poses = _scattered_poses(18)  # above the exact solver's 13 nodes: fast-tsp
    free, st0 = tool_order(poses, 50.0, 200.0, rng=0)
    forbid = set(itertools.pairwise(free[::2])) | set(itertools.pairwise(free[:9]))
    order, st = tool_order(poses, 50.0, 200.0, rng=0, forbid=forbid)
    assert sorted(order) == sorted(free) and st["forbidden_used"] == 0
    assert not {frozenset(p) for p in itertools.pairwise(order)} & {frozenset(p) for p in forbid}
    assert st["tool_order"]["cost"] >= st0["tool_order"]["cost"] - 1e-9


def test_a_weld_forbidden_with_every_other_still_gets_an_order():
    poses = _scattered_poses(5)
    ids = [p.id for p in poses.poses]
    forbid = {("a", w) for w in ids[1:]}  # a cannot be joined to anything: no order avoids it
    order, st = tool_order(poses, 50.0, 200.0, rng=0, forbid=forbid)
    assert sorted(order) == ids and st["forbidden_used"] == 1
    assert "a" in (order[0], order[-1])  # one forbidden pair, not two


def _walled_station():
    plate = trimesh.creation.box((600, 800, 2)).apply_translation((50, 100, -1))
    wall = trimesh.creation.box((4, 100, 300)).apply_translation((50, 0, 150))
    part = trimesh.util.concatenate([plate, wall])
    joints = Joints(
        ids=["a", "b", "c"], xyz=[(0, 0, 0), (100, 0, 0), (50, 300, 0)],
        directions=[[0, 0, 1.0]] * 3,
    )  # fmt: skip
    torch = arc_torch(bend_angle=0.0)
    return part, torch, plan_weld_poses(part, joints, torch)


def test_a_blocked_transition_reorders_the_welds_round_the_wall():
    # a 300 mm wall between a and b: the cheapest order joins them and the 50 mm retract cannot
    # pass the wall (no SE(3)); priced out, the next order goes round by c and is free
    part, torch, poses = _walled_station()
    no_se3 = TransitionSettings(retract=50.0, seed=0, se3=False)
    path = plan_ordered_transitions(part, torch, poses, no_se3, OrderSettings(rot_weight=200.0))
    assert not path.blocked and path.stats["order_rounds"] == 2
    assert path.stats["forbidden_pairs"] == 1
    pairs = {frozenset(p) for p in itertools.pairwise(path.order)}
    assert frozenset("ab") not in pairs and len(path.order) == 3
    kept = plan_ordered_transitions(part, torch, poses, no_se3, OrderSettings(keep_order=True))
    assert kept.order == ("a", "b", "c") and len(kept.blocked) == 1
    assert kept.stats["order_rounds"] == 1


def test_the_planner_plans_a_pair_of_poses_once():
    from weldplan.tool.transitions import TransitionPlanner

    part, torch, poses = _walled_station()
    no_se3 = TransitionSettings(se3=False)
    tp = TransitionPlanner(part, torch, no_se3, clearance=5.0, contact_radius=20.0)
    a, b, c = poses.poses
    first = tp.plan(a, c)
    n = tp.samples
    assert n > 0 and tp.plan(a, c) is first and tp.samples == n
    assert tp.plan(c, a) is not first and tp.samples > n  # the other direction is its own
