"""The shared KUKA KR 150 R3100-2 with the shared spot gun on the box route of route_fixtures.

The joint route here is test scaffolding, not the planner's: one IK solution per waypoint (TCP
straight down, the gun's TCP), each the solution nearest the previous one, starting from the
branch of the robot's usual pose (elbow up, wrist positive). The robot engineer's branch choice
(weldplan.robot.route.configs) replaces it in the pipeline.
"""

from __future__ import annotations

import numpy as np

from tests.conftest import require_shared
from tests.route_fixtures import box_route

#: the robot's base in the part frame: 1.9 m behind the box part, 1 m below it
BASE = np.array([[1, 0, 0, -1900.0], [0, 1, 0, 0], [0, 0, 1, -1000.0], [0, 0, 0, 1]])


def shared_robot():
    from weldplan.robot import load_robot

    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    return load_robot(urdf, base=BASE)


def gun_tcp(robot):
    """``(T_flange_tcp (4, 4) mm, gun URDF path)``."""
    from weldplan.robot.model import chain_transform

    gun = require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")
    return robot.tool_transform(chain_transform(gun, "nozzle_tip")), gun


def box_joint_route(robot, Tft, route=None):
    """``(route, q (n, 6))``: the box route with the TCP pointing down at every waypoint."""
    from weldplan.io.export import route_rows

    route = route or box_route(directions=True)
    rows = route_rows(route)
    R = np.diag([1.0, -1.0, -1.0])
    inv = np.linalg.inv(Tft)
    Q = []
    for r in rows:
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = [r["x"], r["y"], r["z"]]
        sol = robot.ik(T @ inv)
        assert len(sol), f"row {r['step']} unreachable"
        if not Q:
            k = int(np.argmin(np.where(sol.branch == 0, 0, 1) * 10 + np.abs(sol.q).sum(axis=1)))
            q = sol.q[k]
        else:  # A4 and A6 turn +-350 deg: take the turn nearest the previous value
            turns = np.round((Q[-1] - sol.q) / (2 * np.pi)) * (2 * np.pi)
            turns[:, [0, 1, 2, 4]] = 0.0
            cand = sol.q + turns
            cand = np.where(robot.in_limits(cand)[:, None], cand, sol.q)
            k = int(np.argmin(np.abs(cand - Q[-1]).sum(axis=1)))
            q = cand[k]
        Q.append(q)
    return route, np.array(Q)
