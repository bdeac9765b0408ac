"""Exact baselines for the planar tables: any-angle shortest paths and 8-connected grid A*.

The parts live in their own modules; every name stays importable from here:
:mod:`~weldplan.planar.visibility` (visibility graph), :mod:`~weldplan.planar.grid_astar` (grid
A*), :mod:`~weldplan.planar.movingai` (Moving AI readers), :mod:`~weldplan.planar.meshspace`
(navigation-mesh free space), :mod:`~weldplan.planar.exact_path` (the result).

The production any-angle planner is Polyanya (:mod:`weldplan.planar.polyanya`, used by
``exact_optimum`` and ``weldplan bench queries``); the visibility graph here is the
independent cross-check its tests compare against.

* :func:`visibility_shortest_path`: the shortest path among polygonal obstacles runs through
  obstacle vertices where free space is reflex, so Dijkstra over the visibility graph of those
  vertices (plus start and goal) is exact. Circles are handled with a stated tolerance: their
  candidate turning points are the vertices of a circumscribed regular ``circle_sides``-gon,
  while visibility is judged against the true circles; the result is a feasible path at most
  about ``(pi / n)^2 / 3`` (relative, on the arcs) longer than the true optimum
  (2e-4 for the default n = 128). A path may not squeeze through a point where two obstacles
  touch (:meth:`Obstacles2D.pinch_points`).
* :func:`astar_grid`: A* on an occupancy grid, 8-connected, octile costs (1 and sqrt 2), no
  corner cutting (a diagonal move needs both orthogonal neighbours free), the rules of the
  Moving AI benchmarks.
* Readers for Moving AI ``.map``/``.scen`` files and Polyanya ``.mesh`` (v2) navigation meshes,
  and :class:`MeshFreeSpace`, the free space of a mesh with the same segment queries as
  :class:`Obstacles2D`, so the visibility graph runs on either.
"""

from weldplan.planar.exact_path import ExactPath
from weldplan.planar.grid_astar import SQRT2, astar_grid, grid_graph, grid_lengths, octile
from weldplan.planar.meshspace import MeshFreeSpace
from weldplan.planar.movingai import MOVINGAI_PASSABLE, ScenarioSet, read_movingai_map, read_scen
from weldplan.planar.visibility import (
    CHUNK,
    CIRCLE_SIDES,
    VisibilityGraph,
    candidate_vertices,
    mesh_shortest_path_bounded,
    space_free,
    visibility_shortest_path,
)

__all__ = [
    "CHUNK",
    "CIRCLE_SIDES",
    "MOVINGAI_PASSABLE",
    "SQRT2",
    "ExactPath",
    "MeshFreeSpace",
    "ScenarioSet",
    "VisibilityGraph",
    "astar_grid",
    "candidate_vertices",
    "grid_graph",
    "grid_lengths",
    "mesh_shortest_path_bounded",
    "octile",
    "read_movingai_map",
    "read_scen",
    "space_free",
    "visibility_shortest_path",
]
