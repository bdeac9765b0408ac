"""``weldplan bench robot``: the whole pipeline users run, on a station, per seed and per base.

The station (:func:`car2_station`): car2 (``../shared/data/bodies/car2.obj`` scaled to 4500 mm,
``--up y`` stands it upright in the cell) with the synthetic ``n``-joint set of
``assets/car2/car2_synthetic_{n}.csv`` (:mod:`weldplan.weld.synthetic`, seed 0, SYNTHETIC spots;
n = 50, 200, 1000 or 4000), the shared spot gun or the built-in straight arc torch on the KUKA
KR 150 R3100-2, its base searched on the floor or given with ``--robot-base``. ``--station FILE``
runs any station file instead (docs/station.md), e.g. ``examples/car2_wall_station.toml``.

Each run is :func:`weldplan.plan`, the same call as ``weldplan plan`` (the point-tip route, the
reach test, the tool poses and transitions, the joint route with its detours, the timing and
the program): one per seed of ``--seeds`` (``0-4``), then, with ``--yaw-offsets``, one per
offset with the seed-0 searched base given turned by it (issue 27's perturbed bases). It prints
one table row per run (:mod:`weldplan.bench.robot_runs`): welds in the program / reachable at
that base / total, flips, the robot route's independent re-check, wall and CPU seconds per
stage, and a digest of the route (equal digests: the same program). ``--json`` prints the rows
as JSON; ``--out`` keeps both.

:func:`station` and :func:`straight_route` keep the earlier set-up (straight legs through the
spots' virtual joints, the gun poses of :func:`weldplan.tool.plan_weld_poses`) for the scripts
and tests that build a robot route without the pair planner.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
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
    from weldplan.tool.settings import PoseSearchSettings
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
        search = PoseSearchSettings(cone=cone, spin_step=spin_step)
        poses = plan_weld_poses(part, route, gun, search)
        log.info("gun poses for %d spots: %.1f s", n, time.perf_counter() - t)
        if f is not None:
            f.parent.mkdir(parents=True, exist_ok=True)
            f.write_text(poses.to_json())
    return part, route, poses, gun


#: the up axes ``--up`` takes (:data:`weldplan.cellframe.UP_AXES`)
UP_CHOICES = ("x", "y", "z", "-x", "-y", "-z")


def parse_seeds(text: str) -> tuple[int, ...]:
    """``"0-4"`` -> ``(0, 1, 2, 3, 4)``, ``"0,3,7"`` -> ``(0, 3, 7)``, ``"5"`` -> ``(5,)``:
    integers >= 0, each once, in the order given."""
    out: list[int] = []
    try:
        for part in text.split(","):
            a, sep, b = part.strip().partition("-")
            lo, hi = int(a), int(b) if sep else int(a)
            if lo < 0 or hi < lo:
                raise ValueError
            out += [k for k in range(lo, hi + 1) if k not in out]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"seeds must be A-B or A,B,... (integers >= 0, A <= B), got {text!r}"
        ) from None
    return tuple(out)


def parse_offsets(text: str) -> tuple[float, ...]:
    """``"-30,-15,15,30"`` -> ``(-30.0, -15.0, 15.0, 30.0)`` (degrees, finite, each once)."""
    try:
        out = tuple(float(v) for v in text.split(","))
    except ValueError:
        out = ()
    if not out or not all(math.isfinite(v) and abs(v) <= 180.0 for v in out):
        raise argparse.ArgumentTypeError(
            f"yaw offsets must be degrees in [-180, 180] separated by commas, got {text!r}"
        )
    if len(set(out)) != len(out):
        raise argparse.ArgumentTypeError(f"yaw offsets repeat a value: {text!r}")
    return out


#: flange -> TCP of the straight arc torch: its TCP 425 mm out along the flange's z axis
#: (stick-out 15 + nozzle 60 + neck 150 + body 200 mm, the body's end on the flange)
TORCH_REACH_MM = 425.0


#: kg of the built-in arc torch on the flange (its body, neck and nozzle; an assumption)
TORCH_MASS_KG = 5.0


def car2_station(
    n: int, tool_name: str = "gun", base: str | None = None, up: str | None = None, **kw: Any
) -> Any:
    """The ``n``-joint car2 :class:`~weldplan.station.model.Station` (module docstring), stood
    with its ``up`` axis to the cell's +z when given (``"y"``: car2 upright, docs/cell-frame.md);
    ``kw``: ``search_step`` (mm), ``cone`` (deg, the gun-pose search's tilt)."""
    from weldplan.cellframe import PartPose
    from weldplan.station import model as m
    from weldplan.tool.model.torch import SHARED_GUN_DIR
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
        part_pose=None if up is None else PartPose.from_up(up),
    )


HELP = "the whole pipeline (weldplan.plan) on a car2 station, timed by stage, per seed and base"


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
    p.add_argument(
        "--up",
        choices=UP_CHOICES,
        default=None,
        help="stand car2 with this axis up in the cell (y: upright; default: the part frame)",
    )
    p.add_argument("--station", metavar="TOML", help="run this station file instead")
    p.add_argument("--seed", type=int, default=None, help="the run's seed (default 0)")
    p.add_argument(
        "--seeds",
        type=parse_seeds,
        default=None,
        metavar="A-B|A,B,...",
        help="one run per seed, e.g. 0-4 (default 0)",
    )
    p.add_argument(
        "--yaw-offsets",
        type=parse_offsets,
        default=(),
        metavar="DEG,...",
        help="then one seed-0 run per offset, the base given at the seed-0 searched base turned "
        "by that many degrees about +z (write --yaw-offsets=-30,-15,15,30)",
    )
    p.add_argument("--json", action="store_true", help="print the runs as JSON, not the table")


def run(args: argparse.Namespace) -> int:
    from weldplan.bench.robot_runs import format_row, format_table, run_all, table_head

    try:
        if args.station:
            from weldplan.station import load_station

            st = load_station(args.station)
            name = Path(args.station).stem
        else:
            st = car2_station(
                args.n, args.tool, args.robot_base, args.up, search_step=args.search_step,
                cone=args.pose_cone,
            )  # fmt: skip
            name = f"robot-{args.n}-{args.tool}" + (f"-up{args.up}" if args.up else "")
        seeds = args.seeds or ((0,) if args.seed is None else (args.seed,))
        if not args.json:  # the rows as they come: a long bench shows its progress
            print("\n".join(table_head(name)), flush=True)
        show = None if args.json else (lambda r: print(format_row(r), flush=True))
        rows = run_all(st, seeds, tuple(args.yaw_offsets), on_row=show)
    except WeldplanError as exc:
        print(f"error: {exc}")
        return 2
    text = json.dumps([r.to_dict() for r in rows], indent=1)
    if args.json:
        print(text)
    folder = getattr(args, "out", None)
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        (Path(folder) / f"{name}.json").write_text(text + "\n")
        (Path(folder) / f"{name}.md").write_text(format_table(rows, title=name) + "\n")
    return 0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m weldplan.bench.robot", description=__doc__)
    add_arguments(p)
    return run(p.parse_args(argv))


if __name__ == "__main__":
    raise SystemExit(main())
