"""A conservative broad phase for "is this point farther than ``need`` from the part?".

Used by the robot's collision proof and by the tool's swept check in SE(3) re-plans
(:mod:`weldplan.tool.transitions.sweep_bound`). The robot's collision proof
(:mod:`weldplan.robot.collision.checker`) asks, for many sphere centres at many samples of a motion,
whether each centre is farther from the part than a threshold (its radius, half its motion between
samples and the gap). Most of them are far: asking open3d for the exact distance of every one
dominated the check (18 ms a call, 60 % of an OMPL re-plan).

:class:`DistanceBound` answers most of them from a table, and soundly: the distance to a set is
1-Lipschitz, so with ``D(g)`` the exact distance at a grid node ``g``

    d(x) >= D(g) - |x - g| - tol

for every point ``x`` (``tol`` the single-precision round-off of open3d's distances,
:attr:`~weldplan.geometry.distance.SurfaceDistance.tolerance`). The part also lies inside its
bounding box, so ``d(x) >= dist(x, box)``. A point whose larger lower bound exceeds its
threshold is clear; only the others are sent to open3d for their exact distance. The answer is
therefore the same as asking open3d for every point (up to the round-off both carry), only
cheaper; nothing is approximated.

The table covers the part's box padded by :data:`PAD_MM` with at most :data:`MAX_NODES` nodes
(the cell grows for large parts: 5.6 mm on the demo part, 24 mm on the 4.5 m car body). It is
filled lazily, in blocks of :data:`BLOCK` ^ 3 nodes, the first time a query falls in a block
(open3d on the whole table cost 8 s on the demo part, 21 s on the car body at load 10; a robot
works in a small part of it).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from weldplan.geometry.distance import SurfaceDistance

log = logging.getLogger(__name__)

#: mm: the table reaches this far beyond the part's bounding box (farther points are decided by
#: the box alone: the cover spheres' thresholds are tens of mm)
PAD_MM = 200.0
#: the most grid nodes the table holds (float32: 6 MB)
MAX_NODES = 1_500_000
#: mm: the finest cell
MIN_CELL_MM = 5.0
#: nodes along each edge of a block of the table computed at once
BLOCK = 16


class DistanceBound:
    """Lower bounds of the distance to a part, exact where they do not decide (module docstring).

    Parameters
    ----------
    distance
        The part's exact distance (:class:`~weldplan.geometry.distance.SurfaceDistance`).
    lo, hi
        ``(3,)`` mm: the part's bounding box.
    pad, max_nodes, min_cell
        The table's padding (mm), size cap and finest cell (mm).
    """

    def __init__(
        self,
        distance: SurfaceDistance,
        lo: ArrayLike,
        hi: ArrayLike,
        *,
        pad: float = PAD_MM,
        max_nodes: int = MAX_NODES,
        min_cell: float = MIN_CELL_MM,
    ) -> None:
        self.distance = distance
        self.lo = np.asarray(lo, dtype=np.float64)
        self.hi = np.asarray(hi, dtype=np.float64)
        g0 = self.lo - pad
        ext = self.hi - self.lo + 2 * pad
        cell = max(float(min_cell), float(np.cbrt(np.prod(ext) / max_nodes)))
        n = np.maximum(np.ceil(ext / cell).astype(np.int64) + 1, 2)
        self.origin = g0
        self.cell = cell
        self.shape = tuple(int(k) for k in n)
        self.table = np.full(self.shape, np.nan, dtype=np.float32)
        self._done = np.zeros(tuple(-(-n // BLOCK)), dtype=bool)
        #: every block computed (:meth:`_fill` has nothing left to look for)
        self._complete = False
        self.tol = float(getattr(distance, "tolerance", 0.0)) + 1e-3
        log.debug("distance table %s nodes at %.1f mm", self.shape, cell)

    def lower(self, points: ArrayLike) -> NDArray[np.float64]:
        """``(n,)`` mm: a lower bound of each point's distance ``(n, 3)`` to the part."""
        return self.bounds(points)[0]

    def bounds(self, points: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(n,)`` mm each: a lower and an upper bound of each point's distance ``(n, 3)`` to
        the part. The upper one is the same Lipschitz bound the other way, ``D(g) + |x - g|``
        (any node ``g`` will do, so it holds outside the table too), plus twice the round-off:
        open3d's own distance of the point is never above it, so a point whose upper bound is
        below a threshold needs no exact distance to be known short of it."""
        P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        idx = np.rint((P - self.origin) / self.cell).astype(np.int64)
        np.clip(idx, 0, np.array(self.shape) - 1, out=idx)
        self._fill(idx)
        g = self.origin + idx * self.cell
        D = self.table[idx[:, 0], idx[:, 1], idx[:, 2]]
        off = np.linalg.norm(P - g, axis=1)
        box = np.linalg.norm(np.maximum(np.maximum(self.lo - P, P - self.hi), 0.0), axis=1)
        return np.maximum(D - off, box) - self.tol, D + off + 2 * self.tol

    def fill_all(self) -> None:
        """Compute the whole table now (a caller with a time budget, such as an SE(3) re-plan
        whose queries roam the whole box, pays for it before its clock starts)."""
        nb = np.array(self._done.shape)
        blocks = np.stack(np.unravel_index(np.arange(int(np.prod(nb))), tuple(nb)), axis=1)
        self._fill(blocks * BLOCK)

    def _fill(self, idx: NDArray[np.int64]) -> None:
        """Compute the blocks of the table that the nodes ``idx (n, 3)`` fall in, where not yet
        done."""
        if self._complete:
            return
        b = idx // BLOCK
        new = ~self._done[b[:, 0], b[:, 1], b[:, 2]]
        if not new.any():
            return
        nb = np.array(self._done.shape)
        flat = np.unique(np.ravel_multi_index(tuple(b[new].T), tuple(nb)))
        todo = np.stack(np.unravel_index(flat, tuple(nb)), axis=1)
        span = np.arange(BLOCK)
        local = np.stack(np.meshgrid(span, span, span, indexing="ij"), axis=-1).reshape(-1, 3)
        nodes = (todo[:, None, :] * BLOCK + local[None]).reshape(-1, 3)
        nodes = nodes[np.all(nodes < np.array(self.shape), axis=1)]
        self.table[nodes[:, 0], nodes[:, 1], nodes[:, 2]] = self.distance(
            self.origin + nodes * self.cell
        )
        self._done[todo[:, 0], todo[:, 1], todo[:, 2]] = True
        self._complete = bool(self._done.all())

    def clear(self, points: ArrayLike, need: ArrayLike) -> NDArray[np.bool_]:
        """``(n,) bool``: whether each point ``(n, 3)`` is farther than ``need`` (mm, scalar or
        ``(n,)``) from the part; the table decides where its bound does, open3d elsewhere."""
        P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        need = np.broadcast_to(np.asarray(need, dtype=np.float64), (len(P),))
        ok = self.lower(P) > need
        rest = np.flatnonzero(~ok)
        if len(rest):
            ok[rest] = self.distance(P[rest]) > need[rest]
        return ok
