"""Crops of the part for the conservative advancement: the same FCL distances as the whole part."""

from __future__ import annotations

import fcl
import numpy as np
import trimesh

from weldplan.robot.collision import AlongMotion, PartCrops, fcl_distance
from weldplan.tool.model import bvh


def _sheet() -> trimesh.Trimesh:
    """A bent sheet of many small triangles (so that a crop holds few of them)."""
    s = trimesh.creation.box((800.0, 600.0, 2.0)).subdivide().subdivide().subdivide()
    w = trimesh.creation.box((2.0, 600.0, 300.0)).subdivide().subdivide()
    w.apply_translation((400.0, 0.0, 150.0))
    return trimesh.util.concatenate([s, w])


def _pose(p: np.ndarray, angle: float) -> np.ndarray:
    T = np.eye(4)
    c, s = np.cos(angle), np.sin(angle)
    T[:3, :3] = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
    T[:3, 3] = p
    return T


def test_near_holds_every_triangle_within_reach():
    part = _sheet()
    crops = PartCrops(part.vertices, part.faces, None)
    rng = np.random.default_rng(0)
    for _ in range(20):
        c = rng.uniform(part.bounds[0] - 50.0, part.bounds[1] + 50.0, (3, 3))
        reach = rng.uniform(5.0, 80.0, 3)
        got = set(crops.near(c, reach).tolist())
        for ci, r in zip(c, reach, strict=True):
            cp = trimesh.triangles.closest_point(part.triangles, np.tile(ci, (len(part.faces), 1)))
            within = np.flatnonzero(np.linalg.norm(cp - ci, axis=1) <= r)
            assert set(within.tolist()) <= got


def test_distances_along_a_motion_are_the_whole_parts():
    part = _sheet()
    whole = fcl.CollisionObject(bvh(part.vertices, part.faces), fcl.Transform())
    crops = PartCrops(part.vertices, part.faces, whole)
    body = trimesh.creation.capsule(height=120.0, radius=15.0).subdivide()
    obj = fcl.CollisionObject(bvh(body.vertices, body.faces), fcl.Transform())
    centres = np.array([[0.0, 0.0, -60.0], [0.0, 0.0, 0.0], [0.0, 0.0, 60.0]])
    radii = np.full(3, 60.0 + 1e-6)
    rng = np.random.default_rng(1)
    n_crop = 0
    closest = np.inf
    for _ in range(6):
        # a straight slide from 80 mm above the sheet down to it (contact at the end), turning
        a = np.array([*rng.uniform(-300.0, 300.0, 2), 180.0])
        b = np.array([*rng.uniform(-300.0, 300.0, 2), 70.0])
        ta, tb = rng.uniform(-1.0, 1.0, 2)
        rate = float(np.linalg.norm(b - a) + abs(tb - ta) * 140.0)  # mm over the whole motion
        along = AlongMotion(crops, obj, centres, radii, rate)
        t = 0.0
        for _ in range(60):
            T = _pose(a + t * (b - a), ta + t * (tb - ta))
            d = along.distance(T, t)
            assert d == fcl_distance(obj, T, whole)
            n_crop += along.target is not whole
            closest = min(closest, d)
            if d <= 1.0 or t >= 1.0:
                break
            t = min(1.0, t + (d - 1.0) / rate)
    assert n_crop > 0  # the crops were used, not only the whole part
    assert closest < 1.01  # and near contact, where the steps are many
