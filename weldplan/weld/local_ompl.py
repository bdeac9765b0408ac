"""Joint-to-joint torch paths by OMPL (``--planner ompl``; the peer of ``weldplan bench local``).

The same problem as :mod:`weldplan.weld.local`: from the virtual joint of ``i`` to the virtual
joint of ``j`` inside the cell's grid box, the torch tip a sphere of radius = clearance, then the
legs to the real joints. OMPL searches R^3 continuously (no grid); the judge is weldplan's own:

- a state is free when the FCL sphere of radius = clearance misses the part's triangles
  (:meth:`CollisionModel.segments_free` with ``method="fcl"`` on a zero-length segment) and the
  point is inside no closed solid of the part (:meth:`ClosedSolids.contains`: a sphere deep inside
  a solid touches no triangle);
- a motion is free when the FCL capsule it sweeps misses the part (the same ``method="fcl"``
  capsule check the grid planners use for their shortcuts). A motion whose capsule misses every
  triangle cannot cross a solid's surface, so with free ends it stays outside every solid.

The path OMPL returns (after its simplifier) is checked again segment by segment with the same
capsule and its vertices inside-tested before it becomes a :class:`LocalPath`; a path that fails
is returned as a failure, never repaired. Routes built from these paths are verified by
:func:`weldplan.weld.verify.verify_route` like any other.
"""

from __future__ import annotations

import logging
import math
import time
import weakref
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.geometry.collision import CollisionModel
from weldplan.geometry.pathcore import polyline_length
from weldplan.geometry.solids import ClosedSolids
from weldplan.motion.sampling import plan_rn
from weldplan.motion.settings import SamplingSettings
from weldplan.random import RNGLike, seed_of

log = logging.getLogger(__name__)

#: the OMPL planner of ``--planner ompl``
DEFAULT_PLANNER = "bitstar"
#: planning time of ``--planner ompl`` when no ``local_time_budget`` is set, s
DEFAULT_TIME_S = 1.0

_SOLIDS: weakref.WeakKeyDictionary[CollisionModel, ClosedSolids] = weakref.WeakKeyDictionary()


class TorchChecks:
    """The torch tip's state and motion checks on a cell, counting the calls.

    Parameters
    ----------
    cell
        A :class:`weldplan.weld.cell.Cell` (``part``, ``collision``, ``clearance``).
    """

    def __init__(self, cell: Any) -> None:
        self.collision: CollisionModel = cell.collision
        self.radius = float(cell.clearance)
        solids = _SOLIDS.get(self.collision)
        if solids is None:
            solids = _SOLIDS[self.collision] = ClosedSolids.of(cell.part)
        self.solids = solids
        self.states = 0
        self.motions = 0

    def inside(self, points: NDArray[np.float64]) -> NDArray[np.bool_]:
        """``(n,) bool``: points ``(n, 3)`` mm inside a closed solid of the part."""
        P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        out = np.zeros(len(P), dtype=bool)
        if len(self.solids) == 0:
            return out
        # one vectorised box test first: most states lie in no solid's bounding box
        b = self.solids.bounds
        near = np.any(
            np.all((P[:, None] >= b[None, :, 0]) & (P[:, None] <= b[None, :, 1]), axis=2), axis=1
        )
        if near.any():
            out[near] = self.solids.contains(P[near])
        return out

    def state_free(self, x: NDArray[np.float64]) -> bool:
        """Whether the tip sphere at ``x (3,)`` mm misses the part and lies outside its solids."""
        self.states += 1
        p = np.asarray(x, dtype=np.float64).reshape(1, 3)
        if not self.collision.segments_free(p, p, self.radius, method="fcl")[0]:
            return False
        return not bool(self.inside(p)[0])

    def segment_free(self, a: NDArray[np.float64], b: NDArray[np.float64]) -> bool:
        """Whether the capsule swept from ``a`` to ``b`` (3,) mm misses the part."""
        self.motions += 1
        return bool(
            self.collision.segments_free(
                np.reshape(a, (1, 3)), np.reshape(b, (1, 3)), self.radius, method="fcl"
            )[0]
        )

    def path_free(self, points: NDArray[np.float64]) -> bool:
        """Every segment of ``points (n, 3)`` free by the capsule check, no vertex in a solid."""
        P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        if len(P) >= 2:
            ok = self.collision.segments_free(P[:-1], P[1:], self.radius, method="fcl")
            self.motions += len(P) - 1
            if not ok.all():
                return False
        return not bool(self.inside(P).any())


def _assemble(
    start: NDArray[np.float64], inner: NDArray[np.float64], goal: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Real joint, the inner path, real joint (a leg dropped when a joint is its virtual joint)."""
    parts = []
    if np.linalg.norm(inner[0] - start) > 1e-9:
        parts.append(start[None])
    parts.append(inner)
    if np.linalg.norm(inner[-1] - goal) > 1e-9:
        parts.append(goal[None])
    return np.concatenate(parts)


def plan_pair_ompl(
    cell: Any,
    i: int,
    j: int,
    *,
    planner: str = DEFAULT_PLANNER,
    time_s: float = DEFAULT_TIME_S,
    rng: RNGLike = None,
    simplify: bool = True,
    checks: TorchChecks | None = None,
) -> Any:
    """Local path from joint position ``i`` to ``j`` (0..n-1) of ``cell`` by an OMPL planner.

    Parameters
    ----------
    cell
        A :class:`weldplan.weld.cell.Cell`.
    i, j
        Joint positions.
    planner
        A name in :data:`weldplan.motion.sampling.PLANNERS` (BIT* by default).
    time_s
        OMPL's planning time, s (anytime planners use all of it; the simplifier runs after).
    rng
        Seed (an int or a Generator) for OMPL's process-wide RNG (see
        :mod:`weldplan.motion.sampling`); ``None`` leaves it alone.
    simplify
        Run OMPL's simplifier (shortcuts, vertex reduction, smoothing, all checked by the FCL
        capsule) after planning.
    checks
        The cell's :class:`TorchChecks` (built when ``None``; pass one to reuse its solids and
        count its calls).

    Returns
    -------
    weldplan.weld.local.LocalPath
        ``method="ompl"``; ``reason`` is OMPL's status line (on success too); ``success=False``
        when OMPL found no exact path in time or its path failed the re-check. When the straight
        segment between the virtual joints is free it is the path (``fast_path``), as for the
        grid planners.
    """
    from weldplan.weld.local import LocalPath

    t0, c0 = time.perf_counter(), time.process_time()
    n = cell.n_joints
    for name, k in (("i", i), ("j", j)):
        if not 0 <= int(k) < n:
            raise IndexError(f"joint position {name}={k} out of range 0..{n - 1}")
    ch = TorchChecks(cell) if checks is None else checks
    m0 = ch.states + ch.motions
    xyz = np.asarray(cell.joints.xyz, dtype=np.float64)
    vs = np.asarray(cell.virtual_xyz[i], dtype=np.float64)
    vg = np.asarray(cell.virtual_xyz[j], dtype=np.float64)

    def done(inner: NDArray[np.float64] | None, reason: str, **kw: Any) -> Any:
        ok = inner is not None
        pts = _assemble(xyz[i], inner, xyz[j]) if ok else np.zeros((0, 3))
        inner_len = polyline_length(inner) if ok else math.inf
        return LocalPath(
            points=pts,
            length=polyline_length(pts) if ok else math.inf,
            inner_length=inner_len,
            method="ompl",
            success=ok,
            reason=reason,
            raw_length=kw.pop("raw_length", inner_len),
            seconds=time.perf_counter() - t0,
            cpu_seconds=time.process_time() - c0,
            seed=seed_of(rng),
            collision_checks=ch.states + ch.motions - m0,
            **kw,
        )

    if i == j or ch.segment_free(vs, vg):
        inner = vs[None] if i == j else np.stack([vs, vg])
        return done(inner, "straight segment free", fast_path=True)
    lo, hi = cell.grid.bounds
    sp = plan_rn(
        vs,
        vg,
        lo,
        hi,
        ch.state_free,
        motion_valid=ch.segment_free,
        settings=SamplingSettings(planner=planner, time_s=time_s, simplify=simplify),
        seed=rng,
    )
    if not sp.solved:
        return done(None, f"OMPL found no path: {sp.status}")
    if not ch.path_free(sp.points):
        # OMPL only ever asked our checks; a failure here is a bug or a numerical edge case
        log.warning("OMPL path failed the FCL re-check (%s)", sp.status)
        return done(None, f"OMPL's path failed the FCL re-check: {sp.status}")
    return done(np.asarray(sp.points), sp.status)
