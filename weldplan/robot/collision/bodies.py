"""The robot's rigid bodies as the collision checks see them, where a motion was found blocked,
and the structures shared by every checker of one part (:mod:`weldplan.robot.collision.checker`
uses them).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field

import fcl
import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.tool.model.tool import bvh


@dataclass(frozen=True, eq=False)
class Body:
    """A rigid body of the robot: mesh in the frame of link ``frame`` (0 = base), its sphere
    cover and its FCL object."""

    name: str
    frame: int
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    centres: NDArray[np.float64]
    radii: NDArray[np.float64]
    group: NDArray[np.int64]
    centre: NDArray[np.float64]
    radius: float
    parts: dict[tuple[int, ...], fcl.CollisionObject] = field(default_factory=dict, repr=False)
    groups: list[tuple[NDArray, ...]] = field(default_factory=list, repr=False)

    @property
    def obj(self) -> fcl.CollisionObject:
        """The FCL object of the whole body (built once)."""
        if () not in self.parts:
            self.parts[()] = fcl.CollisionObject(bvh(self.vertices, self.faces), fcl.Transform())
        return self.parts[()]

    def union(self, spheres: NDArray[np.int64]) -> fcl.CollisionObject:
        """An FCL object of the triangles in ``spheres`` (cached per set of spheres)."""
        key = tuple(int(x) for x in np.sort(spheres))
        if key not in self.parts:
            f = self.faces[np.isin(self.group, key)]
            used, inv = np.unique(f, return_inverse=True)
            sub = bvh(self.vertices[used], inv.reshape(-1, 3))
            self.parts[key] = fcl.CollisionObject(sub, fcl.Transform())
        return self.parts[key]


@dataclass(frozen=True)
class Hit:
    """Where a motion was found blocked.

    Attributes
    ----------
    segment
        The motion's index (rows ``segment -> segment + 1``).
    t
        Fraction of the motion (0..1) where the body came within
        :data:`~weldplan.robot.collision.checker.MIN_GAP_MM`.
    body
        The body's name (a link name or ``tool``), or the pair that met (``"tool/link_3"``,
        ``"link_2/floor"``: :mod:`weldplan.robot.collision.selfcollision`).
    distance
        mm: FCL distance there (0 when the meshes intersect).
    """

    segment: int
    t: float
    body: str
    distance: float


#: structures that depend on a part alone (its exact distance, its distance table), shared by
#: every checker of it: by the part object's id and content hash (trimesh's, changed by any
#: edit of the mesh), an entry dropped when its part is collected
BY_PART: dict[tuple[int, int], dict[str, object]] = {}


def of_part(part: trimesh.Trimesh) -> dict[str, object]:
    """The shared structures of ``part`` (see :data:`BY_PART`), an empty dict at first."""
    key = (id(part), hash(part))
    got = BY_PART.get(key)
    if got is None:
        got = BY_PART[key] = {}
        weakref.finalize(part, BY_PART.pop, key, None)
    return got
