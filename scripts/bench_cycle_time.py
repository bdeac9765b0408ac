"""Benchmark: cycle time of the demo cell (and car2 stations) with the shared KUKA and spot gun.

Usage (from the repository root)::

    python scripts/bench_cycle_time.py [--stations demo,car2_50] [--robot-base X,Y,Z,YAW]
                                       [--weld-time 0.5] [--tcp-speed 1000]
                                       [--cost length,time] [--moves linear,joint]

For each station: the route, the weld poses, the robot route (base searched unless given,
:func:`weldplan.robot.route.plan_robot_route`), then the program and its timing
(:func:`weldplan.robot.program.robot_program`) with linear and with joint moves. Prints a
markdown table: welds served, whether the robot route is collision-free, the cycle time (toppra)
beside the same route at a constant TCP speed, the moving time, the TCP's largest distance from
the Cartesian lines, the emitted programs' FK round trip (RAPID and KRL parsed back), seconds of
each stage, and the load average. With ``--cost time`` the order minimises the robot's leg
times (:func:`weldplan.robot.route.cell_leg_times`, the base fixed before the order) and the
row also gives the order's seconds over those bounds and the proved lower bound of the cycle.
A robot route that is not collision-free is timed all the same
and said so: its figures are not those of a program weldplan would write.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from pathlib import Path

import numpy as np

import weldplan
from weldplan.commands._robot import check_program
from weldplan.io.posts.krl import render_krl
from weldplan.io.posts.rapid import render_rapid
from weldplan.robot import load_robot
from weldplan.robot.model import urdf_payload
from weldplan.robot.placement import BaseSearch, parse_base
from weldplan.robot.program import robot_program
from weldplan.robot.route import cell_leg_times, plan_robot_route, time_stats, tool_flange_tcp
from weldplan.robot.settings import ProgramSettings, RobotCell, ToolOnRobot
from weldplan.tool import plan_weld_poses, verify_poses
from weldplan.tool.model import load_tool
from weldplan.weld.verify import verify_route

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
CAR2 = SHARED / "bodies" / "car2.obj"
GUN = SHARED / "tools" / "spot_welding_gun" / "spot_welding_gun.urdf"
KUKA = SHARED / "robots" / "kuka_kr150r3100_2" / "kr150r3100_2.urdf"


def _cell(name: str):
    if name == "demo":
        return weldplan.demo_cell()
    joints = ROOT / "assets" / "car2" / f"car2_synthetic_{name.split('_')[1]}.csv"
    return weldplan.load_cell(CAR2, joints, length=4500)


def run(
    name: str,
    base: str | None,
    weld_time: float,
    tcp_speed: float,
    cost: str = "length",
    moves_list: tuple[str, ...] = ("linear", "joint"),
) -> list[str]:
    t0 = time.perf_counter()
    cell = _cell(name)
    tool, prov = load_tool(GUN)
    robot = load_robot(KUKA)
    Tft = tool_flange_tcp(robot, GUN)
    stats = "-"
    if cost == "time":
        placed = robot if base is None else robot.with_base(parse_base(base))
        legs, placed = cell_leg_times(
            cell, tool, placed, Tft, weld_time=weld_time,
            search=BaseSearch() if base is None else None,
        )  # fmt: skip
        B = placed.base
        yaw = np.degrees(np.arctan2(B[1, 0], B[0, 0]))
        base = f"{B[0, 3]},{B[1, 3]},{B[2, 3]},{yaw}"
        route = weldplan.plan_route(cell, rng=0, leg_cost=legs.cost)
        st = time_stats(legs, tuple(str(i) for i in cell.joints.ids), route.order)
        stats = f"{st['time_cost']:.2f} / {st['time_bound']:.2f} ({st['time_bound_method']})"
    else:
        route = weldplan.plan_route(cell, rng=0)
    assert verify_route(route, cell.part, joints=cell.joints).ok
    poses = plan_weld_poses(cell, route, tool)
    assert verify_poses(poses, cell.part, tool).ok
    route = dataclasses.replace(route, tool={"provenance": prov, "poses": poses.to_dict()})
    t_route = time.perf_counter() - t0
    t1 = time.perf_counter()
    mass, cog = urdf_payload(GUN)
    on = ToolOnRobot(Tft, tool, mass=mass, cog=(robot.mount @ np.r_[cog, 1.0])[:3])
    at = RobotCell(
        cell.part, base=None if base is None else parse_base(base),
        search=BaseSearch() if base is None else None,
    )  # fmt: skip
    rr = plan_robot_route(route, poses, robot, tool=on, cell=at, rng=0)
    t_robot = time.perf_counter() - t1
    rb = robot.with_base(rr.base)
    rows = []
    for moves in moves_list:
        t2 = time.perf_counter()
        b = robot_program(
            route, rr.q, rb, on, part=cell, row=rr.row, exact=rr.exact,
            settings=ProgramSettings(moves=moves, weld_time=weld_time, tcp_speed=tcp_speed),
        )  # fmt: skip
        t_prog = time.perf_counter() - t2
        src, dat = render_krl(b.program)
        err = max(
            check_program("rapid", {"post": render_rapid(b.program)}, b.program, rb),
            check_program("krl", {"post": src, "post_dat": dat}, b.program, rb),
        )
        tt = b.timing
        x, y, z, yaw = rr.stats["placement"]["base_xyz_yaw"]
        rows.append(
            f"| {name} | {cost} | {route.length:.1f} | {stats} | "
            f"{moves} ({sum(t.move == 'linear' for t in b.program.targets)} lin) | "
            f"{rr.n_ok}/{len(rr.status)} | "
            f"{rr.stats.get('collision_free')} ({len(rr.stats.get('hits', []))} hits) | "
            f"{tt.total:.2f} | {b.constant_speed_time:.2f} | {tt.motion_time:.2f} | "
            f"{b.tcp_deviation:.2f} | {err:.1e} | ({x:.0f}, {y:.0f}, {z:.0f}, {yaw:.0f}) | "
            f"{t_route:.1f} / {t_robot:.1f} / {t_prog:.1f} |"
        )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stations", default="demo")
    ap.add_argument("--robot-base", default=None)
    ap.add_argument("--weld-time", type=float, default=0.5)
    ap.add_argument("--tcp-speed", type=float, default=1000.0)
    ap.add_argument("--cost", default="length", help="length, time or length,time")
    ap.add_argument("--moves", default="linear,joint")
    a = ap.parse_args()
    print(
        "| station | cost | route mm | order s / proved bound s | moves | welds served | "
        "collision-free | cycle s | at constant "
        f"{a.tcp_speed:g} mm/s s | moving s | TCP off lines mm | post FK error mm | base x,y,z,yaw "
        "| s: route+poses / robot / program |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in a.stations.split(","):
        for cost in a.cost.split(","):
            for row in run(name, a.robot_base, a.weld_time, a.tcp_speed, cost,
                           tuple(a.moves.split(","))):  # fmt: skip
                print(row, flush=True)
    print(f"\nweld time {a.weld_time} s a spot; load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
