"""The 3D obstacle grid: voxel centres of a region of interest marked free or obstacle.

A grid is a boolean array plus an origin and a pitch (trimesh's idea of a voxel grid, without the
4x4 transform since the axes are never rotated). Index ``(i, j, k)`` is the cube whose centre is
``origin + pitch * (i, j, k)`` in world millimetres.

Building a grid from a part (the obstacle rule of Wang et al. 2017, section 3) lives in
:func:`build_grid`; this module's :class:`ObstacleGrid` is only the container and its conversions,
so that searches (ant colony, exact grid search) depend on nothing but arrays.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray


@dataclass(frozen=True, eq=False)
class ObstacleGrid:
    """Voxel centres of a box region, each free or obstacle.

    Parameters
    ----------
    occupied
        ``(nx, ny, nz) bool``: True where the cube centre is an obstacle (the part surface is
        closer than the clearance), False where the torch tip may stand.
    origin
        ``(3,) float``: world position (mm) of the centre of voxel ``(0, 0, 0)``.
    pitch
        Side length of a cube in mm (5 mm in the paper: the electrode is 4.48 mm across).
    clearance
        The clearance (mm) the grid was built with; kept so that checks agree with the grid.
    """

    occupied: NDArray[np.bool_]
    origin: NDArray[np.float64]
    pitch: float
    clearance: float
    _free: NDArray[np.bool_] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        occ = np.asarray(self.occupied, dtype=bool)
        if occ.ndim != 3:
            raise ValueError(f"occupied must be a 3D array, got shape {occ.shape}")
        if not self.pitch > 0:
            raise ValueError(f"pitch must be positive, got {self.pitch}")
        origin = np.asarray(self.origin, dtype=np.float64).reshape(3)
        occ.setflags(write=False)
        origin.setflags(write=False)
        object.__setattr__(self, "occupied", occ)
        object.__setattr__(self, "origin", origin)
        object.__setattr__(self, "pitch", float(self.pitch))
        object.__setattr__(self, "clearance", float(self.clearance))
        free = ~occ
        free.setflags(write=False)
        object.__setattr__(self, "_free", free)

    @property
    def shape(self) -> tuple[int, int, int]:
        return self.occupied.shape  # type: ignore[return-value]

    @property
    def free(self) -> NDArray[np.bool_]:
        """``(nx, ny, nz) bool``: True where the torch tip may stand."""
        return self._free

    @property
    def n_free(self) -> int:
        return int(self._free.sum())

    @property
    def n_obstacle(self) -> int:
        return int(self.occupied.sum())

    @property
    def bounds(self) -> NDArray[np.float64]:
        """``(2, 3) float``: world min and max corners of the voxelised box (mm)."""
        lo = self.origin - 0.5 * self.pitch
        hi = self.origin + (np.asarray(self.shape) - 0.5) * self.pitch
        return np.stack([lo, hi])

    def index_to_world(self, idx: ArrayLike) -> NDArray[np.float64]:
        """Cube centres in world mm for integer indices ``(..., 3)``."""
        return self.origin + self.pitch * np.asarray(idx, dtype=np.float64)

    def world_to_index(self, xyz: ArrayLike) -> NDArray[np.int64]:
        """Index ``(..., 3)`` of the cube containing each world point (nearest centre).

        Points outside the grid give indices outside ``[0, shape)``; see :meth:`contains`.
        """
        rel = (np.asarray(xyz, dtype=np.float64) - self.origin) / self.pitch
        return np.floor(rel + 0.5).astype(np.int64)

    def contains(self, idx: ArrayLike) -> NDArray[np.bool_]:
        """``(...,) bool``: whether each index ``(..., 3)`` lies inside the grid."""
        idx = np.asarray(idx)
        return np.all((idx >= 0) & (idx < np.asarray(self.shape)), axis=-1)

    def is_free(self, idx: ArrayLike) -> NDArray[np.bool_]:
        """``(...,) bool``: inside the grid and free (outside counts as not free)."""
        idx = np.asarray(idx, dtype=np.int64)
        inside = self.contains(idx)
        out = np.zeros(idx.shape[:-1], dtype=bool)
        sel = idx[inside]
        out[inside] = self._free[sel[:, 0], sel[:, 1], sel[:, 2]]
        return out

    def ravel(self, idx: ArrayLike) -> NDArray[np.int64]:
        """Flat indices (C order) of ``(..., 3)`` grid indices."""
        idx = np.asarray(idx, dtype=np.int64)
        return np.ravel_multi_index(np.moveaxis(idx, -1, 0), self.shape)

    def unravel(self, flat: ArrayLike) -> NDArray[np.int64]:
        """Grid indices ``(..., 3)`` of flat (C order) indices."""
        return np.stack(np.unravel_index(np.asarray(flat, dtype=np.int64), self.shape), axis=-1)
