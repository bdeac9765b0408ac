"""The part's triangles near a moving body, for the conservative advancement's FCL distances.

Conservative advancement (:meth:`weldplan.robot.collision.RobotCollision._advance`) asks FCL for
the distance of a body to the part at every step; near contact it takes hundreds of steps, and
each distance against the whole part (the car body: 18k triangles) cost 10-20 ms. The answer
depends only on the part's triangles nearest the body, so it is asked of a *crop*: the triangles
whose bounding box comes within ``margin`` mm of the body's cover spheres at one configuration
(a superset of those within ``margin`` of the body).

Why the answer is the same. FCL's distance is the least distance over pairs of triangles (its
traversal prunes only bounding volumes farther than the best pair found), computed from the same
coordinates whichever set holds them. Let the crop be taken with the body at ``t_c`` and let
every point of the body move at most ``moved`` mm between ``t_c`` and now. If the body's
distance ``d`` to the whole part is below ``margin - moved``, the part point nearest the body
is within ``d + moved < margin`` of the body as it was at ``t_c``, so its triangle is in the
crop and the crop's distance is ``d`` (and a contact is a contact of the crop). If ``d`` is not
below it, the crop's distance (never below ``d``) is not below it either. So a crop distance
below ``margin - moved`` is the exact distance; any other answer is not used, and the crop is
taken again about the body where it is now, with a margin above the distance just found (an
empty crop: four times the margin), which then answers (:meth:`AlongMotion.distance`). On the
200-joint bench the tool's 3906 distances of the first check, asked of a crop at each step,
all equal the whole part's to the bit, and the check's 25 hits (``t``, distance) are unchanged.
"""

from __future__ import annotations

import fcl
import numpy as np
from numpy.typing import NDArray

from weldplan.tool.model.tool import bvh

#: mm: the first crop's margin about the body (later ones: twice the distance found, plus this)
CROP_MARGIN_MM = 20.0
#: above this share of the part's triangles a crop is not worth its BVH: the whole part is used
CROP_SHARE = 0.5


def fcl_tf(T: NDArray[np.float64]) -> fcl.Transform:
    """The FCL transform of ``T (4, 4)``."""
    return fcl.Transform(T[:3, :3], T[:3, 3])


def fcl_distance(
    obj: fcl.CollisionObject, T: NDArray[np.float64], other: fcl.CollisionObject
) -> float:
    """mm: FCL distance of ``obj`` placed at ``T (4, 4)`` to ``other``; 0 when they touch."""
    obj.setTransform(fcl_tf(T))
    if fcl.collide(obj, other, fcl.CollisionRequest(), fcl.CollisionResult()):
        return 0.0
    return max(float(fcl.distance(obj, other, fcl.DistanceRequest(), fcl.DistanceResult())), 0.0)


class PartCrops:
    """The part's triangles, their bounding boxes and the whole part's FCL object.

    Parameters
    ----------
    vertices, faces
        The part mesh (mm).
    whole
        The FCL object of the whole part (identity transform).
    """

    def __init__(
        self, vertices: NDArray[np.float64], faces: NDArray[np.int64], whole: fcl.CollisionObject
    ) -> None:
        self.vertices = np.asarray(vertices, dtype=np.float64)
        self.faces = np.asarray(faces, dtype=np.int64)
        tri = self.vertices[self.faces]
        self.lo = tri.min(axis=1)
        self.hi = tri.max(axis=1)
        self.whole = whole

    def near(self, centres: NDArray[np.float64], reach: NDArray[np.float64]) -> NDArray[np.int64]:
        """Indices of the triangles whose bounding box comes within ``reach (k,)`` mm of any of
        ``centres (k, 3)`` (a superset of the triangles within that reach)."""
        top = (centres + reach[:, None]).max(axis=0)
        bot = (centres - reach[:, None]).min(axis=0)
        cand = np.flatnonzero(np.all((self.lo <= top) & (self.hi >= bot), axis=1))
        if len(cand) == 0:
            return cand
        gap = np.clip(centres[None], self.lo[cand, None], self.hi[cand, None]) - centres[None]
        return cand[np.any(np.einsum("cki,cki->ck", gap, gap) <= reach[None] ** 2, axis=1)]

    def crop(
        self, centres: NDArray[np.float64], reach: NDArray[np.float64]
    ) -> fcl.CollisionObject | None:
        """An FCL object of :meth:`near`'s triangles; the whole part when they are more than
        :data:`CROP_SHARE` of it; ``None`` when there are none."""
        idx = self.near(centres, reach)
        if len(idx) == 0:
            return None
        if len(idx) > CROP_SHARE * len(self.faces):
            return self.whole
        return fcl.CollisionObject(bvh(self.vertices, self.faces[idx]), fcl.Transform())


class AlongMotion:
    """Exact FCL distances of one body to the part along one motion, asked of crops (module
    docstring).

    Parameters
    ----------
    crops
        The part (:class:`PartCrops`).
    obj
        The body's FCL object (in its link's frame).
    centres, radii
        ``(k, 3)`` mm in the link's frame, ``(k,)`` mm: spheres that hold the body.
    rate
        mm: no point of the body moves more than this over the whole motion (``t`` 0 to 1).
    crop
        Ask crops; ``False``: the whole part (the same answers).
    """

    def __init__(
        self,
        crops: PartCrops,
        obj: fcl.CollisionObject,
        centres: NDArray[np.float64],
        radii: NDArray[np.float64],
        rate: float,
        *,
        crop: bool = True,
    ) -> None:
        self.crops = crops
        self.obj = obj
        self.centres = centres
        self.radii = radii
        self.rate = rate
        self.target: fcl.CollisionObject | None = None if crop else crops.whole
        self.t_c = 0.0
        self.margin = CROP_MARGIN_MM

    def distance(self, T: NDArray[np.float64], t: float) -> float:
        """mm: FCL distance to the whole part of the body at ``T (4, 4)`` (its link frame), at
        fraction ``t`` of the motion; 0 on contact."""
        while True:
            if self.target is None:
                self._take(T, t)
            if self.target is self.crops.whole:
                return fcl_distance(self.obj, T, self.target)
            moved = self.rate * abs(t - self.t_c)
            d = np.inf if self.target is _EMPTY else fcl_distance(self.obj, T, self.target)
            if d < self.margin - moved:
                return d
            self.margin = 2.0 * d + CROP_MARGIN_MM if np.isfinite(d) else 4.0 * self.margin
            self.target = None

    def _take(self, T: NDArray[np.float64], t: float) -> None:
        """Crop the part about the body at ``T``, ``t`` with the current margin."""
        c = self.centres @ T[:3, :3].T + T[:3, 3]
        crop = self.crops.crop(c, self.radii + self.margin)
        self.target = _EMPTY if crop is None else crop
        self.t_c = t


#: a crop that holds no triangle
_EMPTY = fcl.CollisionObject(fcl.Sphere(1.0), fcl.Transform())
