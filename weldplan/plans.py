"""``weldplan.plan``: a station with one robot (or none) or with several.

One robot, or only the point tip and a tool: :func:`weldplan.station.pipeline.plan`, a
:class:`~weldplan.station.pipeline.Plan`. Several robots:
:func:`weldplan.multi.station.plan_station` (allocation, then the single-robot pipeline per
robot), a
:class:`~weldplan.multi.station.StationPlan`. The dispatch lives above both, so the single-robot
pipeline never imports the station of several robots built on it.
"""

from __future__ import annotations

from typing import Any


def plan(station: Any, *, rng: Any = None, executor: Any = None, progress: Any = None) -> Any:
    """Plan ``station`` (:func:`weldplan.load_station`); ``rng``, ``executor`` and ``progress``
    as :func:`weldplan.station.pipeline.plan` takes them."""
    if len(station.robots) > 1:
        from weldplan.multi.station import plan_station
        from weldplan.station.pipeline import draw_seed

        seed = draw_seed(rng, station.seed)
        return plan_station(station, seed=seed, executor=executor, progress=progress)
    from weldplan.station.pipeline import plan as plan_one

    return plan_one(station, rng=rng, executor=executor, progress=progress)
