"""Two shared KUKA KR 150 on synthetic timed routes (tests of weldplan.multi.interference,
zones and replay): each robot swings its first axis through a weld row, its arm stretched
forward (A2 -90 deg, A3 +90 deg). ``facing``: the bases 3 m apart, facing each other, so the arms
cross in the middle; ``far``: the second robot 12 m away. Test scaffolding, not the planner's
routes: the timing is the real one (weldplan.robot.program.time_route, the URDF's limits)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.conftest import require_shared

#: A1..A6 rad: the arm stretched forward, the forearm level
HOME = np.array([0.0, -np.pi / 2, np.pi / 2, 0.0, 0.0, 0.0])
#: s at each weld
WELD_S = 0.5


def urdf() -> Path:
    return require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")


def base(x: float, yaw: float) -> np.ndarray:
    """``(4, 4)`` mm: a base on the floor at ``(x, 0, 0)`` turned ``yaw`` rad about z."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0, x], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def sweep(robot, a1, weld_rows=(1,), weld_time=WELD_S):
    """The timed route through the A1 values ``a1`` (rad) from :data:`HOME`, every row a stop."""
    from weldplan.robot.program import time_route

    Q = np.array([HOME + [a, 0, 0, 0, 0, 0] for a in a1])
    return time_route(
        Q, robot.velocity, robot.acceleration, weld_rows=list(weld_rows),
        stops=np.ones(len(Q), bool), weld_time=weld_time, joint_names=robot.joint_names,
    )  # fmt: skip


def pair(distance: float = 3000.0, a1=(1.0, 0.0, -1.0), b1=(-1.0, 0.0, 1.0)):
    """``(robots, timings)``: robot 1 at ``-distance / 2`` facing +x, robot 2 at
    ``+distance / 2`` facing -x, each sweeping its A1 through ``a1`` / ``b1``."""
    from weldplan.robot import load_robot

    robots = [
        load_robot(urdf(), base=base(-distance / 2, 0.0)),
        load_robot(urdf(), base=base(distance / 2, np.pi)),
    ]
    return robots, [sweep(robots[0], a1), sweep(robots[1], b1)]


def movers(robots, timings):
    from weldplan.multi.interference import MovingRobot

    return [
        MovingRobot(f"robot{k + 1}", r, t)
        for k, (r, t) in enumerate(zip(robots, timings, strict=True))
    ]


def replayed(robots, timings):
    from weldplan.multi.replay import ReplayRobot

    return [
        ReplayRobot(f"robot{k + 1}", urdf(), np.asarray(r.base), t)
        for k, (r, t) in enumerate(zip(robots, timings, strict=True))
    ]
