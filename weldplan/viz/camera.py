"""The opening view of a page: the scene scaled about the origin and the camera framed on it.

Every page (route, robot cell, feasibility study) opens on the bounding box of everything it
draws: the part, the route, the robot over its whole cycle, the tool. :func:`frame_scene` sets the
scene's mm -> viewer transform (:func:`scene_transform`: the box centred on the origin, where
meshcat's orbit controls look, about :data:`SCENE_SIZE` viewer units across) and puts the camera
on a diagonal (:data:`AZIMUTH_DEG`, :data:`ELEVATION_DEG`; z up in the drawn frame, the cell's
when the part has a pose in it) at the smallest distance at which every framed point (the
corners of the part's box, the route, the corners of each link's box at each frame...) fits in
the field of view (:func:`camera_view`, with :data:`MARGIN`): a pinhole fit of the points
themselves, tighter than one of their box's corners. The near and far planes
follow the scene's size, so a 0.3 m demo part and a 4.5 m car body both open whole and can be
zoomed into without clipping.

meshcat's camera hangs under ``/Cameras/default/rotated``, a quarter turn about x (three.js is
y up): a point ``(x, y, z)`` of the scene is ``(x, z, -y)`` in that frame (:func:`camera_local`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: the scene spans about this many viewer units (meshcat's camera is made for a metre or two)
SCENE_SIZE = 2.0
#: the camera's vertical field of view (deg): narrower than meshcat's 75, so that the near side
#: of the cell is not blown up by perspective (the camera stands farther back instead)
FOV_DEG = 40.0
#: the view from the front right (deg about z from +x; -90 is looking along +y) ...
AZIMUTH_DEG = -55.0
#: ... and from above (deg over the horizontal)
ELEVATION_DEG = 28.0
#: the framed points fill at most 1 / MARGIN of the view's height (and of its width at
#: :data:`ASPECT`): room for the labels standing over the topmost welds
MARGIN = 1.2
#: the width over the height the view is framed for (a landscape window; the height binds first)
ASPECT = 4.0 / 3.0
#: the robot cell is seen across the robot's reach: from this far (deg) to the left of the line
#: from the robot's base to the part, and lower, so the arm shows in profile
ROBOT_AZIMUTH_OFFSET_DEG = 60.0
ROBOT_ELEVATION_DEG = 15.0
#: the near and far planes, in multiples of the box's diagonal (viewer units)
NEAR_FRACTION = 1e-3
FAR_MULTIPLE = 40.0


@dataclass(frozen=True)
class CameraView:
    """Where the camera stands, in scene coordinates (viewer units, z up), looking at the origin.

    Attributes
    ----------
    position
        ``(3,)`` the camera's position.
    near, far
        The clipping planes (viewer units).
    """

    position: tuple[float, float, float]
    near: float
    far: float

    def apply(self, vis: Any) -> None:
        """Set meshcat's default camera in visualizer ``vis`` (and hide the grid and axes)."""
        cam = vis["/Cameras/default/rotated/<object>"]
        cam.set_property("fov", FOV_DEG)
        cam.set_property("position", camera_local(self.position))
        cam.set_property("near", self.near)
        cam.set_property("far", self.far)
        vis["/Grid"].set_property("visible", False)
        vis["/Axes"].set_property("visible", False)


def camera_local(p: ArrayLike) -> list[float]:
    """A scene point ``(x, y, z)`` in the camera's parent frame (y up): ``[x, z, -y]``."""
    x, y, z = (float(v) for v in np.asarray(p, dtype=float).reshape(3))
    return [x, z, -y]


def view_direction(azimuth_deg: float = AZIMUTH_DEG, elevation_deg: float = ELEVATION_DEG):
    """``(3,)`` unit vector from the target towards the camera (z up)."""
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    return np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])


def robot_azimuth(base: ArrayLike, target: ArrayLike) -> float:
    """The robot cell's azimuth (deg): :data:`ROBOT_AZIMUTH_OFFSET_DEG` to the left of the line
    from the robot's ``base`` ``(3,)`` to the ``target`` ``(3,)`` (the part's or the route's
    centre), so the arm reaching for the part is seen from its side; :data:`AZIMUTH_DEG` when
    the base stands over the target."""
    v = np.asarray(target, dtype=float)[:2] - np.asarray(base, dtype=float)[:2]
    if np.hypot(*v) < 1e-9:
        return AZIMUTH_DEG
    return float(np.degrees(np.arctan2(v[1], v[0])) + ROBOT_AZIMUTH_OFFSET_DEG)


def scene_transform(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(4, 4)`` mm -> viewer units: the bounding box of ``points (k, 3)`` mm centred on the
    origin (where the camera looks) and :data:`SCENE_SIZE` across its longest side."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    extent = float(np.max(hi - lo)) or 1.0
    s = SCENE_SIZE / extent
    T = np.eye(4) * s
    T[3, 3] = 1.0
    T[:3, 3] = -s * (lo + hi) / 2
    return T


def camera_view(
    points: ArrayLike,
    *,
    aspect: float = ASPECT,
    azimuth_deg: float = AZIMUTH_DEG,
    elevation_deg: float = ELEVATION_DEG,
) -> CameraView:
    """The camera on the diagonal of :func:`view_direction` that frames ``points``.

    Parameters
    ----------
    points
        ``(k, 3)`` what must be in view (viewer units); the camera looks at the origin.
    aspect
        The view's width over its height.
    azimuth_deg, elevation_deg
        Where the camera looks from (:func:`view_direction`).

    Returns
    -------
    CameraView
        At the smallest distance ``D`` for which every point ``c`` has
        ``|c . up| <= tan(fov / 2) (D - c . d) / MARGIN`` and the same across with
        ``aspect tan(fov / 2)``: a pinhole camera's view of the points.
    """
    corners = np.asarray(points, dtype=float).reshape(-1, 3)
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    d = view_direction(azimuth_deg, elevation_deg)
    right = np.cross(-d, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -d)
    t_v = np.tan(np.radians(FOV_DEG) / 2) / MARGIN
    t_h = t_v * aspect
    along = corners @ d
    dist = float(np.max(along + np.maximum(np.abs(corners @ up) / t_v,
                                           np.abs(corners @ right) / t_h)))  # fmt: skip
    diag = float(np.linalg.norm(hi - lo)) or 1.0
    dist = max(dist, float(along.max()) + NEAR_FRACTION * diag * 10)
    pos = dist * d
    return CameraView(
        (float(pos[0]), float(pos[1]), float(pos[2])),
        NEAR_FRACTION * diag,
        float(FAR_MULTIPLE * (dist + diag)),
    )


def frame_scene(
    vis: Any,
    root: Any,
    points: NDArray[np.float64],
    *,
    camera: bool = True,
    azimuth_deg: float = AZIMUTH_DEG,
    elevation_deg: float = ELEVATION_DEG,
) -> float:
    """Scale ``root`` (mm) about the origin to frame ``points (k, 3)`` mm and, with ``camera``,
    set the camera on them from ``azimuth_deg``, ``elevation_deg`` (:func:`camera_view`).
    Returns the scale (viewer units per mm)."""
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    T = scene_transform(P)
    root.set_transform(T)
    s = float(T[0, 0])
    if camera:
        view = camera_view(s * P + T[:3, 3], azimuth_deg=azimuth_deg, elevation_deg=elevation_deg)
        view.apply(vis)
    return s
