"""The stages the default ``weldplan planar`` adds after the optimiser (none is in a paper).

The default pipeline is::

    optimiser (the paper's algorithm; sma and lrsma seeded along a coarse A* roadmap)
      -> repair  (each colliding stretch re-routed along the free-space mesh)
      -> polish  (the path pulled taut: the shortest path inside the triangles it crosses)

Each stage is measured by the same independent check as every planar path
(:func:`weldplan.geometry.pathmetrics.measure` against :attr:`Scenario.world`, the
:class:`~weldplan.geometry.obstacles2d.Obstacles2D` of the map), never by the stage that made
it, and recorded as a :class:`PlanarStage` (length, collisions, time, what it did), so that the
optimiser's own result stays visible beside what the stages changed. The rule for a path
touching an obstacle is the check's: a segment that grazes a boundary or a corner at zero
depth (within ``GRAZE_TOL`` of the map size) is free, as the exact any-angle optimum does at
every corner it turns; passing through a pinch point (two obstacles touching) is a collision,
and the stages never route through one (:attr:`FreeSpaceMesh.blocked`).

Repair (ours): a path vertex outside the free-space mesh, or a segment that collides or crosses
the mesh outline, starts a stretch that runs to the next vertex in the mesh whose following
segment is sound (or to the goal); the stretch is replaced by the shortest mesh-edge path
between its two ends (:meth:`FreeSpaceMesh.route`). The result is free by construction on the
mesh, and checked.

Polish (ours): the shortest mesh-edge path from start to goal inside the triangles the repaired
path meets (:meth:`FreeSpaceMesh.corridor_nodes`), pulled taut by the simple stupid funnel of
:meth:`weldplan.planar.meshmap.TriangleMap.funnel`: the shortest path in that corridor, which is
the taut path in the path's homotopy class when the corridor is a sleeve. The coarse A*
roadmap that seeded the optimiser is a second corridor, pulled taut the same way and kept only
when strictly shorter (the note then says "roadmap's corridor": the optimiser contributed
nothing to the final length, and the summary shows it). A taut path is kept only if the check
finds it collision-free and it is not longer than its input.

Paper 002's B-spline smoothing (eq. 14) is not applied: a smoothing of a path taut against
obstacle corners cuts those corners, so it would collide by construction.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import PlanningError
from weldplan.geometry.obstacles2d import Obstacles2D
from weldplan.geometry.pathmetrics import measure
from weldplan.planar.freespace import FreeSpaceMesh, free_space_mesh
from weldplan.planar.scenarios import Scenario

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

#: the stages of the default pipeline, in order
STAGES = ("optimiser", "repair", "polish")


@dataclass(frozen=True)
class PlanarStage:
    """One stage's path, measured by the independent check.

    Attributes
    ----------
    name
        ``"optimiser"``, ``"repair"`` or ``"polish"``.
    length
        Polyline length after the stage (map units).
    collisions
        Segments that enter an obstacle (:meth:`Obstacles2D.segments_hit`).
    seconds
        Wall time of the stage (the optimiser's: its run).
    note
        What the stage did (or why it left the path as it was).
    """

    name: str
    length: float
    collisions: int
    seconds: float
    note: str = ""


def _dedupe(P: FloatArray) -> FloatArray:
    keep = np.ones(len(P), dtype=bool)
    keep[1:] = np.any(np.diff(P, axis=0) != 0.0, axis=1)
    keep[-1] = True
    return P[keep]


def repair_path(path: ArrayLike, fs: FreeSpaceMesh, world: Obstacles2D) -> tuple[FloatArray, str]:
    """Re-route the colliding stretches of ``path (n, 2)`` along the mesh (module docstring).

    Returns the repaired path and a note. Raises :class:`PlanningError` when a stretch cannot
    be re-routed (its end unreachable on the mesh).
    """
    P = _dedupe(np.asarray(path, dtype=np.float64).reshape(-1, 2))
    n = len(P)
    inmesh = fs.locate(P) >= 0
    inmesh[0] = inmesh[-1] = True
    A, B = P[:-1], P[1:]
    sound = inmesh[:-1] & inmesh[1:] & ~fs.crosses_outline(A, B) & world.segments_free(A, B)
    if sound.all():
        return P, "nothing to repair"
    out = [P[0]]
    i, n_stretch = 0, 0
    while i < n - 1:
        if sound[i]:
            out.append(P[i + 1])
            i += 1
            continue
        j = i + 1
        while j < n - 1 and not (inmesh[j] and sound[j]):
            j += 1
        out.extend(fs.route(P[i], P[j])[1:])
        n_stretch += 1
        i = j
    return _dedupe(np.asarray(out)), f"{n_stretch} stretch(es) re-routed"


def polish_path(path: ArrayLike, fs: FreeSpaceMesh) -> FloatArray:
    """The taut path in the corridor of triangles ``path (n, 2)`` meets (module docstring)."""
    nodes = fs.corridor_nodes(np.asarray(path, dtype=np.float64))
    return np.asarray(fs.mesh.funnel(nodes), dtype=np.float64)


def run_stages(
    scenario: Scenario,
    points: ArrayLike,
    optimiser_seconds: float,
    roadmap: ArrayLike | None = None,
) -> tuple[FloatArray, tuple[PlanarStage, ...]]:
    """Repair and polish the optimiser's path ``points (n, 2)`` on ``scenario``.

    ``roadmap (p, 2)``, the coarse A* path that seeded the optimiser
    (:meth:`PathProblem.roadmap_path`), is a second corridor for the polish: when its taut path
    is shorter than the optimiser's, it is kept, and the polish's note says so (the optimiser
    then contributed nothing to the final length).

    Returns the final path and the three :class:`PlanarStage` records (optimiser, repair,
    polish). A stage that fails (no mesh route, a corridor that does not join the ends, a
    result the check rejects) leaves the path as it was and says why in its note.
    """
    world = scenario.world
    P = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    m = measure(P, world)
    stages = [PlanarStage("optimiser", m.length, m.collisions, optimiser_seconds)]
    t0 = time.perf_counter()
    try:
        fs = free_space_mesh(scenario)
    except PlanningError as exc:
        note = f"skipped: no free-space mesh ({exc})"
        stages += [PlanarStage(s, m.length, m.collisions, 0.0, note) for s in STAGES[1:]]
        return P, tuple(stages)
    mesh_s = time.perf_counter() - t0

    t0 = time.perf_counter()
    try:
        R, note = repair_path(P, fs, world)
    except PlanningError as exc:
        R, note = P, f"failed: {exc}"
    mr = measure(R, world)
    if mr.collisions > m.collisions:  # pragma: no cover - the mesh is inside the free space
        R, mr, note = P, m, f"rejected by the check ({mr.collisions} collisions)"
    stages.append(
        PlanarStage("repair", mr.length, mr.collisions, time.perf_counter() - t0 + mesh_s, note)
    )

    t0 = time.perf_counter()
    Q, mq, note = R, mr, "rejected: not shorter"
    notes = []
    sources = [("optimiser's", R)] + ([] if roadmap is None else [("roadmap's", roadmap)])
    for k, (what, src) in enumerate(sources):
        # the optimiser's corridor may equal its input; the roadmap's must be strictly shorter
        slack = 1e-12 if k == 0 else -1e-9
        try:
            C = polish_path(src, fs)
        except PlanningError as exc:
            notes.append(f"{what} corridor skipped: {exc}")
            continue
        mc = measure(C, world)
        if mc.collisions > 0:
            notes.append(f"{what} corridor rejected by the check ({mc.collisions} collisions)")
        elif mq.collisions > 0 or mc.length <= mq.length * (1.0 + slack):
            Q, mq = C, mc
            note = f"taut in the {what} corridor, {len(C) - 2} corner(s)"
    note = "; ".join([note, *notes])
    stages.append(PlanarStage("polish", mq.length, mq.collisions, time.perf_counter() - t0, note))
    log.debug("stages on %s: %s", scenario.name, stages)
    return Q, tuple(stages)
