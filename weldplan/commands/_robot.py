"""The robot options of ``plan`` and ``demo`` and the robot stage of a planning run (issue 17).

With ``--robot URDF`` (and a URDF ``--tool``: its root link is mounted on the robot's flange), a
planning run chooses the weld poses with the robot's reach test (:func:`pose_acceptance`, from
``--robot-base`` or from a base searched on the poses chosen without it, then kept: a gun pose
the robot cannot take on a usable branch with its links clear of the part gives way to the next
least-rotation free pose; :mod:`weldplan.robot.posechoice`) and, after the route and the weld
poses were verified, runs :func:`robot_stage`:

1. the joint route (:func:`weldplan.robot.plan.plan_robot_route`: base given by
   ``--robot-base`` or searched, one continuous IK branch, robot + tool collision check,
   blocked legs re-planned in joint space). When the tool stage planned transitions, the robot
   follows them: the welds in the tool's order, each leg the gun's TCP path as Cartesian steps
   (:mod:`weldplan.robot.gunpath`), a leg the robot cannot follow detoured as any blocked leg;
   the summary says which order the program follows and why, and how each leg goes. A path
   that still collides is an error; a weld the robot cannot serve (no pose, out of reach,
   joint limit, singular) is passed without welding, listed with its reason, and the run exits
   with :data:`~weldplan.errors.EXIT_PARTIAL`;
2. the program and its cycle time (:func:`weldplan.robot.program.robot_program`: toppra under the
   URDF velocities x ``--vel-scale`` and the robot's accelerations x ``--acc-scale``,
   ``--weld-time`` a spot; the same route at ``--tcp-speed`` beside it);
3. the posts' own check (:func:`check_program`): the program text is parsed back and every target
   re-solved by forward kinematics of the URDF chain (<= 0.01 mm, 0.01 deg), so what is written
   is what was planned;
4. the texts: ``--post rapid`` (``.mod``), ``--post krl`` (``.src`` + ``.dat`` beside it) and
   ``--trajectory F`` (:mod:`weldplan.io.trajectory`) and ``--robot-html F``
   (:mod:`weldplan.viz.robot_scene`), written with the run's other outputs as one set.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from weldplan.commands._robot_cost import cost_rows, flange_tcp, is_urdf, tool_load
from weldplan.errors import InputError, PlanningError, WeldplanError

log = logging.getLogger(__name__)

#: the round trip of an emitted program must close within these (mm, deg): the issue's target
CHECK_MM = 0.01
CHECK_DEG = 0.01
#: s a spot takes when ``--weld-time`` is not given (squeeze, weld and hold of a typical
#: sheet-steel spot; an assumption, say yours)
DEFAULT_WELD_TIME = 0.5


def _number(kind: str, lo: float, hi: float, lo_open: bool = False):
    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        ok = math.isfinite(v) and (v > lo if lo_open else v >= lo) and v <= hi
        if not ok:
            rng = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
            raise argparse.ArgumentTypeError(f"must be a {kind} in {rng}, got {text!r}")
        return v

    return parse


def add_robot_arguments(p: argparse.ArgumentParser) -> None:
    """``--robot`` and the options of the robot stage."""
    g = p.add_argument_group("robot (a joint-space route, its cycle time, programs)")
    g.add_argument("--robot", metavar="URDF", help="6-axis robot (URDF with limits; OPW beside it)")
    g.add_argument(
        "--opw", metavar="F", help="OPW parameters (default: opw_parameters.yaml beside)"
    )
    g.add_argument(
        "--robot-base",
        metavar="X,Y,Z,YAW",
        help="robot base in the planning frame (the cell frame with --up/--part-pose, else the "
        "part frame; mm, degrees about +z); default: searched on the floor",
    )
    g.add_argument(
        "--floor-z",
        metavar="MM",
        type=_number("height in mm", -1e6, 1e6),
        help="the cell's floor height (in the cell frame with --up/--part-pose, default 0 there; "
        "else in the part frame): the base search stands the robot on it (default without a "
        "part pose: the part's lowest point) and no link nor the tool may reach below it "
        "(default without a part pose: no floor known, not checked)",
    )
    g.add_argument(
        "--weld-time",
        metavar="S",
        type=_number("number of s", 0.0, 3600.0),
        default=DEFAULT_WELD_TIME,
        help=f"seconds per spot in the cycle time (default {DEFAULT_WELD_TIME})",
    )
    g.add_argument(
        "--acc-scale",
        metavar="F",
        type=_number("fraction", 0.0, 1.0, lo_open=True),
        default=1.0,
        help="scale of the robot's joint accelerations (default 1: each joint reaches its URDF "
        "velocity in 0.5 s)",
    )
    g.add_argument(
        "--vel-scale",
        metavar="F",
        type=_number("fraction", 0.0, 1.0, lo_open=True),
        default=1.0,
        help="scale of the URDF joint velocity limits (default 1)",
    )
    g.add_argument(
        "--tcp-speed",
        metavar="MM/S",
        type=_number("speed in mm/s", 0.0, 1e5, lo_open=True),
        default=1000.0,
        help="constant TCP speed the cycle time is compared with (default 1000)",
    )
    g.add_argument(
        "--moves",
        choices=("linear", "joint"),
        default="linear",
        help="program moves between route rows: linear (blended where verified) or joint "
        "(exact stops, the checked joint path itself); default linear",
    )
    g.add_argument(
        "--tool-mass",
        metavar="KG",
        type=_number("mass in kg", 0.0, 5000.0, lo_open=True),
        help="tool mass for the programs (default: the tool URDF's <inertial> masses)",
    )
    g.add_argument(
        "--cost",
        choices=("length", "time"),
        default="length",
        help="what the sequencer minimises: route length (default) or the robot's cycle time "
        "(rest-to-rest bounds between the welds' IK configurations; needs --robot)",
    )
    g.add_argument("--trajectory", metavar="F", help="write the timed joint trajectory as CSV")
    g.add_argument(
        "--robot-html",
        metavar="F",
        help="write a 3D page of the robot, tool and part animated along the timed trajectory",
    )


def robot_from_args(args: argparse.Namespace) -> Any:
    """The robot (placed at ``--robot-base`` when given), ``None`` without ``--robot``; options
    that need it, or a tool, fail here, before any planning."""
    if not getattr(args, "robot", None):
        for opt in ("opw", "robot_base", "floor_z", "trajectory", "tool_mass", "robot_html"):
            if getattr(args, opt, None) is not None:
                raise WeldplanError(f"--{opt.replace('_', '-')} needs --robot")
        if getattr(args, "cost", "length") == "time":
            raise WeldplanError("--cost time needs --robot (and a --tool)")
        return None
    if not getattr(args, "tool", None):
        raise InputError(
            "--robot needs a --tool (a URDF whose root link is what the flange carries, or a "
            "mesh in its mounting frame with --tcp and --tool-mass)",
            field="--tool",
        )
    if not is_urdf(args.tool) and args.tool_mass is None:
        raise InputError(
            "a mesh tool has no mass: give --tool-mass with --robot",
            path=args.tool,
            field="--tool-mass",
        )
    from weldplan.robot import load_robot
    from weldplan.robot.reach import parse_base

    base = parse_base(args.robot_base) if args.robot_base else None
    return load_robot(args.robot, args.opw, base=base)


@dataclass(frozen=True, eq=False)
class RobotAcceptance:
    """The robot's side of the pose stage (:func:`pose_acceptance`)."""

    #: the pose choice's acceptance test (:class:`weldplan.robot.posechoice.ReachTest`)
    accept: Any
    #: the robot at the base the test judges from
    robot: Any
    #: the base searched on the first-pass poses; ``None`` when it was given (``--robot-base``,
    #: or fixed by ``--cost time``)
    placement: Any = None
    #: s spent on the first-pass poses and the base search
    seconds: float = 0.0


def pose_acceptance(
    args: argparse.Namespace, cell: Any, route: Any, tool: Any, robot: Any
) -> RobotAcceptance | None:
    """The robot's reach test for the weld poses (:mod:`weldplan.robot.posechoice`), from the
    base the robot stage will use: ``--robot-base`` (or the one ``--cost time`` fixed), else the
    base searched for the tool stage's poses chosen without the robot (a first pass of the pose
    choice; :func:`weldplan.robot.posechoice.place_for_poses`). ``None`` (logged) when no base
    candidate serves a weld: the robot stage then searches as without the test."""
    import time

    from weldplan.robot.collision import RobotCollision
    from weldplan.robot.posechoice import ReachTest, place_for_poses
    from weldplan.robot.reach import BaseSearch
    from weldplan.tool import plan_weld_poses

    t0 = time.perf_counter()
    F = flange_tcp(args, robot)
    floor = getattr(args, "floor_z", None)
    checker = RobotCollision(
        robot, cell.part, None, F, contact_radius=args.contact_radius, floor_z=floor
    )
    placement = None
    if not _base_fixed(args):
        first = plan_weld_poses(
            cell, route, tool, cone=args.tool_cone, contact_radius=args.contact_radius
        )
        try:
            placement = place_for_poses(
                robot, route, first, F, cell.part, checker, BaseSearch(floor_z=floor)
            )
        except PlanningError as exc:
            log.warning("robot reach test skipped: no base for the first-pass poses (%s)", exc)
            return None
        robot = robot.with_base(placement.base)
    test = ReachTest(robot, F, checker.with_robot(robot))
    return RobotAcceptance(test, robot, placement, time.perf_counter() - t0)


def _base_fixed(args: argparse.Namespace) -> bool:
    """With ``--cost time`` the base was fixed (given or searched) before the order."""
    return args.robot_base is not None or getattr(args, "cost", "length") == "time"


@dataclass(frozen=True, eq=False)
class RobotStage:
    """What the robot stage hands to the writer and the summary."""

    robot_route: Any
    build: Any
    texts: dict[str, str]
    rows: list[tuple[str, str]]
    skipped: tuple[str, ...] = ()
    route: Any = None  # the route carrying the robot route (route.tool["robot"])


def robot_stage(
    args: argparse.Namespace,
    cell: Any,
    route: Any,
    tool: Any,
    robot: Any,
    outputs: dict,
    reach: RobotAcceptance | None = None,
) -> RobotStage:
    """Steps 1-4 of the module docstring. Raises :class:`PlanningError` when a weld cannot be
    served or the emitted program does not close its FK round trip. ``reach``: the pose stage's
    robot test (:func:`pose_acceptance`); its base, when it searched one, is kept (the poses
    were chosen for it)."""
    from weldplan.robot.program import robot_program
    from weldplan.robot.routejson import attach_robot_route, poses_contact_radius

    rr, gun, follow = _joint_route(args, cell, route, tool, robot, reach)
    if reach is not None:
        robot = reach.robot
    rb = dataclasses.replace(
        robot.with_base(rr.base),
        velocity=robot.velocity * args.vel_scale,
        acceleration=robot.acceleration * args.acc_scale,
    )
    mass, cog = tool_load(args, robot, tool, rr.flange_tcp)
    stem = Path(outputs.get("post", outputs["csv"])).stem
    build = robot_program(
        follow,
        rr.q,
        rb,
        rr.flange_tcp,
        part=cell,
        tool_mass=mass,
        tool_cog=cog,
        row=rr.row,
        exact=rr.exact,
        moves=args.moves,
        weld_time=args.weld_time,
        tcp_speed=args.tcp_speed,
        name=stem,
        tool=tool,
        contact_radius=poses_contact_radius(route),
    )
    if len(build.skipped) == len(rr.weld_ids):
        raise PlanningError(f"the robot serves none of the welds ({', '.join(rr.status)})")
    if getattr(cell, "part_pose", None) is not None:  # the work object carries the part pose
        prog = dataclasses.replace(build.program, part_pose=cell.part_pose.matrix)
        build = dataclasses.replace(build, program=prog)
    texts = _texts(args, build, rr, rb, outputs)
    if "robot_html" in outputs:
        from weldplan.viz.robot_scene import robot_html

        texts["robot_html"] = robot_html(
            rb, build.timing, rr.flange_tcp, part=cell.part, tool=tool,
            route_points=follow.waypoints(),
        )  # fmt: skip
    rows = _rows(rr, build) + _order_rows(route, gun, rr) + _reach_rows(reach)
    rows += cost_rows(route, build.timing.total)
    unposed = () if gun is None else tuple(i for i in route.order if i not in gun.route.order)
    route = attach_robot_route(
        route, rr, urdf=args.robot, contact_radius=poses_contact_radius(route), gun=gun
    )
    return RobotStage(rr, build, texts, rows, (*build.skipped, *unposed), route)


def _joint_route(
    args: argparse.Namespace,
    cell: Any,
    route: Any,
    tool: Any,
    robot: Any,
    reach: RobotAcceptance | None,
) -> tuple[Any, Any, Any]:
    """Step 1: ``(robot route, gun route or None, the route followed)``; along the tool stage's
    transitions when the route carries them (:func:`_gun_route`), else the point-tip route.
    Raises :class:`PlanningError` when the path still collides."""
    from weldplan.robot.plan import plan_robot_route
    from weldplan.robot.reach import BaseSearch
    from weldplan.tool.route_frames import route_poses

    poses = route_poses(route)
    given = _base_fixed(args) or (reach is not None and reach.placement is not None)
    if reach is not None:
        robot = reach.robot
    gun = _gun_route(route, poses)  # None: the robot follows the point-tip route
    follow = route if gun is None else gun.route
    rr = plan_robot_route(
        follow,
        poses if gun is None else gun.poses,
        robot,
        flange_tcp=flange_tcp(args, robot),
        part=cell.part,
        tool=tool,
        base=robot.base if given else None,
        search=None if given else BaseSearch(floor_z=getattr(args, "floor_z", None)),
        rng=args.seed,
        tcp_poses=None if gun is None else gun.tcp,
        zone=None if gun is None else gun.zone,
        exits=None if gun is None else gun.exits,
        floor_z=getattr(args, "floor_z", None),  # a given floor is checked whatever the base
    )
    if reach is not None and reach.placement is not None:  # searched, before the poses
        rr.stats["placement"].update(
            searched=True, candidates=reach.placement.candidates, on="first-pass poses"
        )
    if "ok" not in rr.status:
        raise PlanningError(f"{_none_served(rr)}; nothing written")
    if rr.stats.get("collision_free") is False:
        hits = rr.stats.get("hits") or []
        first = (
            f"first: {hits[0]['body']} at motion {hits[0]['segment']}, t {hits[0]['t']:.2f}"
            if hits and isinstance(hits[0], dict) and "body" in hits[0]
            else f"first: {hits[0] if hits else '?'}"
        )
        raise PlanningError(
            f"the robot route still collides after re-planning ({len(hits)} hit(s), {first}); "
            "nothing written"
        )
    return rr, gun, follow


def _none_served(rr: Any) -> str:
    """One line: the robot serves no weld from its base, and why each was left out (the
    statuses counted, the first weld of each with its detail)."""
    from collections import Counter

    x, y, z = rr.base[:3, 3]
    yaw = math.degrees(math.atan2(rr.base[1, 0], rr.base[0, 0]))
    detail = dict(zip(rr.weld_ids, rr.detail or ("",) * len(rr.weld_ids), strict=True))
    first: dict[str, str] = {}
    for w, st in zip(rr.weld_ids, rr.status, strict=True):
        first.setdefault(st, w)

    def one(st: str, n: int) -> str:
        w = first[st]
        return f"{n} {st} (first weld {w}" + (f": {detail[w]})" if detail[w] else ")")

    why = "; ".join(one(st, n) for st, n in Counter(rr.status).most_common())
    return (
        f"the robot serves none of the {len(rr.weld_ids)} weld(s) with a tool pose from its base "
        f"({x:.0f}, {y:.0f}, {z:.0f}) mm, yaw {yaw:.1f} deg: {why}"
    )


def _gun_route(route: Any, poses: Any) -> Any:
    """The route along the tool stage's transitions, in its order
    (:func:`weldplan.robot.gunpath.gun_route`); ``None`` when the route carries none."""
    from weldplan.robot.gunpath import gun_route
    from weldplan.robot.routejson import poses_contact_radius
    from weldplan.tool.route_frames import route_tool_path

    path = route_tool_path(route)
    if path is None or not path.order:
        return None
    return gun_route(route, poses, path, contact_radius=poses_contact_radius(route))


def _ends(rr: Any) -> str:
    """How the detours left and reached their welds (``stats["detour_ends"]``), as
    ``"; welds left or reached: 2 by a gun exit, 4 by a retract"``."""
    ends = rr.stats.get("detour_ends") or {}
    if not ends:
        return ""
    return "; welds left or reached: " + ", ".join(f"{v} by a {k}" for k, v in ends.items())


def _legs(rr: Any, gun: Any) -> list[tuple[str, str, str]]:
    """``(from, to, how)`` of each leg between consecutive served welds."""
    from weldplan.robot.gunpath import legs_taken

    served = [w for w, s in zip(rr.weld_ids, rr.status, strict=True) if s == "ok"]
    taken = legs_taken(gun.via, rr.status, rr.replanned)
    return [(a, b, k) for a, b, k in zip(served[:-1], served[1:], taken, strict=True)]


def _order_rows(route: Any, gun: Any, rr: Any) -> list[tuple[str, str]]:
    """Summary rows: the order the program follows (and why, when it is not the point-tip
    route's), how each leg between served welds goes, and the welds the tool never reaches."""
    if gun is None:
        return []
    from collections import Counter

    order = gun.route.order
    pt = tuple(i for i in route.order if i in set(order))
    why = (
        "the tool stage's order, the same as the point-tip route's"
        if pt == order
        else f"the tool stage's order, not the point-tip route's ({'-'.join(pt)}): the gun's "
        "transitions were planned and checked between consecutive welds of the tool order, "
        "which avoids the pairs found blocked for the gun"
    )
    legs_by = _legs(rr, gun)
    taken = Counter(k for _, _, k in legs_by)
    gun_legs = {k[4:]: v for k, v in taken.items() if k.startswith("gun ")}
    detoured = [f"{a}->{b}" for a, b, k in legs_by if k == "detour"]
    legs = (
        f"{sum(gun_legs.values())} along the gun's transitions"
        + (f" ({', '.join(f'{k} {v}' for k, v in gun_legs.items())})" if gun_legs else "")
        + f", {taken['detour']} detoured (leave, joint-space transfer, approach"
        + (f": {', '.join(detoured)}" if detoured else "")
        + _ends(rr)
        + f"), {taken['joint']} by one joint motion where the gun's transition is blocked"
    )
    rows = [("robot order", f"{'-'.join(order)}: {why}"), ("robot legs", legs)]
    rows += [
        (f"  weld {i}", "not welded: no tool pose (the tool never reaches it)")
        for i in route.order
        if i not in order
    ]
    return rows


def _texts(args: argparse.Namespace, build: Any, rr: Any, rb: Any, outputs: dict) -> dict:
    from weldplan.io.trajectory import trajectory_csv_text

    texts: dict[str, str] = {}
    if "post" in outputs:
        if args.post == "rapid":
            from weldplan.io.posts.rapid import render_rapid

            texts["post"] = render_rapid(build.program)
        else:
            from weldplan.io.posts.krl import render_krl

            texts["post"], texts["post_dat"] = render_krl(build.program)
        check_program(args.post, texts, build.program, rb)
    if "trajectory" in outputs:
        texts["trajectory"] = trajectory_csv_text(build.timing, build.row)
    return texts


def check_program(post: str, texts: dict[str, str], program: Any, robot: Any) -> float:
    """Parse the emitted program and re-solve every target by FK of the URDF chain.

    Returns the largest position error (mm); raises :class:`PlanningError` past
    :data:`CHECK_MM` / :data:`CHECK_DEG`.
    """
    from weldplan.io.posts.parse import parse_krl, parse_rapid

    if post == "rapid":
        mod = parse_rapid(texts["post"])
        frame, tool = mod.wobj, mod.tool
        poses = [mod.targets[name][0] for _, name, _, _ in mod.moves]
    else:
        prog = parse_krl(texts["post"], texts["post_dat"])
        frame, tool = prog.base, prog.tool
        poses = [prog.points[name][0] for _, name, _, _ in prog.moves]
    Q = np.array([t.q for t in program.targets])
    T_fk = np.linalg.solve(robot.base, robot.fk(Q))  # flange in the robot base frame
    T_prog = frame @ np.array(poses) @ np.linalg.inv(tool)
    mm = float(np.linalg.norm(T_fk[:, :3, 3] - T_prog[:, :3, 3], axis=1).max())
    c = (np.einsum("nij,nij->n", T_fk[:, :3, :3], T_prog[:, :3, :3]) - 1.0) / 2.0
    deg = float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))).max())
    if mm > CHECK_MM or deg > CHECK_DEG:
        raise PlanningError(
            f"the emitted {post} program misses FK of its joint values by {mm:.3g} mm, "
            f"{deg:.3g} deg; nothing written"
        )
    return mm


def _rows(rr: Any, build: Any) -> list[tuple[str, str]]:
    tt = build.timing
    x, y, z, yaw = rr.stats.get("placement", {}).get("base_xyz_yaw", [math.nan] * 4)
    legs = tt.leg_times()
    miss = [
        (f"  weld {w}", f"not welded: {s.replace('_', ' ')}" + (f"; {d}" if d else ""))
        for w, s, d in zip(rr.weld_ids, rr.status, rr.detail or [""] * len(rr.status), strict=True)
        if s != "ok"
    ]
    return [
        ("robot", f"{rr.robot}, base ({x:.0f}, {y:.0f}, {z:.0f}) mm yaw {yaw:.1f} deg"),
        (
            "robot route",
            f"{rr.n_ok} / {len(rr.status)} welds, {len(rr.flips)} branch flip(s), "
            f"{len(rr.replanned)} leg(s) re-planned in joint space, collision-free "
            f"{rr.stats.get('collision_free', 'not checked')}"
            + (f"; {len(miss)} weld(s) not in the program (exit code 3)" if miss else ""),
        ),
        *miss,
        *_walk_rows(rr),
        (
            "cycle time",
            f"{tt.total:.2f} s ({tt.motion_time:.2f} s moving, {tt.weld_time:g} s a weld; legs "
            f"{', '.join(f'{v:.2f}' for v in legs[:6])}{' ...' if len(legs) > 6 else ''} s); "
            f"at a constant {build.tcp_speed:g} mm/s TCP: {build.constant_speed_time:.2f} s",
        ),
        (
            "program",
            f"{sum(t.move == 'linear' for t in build.program.targets)} linear and "
            f"{sum(t.move == 'joint' for t in build.program.targets)} joint moves, "
            f"{sum(t.blend >= 0.3 for t in build.program.targets)} fly-by points; the timed path "
            f"within {tt.deviation:.1e} rad of the joint path, its TCP up to "
            f"{build.tcp_deviation:.2f} mm off the linear moves' lines",
        ),
    ]


def _walk_rows(rr: Any) -> list[tuple[str, str]]:
    """The summary row of the walk over the welds: its work and the welds it left out, by
    cause (:class:`weldplan.robot.walkstats.WalkStats`)."""
    from weldplan.robot.walkstats import WalkStats

    walk = rr.stats.get("walk")
    return [("robot walk", WalkStats.from_dict(walk).describe())] if walk else []


def _reach_rows(reach: RobotAcceptance | None) -> list[tuple[str, str]]:
    """The summary row of the robot's reach test in the pose choice."""
    if reach is None:
        return []
    t = reach.accept
    why = ", ".join(f"{k} {v}" for k, v in t.vetoes.most_common())
    base = "searched on the poses chosen without the robot" if reach.placement else "given"
    return [
        (
            "robot reach test",
            f"{t.calls} gun pose(s) judged, {sum(t.vetoes.values())} vetoed"
            + (f" ({why})" if why else "")
            + f"; base {base} ({reach.seconds:.1f} s)",
        )
    ]
