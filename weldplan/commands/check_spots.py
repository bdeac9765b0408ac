"""``weldplan check-spots MESH SPOTS --tool T [--robot URDF] -o table.csv``: the weld feasibility
study (:mod:`weldplan.study.feasibility`).

Per spot: its distance to the part, the stack it joins (not analysed yet), whether each gun
closes on it (free candidate poses, the closest miss and which part of the gun hits), whether
each robot, carrying each gun at its given or searched base, reaches a free pose on a usable IK
branch without collision (or why not). Writes the table (CSV), optionally the study as JSON and
a self-contained 3D page coloured by verdict, all or none. Exit 0 when every spot is feasible,
3 when some are not (listed in the table), 2 for bad input (one line naming file, line, field).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from weldplan.commands._planning_args import add_part_pose_arguments, part_pose_from_args
from weldplan.commands._settings_args import add_settings_options, settings_from_args
from weldplan.commands._types import finite_mm
from weldplan.commands.plan import add_cell_arguments
from weldplan.errors import EXIT_OK, EXIT_PARTIAL, InputError
from weldplan.study.feasibility import StudySettings

HELP = "weld feasibility study: which spots each gun closes on and each robot reaches"

#: the ``--robot-base`` word for a base searched on the floor
SEARCHED = "searched"
#: the ``--tool`` prefix of a built-in tool (``builtin:arc_torch[,bend_angle=0,...]``)
BUILTIN = "builtin:"
#: this command's exit codes (``weldplan check-spots --help``)
EPILOG = """exit codes:
  0  every spot is feasible (some robot reaches it with some gun; without --robot: some gun
     closes on it)
  1  the run failed: a searched base found no floor candidate within reach of any spot, or
     the environment failed
  2  bad input or settings: the message names the file, line and field or the option
  3  some spots are not feasible: the table says why for each
  130  interrupted (Ctrl-C)"""


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.epilog = EPILOG
    p.add_argument("mesh", help="part mesh (STL, OBJ, PLY, OFF, GLB/GLTF)")
    p.add_argument("spots", help="spots CSV (id, x, y, z[, nx, ny, nz]; part frame)")
    add_cell_arguments(p)
    add_part_pose_arguments(p)
    p.add_argument("-o", "--output", required=True, help="the table to write (CSV)")
    p.add_argument("--json", metavar="F", help="also write the whole study as JSON")
    p.add_argument("--html", metavar="F", help="also write a 3D page coloured by verdict")
    _add_tool_arguments(p)
    _add_robot_arguments(p)
    p.add_argument("--quiet", action="store_true", help="no summary on stdout")


def _add_tool_arguments(p: argparse.ArgumentParser) -> None:
    """The guns (``--tool`` with its ``--tcp``, repeatable) and how each is judged at a spot."""
    g = p.add_argument_group("tools (each --tool may be repeated, with its own --tcp)")
    g.add_argument(
        "--tool",
        action="append",
        required=True,
        metavar="URDF|MESH|builtin:arc_torch",
        help="a gun: URDF (TCP its last fixed joint), a mesh with --tcp, or the built-in arc "
        "torch 'builtin:arc_torch[,bend_angle=0,stickout=15,...]' (a station's tool.builtin; "
        "weldplan.tool.arc_torch)",
    )
    g.add_argument(
        "--tcp",
        action="append",
        metavar="NAME|X,Y,Z,RX,RY,RZ",
        help="per --tool, in order: the URDF's TCP joint or link, or a mesh's TCP",
    )
    g.add_argument("--tool-units", choices=("m", "mm"), help="unit of mesh tools (default mm)")
    add_settings_options(
        g, StudySettings, None, only=("cone", "contact_radius", "clearance", "max_spot_distance")
    )
    g.add_argument(
        "--walls",
        action="store_true",
        help="the stack column: a single body thin enough for the gun to straddle near a free "
        "edge counts as a wall (slab models such as car2); default: a spot joins two sheets",
    )


def _add_robot_arguments(p: argparse.ArgumentParser) -> None:
    """The robots (``--robot`` with its ``--opw`` and ``--robot-base``, repeatable), the floor."""
    r = p.add_argument_group("robots (each --robot may be repeated, with its own --robot-base)")
    r.add_argument(
        "--robot",
        action="append",
        metavar="URDF",
        help="6-axis robot (URDF with limits, OPW parameters beside it)",
    )
    r.add_argument(
        "--opw",
        action="append",
        metavar="F",
        help="per --robot, in order: its OPW parameters (default: opw_parameters.yaml beside)",
    )
    r.add_argument(
        "--robot-base",
        action="append",
        metavar="X,Y,Z,YAW|searched",
        help="per --robot, in order: its base in the part frame, or the cell frame with "
        "--up / --part-pose (mm, deg about +z) "
        "or 'searched' on the floor (default searched)",
    )
    r.add_argument(
        "--floor-z",
        metavar="MM",
        type=finite_mm,
        help="the floor height in the part frame, or in the cell frame with --up / --part-pose "
        "(default 0 there): searched bases stand on it, no link may reach below it (default "
        "without a pose: the part's lowest point, not checked)",
    )


def _paired(values: list[str] | None, n: int, what: str, of: str) -> list[str | None]:
    """``values`` given once per ``of`` (or once for all, or not at all), as ``n`` entries."""
    if not values:
        return [None] * n
    if len(values) == 1 and n > 1:
        return values * n
    if len(values) != n:
        raise InputError(
            f"give {what} once, or once per {of} ({n}), got {len(values)}",
            field=f"--{what.lstrip('-')}",
        )
    return list(values)


def _names(paths: list[str]) -> list[str]:
    """Names from file stems, numbered where two share one."""
    stems = [Path(p).stem for p in paths]
    return [s if stems.count(s) == 1 else f"{s}#{k + 1}" for k, s in enumerate(stems)]


def _tools(args: argparse.Namespace) -> list[Any]:
    from weldplan.study.feasibility import load_study_tool

    tcps = _paired(args.tcp, len(args.tool), "--tcp", "--tool")
    names = _names([_builtin_name(p) or p for p in args.tool])
    return [
        _builtin_tool(path, tcp, name)
        if _builtin_name(path)
        else load_study_tool(path, tcp=tcp, units=args.tool_units, name=name)
        for path, tcp, name in zip(args.tool, tcps, names, strict=True)
    ]


def _builtin_name(text: str) -> str | None:
    """``"arc_torch"`` for ``--tool builtin:arc_torch[,k=v...]``, ``None`` for a file."""
    return text[len(BUILTIN) :].split(",")[0] if text.startswith(BUILTIN) else None


def _builtin_tool(text: str, tcp: str | None, name: str) -> Any:
    """The built-in tool of ``--tool builtin:arc_torch[,bend_angle=0,...]`` as ``weldplan
    plan --tool`` and a station's ``tool.builtin`` read it
    (:func:`weldplan.commands._station_args.tool_spec`), with its own TCP."""
    from weldplan.commands._station_args import tool_spec
    from weldplan.station.mount import load_tool_spec
    from weldplan.study.feasibility import StudyTool

    if tcp is not None:
        raise InputError(
            f"{text}: the built-in tool carries its own TCP; --tcp goes with a tool file",
            field="--tcp",
        )
    spec = tool_spec(argparse.Namespace(tool=text, tcp=None, tool_units=None, tool_mesh=None))
    tool, _ = load_tool_spec(spec)
    return StudyTool(name, tool, spec)


def _robots(args: argparse.Namespace) -> list[Any]:
    if not args.robot:
        if args.robot_base or args.opw or args.floor_z is not None:
            raise InputError("--robot-base, --opw and --floor-z need --robot", field="--robot")
        return []
    from weldplan.robot import load_robot
    from weldplan.robot.placement.reach import parse_base
    from weldplan.study.feasibility import StudyRobot

    bases = _paired(args.robot_base, len(args.robot), "--robot-base", "--robot")
    opws = _paired(args.opw, len(args.robot), "--opw", "--robot")
    out = []
    for path, base, opw, name in zip(args.robot, bases, opws, _names(args.robot), strict=True):
        searched = base is None or base.strip().lower() == SEARCHED
        B = None if searched else parse_base(base)
        robot = load_robot(path, opw, base=B)
        out.append(StudyRobot(name, robot, searched, source=str(path)))
    return out


def _placed(part: Any, spots: Any, pose: Any) -> tuple[Any, Any, str]:
    """``(part, spots, frame)``: in the cell frame with a part pose (weldplan.cellframe), else
    as given, in the part frame."""
    if pose is None:
        return part, spots, "part"
    from weldplan.cellframe import place_part

    part, spots, _ = place_part(part, spots, pose)
    return part, spots, "cell"


def run(args: argparse.Namespace) -> int:
    from weldplan.io.joints import read_joints
    from weldplan.io.mesh import load_part
    from weldplan.io.outputset import check_outputs, write_outputs
    from weldplan.study.feasibility import check_spots
    from weldplan.study.table import study_csv_text

    outputs = {"csv": Path(args.output)}
    for kind in ("json", "html"):
        if getattr(args, kind):
            outputs[kind] = Path(getattr(args, kind))
    check_outputs(outputs)
    pose = part_pose_from_args(args)
    floor = args.floor_z if args.floor_z is not None or pose is None else pose.floor_z
    settings = settings_from_args(StudySettings, args, floor_z=floor)
    spots = read_joints(args.spots, units=args.units)
    tools, robots = _tools(args), _robots(args)
    part = load_part(args.mesh, units=args.units, scale=args.scale, length=args.length)
    part, spots, frame = _placed(part, spots, pose)
    from weldplan.study.stacks import flange_stacks

    study = check_spots(
        part, spots, tools, robots, settings, stacks=flange_stacks(args.walls), frame=frame
    )
    title = f"weldplan check-spots {args.mesh} {args.spots}"
    texts = {outputs["csv"]: study_csv_text(study, title=title)}
    if "json" in outputs:
        texts[outputs["json"]] = study.to_json()
    if "html" in outputs:
        from weldplan.viz.study_scene import study_html

        texts[outputs["html"]] = study_html(study, part)
    write_outputs(texts)
    if not args.quiet:
        print(_summary(study, title, [str(p) for p in texts]))
    return EXIT_OK if study.all_feasible else EXIT_PARTIAL


def _summary(study: Any, title: str, written: list[str]) -> str:
    """The lines on stdout: counts per verdict, the bases, the time, the files."""
    c = study.counts()
    lines = [title, "-" * len(title), f"spots          {c['spots']}"]
    lines.append(f"feasible       {c['feasible']} / {c['spots']}")
    for t, words in c["gun"].items():
        lines.append(f"gun {t:<10} " + ", ".join(f"{k} {v}" for k, v in sorted(words.items())))
    for tr, words in c["robot"].items():
        lines.append(f"robot {tr}: " + ", ".join(f"{k} {v}" for k, v in sorted(words.items())))
    for r in study.robots:
        x, y, z, yaw = r.xyz_yaw()
        how = "searched" if r.searched else (r.note or "given")
        lines.append(f"base {r.name}: {x:.0f},{y:.0f},{z:.0f},{yaw:.1f} ({how})")
    s = study.stats

    def secs(key: str) -> str:
        return ", ".join(f"{v:.1f}" for v in s[key]) or "-"

    lines.append(
        f"time           gun {secs('gun_s')} s, robot {secs('robot_s')} s, total "
        f"{s['total_s']:.1f} s wall; CPU gun {secs('gun_cpu_s')} s, robot "
        f"{secs('robot_cpu_s')} s, total {s['total_cpu_s']:.1f} s"
    )
    lines.append(f"written        {', '.join(written)}")
    if not study.all_feasible:
        lines.append("exit code 3: some spots are not feasible (see the table)")
    return "\n".join(lines)
