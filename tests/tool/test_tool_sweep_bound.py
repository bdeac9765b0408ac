"""The sphere bound of the swept check (weldplan.tool.transitions.sweep_bound) and the checker that
asks it first (weldplan.tool.transitions.sweep_fast): never "free" where exact FCL says not, on
synthetic tools and on the shared gun against the demo part."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from tests.conftest import require_shared
from weldplan.tool import Tool, TransitionSettings, shared_spot_gun
from weldplan.tool.transitions import (
    BLOCKED,
    REPLANNED,
    SphereTree,
    SweepBound,
    SweepChecker,
    interpolate,
    plan_transitions,
    quat_to_matrix,
)
from weldplan.tool.transitions.sweep_fast import FastSweep, _bisection_order
from weldplan.tool.verify import verify_sweeps

DEMO_PART = "assets/demo/part.stl"


def _box(extents, centre) -> trimesh.Trimesh:
    return trimesh.creation.box(extents).apply_translation(centre)


def _fork() -> Tool:
    """A stick behind the TCP and a jaw ahead of it round a sheet's edge (a small C-gun)."""
    m = trimesh.util.concatenate(
        [
            _box((10, 10, 200), (0, 0, -100)),
            _box((10, 10, 40), (100, 0, 10)),
            _box((110, 10, 10), (50, 0, 35)),
        ]
    )
    return Tool("fork", np.asarray(m.vertices), np.asarray(m.faces), straddles=True)


def _random_poses(rng, lo, hi, n):
    P = rng.uniform(lo, hi, (n, 3))
    Q = Rotation.random(n, random_state=int(rng.integers(1 << 31))).as_quat()
    return P, np.roll(Q, 1, axis=1)  # wxyz


def test_the_sphere_tree_holds_the_tool_and_each_sphere_its_children():
    tool = _fork()
    tree = SphereTree.build(tool.vertices, tool.faces, (4.0, 12.0, 40.0))
    fine_c, fine_r = tree.centres[-1], tree.radii[-1]
    # every point of the tool (its triangles, sampled) lies in a finest sphere
    pts, _ = trimesh.sample.sample_surface(tool.mesh, 3000, seed=0)
    pts = np.vstack([pts, tool.vertices])
    gap = np.linalg.norm(pts[:, None] - fine_c[None], axis=2) - fine_r[None]
    assert np.all(gap.min(axis=1) <= 1e-9)
    # each coarser sphere holds its children, and every finer sphere has one parent
    for level in range(len(tree.radii) - 1):
        idx, owner = tree.open(level, np.arange(len(tree.radii[level])))
        assert np.array_equal(np.sort(idx), np.arange(len(tree.radii[level + 1])))
        child = np.linalg.norm(tree.centres[level + 1][idx] - tree.centres[level][owner], axis=1)
        assert np.all(child + tree.radii[level + 1][idx] <= tree.radii[level][owner] + 1e-9)


def test_bisection_order_visits_every_sample_once_the_middle_first():
    for n in (1, 2, 3, 8, 9, 33):
        order = _bisection_order(n)
        assert sorted(order.tolist()) == list(range(n))
        if n > 2:
            assert order[0] == (n - 1) // 2 or abs(order[0] - (n - 1) / 2) <= 1
            assert set(order[-2:].tolist()) == {0, n - 1}


def _sheet_and_rib() -> trimesh.Trimesh:
    sheet = _box((400, 400, 2), (-140, 0, -1))
    rib = _box((560, 4, 60), (-60, 0, 30))
    return trimesh.util.concatenate([sheet, rib])


@pytest.mark.parametrize("exempt", [False, True])
def test_states_the_bound_clears_are_free_for_fcl_and_the_fast_answer_is_fcls(exempt):
    part = _sheet_and_rib()
    fork = _fork()
    chk = SweepChecker(part, fork, clearance=5.0, contact_radius=20.0)
    fast = FastSweep(chk, SweepBound(part, fork, 5.0, 20.0))
    spots = np.array([[30.0, -100, 0], [30, 100, 0]]) if exempt else None
    rng = np.random.default_rng(7)
    P, Q = _random_poses(rng, part.bounds[0] - 150, part.bounds[1] + 150, 400)
    cleared = 0
    for p, q in zip(P, Q, strict=True):
        R = quat_to_matrix(q)
        exact = chk.slack(p, R, spots)
        if fast.bound.state_clear(p, R, exempt):
            cleared += 1
            assert exact >= 0.0, (p, q)
        assert fast.state_ok(p, q, spots) == (exact >= 0.0)
    assert 0 < cleared < len(P)  # the bound decides some, not all


def test_motions_the_fast_check_passes_keep_the_clearance_and_pass_the_exact_check():
    part = _sheet_and_rib()
    fork = _fork()
    chk = SweepChecker(part, fork, clearance=5.0, contact_radius=20.0)
    fast = FastSweep(chk, SweepBound(part, fork, 5.0, 20.0))
    rng = np.random.default_rng(11)
    P, Q = _random_poses(rng, part.bounds[0] - 100, part.bounds[1] + 200, 160)
    passed = blocked = 0
    for k in range(0, len(P) - 1, 2):
        p0, q0, p1 = P[k], Q[k], P[k] + rng.normal(0.0, 60.0, 3)
        q1 = np.roll((Rotation.from_quat(np.roll(q0, -1)) * Rotation.from_rotvec(
            rng.normal(0.0, 0.3, 3))).as_quat(), 1)  # fmt: skip
        if not (chk.state_ok(p0, q0) and chk.state_ok(p1, q1)):
            continue
        out = fast.check(p0, q0, p1, q1, None, (False, False))
        if not out.ok:
            blocked += 1
            continue
        passed += 1
        assert chk.check(p0, q0, p1, q1, None, (False, False)).ok
        pos, rots = interpolate(p0, q0, p1, q1, np.linspace(0.0, 1.0, 41))
        assert min(chk.slack(a, b) for a, b in zip(pos, rots, strict=True)) >= 0.0
    assert passed > 5 and blocked > 0


@pytest.mark.slow
def test_only_se3_joins_two_welds_across_a_rib_and_the_recheck_agrees():
    pytest.importorskip("ompl")
    from weldplan.tool import WeldPose, WeldPoses
    from weldplan.tool.poses import OK, quat_wxyz

    part = _sheet_and_rib()
    q = tuple(float(v) for v in quat_wxyz(np.diag([1.0, -1.0, -1.0])[None])[0])
    poses = WeldPoses(
        tuple(WeldPose(i, OK, p, (0.0, 0.0, -1.0), q) for i, p in
              (("a", (30.0, -100.0, 0.0)), ("b", (30.0, 100.0, 0.0)))),  # fmt: skip
        "fork", 0.0, {"clearance": 5.0, "contact_radius": 20.0},
    )  # fmt: skip
    fork = _fork()
    # no slide, axial retract or side exit passes the rib (test_tool_transitions)
    side = TransitionSettings(retract=50.0, side_exit=120.0)
    without = plan_transitions(part, fork, poses, replace(side, se3=False))
    assert without.transitions[0].status == BLOCKED
    # the time is only a cap (RRT-Connect stops at its first solution; a loaded machine is slow)
    path = plan_transitions(part, fork, poses, replace(side, time_s=60.0, seed=3))
    (t,) = path.transitions
    assert t.status == REPLANNED and t.via == "se3", t.reason
    # the TCP rises over the 60 mm rib somewhere between the two welds
    assert t.positions[:, 2].max() > 60.0
    v = verify_sweeps(path, poses, part, fork)
    assert v.ok and v.checked == 1, v.describe()


@pytest.fixture(scope="module")
def demo_gun():
    """``(part, exact checker, fast check)`` of the shared gun on the demo part (built once: the
    fast check's distance table is a cache of exact distances, so sharing it changes no answer)."""
    d = require_shared("tools", "spot_welding_gun")
    gun = shared_spot_gun(d)
    part = trimesh.load(DEMO_PART, force="mesh")
    chk = SweepChecker(part, gun, clearance=5.0, contact_radius=20.0)
    return part, chk, FastSweep(chk, SweepBound(part, gun, 5.0, 20.0))


@pytest.mark.slow
def test_on_the_demo_part_the_shared_gun_is_never_cleared_where_fcl_says_not(demo_gun):
    part, chk, fast = demo_gun
    rng = np.random.default_rng(5)
    # TCPs near the part's surface (where the gun works) and anywhere in its reach
    near, _ = trimesh.sample.sample_surface(part, 150, seed=1)
    near = near + rng.normal(0.0, 25.0, near.shape)
    far = rng.uniform(part.bounds[0] - 400, part.bounds[1] + 400, (150, 3))
    spots = np.asarray(part.vertices[:2], dtype=np.float64)
    cleared = free = 0
    for k, p in enumerate(np.vstack([near, far])):
        q = np.roll(Rotation.random(random_state=k).as_quat(), 1)
        R = quat_to_matrix(q)
        exact = chk.slack(p, R, spots)
        free += exact >= 0.0
        if fast.bound.state_clear(p, R, True):
            cleared += 1
            assert exact >= 0.0, (p, q, exact)
        assert fast.state_ok(p, q, spots) == (exact >= 0.0)
    assert cleared > 0.5 * free


@pytest.mark.slow
def test_on_the_demo_part_gun_motions_the_fast_check_passes_keep_the_clearance(demo_gun):
    part, chk, fast = demo_gun
    rng = np.random.default_rng(13)
    spots = np.asarray(part.vertices[:2], dtype=np.float64)
    passed = 0
    for k in range(60):
        p0 = rng.uniform(part.bounds[0] - 300, part.bounds[1] + 300)
        q0 = np.roll(Rotation.random(random_state=100 + k).as_quat(), 1)
        p1 = p0 + rng.normal(0.0, 80.0, 3)
        turn = Rotation.from_rotvec(rng.normal(0.0, 0.2, 3))
        q1 = np.roll((Rotation.from_quat(np.roll(q0, -1)) * turn).as_quat(), 1)
        if not (fast.state_ok(p0, q0, spots) and fast.state_ok(p1, q1, spots)):
            continue
        if not fast.check(p0, q0, p1, q1, spots, (False, False)).ok:
            continue
        passed += 1
        pos, rots = interpolate(p0, q0, p1, q1, np.linspace(0.0, 1.0, 21))
        assert min(chk.slack(a, b, spots) for a, b in zip(pos, rots, strict=True)) >= 0.0
    assert passed > 5


def test_slack_answers_a_repeated_query_from_memory_and_tells_the_crops_apart(monkeypatch):
    """SweepChecker.slack keeps its answers: asked again (same pose, same spots, same part
    object) it asks FCL nothing and says the same; with other spots, or against a focus' crop,
    it measures afresh, and every answer is a fresh checker's."""
    import fcl

    part = _sheet_and_rib()
    fork = _fork()
    chk = SweepChecker(part, fork, clearance=5.0, contact_radius=20.0)
    rng = np.random.default_rng(11)
    P, Q = _random_poses(rng, part.bounds[0] - 50, part.bounds[1] + 50, 30)
    spots = np.array([[30.0, -100, 0], [30, 100, 0]])
    calls = []
    real = fcl.distance

    def spy(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(fcl, "distance", spy)
    poses = [(p, quat_to_matrix(q)) for p, q in zip(P, Q, strict=True)]
    first = [(chk.slack(p, R), chk.slack(p, R, spots)) for p, R in poses]
    n = len(calls)
    assert n >= 2 * len(poses)  # every one measured
    assert [(chk.slack(p, R), chk.slack(p, R, spots)) for p, R in poses] == first
    assert len(calls) == n  # from memory
    fresh = SweepChecker(part, fork, clearance=5.0, contact_radius=20.0)
    assert [(fresh.slack(p, R), fresh.slack(p, R, spots)) for p, R in poses] == first
    chk.focus(P.min(axis=0), P.max(axis=0))  # every pose in the box: the crop answers
    fresh.focus(P.min(axis=0), P.max(axis=0))
    n = len(calls)
    crop = [chk.slack(p, R, spots) for p, R in poses]
    assert len(calls) > n  # another part object: measured afresh
    assert crop == [fresh.slack(p, R, spots) for p, R in poses]
