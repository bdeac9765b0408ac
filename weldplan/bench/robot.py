"""``weldplan bench robot``: the whole pipeline users run, on a car2 station, timed by stage.

The station (:func:`car2_station`): car2 (``../shared/data/bodies/car2.obj`` scaled to 4500 mm)
with the synthetic ``n``-joint set of ``assets/car2/car2_synthetic_{n}.csv``
(:mod:`weldplan.weld.synthetic`, seed 0, SYNTHETIC spots; n = 50, 200, 1000 or 4000), the shared
spot gun or the built-in straight arc torch on the KUKA KR 150 R3100-2, its base searched on the
floor (the part's lowest point) or given with ``--robot-base``. ``--station FILE`` runs any
station file instead (docs/station.md).

It runs :func:`weldplan.plan`, the same call as ``weldplan plan`` (the point-tip route, the
reach test, the tool poses and transitions, the joint route with its detours, the timing and
the program), and reports each stage's wall seconds, the process's CPU seconds and the load.
The issue-17 target (the robot stage of a 200-joint station in <= 30 s on 2 cores) is the
``robot`` stage's figure.

:func:`station` and :func:`straight_route` keep the earlier set-up (straight legs through the
spots' virtual joints, the gun poses of :func:`weldplan.tool.plan_weld_poses`) for the scripts
and tests that build a robot route without the pair planner.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import time
from pathlib import Path
from typing import Any

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


#: kg of the built-in arc torch on the flange (its body, neck and nozzle; an assumption)
TORCH_MASS_KG = 5.0


def car2_station(n: int, tool_name: str = "gun", base: str | None = None, **kw: Any) -> Any:
    """The ``n``-joint car2 :class:`~weldplan.station.model.Station` (module docstring); ``kw``:
    ``search_step`` (mm), ``cone`` (deg, the gun-pose search's tilt)."""
    from weldplan.station import model as m
    from weldplan.tool.torch import SHARED_GUN_DIR
    from weldplan.weld.synthetic import CAR2

    welds = Path(__file__).resolve().parents[2] / "assets" / "car2" / f"car2_synthetic_{n}.csv"
    if not welds.is_file():
        raise WeldplanError(f"no synthetic set of {n} joints ({welds}); use 50, 200, 1000, 4000")
    robot_dir = Path(CAR2).parents[1] / "robots" / "kuka_kr150r3100_2"
    if tool_name == "gun":
        tool = m.ToolSpec(file=SHARED_GUN_DIR / "spot_welding_gun.urdf")
    else:
        tool = m.ToolSpec(builtin="arc_torch", params={"bend_angle": 0.0}, mass=TORCH_MASS_KG)
    where: dict[str, Any] = {"search": {"step": kw.get("search_step", 250.0)}}
    if base:
        where = {"base": tuple(float(v) for v in base.split(","))}
    robot = m.RobotSpec(tool=tool, urdf=robot_dir / "kr150r3100_2.urdf", **where)
    return m.Station(
        part=m.PartSpec(Path(CAR2), welds, length=4500.0),
        robots=(robot,),
        tool=m.ToolSettings(cone=kw.get("cone", m.ToolSettings.cone)),
        name=f"car2_{n}",
    )


def measure(station: Any, seed: int = 0) -> dict:
    """Plan ``station`` (:func:`weldplan.plan`) and return its figures."""
    import weldplan

    t0 = time.perf_counter()
    c0 = time.process_time()
    p = weldplan.plan(station, rng=seed)
    total, cpu = time.perf_counter() - t0, time.process_time() - c0
    out: dict[str, Any] = {
        "station": str(station.source or station.name),
        "joints": len(p.cell.joints.ids),
        "order": "-".join(p.route.order),
        "route_mm": round(p.route.length, 2),
    }
    if p.poses is not None:
        out["tool_poses_ok"] = p.poses.poses.n_ok
        out["transitions_blocked"] = len(p.transitions.path.blocked)
    if p.robot is not None:
        rr = p.robot.robot_route
        out.update(
            welds={s: rr.status.count(s) for s in sorted(set(rr.status))},
            flips=len(rr.flips),
            replanned_legs=len(rr.replanned),
            base_xyz_yaw=[round(v, 1) for v in rr.stats["placement"]["base_xyz_yaw"]],
            collision_free=rr.stats.get("collision_free"),
            fk_max_error_mm=rr.stats["fk_max_error_mm"],
            cycle_s=round(p.program.timing.total, 3),
        )
    out["not_served"] = p.partial()
    out["seconds_by_stage"] = {s.name: round(s.seconds, 2) for s in p.stages}
    out["seconds_total"] = round(total, 2)
    # CPU seconds of this process (all its threads): the wall time's share of a loaded box
    out["cpu_seconds_total"] = round(cpu, 2)
    out["load_average"] = os.getloadavg()
    return out


HELP = "the whole pipeline (weldplan.plan) on a car2 station, timed by stage"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("-n", type=int, default=200, help="joints in the station (default 200)")
    p.add_argument("--robot-base", default=None, help="x,y,z,yaw (mm, deg); default: searched")
    p.add_argument("--search-step", type=float, default=250.0, help="floor grid step (mm)")
    p.add_argument(
        "--pose-cone",
        type=float,
        default=15.0,
        help="tilt cone of the gun-pose search, deg (default 15, plan's)",
    )
    p.add_argument(
        "--tool",
        choices=("gun", "torch"),
        default="gun",
        help="the shared spot gun (default) or the built-in straight arc torch",
    )
    p.add_argument("--station", metavar="TOML", help="run this station file instead")
    p.add_argument("--seed", type=int, default=0, help="the run's seed (default 0)")


def run(args: argparse.Namespace) -> int:
    try:
        if args.station:
            from weldplan.station import load_station

            st = load_station(args.station)
            name = Path(args.station).stem
        else:
            st = car2_station(
                args.n, args.tool, args.robot_base, search_step=args.search_step,
                cone=args.pose_cone,
            )  # fmt: skip
            name = f"robot-{args.n}-{args.tool}"
        out = measure(st, args.seed)
    except WeldplanError as exc:
        print(f"error: {exc}")
        return 2
    text = json.dumps(out, indent=1)
    print(text)
    folder = getattr(args, "out", None)
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        (Path(folder) / f"{name}.json").write_text(text + "\n")
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m weldplan.bench.robot", description=__doc__)
    add_arguments(p)
    return run(p.parse_args(argv))


if __name__ == "__main__":
    raise SystemExit(main())
