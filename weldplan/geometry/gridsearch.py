"""Exact shortest paths over the free voxels of an obstacle grid (the baseline of local planning).

The search runs directly on the array, never on a graph object: networkx on a 5 mm grid costs
seconds and a gigabyte to build (DESIGN.md). The free array is padded with one layer of obstacle
so that a neighbour is a constant offset in the flat (C order) index and never leaves the array;
A* with a binary heap (:mod:`heapq`) and the exact free-space distance of the lattice as heuristic
(the "octile" distance in 3D, consistent, so the first time the goal is popped its cost is the
optimum) expands few nodes when the straight line is nearly free.

Distances are in grid steps times ``pitch`` (mm when ``pitch`` is the grid's pitch).
"""

from __future__ import annotations

import array
import heapq
import itertools
import logging
import math
import time
import weakref
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

log = logging.getLogger(__name__)

__all__ = [
    "PaddedGrid",
    "GridPathResult",
    "neighbour_offsets",
    "pad_free",
    "shortest_grid_path",
    "lattice_distance",
]

_SQRT2 = math.sqrt(2.0)
_SQRT3 = math.sqrt(3.0)


def neighbour_offsets(connectivity: int) -> NDArray[np.int64]:
    """Integer moves ``(k, 3)`` of a voxel lattice.

    Parameters
    ----------
    connectivity
        6 (faces: +-x, +-y, +-z, the ant moves of Wang et al. 2017, section 4.2, step 6),
        18 (faces and edges) or 26 (faces, edges and corners).

    Returns
    -------
    ``(connectivity, 3) int64``. For 6 the order is +x, -x, +y, -y, +z, -z.
    """
    if connectivity == 6:
        return np.array(
            [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.int64
        )
    if connectivity not in (18, 26):
        raise ValueError(f"connectivity must be 6, 18 or 26, got {connectivity}")
    moves = [
        m
        for m in itertools.product((-1, 0, 1), repeat=3)
        if any(m) and sum(map(abs, m)) <= (2 if connectivity == 18 else 3)
    ]
    return np.array(moves, dtype=np.int64)


@dataclass(frozen=True, eq=False)
class PaddedGrid:
    """The free array with one obstacle layer around it, flattened for constant-offset moves.

    Attributes
    ----------
    free
        ``(nx + 2) * (ny + 2) * (nz + 2)`` bool, flat C order; the border is False.
    shape
        The unpadded shape ``(nx, ny, nz)``.
    strides
        Flat-index step of +1 along x, y and z in the padded array.
    """

    free: NDArray[np.bool_]
    shape: tuple[int, int, int]
    strides: tuple[int, int, int]

    @property
    def padded_shape(self) -> tuple[int, int, int]:
        nx, ny, nz = self.shape
        return nx + 2, ny + 2, nz + 2

    def flat(self, idx: ArrayLike) -> NDArray[np.int64]:
        """Padded flat indices of unpadded grid indices ``(..., 3)``."""
        idx = np.asarray(idx, dtype=np.int64) + 1
        return idx @ np.asarray(self.strides, dtype=np.int64)

    def index(self, flat: ArrayLike) -> NDArray[np.int64]:
        """Unpadded grid indices ``(..., 3)`` of padded flat indices."""
        un = np.unravel_index(np.asarray(flat, dtype=np.int64), self.padded_shape)
        return np.stack(un, axis=-1) - 1

    def offsets(self, moves: NDArray[np.int64]) -> NDArray[np.int64]:
        """Flat-index offsets of integer moves ``(k, 3)``."""
        return moves @ np.asarray(self.strides, dtype=np.int64)


def pad_free(free: ArrayLike) -> PaddedGrid:
    """Pad a ``(nx, ny, nz) bool`` free array with one obstacle layer and flatten it."""
    free = np.asarray(free, dtype=bool)
    if free.ndim != 3:
        raise ValueError(f"free must be a 3D array, got shape {free.shape}")
    padded = np.zeros(tuple(s + 2 for s in free.shape), dtype=bool)
    padded[1:-1, 1:-1, 1:-1] = free
    _, py, pz = padded.shape
    flat = padded.ravel()
    flat.setflags(write=False)
    return PaddedGrid(flat, tuple(int(s) for s in free.shape), (py * pz, pz, 1))  # type: ignore[arg-type]


def lattice_distance(a: ArrayLike, b: ArrayLike, connectivity: int = 26) -> NDArray[np.float64]:
    """Shortest distance in grid steps between indices ``a`` and ``b`` (..., 3) with no obstacles.

    For 26-connectivity, with the absolute differences sorted ``d1 >= d2 >= d3``:
    ``(d1 - d2) + sqrt(2) (d2 - d3) + sqrt(3) d3``; for 6-connectivity the Manhattan distance
    ``d1 + d2 + d3``. Only 6 and 26 (the two the planners use) are supported.
    """
    d = np.abs(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64))
    if connectivity == 6:
        return d.sum(axis=-1)
    if connectivity != 26:
        raise ValueError(f"lattice_distance supports 6 and 26, got {connectivity}")
    hi = d.max(axis=-1)
    lo = d.min(axis=-1)
    mid = d.sum(axis=-1) - hi - lo
    return (hi - mid) + _SQRT2 * (mid - lo) + _SQRT3 * lo


@dataclass(frozen=True)
class GridPathResult:
    """The outcome of :func:`shortest_grid_path`.

    Attributes
    ----------
    path
        ``(n, 3) int64`` grid indices from start to goal, or ``None`` when there is no path.
    length
        Path length, ``pitch`` times grid steps (``inf`` when there is no path).
    expansions
        Nodes popped from the heap and expanded.
    reason
        Empty on success; otherwise why there is no path.
    """

    path: NDArray[np.int64] | None
    length: float
    expansions: int
    reason: str = ""

    @property
    def success(self) -> bool:
        return self.path is not None


#: per padded grid and connectivity: the move tables without corner cutting (built once)
_TABLES: weakref.WeakKeyDictionary[PaddedGrid, dict[int, Any]] = weakref.WeakKeyDictionary()


def _move_tables(
    pg: PaddedGrid, moves: NDArray[np.int64], pairs: list[tuple[int, float]]
) -> tuple[dict[int, list[tuple[int, float]]], array.array]:
    """Per voxel, the bit mask of the moves whose spanned box is free, and mask -> moves."""
    free = pg.free
    n = len(free)
    offs = pg.offsets(moves)
    strides = np.asarray(pg.strides, dtype=np.int64)
    mask = np.zeros(n, dtype=np.int64)
    lo, hi = int(np.abs(offs).max()), n - int(np.abs(offs).max())
    idx = np.arange(max(lo, 0), max(hi, lo))
    for k, m in enumerate(moves):
        ok = free[idx] & free[idx + offs[k]]
        for sub in itertools.product(*[(0, c) if c else (0,) for c in m]):
            sub = np.asarray(sub)
            if sub.any() and not np.array_equal(sub, m):
                ok &= free[idx + int(sub @ strides)]
        mask[idx[ok]] |= 1 << k
    # a compact int64 array (8 bytes a voxel) rather than a list of 1 M Python ints (~36 bytes)
    masks = array.array("q")
    masks.frombytes(mask.astype(np.int64).tobytes())
    table = {int(b): [pr for k, pr in enumerate(pairs) if b >> k & 1] for b in np.unique(mask)}
    return table, masks


def shortest_grid_path(
    grid: PaddedGrid | ArrayLike,
    start: ArrayLike,
    goal: ArrayLike,
    *,
    connectivity: int = 26,
    pitch: float = 1.0,
    blocked_edges: Iterable[tuple[int, int]] | None = None,
    deadline: float | None = None,
    corner_cutting: bool = True,
    forbidden: ArrayLike | None = None,
    max_expansions: int | None = None,
) -> GridPathResult:
    """A* over the free voxels: the exact shortest lattice path from ``start`` to ``goal``.

    Parameters
    ----------
    grid
        A :class:`PaddedGrid`, or a ``(nx, ny, nz) bool`` free array (padded here).
    start, goal
        ``(3,) int`` grid indices; both must be free.
    connectivity
        6 or 26 (a move's cost is its Euclidean length: 1, sqrt 2 or sqrt 3 steps).
    pitch
        Millimetres per grid step; lengths are scaled by it.
    blocked_edges
        Pairs of padded flat indices ``(u, v)`` whose move is forbidden in both directions
        (a lattice move that the exact collision check rejected).
    deadline
        ``time.perf_counter()`` value after which the search gives up.
    corner_cutting
        When False, a diagonal move is allowed only if every voxel of the box it spans is free
        (the 2 face neighbours of an edge move, the 6 of a corner move): the usual rule that
        keeps a lattice path from slicing past an obstacle's edge between two free centres.
    forbidden
        Padded flat indices of free voxels the search must not enter (besides the obstacles),
        e.g. the corridor of an earlier route when looking for another homotopy class
        (:mod:`weldplan.weld.homotopy`). The move tables stay those of the free array: a
        diagonal move may pass between two forbidden voxels (they are not obstacles).
    max_expansions
        Give up (``path=None``, reason "expansion cap reached") after this many expansions: a
        deterministic bound on a search, unlike ``deadline``.

    Returns
    -------
    GridPathResult
        The path, or ``path=None`` with the reason (unreachable, or out of time).
    """
    pg = grid if isinstance(grid, PaddedGrid) else pad_free(grid)
    s = int(pg.flat(start))
    g = int(pg.flat(goal))
    free = pg.free
    for name, v in (("start", s), ("goal", g)):
        if not free[v]:
            raise ValueError(f"{name} voxel is not free (or outside the grid)")
    moves = neighbour_offsets(connectivity)
    offs = pg.offsets(moves).tolist()
    costs = np.sqrt((moves * moves).sum(axis=1)).tolist()
    blocked = set()
    for u, v in blocked_edges or ():
        blocked.add((int(u), int(v)))
        blocked.add((int(v), int(u)))
    if s == g:
        return GridPathResult(pg.index([s]), 0.0, 0)
    pairs = list(zip(offs, costs, strict=True))
    tables = None
    if not corner_cutting:
        per_grid = _TABLES.setdefault(pg, {})
        if connectivity not in per_grid:
            per_grid[connectivity] = _move_tables(pg, moves, pairs)
        tables = per_grid[connectivity]
    h = _lattice_heuristic(pg, g, connectivity == 6)
    banned = None if forbidden is None else np.asarray(forbidden, dtype=np.int64).ravel()
    if banned is not None and (np.any(banned == s) or np.any(banned == g)):
        raise ValueError("the start or goal voxel is forbidden")
    best, parent, expansions, reason = _astar(
        free, s, g, h, pairs, tables, blocked, deadline, banned, max_expansions
    )
    if reason:
        return GridPathResult(None, math.inf, expansions, reason)
    flat = [g]
    while flat[-1] != s:
        flat.append(parent[flat[-1]])
    flat.reverse()
    path = pg.index(np.asarray(flat, dtype=np.int64))
    return GridPathResult(path, best[g] * pitch, expansions)


def _lattice_heuristic(pg: PaddedGrid, g: int, six: bool) -> Callable[[int], float]:
    """``h(v)``: the lattice distance (grid steps) from padded flat index ``v`` to ``g``
    (Manhattan for 6-connectivity, the 3D octile distance for 26), computed only for the voxels
    the search touches (a whole-grid table costs O(n) a pair: 1 M voxels on the demo cell)."""
    sx, sy, _ = pg.strides
    gx, rem = divmod(g, sx)
    gy, gz = divmod(rem, sy)
    d2, d3 = _SQRT2 - 1.0, _SQRT3 - _SQRT2

    def h(v: int) -> float:
        x, r = divmod(v, sx)
        y, z = divmod(r, sy)
        a = x - gx if x > gx else gx - x
        b = y - gy if y > gy else gy - y
        c = z - gz if z > gz else gz - z
        if six:
            return float(a + b + c)
        hi = max(a, b, c)
        lo = min(a, b, c)
        return hi + d2 * (a + b + c - hi - lo) + d3 * lo

    return h


def _astar(
    free: NDArray[np.bool_],
    s: int,
    g: int,
    h: Callable[[int], float],
    pairs: list[tuple[int, float]],
    tables: tuple[dict[int, list[tuple[int, float]]], array.array] | None,
    blocked: set[tuple[int, int]],
    deadline: float | None,
    banned: NDArray[np.int64] | None = None,
    cap: int | None = None,
) -> tuple[dict[int, float], dict[int, int], int, str]:
    """The A* loop over padded flat indices: ``(g-costs, parents, expansions, reason)``,
    ``reason`` empty when ``g`` was reached. ``pairs``: every (flat offset, cost) move;
    ``tables``: :func:`_move_tables` (no corner cutting), ``None`` to allow every move;
    ``banned``: flat indices closed from the start; ``cap``: most expansions."""
    table, maskl = tables if tables is not None else (None, None)
    if banned is not None and len(banned):
        free = free.copy()
        free[banned] = False
    ok = bytearray(free.tobytes())  # free and not yet closed
    mark = bytearray(len(free)) if blocked else b""  # endpoints of blocked moves
    for u, v in blocked:
        mark[u] = mark[v] = 1  # type: ignore[index]
    inf = math.inf
    cap = -1 if cap is None else int(cap)
    best: dict[int, float] = {s: 0.0}
    parent: dict[int, int] = {s: -1}
    heap: list[tuple[float, float, int]] = [(h(s), 0.0, s)]
    expansions = 0
    push, pop = heapq.heappush, heapq.heappop
    while heap:
        _, gneg, u = pop(heap)
        if not ok[u]:
            continue  # already closed (a stale heap entry)
        if u == g:
            return best, parent, expansions, ""
        ok[u] = 0
        if expansions == cap:
            return best, parent, expansions, "expansion cap reached"
        expansions += 1
        if deadline is not None and not expansions & 1023 and time.perf_counter() > deadline:
            return best, parent, expansions, "time budget exhausted"
        gu = -gneg
        check = blocked and mark[u]
        for off, c in pairs if table is None else table[maskl[u]]:
            v = u + off
            if ok[v]:
                gv = gu + c
                if gv < best.get(v, inf) - 1e-12:
                    if check and mark[v] and (u, v) in blocked:
                        continue
                    best[v] = gv
                    parent[v] = u
                    # ties in f broken towards larger g (deeper nodes): fewer expansions
                    push(heap, (gv + h(v), -gv, v))
    return best, parent, expansions, "goal not reachable from start"
