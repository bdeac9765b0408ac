"""A distance measured on one motion proves the next ones (weldplan.robot.collision.checker._Carry,
SelfCheck.motions' slack) and the linear moves checked in one call: the same verdicts, and hits,
as motion by motion and move by move, with fewer FCL distances. The shared KUKA KR 150 and spot
gun over a plate with a block in the way."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import weldplan.robot.collision.nearpart as nearpart
import weldplan.robot.collision.selfcollision as selfcollision
from tests.robot.test_robot_selfcollision import FAR_PART, FOLDED, HOME
from tests.robot_fixtures import box_joint_route, gun_tcp, shared_robot
from tests.test_linear_moves import _long_route, _plate
from weldplan.robot.collision import RobotCollision
from weldplan.robot.route import check_linear_moves
from weldplan.tool import shared_spot_gun


@pytest.fixture(scope="module")
def scene():
    """The gun on the KUKA over a 800 mm plate, a 20 mm block 40 mm above the flange's path
    half way along the 600 mm move ``Q[1] -> Q[2]`` (test_linear_moves)."""
    robot = shared_robot()
    Tft, _ = gun_tcp(robot)
    _, Q = box_joint_route(robot, Tft, _long_route())
    F = robot.fk(Q[[1, 2]])[:, :3, 3].mean(axis=0)
    block = trimesh.creation.box(extents=[20, 20, 20])
    block.apply_translation(F + [0.0, 0.0, 40.0])
    part = trimesh.util.concatenate([_plate(), block])
    return robot, Tft, Q, RobotCollision(robot, part, shared_spot_gun(), Tft)


def _fresh(chk):
    """A checker like ``chk`` that has checked nothing yet (``path_hits`` keeps the motions a
    checker proved free, and answers them from memory)."""
    return RobotCollision(chk.robot, chk.part, chk._tool, chk.flange_tcp, floor_z=chk.floor_z)


def _one_by_one(chk, Q, zone):
    """The hits of ``Q``'s motions, each checked alone (nothing carried, nothing remembered:
    a fresh checker like ``chk``)."""
    out = []
    chk = _fresh(chk)
    for k in range(len(Q) - 1):
        hits = chk.path_hits(Q[k : k + 2], zone[k : k + 1])
        out += [type(h)(k, h.t, h.body, h.distance) for h in hits]
    return out


def _counting(monkeypatch, module, name):
    calls = []
    real = getattr(module, name)

    def spy(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(module, name, spy)
    return calls


@pytest.mark.parametrize("zone", [True, False])
def test_a_sampled_path_gets_the_hits_of_its_motions_checked_one_by_one(scene, zone, monkeypatch):
    """Through the block and back near the plate: the blocked motions, where and what, equal
    those found motion by motion; the path asks FCL fewer distances."""
    robot, Tft, Q, chk = scene
    path = Q[1] + np.linspace(0.0, 1.0, 61)[:, None] * (Q[2] - Q[1])
    Z = np.full(len(path) - 1, zone)
    calls = _counting(monkeypatch, nearpart, "fcl_distance")
    whole = chk.path_hits(path, Z)
    n_whole = len(calls)
    alone = _one_by_one(chk, path, Z)
    assert whole == alone
    assert whole, "the block stops the path"
    assert all(h.body in ("tool", "link_6", "link_5") for h in whole)
    assert n_whole < len(calls) - n_whole


def test_the_robot_against_itself_on_a_sampled_path_as_motion_by_motion(monkeypatch):
    """Self-collision (the part far away): into the fold from the ordinary pose, and a wander
    about it; each motion's verdict and hit as when checked alone, fewer FCL distances."""
    robot = shared_robot()
    Tft, _ = gun_tcp(robot)
    chk = RobotCollision(robot, FAR_PART, shared_spot_gun(), Tft)
    rng = np.random.default_rng(5)
    fold = HOME + np.linspace(0.0, 1.0, 41)[:, None] * (FOLDED - HOME)
    walk = HOME + np.cumsum(rng.normal(0.0, 0.02, (60, 6)), axis=0)
    for path in (fold, walk):
        Z = np.zeros(len(path) - 1, dtype=bool)
        calls = _counting(monkeypatch, selfcollision, "_pair_distance")
        whole = chk.path_hits(path, Z)
        n_whole = len(calls)
        assert whole == _one_by_one(chk, path, Z)
        assert n_whole < len(calls) - n_whole
    assert chk.path_hits(fold)[-1].body == "tool/link_2"  # the fold is found at its end
    assert chk.path_hits(walk) == []


def test_linear_moves_checked_together_as_one_by_one(scene):
    """The moves of a program checked in one call: the verdicts and reasons of each move alone
    (up from weld A, through the block, down to weld B, and back)."""
    robot, Tft, Q, gun = scene
    chk = RobotCollision(robot, gun.part, None, Tft)  # the links (as test_linear_moves)
    qa = np.concatenate([Q[:-1], Q[:0:-1]])
    qb = np.concatenate([Q[1:], Q[-2::-1]])
    together = check_linear_moves(robot, Tft, qa, qb, checker=chk)
    fresh = _fresh(chk)
    alone = [
        check_linear_moves(robot, Tft, a, b, checker=fresh) for a, b in zip(qa, qb, strict=True)
    ]
    assert together.reason == tuple(c.reason[0] for c in alone)
    assert together.samples.tolist() == [int(c.samples[0]) for c in alone]
    assert together.reason[1] == together.reason[4] == "collision"  # through the block
    assert together.reason[2] == "ok"  # down to weld B (test_linear_moves)


def test_motion_bounds_hold():
    """Every vertex of every body, and every cover-sphere centre, moves no farther over a
    random joint motion (200 samples) than its bound (the static per-body one and the
    per-sphere one)."""
    from weldplan.robot.collision.checker import sphere_rates

    robot = shared_robot()
    Tft, _ = gun_tcp(robot)
    chk = RobotCollision(robot, _plate(), shared_spot_gun(), Tft)
    bodies = chk.bodies
    rng = np.random.default_rng(11)
    t = np.linspace(0.0, 1.0, 200)[:, None]
    for _ in range(4):
        qa = rng.uniform(robot.lower, robot.upper) * 0.5
        qb = qa + rng.normal(0.0, 0.3, 6)
        F = robot.link_frames(qa + t * (qb - qa))  # (200, 7, 4, 4)
        dq = np.abs(qb - qa)
        static = dq @ chk.radii_full  # (b,)
        for b, body in enumerate(bodies):
            Fb = F[:, body.frame]
            v = body.vertices[:: max(1, len(body.vertices) // 300)]
            p = np.einsum("nij,sj->nsi", Fb[:, :3, :3], v) + Fb[:, None, :3, 3]
            assert np.linalg.norm(p - p[:1], axis=2).max() <= static[b] + 1e-6
            c = np.einsum("nij,sj->nsi", Fb[:, :3, :3], body.centres) + Fb[:, None, :3, 3]
            rates = sphere_rates(F[:1], body.frame, body.centres, body.radii, dq[None])
            assert np.all(np.linalg.norm(c - c[:1], axis=2).max(axis=0) <= rates[0] + 1e-6)


def test_a_probe_ends_blocked_motions_early_with_the_same_verdicts(scene, monkeypatch):
    """Long motions through the plate and the block: without the probe the advancement creeps
    to its step cap on each blocked one; with it, the same motions are blocked (same bodies)
    and the same are free, for far fewer FCL distances; and the robot folding into itself."""
    import weldplan.robot.collision.checker as collision

    robot, Tft, Q, chk = scene
    rng = np.random.default_rng(2)
    ends = Q[1] + rng.normal(0.0, 0.5, (12, 6))
    ends[:, 1:3] = Q[1, 1:3] + rng.uniform(-0.2, 0.4, (12, 2))  # down into the plate
    path = np.vstack([Q[1], ends])

    def run(probe):
        monkeypatch.setattr(collision, "PROBE_AFTER", probe)
        monkeypatch.setattr(selfcollision, "PROBE_AFTER", probe)
        fresh = _fresh(chk)  # nothing remembered from the other run
        calls = _counting(monkeypatch, nearpart, "fcl_distance")
        hits = [fresh.path_hits(path[k : k + 2])[:1] for k in range(len(path) - 1)]
        n = len(calls)
        monkeypatch.undo()
        return [(h[0].body if h else None) for h in hits], n

    probed, n_probed = run(selfcollision.PROBE_AFTER)
    crept, n_crept = run(frozenset())
    assert probed == crept
    assert probed.count(None) >= 2 and len(probed) - probed.count(None) >= 4
    assert n_probed < 0.5 * n_crept


def test_a_motion_proved_free_is_not_checked_again_at_that_base(scene, monkeypatch):
    """path_hits remembers the motions it proved free (per base): asked again, the same hits
    and no FCL distance for the free motions; the same checker at another base remembers
    nothing of them; a motion found blocked is checked again (never remembered)."""
    robot, Tft, Q, chk = scene
    chk = _fresh(chk)
    path = Q[1] + np.linspace(0.0, 1.0, 61)[:, None] * (Q[2] - Q[1])  # through the block
    Z = np.zeros(len(path) - 1, dtype=bool)
    first = chk.path_hits(path, Z)
    assert first, "the block stops the path"
    free = np.setdiff1d(np.arange(len(path) - 1), [h.segment for h in first])
    calls = _counting(monkeypatch, nearpart, "fcl_distance")
    assert chk.path_hits(path, Z) == first
    again = len(calls)
    only = np.zeros(len(path) - 1, dtype=bool)
    only[free] = True
    assert chk.path_hits(path, Z, only=only) == []
    assert len(calls) == again  # the free motions alone: nothing asked of FCL
    moved = chk.with_robot(robot.with_base(robot.base @ _shift(1.0)))
    assert moved.path_hits(path, Z, only=only) == _fresh(moved).path_hits(path, Z, only=only)
    assert len(calls) > again  # another base: checked afresh


def _shift(dz):
    """A 4x4 translation by ``dz`` mm along z."""
    T = np.eye(4)
    T[2, 3] = dz
    return T
