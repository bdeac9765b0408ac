"""The second-class stage of the exact local planner: a second A* route outside the first
route's corridor, refined under the same cap, the shorter of the two kept.

Why. The exact planner's A* minimises the 26-connected lattice length, whose metric is up to
8 % off the Euclidean one in 3D, on a grid that closes every voxel whose centre lies within the
clearance. When an obstacle can be passed on two sides whose lattice lengths differ by less than
that distortion, A* may pick the side whose continuous optimum is longer (another homotopy
class), and no refinement of its path can cross the obstacle to the other side. On the demo cell
(joints 6 -> 10 and 2 -> 10) the first class refines to 133.11 and 113.72 mm where the other
reaches 130.44 and 111.38 mm (OMPL BIT* 10 s + simplify: 130.63 and 111.78 mm).

What (:func:`corridor` and :func:`second_class_wins`, called by
:func:`weldplan.weld.local.plan_local_path` when ``LocalParams.second_class`` and ``refine``
are on and the method is ``"exact"``):

1. the *corridor* of the first lattice route: every voxel within ``class_radius`` (mm) of one of
   its voxels, except those within ``class_radius`` + 2 voxels of the two ends (so that the
   second route can leave the start and reach the goal);
2. A* again on the same grid with the corridor closed (its voxels are forbidden, not
   obstacles), the same FCL check of kept lattice moves, repairs and secondary optimisation as
   the first route;
0. skipped when the first refined path is within :data:`CLASS_GAIN` of the straight segment
   between the virtual joints (a lower bound of every class);
3. the *trigger*: the candidate is refined (under the same cap, ``refine_budget``) only when its
   length after the secondary optimisation is within ``class_slack`` of the first route's
   length after the secondary optimisation (the grid path's lengths are cheap to compare, the
   refinement is not); the shorter refined path of the two is kept.

Both candidates are checked by python-fcl as every local path is (kept lattice moves, every
shortcut, the refinement's final check at the clearance): the stage picks between two
verified paths and adds no shortcut of its own.

This is a k = 2 instance of the "k best homotopy classes" idea (e.g. Bhattacharya, Likhachev
and Kumar, "Topological constraints in search-based robot path planning", Autonomous Robots
33 (2012) 273-290, who search classes exactly with homotopy invariants). Deviation, named: the
corridor only makes the second route *different* (at least ``class_radius`` away from the first
somewhere); it does not guarantee another class, nor the best one of more than two.
"""

from __future__ import annotations

import itertools
import logging
import math

import numpy as np
from numpy.typing import NDArray

from weldplan.geometry.gridsearch import PaddedGrid

log = logging.getLogger(__name__)

__all__ = [
    "CLASS_EXPANSIONS",
    "CLASS_GAIN",
    "CLASS_RADIUS",
    "CLASS_SLACK",
    "corridor",
    "second_class_wins",
]

#: default corridor radius around the first route (mm; 3 voxels at the 5 mm pitch)
CLASS_RADIUS = 15.0
#: the stage is skipped when the first refined path is at most this fraction longer than the
#: straight segment between the virtual joints: no class can be shorter than that segment, so
#: the second could gain at most this much (most blocked pairs of a large station only graze
#: an edge)
CLASS_GAIN = 0.001
#: the second search gives up after ``a * e + b`` expansions, ``(a, b)`` these, ``e`` the
#: first search's: a corridor across the straight line can make A* flood a large station
#: (seconds on car2 Z3L), and a route that much longer on the lattice seldom refines shorter
CLASS_EXPANSIONS = (3, 2000)
#: default trigger: refine the second candidate when its grid path (after the secondary
#: optimisation) is at most this fraction longer than the first's. 0: only when it is already
#: no longer. On the 151 blocked pairs of the bench cells (``weldplan bench local --peers``)
#: the second candidate refines more than 0.2 % shorter than the first on 5 pairs, each with
#: a shorter grid path (demo 6 -> 10, 2 -> 10: 2.0 and 2.1 %); the trigger fires on 46 pairs
#: at 0, on 97 at 0.02 (the largest gain 0 misses: 0.19 %)
CLASS_SLACK = 0.0


def _ball(r: int) -> NDArray[np.int64]:
    """Integer offsets ``(k, 3)`` within Euclidean distance ``r`` of the origin."""
    rng = range(-r, r + 1)
    return np.array(
        [m for m in itertools.product(rng, rng, rng) if m[0] ** 2 + m[1] ** 2 + m[2] ** 2 <= r * r],
        dtype=np.int64,
    )


def corridor(
    pg: PaddedGrid,
    route: NDArray[np.int64],
    radius: float,
    pitch: float,
) -> NDArray[np.int64]:
    """Padded flat indices of the free voxels of the first route's corridor (module docstring).

    Parameters
    ----------
    pg
        The padded grid the search ran on.
    route
        ``(n, 3) int`` the first lattice route, in ``pg``'s (unpadded) indices, start to goal.
    radius
        Corridor radius (mm); at least one voxel.
    pitch
        Grid pitch (mm).

    Returns
    -------
    ``(m,) int64`` sorted padded flat indices (empty when the ends leave no corridor).
    """
    route = np.asarray(route, dtype=np.int64).reshape(-1, 3)
    r = max(1, int(round(radius / pitch)))
    vox = (route[:, None, :] + _ball(r)[None]).reshape(-1, 3)
    vox = vox[np.all((vox >= 0) & (vox < np.asarray(pg.shape)), axis=1)]
    keep = r + 2.0
    for end in (route[0], route[-1]):
        vox = vox[np.linalg.norm(vox - end, axis=1) > keep]
    flat = np.unique(pg.flat(vox))
    return flat[pg.free[flat]]


def second_class_wins(so_first: float, so_second: float, slack: float) -> bool:
    """The trigger: is the second candidate's grid path (after the secondary optimisation, mm)
    within ``slack`` of the first's, so that its refinement may end shorter?"""
    return math.isfinite(so_second) and so_second <= (1.0 + slack) * so_first
