"""The tool stages' fast paths give the answers of the exact ones (issue 16, speed target).

Each fast path here is exact or conservative by construction; these tests hold it to the
answers of the plain computation on seeded cases."""

from __future__ import annotations

import fcl
import numpy as np
import pytest
import trimesh

from weldplan.tool.model import ZONE_EDGE_MM, bvh, outside_sphere


def _raw_bvh(v: np.ndarray, f: np.ndarray) -> fcl.BVHModel:
    """A BVH straight from the arrays, every vertex passed (what :func:`bvh` did before)."""
    m = fcl.BVHModel()
    m.beginModel(len(f), len(v))
    m.addSubModel(np.ascontiguousarray(v, dtype=np.float64), np.ascontiguousarray(f))
    m.endModel()
    return m


def _soup(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A triangle soup (three vertices per triangle) with unused vertices around it."""
    m = trimesh.util.concatenate(
        [trimesh.creation.icosphere(2, 40.0), trimesh.creation.box((200, 20, 30))]
    )
    v = np.asarray(m.vertices)[np.asarray(m.faces)].reshape(-1, 3)
    f = np.arange(len(v)).reshape(-1, 3)
    junk = rng.uniform(-500, 500, (50, 3))
    return np.concatenate([junk, v]), f + len(junk)


def test_bvh_of_a_soup_gives_the_distances_and_contacts_of_the_raw_model():
    rng = np.random.default_rng(3)
    v, f = _soup(rng)
    other = trimesh.creation.box((60, 60, 4))
    ob = fcl.CollisionObject(bvh(other.vertices, other.faces), fcl.Transform())
    fast = fcl.CollisionObject(bvh(v, f), fcl.Transform())
    raw = fcl.CollisionObject(_raw_bvh(v, f), fcl.Transform())
    hits = 0
    for _ in range(40):
        R = trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3]
        p = rng.uniform(-80, 80, 3)
        for o in (fast, raw):
            o.setTransform(fcl.Transform(R, p))
        d = [fcl.distance(o, ob, fcl.DistanceRequest(), fcl.DistanceResult()) for o in (fast, raw)]
        assert d[0] == pytest.approx(d[1], abs=1e-9)
        req = fcl.CollisionRequest(num_max_contacts=10_000, enable_contact=True)
        res = [fcl.CollisionResult(), fcl.CollisionResult()]
        n = [fcl.collide(o, ob, req, r) for o, r in zip((fast, raw), res, strict=True)]
        assert n[0] == n[1]
        # the faces keep their order: FCL names the same tool triangles
        assert sorted((c.b1, c.b2) for c in res[0].contacts) == sorted(
            (c.b1, c.b2) for c in res[1].contacts
        )
        hits += n[0] > 0
    assert 5 < hits < 35  # both kinds of pose were tried


def _sliver_fan(n: int = 96, radius: float = 180.0) -> tuple[np.ndarray, np.ndarray]:
    """A flat disc of ``n`` long thin triangles about the origin (like car2's flange strips)."""
    a = np.linspace(0, 2 * np.pi, n + 1)
    rim = np.column_stack([radius * np.cos(a), radius * np.sin(a), np.zeros(n + 1)])
    v = np.concatenate([[[0.0, 0.0, 0.0]], rim])
    f = np.column_stack([np.zeros(n, dtype=int), np.arange(1, n + 1), np.arange(2, n + 2)])
    return v, f


@pytest.mark.parametrize("centre", [(0.0, 0.0, 0.0), (7.0, -3.0, 2.5)])
def test_bisected_cut_keeps_the_guarantee_with_far_fewer_triangles(centre):
    v, f = _sliver_fan()
    r = 20.0
    c = np.asarray(centre)
    mid = outside_sphere(v, f, c, r)
    bis = outside_sphere(v, f, c, r, bisect=True)
    pts, _ = trimesh.sample.sample_surface(trimesh.Trimesh(v, f, process=False), 20_000, seed=1)
    outside = pts[np.linalg.norm(pts - c, axis=1) >= r]
    for kv, kf in (mid, bis):
        tri = kv[kf]
        # nothing wholly inside, and a kept triangle reaching in is finer than ZONE_EDGE_MM
        assert not (np.linalg.norm(tri - c, axis=2) < r).all(axis=1).any()
        cp = trimesh.triangles.closest_point(tri, np.repeat(c[None], len(tri), axis=0))
        reach = np.linalg.norm(cp - c, axis=1) < r
        edges = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
        assert reach.any() and edges[reach].max() <= ZONE_EDGE_MM
        # it covers every point of the mesh outside the sphere
        _, dist, _ = trimesh.proximity.closest_point(
            trimesh.Trimesh(kv, kf, process=False), outside
        )
        assert dist.max() < 1e-6
    assert len(bis[1]) * 3 < len(mid[1])


def test_the_probe_taken_with_the_collision_queries_gives_the_same_miss():
    from weldplan.tool import arc_torch
    from weldplan.tool.poses import (
        MISS_PROBE_CONTACTS,
        PoseSearch,
        candidate_rotations,
        local_candidates,
        probe_positions,
    )

    # a plate, and a small block through which the nozzle's wall passes at some tilts: few
    # triangle pairs touch, and how many depends on the candidate
    part = trimesh.util.concatenate(
        [
            trimesh.creation.box((300, 300, 2)).apply_translation((0, 0, -1)),
            trimesh.creation.box((6, 6, 6)).apply_translation((12.5, 0, 40)),
        ]
    )
    search = PoseSearch(part, arc_torch(bend_angle=0.0), 10.0, 5.0)
    p = np.zeros(3)
    obj, index = search.part_near(p)
    local, params = local_candidates(15.0, 7.5, 15.0, 8)
    rots = candidate_rotations(np.array([[0.0, 0.0, -1.0]]), local)[0]
    hit = search.collides(obj, p, rots)
    rots = rots[hit]  # the miss is asked of candidates none of which is free
    params = np.column_stack([params, np.zeros(len(params))])[hit]
    probe = np.zeros(len(rots), dtype=bool)
    probe[probe_positions(len(rots))] = True
    counts = search.touching(obj, p, rots, probe)
    assert len(rots) > 20 and (counts > 0).all()
    asked = search._touching(obj, p, rots[probe], MISS_PROBE_CONTACTS)
    assert np.array_equal(counts[probe], asked) and len(set(asked.tolist())) > 2
    dist = np.zeros(len(rots))
    plain = search.miss(obj, index, p, rots, dist, params)
    folded = search.miss(obj, index, p, rots, dist, params, np.where(probe, counts, -1))
    assert folded == plain
