"""Where a pair's grid search runs: the padded grid, the growing search boxes, connectivity
(per-grid caches built once and shared by every pair; split out of :mod:`weldplan.weld.local`)."""

from __future__ import annotations

import logging
import math
import weakref

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from weldplan.geometry.grid import ObstacleGrid
from weldplan.geometry.gridsearch import PaddedGrid, pad_free
from weldplan.weld.localpath import LocalParams, SearchLimitError

log = logging.getLogger(__name__)

_PADDED: weakref.WeakKeyDictionary[ObstacleGrid, PaddedGrid] = weakref.WeakKeyDictionary()
_LABELS: weakref.WeakKeyDictionary[ObstacleGrid, dict[int, NDArray[np.int32]]] = (
    weakref.WeakKeyDictionary()
)


def _padded(grid: ObstacleGrid) -> PaddedGrid:
    pg = _PADDED.get(grid)
    if pg is None:
        pg = _PADDED[grid] = pad_free(grid.free)
    return pg


def _box(
    shape: NDArray[np.int64], s: NDArray[np.int64], g: NDArray[np.int64], m: int
) -> tuple[NDArray[np.int64], NDArray[np.int64], int]:
    lo = np.maximum(np.minimum(s, g) - m, 0)
    hi = np.minimum(np.maximum(s, g) + m + 1, shape)
    return lo, hi, int(np.prod(hi - lo))


def _search_grid(
    grid: ObstacleGrid,
    s: NDArray[np.int64],
    g: NDArray[np.int64],
    method: str,
    prm: LocalParams,
    label_conn: int,
) -> tuple[PaddedGrid, NDArray[np.int64], int, int]:
    """The padded array a search runs on, the grid index of its voxel (0, 0, 0), its voxels and
    the boxes built to find it (:class:`LocalParams` ``crop_margin``, ``crop_growth``,
    ``max_search_voxels``).

    Raises
    ------
    SearchLimitError
        No box within the cap connects the pair.
    """
    zero = np.zeros(3, dtype=np.int64)
    shape = np.asarray(grid.shape, dtype=np.int64)
    n_grid = int(np.prod(shape))
    cap = prm.max_search_voxels
    whole_ok = cap is None or n_grid <= cap
    where = f"virtual joints {s.tolist()} -> {g.tolist()}"
    if whole_ok and (method == "exact" or prm.crop_margin is None):
        return _padded(grid), zero, n_grid, 0
    structure = ndimage.generate_binary_structure(3, 1 if label_conn == 6 else 3)
    margin = (prm.crop_margin or 0.0) / grid.pitch
    m = int(math.ceil(margin))
    boxes = 0
    last_fit = -1  # the largest margin (voxels) tried within the cap
    while True:
        lo, hi, vox = _box(shape, s, g, m)
        if cap is not None and vox > cap:
            # the largest margin within the cap, if not tried yet (bisection on the margin)
            a, b = last_fit, m
            while b - a > 1:
                mid = (a + b) // 2
                if _box(shape, s, g, mid)[2] <= cap:
                    a = mid
                else:
                    b = mid
            if a <= last_fit:
                raise SearchLimitError(
                    f"no search box within {cap:,} voxels connects {where} (the next box spans "
                    f"{vox:,} voxels, {boxes} tried; the pair may lie on both sides of a panel): "
                    "raise max_search_voxels to search farther",
                    voxels=vox,
                    cap=cap,
                )
            m = a
            lo, hi, vox = _box(shape, s, g, m)
        boxes += 1
        if vox == n_grid:  # the whole grid (connectivity was checked on it)
            return _padded(grid), zero, n_grid, boxes
        sub = grid.free[lo[0] : hi[0], lo[1] : hi[1], lo[2] : hi[2]]
        labels, _ = ndimage.label(sub, structure=structure)
        if labels[tuple(s - lo)] == labels[tuple(g - lo)]:
            return pad_free(sub), lo, vox, boxes
        del labels
        log.debug("box %d (%d voxels) does not connect %s; growing it", boxes, vox, where)
        last_fit = m
        margin = max(margin, 1.0) * prm.crop_growth
        m = max(m + 1, int(math.ceil(margin)))


def _connected(grid: ObstacleGrid, a: NDArray[np.int64], b: NDArray[np.int64], conn: int) -> bool:
    by_conn = _LABELS.setdefault(grid, {})
    labels = by_conn.get(conn)
    if labels is None:
        structure = ndimage.generate_binary_structure(3, 1 if conn == 6 else 3)
        labels, _ = ndimage.label(grid.free, structure=structure)
        by_conn[conn] = labels
    return bool(labels[tuple(a)] == labels[tuple(b)] != 0)
