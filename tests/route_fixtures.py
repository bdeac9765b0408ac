"""Small hand-made scenes for the route, verify, export and viewer tests (no cell needed).

A 200 x 200 mm floor plate (top face z = 0) with a 60 mm high wall at x = 0 (|y| <= 50).
Three weld spots on the floor: A (-40, 0), B (40, 0) on either side of the wall, C (-40, 60)
beyond its end. Their virtual joints sit 10 mm above the floor. The route A -> C -> B goes
straight from A to C, then around the end of the wall to B.
"""

from __future__ import annotations

import numpy as np
import trimesh

from weldplan.weld.route import Leg, Route

CLEARANCE = 5.0
SPOTS = np.array([[-40.0, 0.0, 0.0], [40.0, 0.0, 0.0], [-40.0, 60.0, 0.0]])
IDS = ("A", "B", "C")
VIRTUAL = SPOTS + [0.0, 0.0, 10.0]


def box_part() -> trimesh.Trimesh:
    floor = trimesh.creation.box(extents=[200.0, 200.0, 2.0])
    floor.apply_translation([0.0, 0.0, -1.0])
    wall = trimesh.creation.box(extents=[2.0, 100.0, 60.0])
    wall.apply_translation([0.0, 0.0, 30.0])
    return trimesh.util.concatenate([floor, wall])


def box_route(directions: bool = False) -> Route:
    A, B, C = SPOTS
    vA, vB, vC = VIRTUAL
    legs = (
        Leg("A", "C", [A, vA, vC, C], "straight"),
        Leg("C", "B", [C, vC, [0.0, 62.0, 10.0], vB, B], "exact"),
    )
    dirs = np.tile([0.0, 0.0, 1.0], (3, 1)) if directions else None  # out of the floor
    return Route(
        order=("A", "C", "B"),
        legs=legs,
        joint_ids=IDS,
        joint_xyz=SPOTS,
        directions=dirs,
        virtual_xyz=VIRTUAL,
        lower_bound=60.0 + float(np.hypot(80.0, 60.0)),
        lower_bound_method="held-karp",
        settings={"clearance": CLEARANCE, "planner": "exact"},
        seed=7,
        stats={"pairs_blocked": 1},
    )


#: four joints on the box part of :func:`box_part`, the CLI tests' station
BOX_JOINTS_CSV = "id,x,y,z\nA,-40,0,0\nB,40,0,0\nC,-40,60,0\nD,40,-30,0\n"


def write_box_station(folder):
    """``box.stl`` and ``joints.csv`` (:data:`BOX_JOINTS_CSV`) in ``folder``.

    Returns ``(folder, mesh, joints)``.
    """
    mesh = folder / "box.stl"
    box_part().export(mesh)
    joints = folder / "joints.csv"
    joints.write_text(BOX_JOINTS_CSV)
    return folder, mesh, joints
