"""The 3D obstacle grid: voxel centres of a region of interest marked free or obstacle.

A grid is a boolean array plus an origin and a pitch (trimesh's idea of a voxel grid, without the
4x4 transform since the axes are never rotated). Index ``(i, j, k)`` is the cube whose centre is
``origin + pitch * (i, j, k)`` in world millimetres.

Building a grid from a part (the obstacle rule of Wang et al. 2017, section 3) lives in
:func:`build_grid`; this module's :class:`ObstacleGrid` is only the container and its conversions,
so that searches (ant colony, exact grid search) depend on nothing but arrays.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import InputError, WeldplanError
from weldplan.geometry.distance import SurfaceDistance
from weldplan.geometry.solids import ClosedSolids

log = logging.getLogger(__name__)


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

    def __getstate__(self) -> dict:
        # bit-packed: a whole-car grid of 1.5e8 voxels pickles in 18 MB, for worker processes
        return {
            "bits": np.packbits(self.occupied, axis=None),
            "shape": self.occupied.shape,
            "origin": self.origin,
            "pitch": self.pitch,
            "clearance": self.clearance,
        }

    def __setstate__(self, state: dict) -> None:
        n = int(np.prod(state["shape"]))
        occ = np.unpackbits(state["bits"], count=n).astype(bool).reshape(state["shape"])
        self.__init__(occ, state["origin"], state["pitch"], state["clearance"])  # type: ignore[misc]

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


#: default voxel pitch (mm): "each side length of the cubes is set to 5 mm" (Wang et al. 2017, s. 3)
DEFAULT_PITCH = 5.0
#: default clearance (mm): "the vertical length is less than 5 mm" (Wang et al. 2017, s. 3)
DEFAULT_CLEARANCE = 5.0
#: default margin (mm) around the joints' bounding box for ``region="joints"``
DEFAULT_MARGIN = 150.0
#: largest grid build_grid agrees to allocate (voxels); 1.5e9 voxels is 1.5 GB of booleans
MAX_VOXELS = 1_500_000_000
#: side (voxels, a power of two) of the coarsest blocks of the coarse-to-fine build
_TOP_BLOCK = 16
#: voxel indices generated at once when filling blocks that are obstacle throughout
_FILL_CHUNK = 1 << 22


def grid_region(
    mesh: trimesh.Trimesh,
    *,
    pitch: float = DEFAULT_PITCH,
    region: str | ArrayLike = "joints",
    points: ArrayLike | None = None,
    margin: float = DEFAULT_MARGIN,
) -> tuple[NDArray[np.float64], tuple[int, int, int]]:
    """Origin and shape of the voxel lattice covering a region of interest.

    Voxel centres sit on the world lattice ``pitch * (i, j, k)`` (integers), so grids built over
    different regions of one part agree voxel for voxel where they overlap.

    Parameters
    ----------
    mesh
        The part (mm); used for ``region="all"``.
    pitch
        Voxel side (mm).
    region
        ``"joints"``: the bounding box of ``points`` grown by ``margin`` on every side;
        ``"all"``: the part's bounding box grown by ``margin``; or explicit ``(2, 3)`` world
        bounds ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]`` (mm), used as given.
    points
        ``(n, 3)`` points (mm), required for ``region="joints"``.
    margin
        Growth of the box (mm) for ``"joints"`` and ``"all"``.

    Returns
    -------
    origin, shape
        ``(3,)`` world centre of voxel ``(0, 0, 0)`` and the grid shape ``(nx, ny, nz)``:
        every voxel centre inside the box.
    """
    if not (np.isfinite(pitch) and pitch > 0):
        raise InputError(f"pitch must be a positive number of mm, got {pitch}", field="pitch")
    if not (np.isfinite(margin) and margin >= 0):
        raise InputError(f"margin must be >= 0 mm, got {margin}", field="margin")
    if isinstance(region, str):
        if region == "joints":
            if points is None:
                raise ValueError('region="joints" needs the joint positions: points=(n, 3) mm')
            P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
            if len(P) == 0:
                raise ValueError('region="joints" needs at least one point')
            lo, hi = P.min(axis=0) - margin, P.max(axis=0) + margin
        elif region == "all":
            lo, hi = np.asarray(mesh.bounds[0]) - margin, np.asarray(mesh.bounds[1]) + margin
        else:
            raise ValueError(f'region must be "joints", "all" or (2, 3) bounds, got {region!r}')
    else:
        box = np.asarray(region, dtype=np.float64)
        if box.shape != (2, 3) or not np.all(np.isfinite(box)) or np.any(box[1] < box[0]):
            raise ValueError(f"region bounds must be (2, 3) [min, max] corners, got {region!r}")
        lo, hi = box[0], box[1]
    f_lo, f_hi = np.ceil(lo / pitch - 1e-9), np.floor(hi / pitch + 1e-9)
    if not (np.all(np.isfinite(f_lo)) and np.all(np.isfinite(f_hi))) or max(
        np.abs(f_lo).max(), np.abs(f_hi).max()
    ) > float(MAX_VOXELS):
        raise InputError(
            f"region [{lo.tolist()}, {hi.tolist()}] mm is beyond any {pitch:g} mm grid: "
            "check the units of the part and the joints"
        )
    i_lo, i_hi = f_lo.astype(np.int64), f_hi.astype(np.int64)
    shape = np.maximum(i_hi - i_lo + 1, 1)
    return i_lo * float(pitch), (int(shape[0]), int(shape[1]), int(shape[2]))


def build_grid(
    mesh: trimesh.Trimesh,
    *,
    pitch: float = DEFAULT_PITCH,
    clearance: float = DEFAULT_CLEARANCE,
    region: str | ArrayLike = "joints",
    points: ArrayLike | None = None,
    margin: float = DEFAULT_MARGIN,
    distance: SurfaceDistance | None = None,
    solids: ClosedSolids | None = None,
    interior: bool = True,
) -> ObstacleGrid:
    """Voxelise a region of interest with the obstacle rule of Wang et al. 2017, section 3.

    A cube centre is an obstacle when the part surface is closer than ``clearance``: the
    unsigned point-triangle distance ``d(c) < clearance`` (the paper's rule projects the centre
    on each triangle's plane and counts only projections inside the triangle; the exact distance
    makes the rule exact at edges and vertices too). Otherwise the centre is free.

    Only centres near the surface are measured one by one: the grid is cut into blocks of
    16^3 voxels; the distance ``d`` at a block's centre and the block's half-diagonal ``r``
    decide the whole block when ``d - r >= clearance`` (all free: distance is 1-Lipschitz) or
    ``d + r < clearance`` (all obstacle); undecided blocks split in eight, down to single voxels.
    The work is thus proportional to the part's area, not the box's volume.

    Closed solids (not in the paper, whose parts are sheets): when the part or a connected
    component of it is a closed volume (:class:`~weldplan.geometry.solids.ClosedSolids`), the
    centres inside it are obstacles too, however far from its surface. Only the centres the
    distance rule left free and that lie in a closed component's bounding box are inside-tested
    (open3d ray parity, :meth:`ClosedSolids.occupancy`), and one query decides each block the
    coarse-to-fine build found free throughout (such a block does not meet the surface, so it
    is wholly inside or wholly outside): the work stays proportional to the area. Sheet-metal
    bodies pay nothing but finding their components.

    Parameters
    ----------
    mesh
        The part (mm).
    pitch
        Voxel side (mm); 5 mm in the paper.
    clearance
        Obstacle distance (mm); 5 mm in the paper.
    region, points, margin
        The region of interest, see :func:`grid_region`.
    distance
        A prebuilt :class:`SurfaceDistance` of ``mesh`` to reuse.
    solids
        The prebuilt :class:`ClosedSolids` of ``mesh`` to reuse (default: found here).
    interior
        Mark the interior of closed components as obstacle (default). ``False`` gives the
        paper's rule alone (benchmarks that reproduce it).

    Returns
    -------
    ObstacleGrid
    """
    if not (np.isfinite(clearance) and clearance >= 0):
        raise InputError(f"clearance must be >= 0 mm, got {clearance}", field="clearance")
    origin, shape = grid_region(mesh, pitch=pitch, region=region, points=points, margin=margin)
    n_vox = int(np.prod(np.asarray(shape, dtype=object)))
    if n_vox > MAX_VOXELS:
        raise WeldplanError(
            f"grid of {shape[0]} x {shape[1]} x {shape[2]} voxels ({n_vox:,}) is too large: "
            f"use a larger pitch or a smaller region (at most {MAX_VOXELS:,} voxels)"
        )
    occupied = np.zeros(shape, dtype=bool)
    if interior and len(mesh.faces) and solids is None:
        solids = ClosedSolids.of(mesh)
    closed = interior and solids is not None and len(solids) > 0
    free_blocks = None
    if len(mesh.faces) and clearance > 0:
        dist = distance if distance is not None else SurfaceDistance(mesh)
        within = None
        if closed:
            within = np.stack([solids.bounds[:, 0].min(axis=0), solids.bounds[:, 1].max(axis=0)])
        free_blocks = _mark_obstacles(
            occupied, origin, float(pitch), float(clearance), dist, free_within=within
        )
    n_inside = 0
    if closed and free_blocks is not None:
        n_inside = _mark_interior_blocks(occupied, origin, float(pitch), solids, free_blocks)
    elif closed:  # clearance 0: no distance rule, test every free centre
        n_inside = _mark_interior(occupied, origin, float(pitch), solids)
    log.info(
        "grid %s at %.3g mm: %d obstacle (%d inside closed solids) / %d voxels",
        shape,
        pitch,
        int(occupied.sum()),
        n_inside,
        n_vox,
    )
    return ObstacleGrid(occupied=occupied, origin=origin, pitch=pitch, clearance=clearance)


def _cube_offsets(n: int, step: int) -> NDArray[np.int64]:
    """``(n^3, 3)`` offsets ``step * (i, j, k)`` for ``i, j, k`` in ``range(n)``."""
    r = np.arange(n, dtype=np.int64) * step
    return np.stack(np.meshgrid(r, r, r, indexing="ij"), axis=-1).reshape(-1, 3)


def _fill_blocks(
    occupied: NDArray[np.bool_], blocks: NDArray[np.int64], ext: NDArray[np.int64], size: int
) -> None:
    """Set every voxel of the blocks ``blocks (m, 3)`` (starts) of extents ``ext (m, 3)``."""
    if len(blocks) == 0:
        return
    inner = _cube_offsets(size, 1)
    per = max(1, _FILL_CHUNK // len(inner))
    for lo in range(0, len(blocks), per):
        keep = np.all(inner[None, :, :] < ext[lo : lo + per, None, :], axis=2)
        vox = (blocks[lo : lo + per, None, :] + inner[None, :, :])[keep]
        occupied[vox[:, 0], vox[:, 1], vox[:, 2]] = True


def _mark_obstacles(
    occupied: NDArray[np.bool_],
    origin: NDArray[np.float64],
    pitch: float,
    clearance: float,
    dist: SurfaceDistance,
    free_within: NDArray[np.float64] | None = None,
) -> list[tuple[NDArray[np.int64], NDArray[np.int64], int]]:
    """Set ``occupied`` True where ``dist(centre) < clearance`` (coarse-to-fine, in place).

    Returns the blocks found free throughout, ``(starts (m, 3), extents (m, 3), size)`` per
    level, of those that meet the world box ``free_within (2, 3)`` (none when it is None):
    no point of such a block is within the clearance of the surface, so the block lies wholly
    inside or wholly outside each closed component.
    """
    shape = np.asarray(occupied.shape, dtype=np.int64)
    size = _TOP_BLOCK
    while size > 1 and size // 2 >= shape.max():
        size //= 2
    axes = [np.arange(0, n, size, dtype=np.int64) for n in shape]
    blocks = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    tol = dist.tolerance
    n_queries = 0
    free_blocks: list[tuple[NDArray[np.int64], NDArray[np.int64], int]] = []

    def keep_free(sel: NDArray[np.bool_], ext: NDArray[np.int64], size: int) -> None:
        if free_within is None or not sel.any():
            return
        b, e = blocks[sel], ext[sel]
        lo = origin + pitch * b
        hi = origin + pitch * (b + e - 1)
        meet = np.all((hi >= free_within[0]) & (lo <= free_within[1]), axis=1)
        if meet.any():
            free_blocks.append((b[meet], e[meet], size))

    while len(blocks):
        ext = np.minimum(size, shape - blocks)  # (m, 3) voxels per axis inside the grid
        centre = origin + pitch * (blocks + 0.5 * (ext - 1))
        d = dist(centre)
        n_queries += len(blocks)
        if size == 1:
            near = d < clearance
            hit = blocks[near]
            occupied[hit[:, 0], hit[:, 1], hit[:, 2]] = True
            keep_free(~near, ext, 1)
            break
        r = 0.5 * pitch * np.linalg.norm(ext - 1, axis=1)
        full = d + r + tol < clearance
        _fill_blocks(occupied, blocks[full], ext[full], size)
        split = ~full & (d - r - tol < clearance)
        keep_free(~full & ~split, ext, size)
        half = size // 2
        offsets = _cube_offsets(2, half)
        children = (blocks[split][:, None, :] + offsets[None, :, :]).reshape(-1, 3)
        blocks = children[np.all(children < shape, axis=1)]
        size = half
    log.debug("obstacle rule: %d distance queries for %d voxels", n_queries, int(shape.prod()))
    return free_blocks


def _mark_interior_blocks(
    occupied: NDArray[np.bool_],
    origin: NDArray[np.float64],
    pitch: float,
    solids: ClosedSolids,
    free_blocks: list[tuple[NDArray[np.int64], NDArray[np.int64], int]],
) -> int:
    """Fill the free blocks whose centre lies inside a closed component; returns the voxels
    filled. One occupancy query per block: a free block does not meet the surface."""
    n_marked = 0
    for blocks, ext, size in free_blocks:
        centre = origin + pitch * (blocks + 0.5 * (ext - 1))
        inside = solids.occupancy(centre)
        _fill_blocks(occupied, blocks[inside], ext[inside], size)
        n_marked += int(np.prod(ext[inside], axis=1).sum())
    return n_marked


def _mark_interior(
    occupied: NDArray[np.bool_],
    origin: NDArray[np.float64],
    pitch: float,
    solids: ClosedSolids,
) -> int:
    """Set ``occupied`` True at the free centres inside a closed component; returns how many.

    Only free centres inside some closed component's bounding box are tested.
    """
    shape = np.asarray(occupied.shape, dtype=np.int64)
    flat: list[NDArray[np.int64]] = []
    for k in range(len(solids)):
        lo, hi = solids.bounds[k]
        i_lo = np.clip(np.ceil((lo - origin) / pitch - 1e-9).astype(np.int64), 0, shape)
        i_hi = np.clip(np.floor((hi - origin) / pitch + 1e-9).astype(np.int64) + 1, 0, shape)
        if np.any(i_hi <= i_lo):
            continue
        box = occupied[i_lo[0] : i_hi[0], i_lo[1] : i_hi[1], i_lo[2] : i_hi[2]]
        idx = np.argwhere(~box) + i_lo
        flat.append(np.ravel_multi_index(idx.T, occupied.shape))
    if not flat:
        return 0
    cand = np.unique(np.concatenate(flat))
    idx = np.stack(np.unravel_index(cand, occupied.shape), axis=-1)
    hit = idx[solids.occupancy(origin + pitch * idx)]
    occupied[hit[:, 0], hit[:, 1], hit[:, 2]] = True
    log.debug("interior: %d of %d candidate centres inside closed solids", len(hit), len(cand))
    return len(hit)
