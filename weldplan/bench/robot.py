"""``python -m weldplan.bench.robot``: IK, branch choice and robot collision on a car2 station.

The station: the synthetic ``n``-joint set on car2 (:func:`weldplan.weld.synthetic.car2_joints`,
seed 0, scaled to 4500 mm, SYNTHETIC spots), visited in its line order; each leg goes straight
from a spot to its virtual joint ``approach_mm`` out along its approach direction, to the next
spot's virtual joint, and down to that spot (the torch route's shape without the pair planner,
whose time is not what this measures). The shared spot gun's pose at each spot comes from
:func:`weldplan.tool.plan_weld_poses` over 12 spins without tilt (:data:`POSE_SPIN_STEP`;
cached in ``--cache``: it is the tool stage's cost, not this one's). The
robot is the KUKA KR 150 R3100-2; its base is searched on the floor (the part's lowest point)
or given with ``--robot-base``.

Timed: :func:`weldplan.robot.plan.plan_robot_route` without re-planning (the base search, IK of
every waypoint, branch and turn choice, the collision check of robot and gun at the welds and
along the whole joint path); ``--replan`` detours blocked legs too. The issue's target: a
200-joint station in <= 30 s on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import time
from pathlib import Path

import numpy as np

from weldplan.errors import WeldplanError

log = logging.getLogger(__name__)

#: mm: how far out along the approach the legs leave and reach a spot
APPROACH_MM = 10.0
#: the gun-pose search of the set-up (deg): spins only, no tilt, so the set-up stays short on 2
#: cores (the poses are still verified; the tool stage's own defaults search a 15 deg cone)
POSE_CONE = 0.0
POSE_SPIN_STEP = 30.0


def straight_route(joints, approach_mm: float = APPROACH_MM):
    """A :class:`~weldplan.weld.route.Route` through ``joints`` in file order, straight legs
    through each spot's virtual joint ``approach_mm`` out along its approach direction."""
    from weldplan.weld.route import Leg, Route

    xyz = np.asarray(joints.xyz, dtype=np.float64)
    v = xyz + approach_mm * np.asarray(joints.directions, dtype=np.float64)
    ids = tuple(joints.ids)
    legs = tuple(
        Leg(ids[i], ids[i + 1], [xyz[i], v[i], v[i + 1], xyz[i + 1]], "straight")
        for i in range(len(ids) - 1)
    )
    return Route(
        order=ids,
        legs=legs,
        joint_ids=ids,
        joint_xyz=xyz,
        directions=np.asarray(joints.directions),
        virtual_xyz=v,
        settings={"clearance": 5.0, "planner": "straight (bench)"},
    )


def station(
    n: int,
    cache: Path | None,
    tool_name: str = "gun",
    cone: float = POSE_CONE,
    spin_step: float = POSE_SPIN_STEP,
):
    """``(part, route, poses, tool)`` of the ``n``-joint car2 station (module docstring); the
    gun-pose search over ``cone`` and ``spin_step`` degrees."""
    from weldplan.tool import WeldPoses, arc_torch, plan_weld_poses, shared_spot_gun
    from weldplan.weld.synthetic import car2_joints, car2_part

    part = car2_part()
    joints = car2_joints(n, mesh=part)
    route = straight_route(joints)
    gun = shared_spot_gun() if tool_name == "gun" else arc_torch(bend_angle=0.0)
    alt = "" if (cone, spin_step) == (POSE_CONE, POSE_SPIN_STEP) else f"_c{cone:g}_s{spin_step:g}"
    f = None if cache is None else cache / f"car2_{n}_{tool_name}{alt}_poses.json"
    if f is not None and f.is_file():
        poses = WeldPoses.from_json(f.read_text())
    else:
        t = time.perf_counter()
        poses = plan_weld_poses(part, route, gun, cone=cone, spin_step=spin_step)
        log.info("gun poses for %d spots: %.1f s", n, time.perf_counter() - t)
        if f is not None:
            f.parent.mkdir(parents=True, exist_ok=True)
            f.write_text(poses.to_json())
    return part, route, poses, gun


#: flange -> TCP of the straight arc torch: its TCP 425 mm out along the flange's z axis
#: (stick-out 15 + nozzle 60 + neck 150 + body 200 mm, the body's end on the flange)
TORCH_REACH_MM = 425.0


def measure(
    n: int,
    base: str | None,
    cache: Path | None,
    search_step: float,
    tool_name: str = "gun",
    replan: bool = False,
    reach_poses: bool = False,
    cone: float = POSE_CONE,
    spin_step: float = POSE_SPIN_STEP,
) -> dict:
    from weldplan.robot import load_robot
    from weldplan.robot.plan import plan_robot_route, tool_flange_tcp
    from weldplan.robot.reach import BaseSearch, parse_base
    from weldplan.tool.torch import SHARED_GUN_DIR
    from weldplan.weld.synthetic import CAR2

    robot_dir = Path(CAR2).parents[1] / "robots" / "kuka_kr150r3100_2"
    part, route, poses, gun = station(n, cache, tool_name, cone, spin_step)
    robot = load_robot(robot_dir / "kr150r3100_2.urdf")
    if tool_name == "gun":
        F = tool_flange_tcp(robot, SHARED_GUN_DIR / "spot_welding_gun.urdf", "nozzle_tip")
    else:
        F = np.eye(4)
        F[2, 3] = TORCH_REACH_MM
    reach: dict = {}
    if reach_poses:
        poses, base_T, reach = _reach_poses(
            robot, F, part, route, poses, gun, base, search_step, cone, spin_step
        )
        kw: dict = {"base": base_T}
    else:
        kw = {"base": parse_base(base)} if base else {"search": BaseSearch(step=search_step)}
    t0 = time.perf_counter()
    c0 = time.process_time()
    rr = plan_robot_route(
        route, poses, robot, flange_tcp=F, part=part, tool=gun, replan=replan, **kw
    )
    total = time.perf_counter() - t0
    cpu = time.process_time() - c0
    st = {s: rr.status.count(s) for s in sorted(set(rr.status))}
    return {
        "station": f"car2 synthetic {n} joints (seed 0), straight legs, tool {tool_name}",
        "gun_poses_ok": poses.n_ok,
        "welds": st,
        # what blocks the welds charged with a collision (body: count)
        "collision_bodies": {
            b: sum(d.split(" ")[0] == b for d in rr.detail if d)
            for b in sorted({d.split(" ")[0] for d in rr.detail if d})
        },
        "first_check_bodies": rr.stats.get("first_check_bodies"),
        "replanned_legs": len(rr.replanned),
        "flips": len(rr.flips),
        "waypoints": len(rr.q),
        "base_xyz_yaw": [round(v, 1) for v in rr.stats["placement"]["base_xyz_yaw"]],
        "base_searched": rr.stats["placement"]["searched"] or bool(reach.get("base_searched")),
        # --reach-poses: the gun poses re-chosen with the robot's reach test at the base
        **({"reach_poses": reach} if reach else {}),
        "seconds_total": round(total, 2),
        # CPU seconds of this process (all its threads): the wall time's share of a loaded box
        "cpu_seconds_total": round(cpu, 2),
        "seconds_ik_configs_incl_search": rr.stats["seconds_ik_configs"],
        "seconds_collision": rr.stats.get("seconds_collision"),
        "collision_free": rr.stats.get("collision_free"),
        "blocked_motions": len(rr.stats.get("hits", [])),
        "fk_max_error_mm": rr.stats["fk_max_error_mm"],
        "load_average": os.getloadavg(),
    }


def _reach_poses(robot, F, part, route, poses, gun, base, search_step, cone, spin_step) -> tuple:
    """The gun poses re-chosen with the robot's reach test (:mod:`weldplan.robot.posechoice`)
    at ``base``, or at the base searched for the first-pass ``poses``: ``(poses, base (4, 4),
    figures)``."""
    from weldplan.robot.collision import RobotCollision
    from weldplan.robot.posechoice import ReachTest, place_for_poses
    from weldplan.robot.reach import BaseSearch, parse_base
    from weldplan.tool import plan_weld_poses

    t0 = time.perf_counter()
    zone = float(poses.settings.get("contact_radius", 20.0))
    checker = RobotCollision(robot, part, None, F, contact_radius=zone)
    if base:
        B = parse_base(base)
    else:
        B = place_for_poses(
            robot, route, poses, F, part, checker, BaseSearch(step=search_step)
        ).base
    t1 = time.perf_counter()
    rb = robot.with_base(B)
    test = ReachTest(rb, F, checker.with_robot(rb))
    again = plan_weld_poses(part, route, gun, cone=cone, spin_step=spin_step, accept=test)
    t2 = time.perf_counter()
    figures = {
        "base_searched": not base,
        "seconds_base_search": round(t1 - t0, 2),
        "seconds_poses_with_test": round(t2 - t1, 2),
        "poses_judged": test.calls,
        "vetoes": dict(test.vetoes),
        "welds_exhausted": again.stats["accept_exhausted"],
        "poses_changed": sum(
            a.quaternion != b.quaternion for a, b in zip(poses.poses, again.poses, strict=True)
        ),
    }
    return again, B, figures


HELP = "IK, branch choice and robot collision on a car2 station (issue 17 target: 200 joints, 30 s)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("-n", type=int, default=200, help="joints in the station (default 200)")
    p.add_argument("--robot-base", default=None, help="x,y,z,yaw (mm, deg); default: searched")
    p.add_argument("--search-step", type=float, default=250.0, help="floor grid step (mm)")
    p.add_argument("--cache", type=Path, default=None, help="folder caching the tool poses")
    p.add_argument(
        "--replan",
        action="store_true",
        help="detour blocked legs too (default: IK, branch choice and the collision check only, "
        "the issue's timed target)",
    )
    p.add_argument(
        "--pose-cone",
        type=float,
        default=POSE_CONE,
        help=f"tilt cone of the gun-pose search, deg (default {POSE_CONE:g}; plan's is 15)",
    )
    p.add_argument(
        "--pose-spin",
        type=float,
        default=POSE_SPIN_STEP,
        help=f"spin step of the gun-pose search, deg (default {POSE_SPIN_STEP:g}; plan's is 15)",
    )
    p.add_argument(
        "--reach-poses",
        action="store_true",
        help="re-choose the gun poses with the robot's reach test first (the base searched for "
        "the first-pass poses, or --robot-base), as plan --robot does; timed apart",
    )
    p.add_argument(
        "--tool",
        choices=("gun", "torch"),
        default="gun",
        help="the shared spot gun (default) or the straight arc torch",
    )


def run(args: argparse.Namespace) -> int:
    try:
        out = measure(
            args.n, args.robot_base, args.cache, args.search_step, args.tool, args.replan,
            args.reach_poses, args.pose_cone, args.pose_spin,
        )  # fmt: skip
    except WeldplanError as exc:
        print(f"error: {exc}")
        return 2
    text = json.dumps(out, indent=1)
    print(text)
    folder = getattr(args, "out", None)
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        (Path(folder) / f"robot-{args.n}-{args.tool}.json").write_text(text + "\n")
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m weldplan.bench.robot", description=__doc__)
    add_arguments(p)
    return run(p.parse_args(argv))


if __name__ == "__main__":
    raise SystemExit(main())
