"""A station and the whole job on it: ``weldplan.load_station(path)``, ``weldplan.plan(station)``.

::

    import weldplan
    station = weldplan.load_station("examples/demo_station.toml")
    plan = weldplan.plan(station, rng=0)
    plan.route.to_csv("route.csv")

:mod:`weldplan.station.model` (the station and each stage's settings), :mod:`.load` (the TOML
file), :mod:`.mount` (a tool on a flange), :mod:`.pipeline` (the stages and the :class:`Plan`),
:mod:`.toolstage` and :mod:`.robotstage` (the stages after the point-tip route),
:mod:`.outputs` (the files), :mod:`.summary` (the table a run prints).
"""

from weldplan.station.load import load_station
from weldplan.station.model import (
    CellSettings,
    OutputSpec,
    PartSpec,
    RobotSettings,
    RobotSpec,
    RouteSettings,
    Station,
    ToolSettings,
    ToolSpec,
)
from weldplan.station.pipeline import Plan, StageRecord, plan

__all__ = [
    "CellSettings",
    "OutputSpec",
    "PartSpec",
    "Plan",
    "RobotSettings",
    "RobotSpec",
    "RouteSettings",
    "StageRecord",
    "Station",
    "ToolSettings",
    "ToolSpec",
    "load_station",
    "plan",
]
