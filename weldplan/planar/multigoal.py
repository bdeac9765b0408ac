"""Multi-goal traversal on triangular-mesh maps (paper 002, section 3): scenarios, the mesh-edge
distances, the random-key encoding, the order polish and the B-spline smoothing.

This module is the public face of four: the tasks (:mod:`weldplan.planar.tour_scenarios`), the
distances and the ordering (:mod:`weldplan.planar.tour_order`), the smoothing
(:mod:`weldplan.planar.tour_smooth`) and the planner (:mod:`weldplan.planar.tour_planner`); their
names are importable from here. The planner modules import the parts, never this module.

The planner itself (:func:`~weldplan.planar.tour_planner.plan_tour`, still importable from
here) lives in :mod:`weldplan.planar.tour_planner`; its **default** orders the stops over exact
any-angle leg lengths (Polyanya, :mod:`weldplan.planar.tour_anyangle`) and joins Polyanya's
paths, a named deviation from the mesh-edge pipeline below, which is ``as_printed=True``.

The robot leaves the start, visits every target once and returns to the start. The pipeline:

1. Triangulate the free space with maximum edge length ``M``, start and targets as mesh nodes
   (:func:`weldplan.planar.meshmap.triangulate_map`).
2. Shortest mesh paths between every pair of start/targets (Dijkstra from each): the
   ``(t + 1, t + 1)`` distance matrix ``D`` and the node paths.
3. Order the targets. A continuous optimiser (ISMA, SMA, WOA, LSO, ... from the registry) works
   on a **random-key encoding**: one real key per target in ``[0, 10 t]`` (paper 002 sec. 1.2:
   lower bound 0, upper bound ten times the number of targets); the visiting order is the
   targets sorted by key (``argsort``), and the cost is the closed tour length over ``D``.
   The ground truth is :func:`weldplan.optim.discrete.sequence.solve_sequence` on the same
   ``D`` (Held-Karp up to 16 stops, else nearest neighbour + 2-opt/Or-opt polish).
4. Pull each mesh path tight inside its triangle corridor (funnel algorithm,
   :meth:`~weldplan.planar.meshmap.TriangleMap.funnel`: the shortest path homotopic to the
   mesh-edge path, so the zig-zag along triangle edges is gone; ``taut=False`` keeps it, as
   paper 002 does), join the legs into the tour polyline and smooth it with a clamped cubic
   B-spline (002 eq. 14, ``Q(u) = sum_k G_k H_{k,v}(u)``) whose control points ``G_k`` are the
   polyline's vertices; each target is a control point of multiplicity ``v`` (the degree) so
   the curve passes through it. The smoothed curve, sampled densely, is checked segment by
   segment against the true obstacles; around a colliding sample the nearest control points are
   raised to multiplicity ``v`` too (the curve is pulled onto the collision-free polyline
   there), for up to :data:`SMOOTH_ROUNDS` rounds; if it still collides the polyline itself is
   returned (``smoothed=False``). A taut leg bends only at obstacle corners, where any rounding
   cuts into the obstacle, so there the curve keeps the corner.

What is the paper's and what is not. Paper 002 runs ISMA with population and iterations both
500 (sec. 3, Table 4) and bounds the variables by ``[0, 10 x number of targets]`` (sec. 1.2,
after eq. 8); those are our defaults. It does not print how a real vector becomes a visiting
order: the random-key reading (sort the keys) is the standard one for those bounds and is ours.
The optimiser itself is run as printed (:class:`weldplan.optim.algorithms.isma.ISMA`, whose own
docstring names its deviations).

Deviations (named):

* ``polish=True`` (the **default** of :func:`plan_tour` and ``weldplan planar tour``): the
  optimiser's best order is polished once, after the run, by the weld sequencer's 2-opt +
  Or-opt iterated local search (:func:`weldplan.optim.discrete.local_search.polish`, with
  :data:`POLISH_KICKS_PER_STOP` kicks per stop). A user asks for the best tour within the time;
  ISMA as printed (``polish=False``) leaves 3-4 % mean and up to 9 % worst gaps on the 11- and
  14-target maps at the paper's budget, and the polish closes them in a few tens of
  milliseconds. The result keeps both: :attr:`TourResult.optimizer_length` is ISMA's own order,
  :attr:`TourResult.length` the polished one. Honest note: on tours of up to 15 stops the same
  polish from a *random* order also reaches the ground truth, so the polish, not ISMA, earns the
  last percents (``weldplan bench tour`` shows that row too).
* ``two_opt=True`` (off by default): a memetic variant that decodes every random key with a
  vectorised 2-opt descent before it is scored (Baldwinian: the keys are not rewritten).
"""

from __future__ import annotations

from typing import Any

from weldplan.planar.tour_order import (  # noqa: F401 - re-exported
    EXACT_STOPS,
    KEY_SCALE,
    PAPER_ITER,
    PAPER_POP,
    POLISH_KICKS_PER_STOP,
    RandomKeyTourProblem,
    TourGraph,
    build_tour_graph,
    polish_order,
    tour_lengths,
    two_opt_batch,
)
from weldplan.planar.tour_scenarios import (  # noqa: F401 - re-exported
    HOUSE_START,
    TOUR_DIR,
    SampledGridWorld,
    TourScenario,
    available_tours,
    house_tour,
    load_tour,
    navmesh_tour,
    tour_from_dict,
    tour_path,
)
from weldplan.planar.tour_smooth import (  # noqa: F401 - re-exported
    SAMPLES_PER_CONTROL,
    SMOOTH_ROUNDS,
    SPLINE_DEGREE,
    segments_clear,
    smooth_tour,
)


def __getattr__(name: str) -> Any:
    """The planner moved to :mod:`weldplan.planar.tour_planner` (this module was past 850 lines);
    its names stay importable from here."""
    if name in ("TourResult", "ground_truth", "plan_tour"):
        from weldplan.planar import tour_planner

        return getattr(tour_planner, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
