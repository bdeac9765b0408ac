"""The pose search's clearance bound (weldplan.tool.poses.bound): it never calls short a pose that
FCL's distance of the whole tool calls free, nor free one it calls short, and the search that
uses it chooses what the whole-tool distance chose."""

from __future__ import annotations

import fcl
import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from tests.conftest import require_shared
from weldplan.io.joints import Joints
from weldplan.tool import PoseSearchSettings, Tool, plan_weld_poses, shared_spot_gun
from weldplan.tool.poses import PoseBound, PoseSearch, ToolPieces
from weldplan.tool.poses import search as pose_search

DEMO_PART = "assets/demo/part.stl"
CLEARANCE = 5.0
RADIUS = 20.0


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


def _sheet() -> trimesh.Trimesh:
    """A sheet with a rib standing on it: some poses clear it by more than the clearance, some
    by less, some hit it."""
    return trimesh.util.concatenate(
        [_box((400, 400, 2), (0, 0, -1)), _box((300, 4, 60), (0, 40, 30))]
    )


def _agree(part: trimesh.Trimesh, tool: Tool, P: np.ndarray, Rs: np.ndarray) -> dict[str, int]:
    """Classify the poses that do not collide, each against FCL's distance of the whole tool
    outside its zone (the search's own exact query); returns counts of what was seen."""
    search = PoseSearch(part, tool, RADIUS, CLEARANCE, crop=False)
    bound = PoseBound(part, tool, RADIUS, CLEARANCE)
    seen = {"free": 0, "short": 0, "bound_free": 0}
    for p, R in zip(P, Rs, strict=True):
        obj, _ = search.part_near(p)
        if obj is None or search.collides(obj, p, R[None])[0]:
            continue
        exact = search.distance(obj, p, R)
        out = bound.classify([obj], p[None], R[None])
        free = bool(out.value[0] >= CLEARANCE)
        assert free == (exact >= CLEARANCE), (p, R, exact, out.value[0])
        if free:
            assert out.value[0] <= exact + 1e-6  # a lower bound where free
        else:
            assert out.value[0] >= exact - 1e-6  # an upper bound where short
        seen["free" if free else "short"] += 1
        seen["bound_free"] += out.bound_free
    return seen


def test_the_pieces_hold_the_tool_and_each_sphere_its_children():
    v, f = _fork().outside_zone(RADIUS)
    pc = ToolPieces.build(v, f)
    # every point of the tool outside its zone lies in some piece's sphere
    pts, _ = trimesh.sample.sample_surface(trimesh.Trimesh(v, f, process=False), 3000, seed=2)
    d = np.linalg.norm(pts[:, None] - pc.centres[-1][None], axis=2) - pc.radii[-1][None]
    assert np.all(d.min(axis=1) <= 1e-9)
    for level, (starts, index) in enumerate(pc.children):
        for s in range(len(pc.radii[level])):
            kids = index[starts[s] : starts[s + 1]]
            gap = np.linalg.norm(pc.centres[level + 1][kids] - pc.centres[level][s], axis=1)
            assert np.all(gap + pc.radii[level + 1][kids] <= pc.radii[level][s] + 1e-9)
    assert len(pc.objects) == len(pc.radii[-1])


def test_on_a_ribbed_sheet_the_bound_is_fcls_answer_both_ways():
    rng = np.random.default_rng(7)
    n = 800
    P = np.column_stack(
        [rng.uniform(-150, 150, n), rng.uniform(-60, 120, n), rng.uniform(0, 40, n)]
    )
    Rs = Rotation.random(n, random_state=11).as_matrix()
    seen = _agree(_sheet(), _fork(), P, Rs)
    assert seen["free"] > 30 and seen["short"] > 30 and seen["bound_free"] > 0, seen


def test_first_free_stops_at_the_first_free_candidate():
    part, tool = _sheet(), _fork()
    search = PoseSearch(part, tool, RADIUS, CLEARANCE, crop=False)
    bound = PoseBound(part, tool, RADIUS, CLEARANCE)
    obj, _ = search.part_near(np.zeros(3))
    Rs = Rotation.random(400, random_state=3).as_matrix()
    p = np.array([0.0, 20.0, 10.0])
    Rs = Rs[~search.collides(obj, p, Rs)]
    P = np.tile(p, (len(Rs), 1))
    every = bound.classify([obj] * len(Rs), P, Rs).value
    first = bound.classify([obj] * len(Rs), P, Rs, first_free=True).value
    k = int(np.argmax(every >= CLEARANCE))
    assert every[k] >= CLEARANCE and np.any(every[:k] < CLEARANCE)  # not the first pose
    np.testing.assert_array_equal(first[: k + 1], every[: k + 1])
    assert np.all(np.isnan(first[k + 1 :]))


def test_the_search_chooses_what_the_whole_tool_distance_chose(monkeypatch):
    # a channel 16 mm wide beside the rib: the 10 mm stick keeps 3 mm from its walls untilted
    # and hits them tilted, so its weld is missed by a clearance shortfall
    walls = [_box((200, 4, 60), (0, -150 + s * 10, 30)) for s in (-1, 1)]
    part = trimesh.util.concatenate([_sheet(), *walls])
    fork = _fork()
    # spots along the rib's foot (short and free candidates side by side), one in the open and
    # one in the channel
    joints = Joints(
        ids=["a", "b", "c", "d", "e"],
        xyz=[
            (-60.0, 30.0, 0.0),
            (0.0, 30.0, 0.0),
            (60.0, 30.0, 0.0),
            (0.0, -80.0, 0.0),
            (0.0, -150.0, 0.0),
        ],
        directions=[[0.0, 0.0, 1.0]] * 5,
    )
    kw = PoseSearchSettings(clearance=CLEARANCE, spin_step=30.0, both_sides=False)
    monkeypatch.setattr(pose_search, "PIECES_AFTER", 0)  # the pieces from the first judgement
    fast = plan_weld_poses(part, joints, fork, kw)

    def whole(self, objs, P, Rs, *, first_free=False):  # the search before the bound
        out = np.full(len(Rs), np.nan)
        for a, (o, p, R) in enumerate(zip(objs, P, Rs, strict=True)):
            out[a] = self.distance(o, p, R)
            if first_free and out[a] >= self.clearance:
                break
        return out

    monkeypatch.setattr(PoseSearch, "clearances", whole)
    exact = plan_weld_poses(part, joints, fork, kw)
    assert fast.stats["clearance_judged"] > 10 and fast.stats["clearance_piece_queries"] > 0
    assert fast.stats["distance_queries"] == exact.stats["distance_queries"]
    for p, q in zip(fast.poses, exact.poses, strict=True):
        assert (p.status, p.quaternion, p.n_collision_free) == (
            q.status,
            q.quaternion,
            q.n_collision_free,
        )
        assert p.miss == q.miss
    assert fast.total_rotation == exact.total_rotation
    assert [p.ok for p in fast.poses] == [True] * 4 + [False]
    assert fast.poses[4].miss.distance > 0  # short, not colliding: measured exactly


def test_a_second_search_of_the_same_part_reuses_the_answers_and_gives_the_same_poses():
    part, fork = _sheet(), _fork()
    joints = Joints(
        ids=["a", "b"], xyz=[(-60.0, 30.0, 0.0), (0.0, 30.0, 0.0)], directions=[[0.0, 0.0, 1.0]] * 2
    )
    kw = PoseSearchSettings(clearance=CLEARANCE, spin_step=30.0)
    first = plan_weld_poses(part, joints, fork, kw)
    again = plan_weld_poses(part, joints, fork, kw)
    assert first.stats["clearance_memo"] == 0
    # every collide and every clearance the first search asked is found, none asked again
    assert (
        again.stats["clearance_memo"]
        == first.stats["collision_queries"] + first.stats["distance_queries"]
    )
    assert again.stats["clearance_judged"] == 0
    assert [p.to_dict() for p in again.poses] == [p.to_dict() for p in first.poses]
    # another part (a copy: the same triangles) starts a memo of its own
    other = plan_weld_poses(part.copy(), joints, fork, kw)
    assert other.stats["clearance_memo"] == 0
    assert [p.to_dict() for p in other.poses] == [p.to_dict() for p in first.poses]


@pytest.fixture(scope="module")
def demo_gun():
    d = require_shared("tools", "spot_welding_gun")
    return trimesh.load(DEMO_PART, force="mesh"), shared_spot_gun(d)


def test_on_the_demo_part_the_bound_never_rejects_a_pose_fcl_calls_free(demo_gun):
    part, gun = demo_gun
    rng = np.random.default_rng(5)
    # TCPs on the part's surface, a little off it (where the gun welds), any orientation; and
    # the approach axis into the sheet, tilted up to 20 deg (where the search looks)
    n = 160
    P, tri = trimesh.sample.sample_surface(part, n, seed=4)
    P = P + rng.normal(0.0, 1.0, P.shape)
    normal = np.asarray(part.face_normals)[tri]
    turn = Rotation.from_rotvec(rng.normal(0.0, np.radians(10.0), (n, 3)))
    z = turn.apply(np.where(rng.random((n, 1)) < 0.5, normal, -normal))
    x = np.cross(z, rng.normal(size=(n, 3)))
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    aligned = np.stack([x, np.cross(z, x), z], axis=2)
    Rs = np.concatenate([Rotation.random(n, random_state=6).as_matrix(), aligned])
    seen = _agree(part, gun, np.concatenate([P, P]), Rs)
    assert seen["free"] > 10 and seen["short"] > 10 and seen["bound_free"] > 0, seen


def test_fcl_distance_of_a_piece_is_never_below_the_whole_tools(demo_gun):
    # the pieces are the tool's own surface: each piece's distance bounds the tool's from above
    part, gun = demo_gun
    bound = PoseBound(part, gun, RADIUS, CLEARANCE)
    search = PoseSearch(part, gun, RADIUS, CLEARANCE, crop=False)
    obj, _ = search.part_near(np.asarray(part.vertices[0]))
    rng = np.random.default_rng(9)
    for k in range(8):
        R = Rotation.random(random_state=k).as_matrix()
        p = np.asarray(part.vertices[k]) + rng.normal(0, 30, 3)
        if search.collides(obj, p, R[None])[0]:
            continue
        whole = search.distance(obj, p, R)
        tf = fcl.Transform(R, p)
        least = min(bound._piece(i, tf, obj) for i in range(len(bound.pieces.objects)))
        assert least == pytest.approx(whole, abs=1e-6)
