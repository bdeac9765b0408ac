"""Small test parts made of axis-aligned boxes, with grids built by the exact box distance.

The cell model of issue 2 builds grids from arbitrary meshes; these helpers build the same kind of
grid (a voxel centre is an obstacle when the part is closer than the clearance) for parts whose
distance is known in closed form, so that local-planning tests do not depend on the voxeliser.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from weldplan.geometry.collision import CollisionModel
from weldplan.geometry.grid import ObstacleGrid

#: joints 3 and 7 of Wang et al. 2017, Table 1 (mm)
J3 = np.array([1356.00, -66.67, 689.57])
J7 = np.array([1504.91, -126.99, 813.51])


@dataclass
class BoxCell:
    grid: ObstacleGrid
    collision: CollisionModel
    boxes: list[tuple[np.ndarray, np.ndarray]]  # (lo, hi) corners

    def virtual(self, xyz: np.ndarray) -> np.ndarray:
        """Index of the free voxel centre nearest to ``xyz``."""
        free = np.argwhere(self.grid.free)
        d = np.linalg.norm(self.grid.index_to_world(free) - xyz, axis=1)
        return free[int(np.argmin(d))]


def box_distance(points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Distance (mm) from points ``(n, 3)`` to the solid box ``[lo, hi]`` (0 inside)."""
    c = 0.5 * (lo + hi)
    h = 0.5 * (hi - lo)
    q = np.abs(points - c) - h
    return np.linalg.norm(np.maximum(q, 0.0), axis=1)


def box_cell(
    boxes: list[tuple[np.ndarray, np.ndarray]],
    lo: np.ndarray,
    hi: np.ndarray,
    *,
    pitch: float = 5.0,
    clearance: float = 5.0,
) -> BoxCell:
    """Grid over the box region ``[lo, hi]`` (mm) around a part made of solid boxes."""
    lo = np.asarray(lo, float)
    hi = np.asarray(hi, float)
    shape = tuple(int(v) for v in np.floor((hi - lo) / pitch) + 1)
    idx = np.indices(shape).reshape(3, -1).T
    centres = lo + pitch * idx
    d = np.full(len(centres), np.inf)
    meshes = []
    for blo, bhi in boxes:
        blo = np.asarray(blo, float)
        bhi = np.asarray(bhi, float)
        d = np.minimum(d, box_distance(centres, blo, bhi))
        m = trimesh.creation.box(extents=bhi - blo)
        m.apply_translation(0.5 * (blo + bhi))
        meshes.append(m)
    occupied = (d < clearance).reshape(shape)
    grid = ObstacleGrid(occupied, lo, pitch, clearance)
    part = trimesh.util.concatenate(meshes)
    return BoxCell(grid, CollisionModel(part), [(np.asarray(a), np.asarray(b)) for a, b in boxes])


def panel_cell(pitch: float = 5.0, clearance: float = 5.0) -> BoxCell:
    """A 2 mm panel (plane x = 1430 mm, 100 x 100 mm) across the straight line from joint 3 to
    joint 7, with the joints' box plus a 40 mm margin as region of interest."""
    mid = 0.5 * (J3 + J7)
    half = np.array([1.0, 50.0, 50.0])
    centre = np.array([1430.0, mid[1], mid[2]])
    panel = (centre - half, centre + half)
    lo = np.minimum(J3, J7) - 40.0
    hi = np.maximum(J3, J7) + 40.0
    return box_cell([panel], lo, hi, pitch=pitch, clearance=clearance)
