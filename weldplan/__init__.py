"""weldplan: collision-free welding-torch routes through car bodies, and 2D path planning.

The 3D entry points are importable from the top level (loaded lazily, so ``import weldplan`` stays
cheap)::

    import weldplan
    cell = weldplan.load_cell("body.stl", "joints.csv")
    cell = weldplan.demo_cell()
    route = weldplan.plan_route(cell, rng=0)
    weldplan.verify_route(route, cell.part).ok

The whole job (tool poses, transitions, robot, program) on a station file::

    station = weldplan.load_station("examples/demo_station.toml")
    plan = weldplan.plan(station, rng=0)
    plan.save("route.json")
    saved = weldplan.load_plan("route.json", mesh="part.stl")
    saved.verify(tool=plan.tool).ok
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

from weldplan._version import __version__

#: public name -> module that defines it
_LAZY: dict[str, str] = {
    "Cell": "weldplan.weld.cell",
    "build_cell": "weldplan.weld.cell",
    "load_cell": "weldplan.weld.cell",
    "demo_cell": "weldplan.weld.cell",
    "Joints": "weldplan.io.joints",
    "read_joints": "weldplan.io.joints",
    "load_part": "weldplan.io.mesh",
    "ObstacleGrid": "weldplan.geometry.grid",
    "build_grid": "weldplan.geometry.grid",
    "CollisionModel": "weldplan.geometry.collision",
    "PlanConfig": "weldplan.weld.pipeline",
    "plan_route": "weldplan.weld.pipeline",
    "Route": "weldplan.weld.route",
    "verify_route": "weldplan.weld.verify",
    "Station": "weldplan.station.model",
    "load_station": "weldplan.station.load",
    "plan": "weldplan.plans",
    "Plan": "weldplan.station.pipeline",
    "write_plan": "weldplan.station.outputs",
    "MountedTool": "weldplan.station.mount",
    "load_plan": "weldplan.station.saved",
    "SavedPlan": "weldplan.station.saved",
    "Verdict": "weldplan.station.recheck",
    "ToolRoute": "weldplan.robot.program.toolroute",
    "allocate": "weldplan.multi.allocate",
    "StationPlan": "weldplan.multi.station",
    "save_station_plan": "weldplan.multi.saved",
    "load_station_plan": "weldplan.multi.saved",
    "SavedStationPlan": "weldplan.multi.saved",
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'weldplan' has no attribute {name!r}")
