"""The command line's options as a :class:`~weldplan.station.model.Station`.

``weldplan plan MESH JOINTS ...`` and ``weldplan demo ...`` are the quick form of a station with
one robot (or a tool alone, or neither): :func:`station_from_args` maps every option onto the
same model that ``weldplan plan station.toml`` reads (:func:`weldplan.station.load_station`).
With a station file the command line gives only the outputs and the run (:data:`RUN_OPTIONS`);
a station option beside it is an error naming the file's key to set instead.
"""

from __future__ import annotations

import argparse
import dataclasses
from typing import Any

import weldplan.station.model as m
from weldplan.commands._settings_args import settings_from_args
from weldplan.errors import InputError, WeldplanError

#: options that are not the station's: the outputs and how the run goes
RUN_OPTIONS = {
    "command", "verbose", "mesh", "joints", "output", "json", "html", "post", "post_file",
    "trajectory", "tool_csv", "robot_html", "png", "seed", "jobs", "dask", "quiet", "func",
    "station_defaults", "usage_error",
}  # fmt: skip
_OUTPUTS = ("json", "html", "post", "post_file", "trajectory", "tool_csv", "robot_html", "png")


def record_defaults(p: argparse.ArgumentParser) -> None:
    """Remember the station options' defaults and names, to tell which a user gave beside a
    file."""
    defaults = {
        a.dest: (a.default, max(a.option_strings, key=len))
        for a in p._actions
        if a.dest not in RUN_OPTIONS and a.dest != "help" and a.option_strings
    }
    p.set_defaults(station_defaults=defaults)


def outputs_from_args(args: argparse.Namespace, base: m.OutputSpec | None = None) -> m.OutputSpec:
    """The outputs: the command line's where given, else the station file's (``base``)."""
    base = base or m.OutputSpec()
    given = {k: getattr(args, k, None) for k in ("output", *_OUTPUTS)}
    given["csv"] = given.pop("output")
    return dataclasses.replace(base, **{k: v for k, v in given.items() if v is not None})


def station_from_file(args: argparse.Namespace, path: str) -> m.Station:
    """The station file's :class:`Station` with the command line's outputs and run options."""
    from weldplan.station import load_station

    station = load_station(path)
    for dest, (default, option) in getattr(args, "station_defaults", {}).items():
        if getattr(args, dest, default) != default:
            raise WeldplanError(
                f"{option}: with a station file, set it in {path} "
                "(the command line gives only the outputs, --seed, --jobs, --dask, --quiet)"
            )
    outputs = outputs_from_args(args, station.outputs)
    if outputs.csv is None:
        outputs = dataclasses.replace(outputs, csv=m.Path("route.csv"))
    jobs = station.jobs if args.jobs is None else args.jobs
    return dataclasses.replace(station, outputs=outputs, jobs=jobs)


def station_from_args(args: argparse.Namespace, part: m.PartSpec) -> m.Station:
    """The quick form's :class:`Station` (module docstring); options that need a companion
    (``--tcp`` a ``--tool``, ``--trajectory`` a ``--robot``, ...) fail here, before any work."""
    robot = _robot_spec(args)
    return m.Station(
        part=part,
        robots=() if robot is None else (robot,),
        clearance=args.clearance,
        floor_z=getattr(args, "floor_z", None),
        cell=settings_from_args(m.CellSettings, args),
        route=route_settings(args),
        tool=settings_from_args(m.ToolSettings, args),
        jobs=1 if args.jobs is None else args.jobs,
        outputs=outputs_from_args(args),
    )


def route_settings(args: argparse.Namespace) -> m.RouteSettings:
    """The route stage's settings (and ``--jobs`` checked: the run's, not the station's)."""
    jobs = getattr(args, "jobs", None)
    if jobs is not None and jobs < 1:
        raise WeldplanError(f"--jobs must be >= 1, got {jobs}")
    return settings_from_args(m.RouteSettings, args)


def tool_spec(args: argparse.Namespace) -> m.ToolSpec | None:
    """``--tool`` (a file, or ``builtin:arc_torch[,k=v...]``) as a :class:`ToolSpec`."""
    if not getattr(args, "tool", None):
        for opt in ("tcp", "tool_units", "tool_mesh", "tip_cone"):
            if getattr(args, opt, None) is not None:
                raise WeldplanError(f"--{opt.replace('_', '-')} needs --tool")
        return None
    kw: dict[str, Any] = dict(tip_cone=getattr(args, "tip_cone", None))
    kw["mass"] = getattr(args, "tool_mass", None)
    if args.tool.startswith("builtin:"):
        return m.ToolSpec(builtin=_builtin(args.tool), params=_params(args.tool), **kw)
    return m.ToolSpec(
        file=args.tool, tcp=args.tcp, units=args.tool_units, mesh=args.tool_mesh, **kw
    )


def _builtin(text: str) -> str:
    return text[len("builtin:") :].split(",")[0]


def _params(text: str) -> dict[str, float]:
    """``builtin:arc_torch,bend_angle=0,stickout=15`` -> ``{"bend_angle": 0.0, ...}``."""
    out = {}
    for item in text.split(",")[1:]:
        k, _, v = item.partition("=")
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise InputError(f"not a number: {item!r}", field="--tool") from None
    return out


def _robot_spec(args: argparse.Namespace) -> m.RobotSpec | None:
    """The one robot entry of the quick form: ``--robot`` with its ``--tool``, or the tool
    alone; None without either."""
    tool = tool_spec(args)
    if not getattr(args, "robot", None):
        for opt in ("opw", "robot_base", "floor_z", "trajectory", "tool_mass", "robot_html"):
            if getattr(args, opt, None) is not None:
                raise WeldplanError(f"--{opt.replace('_', '-')} needs --robot")
        if getattr(args, "cost", "length") == "time":
            raise WeldplanError("--cost time needs --robot (and a --tool)")
        return None if tool is None else m.RobotSpec(tool=tool)
    if tool is None:
        raise InputError(
            "--robot needs a --tool (a URDF whose root link is what the flange carries, or a "
            "mesh in its mounting frame with --tcp and --tool-mass)",
            field="--tool",
        )
    if tool.builtin is None and not tool.is_urdf and tool.mass is None:
        raise InputError(
            "a mesh tool has no mass: give --tool-mass with --robot",
            path=args.tool,
            field="--tool-mass",
        )
    from weldplan.robot.placement.reach import parse_base

    base = None
    if args.robot_base:
        parse_base(args.robot_base)  # the option's own one-line errors
        base = tuple(float(v) for v in args.robot_base.replace(";", ",").split(","))
    return m.RobotSpec(
        tool=tool, urdf=args.robot, opw=args.opw, base=base,
        settings=settings_from_args(m.RobotSettings, args),
    )  # fmt: skip
