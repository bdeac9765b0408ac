"""``weldplan.load_station(path)``: a :class:`~weldplan.station.model.Station` from a TOML file.

The file (docs/station.md)::

    name = "demo"                 # the program's name (optional)
    clearance = 5.0               # mm
    floor_z = -653.0              # mm, optional
    seed = 0
    jobs = 1

    [part]                        # mesh and welds: paths relative to this file
    mesh = "../assets/demo/part.stl"
    welds = "../assets/demo/joints.csv"
    units = "mm"                  # scale, length: optional
    up = "y"                      # optional: the part's up axis, or pose = [x, y, z, rx, ry, rz]
    fixture_z = 0.0               # mm: the part's lowest point above the floor (optional)

    [cell]                        # pitch, margin, approach_cone, max_joint_distance, spot_depth
    [route]                       # planner, sequencer, aco, refine, smooth, ...
    [tool_settings]               # cone, contact_radius, retract, side_exit, ...

    [[robot]]                     # one table per robot
    urdf = "robots/kr150.urdf"    # opw, base = [x, y, z, yaw] or [robot.search]
    weld_time = 0.5               # acc_scale, vel_scale, tcp_speed, moves, cost
    home = [0, -90, 90, 0, 0, 0]  # deg per axis: where the program starts and ends (optional)
    [robot.tool]
    file = "gun.urdf"             # or builtin = "arc_torch" with its parameters
    [robot.search]                # step, half_width, heights, extra_yaws, line

    [output]                      # csv, json, html, post, post_file, trajectory, ...

Every error is an :class:`~weldplan.errors.InputError` naming the file, the line and the key:
a TOML syntax error, an unknown key, a value of the wrong type or range, a file that does not
exist. ``tomllib`` keeps no positions, so :class:`_Lines` finds each key's line in the text.
"""

from __future__ import annotations

import os
import re
import tomllib
from dataclasses import fields
from os import PathLike
from pathlib import Path
from typing import Any

import weldplan.station.model as m
from weldplan.errors import ConfigError, InputError

_TOP = {"name", "clearance", "floor_z", "seed", "jobs", "part", "cell", "route"}
_TOP |= {"tool_settings", "robot", "output"}
_PART = {"mesh", "welds", "units", "scale", "length", "up", "pose", "fixture_z"}
_ROBOT_SETTINGS = {f.name for f in fields(m.RobotSettings)}
_ROBOT = {"urdf", "opw", "base", "search", "tool"} | _ROBOT_SETTINGS
_TOOL = {"file", "builtin", "tcp", "units", "mesh", "tip_cone", "mass"} | set(m.ARC_TORCH_PARAMS)
_SEARCH = {"step", "half_width", "heights", "extra_yaws", "line"}
_TYPES: dict[str, tuple[type, ...]] = {"str": (str,), "num": (int, float), "int": (int,)}


class _Lines:
    """The line of each key of a TOML text: ``line(("robot", 0, "tool", "mass"))``. Tables
    (``[a.b]``, ``[[a]]``) and ``key = value`` lines are tracked; a key inside an inline table
    or a multi-line array falls back to its parent's line."""

    _HEADER = re.compile(r"^\s*(\[\[?)\s*([A-Za-z0-9_.\-\s\"]+?)\s*\]\]?\s*(#.*)?$")
    _KEY = re.compile(r"^\s*([A-Za-z0-9_\-]+)\s*=")

    def __init__(self, text: str) -> None:
        self.lines: dict[tuple[Any, ...], int] = {}
        counts: dict[tuple[str, ...], int] = {}
        table: tuple[Any, ...] = ()
        for n, raw in enumerate(text.splitlines(), start=1):
            h = self._HEADER.match(raw)
            if h:
                names = tuple(p.strip().strip('"') for p in h.group(2).split("."))
                if h.group(1) == "[[":
                    counts[names] = counts.get(names, -1) + 1
                table = self._index(names, counts)
                self.lines.setdefault(table, n)
                continue
            k = self._KEY.match(raw)
            if k:
                self.lines.setdefault((*table, k.group(1)), n)

    @staticmethod
    def _index(names: tuple[str, ...], counts: dict[tuple[str, ...], int]) -> tuple[Any, ...]:
        """``("robot", "tool")`` -> ``("robot", 0, "tool")`` after one ``[[robot]]``."""
        out: list[Any] = []
        for i, name in enumerate(names):
            out.append(name)
            if names[: i + 1] in counts:
                out.append(counts[names[: i + 1]])
        return tuple(out)

    def line(self, key: tuple[Any, ...]) -> int | None:
        while key:
            if key in self.lines:
                return self.lines[key]
            key = key[:-1]
        return None


class _Reader:
    """Reads one station file: checks keys, types and files, each error located."""

    def __init__(self, path: Path, text: str) -> None:
        self.path = path
        self.folder = path.absolute().parent
        self.where = _Lines(text)

    def error(self, key: tuple[Any, ...], message: str) -> InputError:
        name = ".".join(str(k) for k in key if not isinstance(k, int))
        return InputError(message, path=self.path, line=self.where.line(key), field=name or None)

    def table(self, data: Any, key: tuple[Any, ...], allowed: set[str]) -> dict[str, Any]:
        if not isinstance(data, dict):
            raise self.error(key, f"must be a table, got {type(data).__name__}")
        for k in data:
            if k not in allowed:
                raise self.error(
                    (*key, k), f"unknown key {k!r}; known: {', '.join(sorted(allowed))}"
                )
        return data

    def typed(self, data: dict[str, Any], key: tuple[Any, ...], types: dict[str, str]) -> None:
        for k, kind in types.items():
            v = data.get(k)
            if v is None:
                continue
            ok = isinstance(v, _TYPES[kind]) and not isinstance(v, bool)
            if not ok:
                raise self.error((*key, k), f"must be a {_KIND_WORDS[kind]}, got {v!r}")

    def file(self, data: dict[str, Any], key: tuple[Any, ...], name: str) -> Path | None:
        v = data.get(name)
        if v is None:
            return None
        if not isinstance(v, str):
            raise self.error((*key, name), f"must be a path (a string), got {v!r}")
        p = Path(os.path.normpath(self.folder / v))
        if not p.is_file():
            raise self.error((*key, name), f"no such file: {p}")
        return p

    def build(self, cls: type, key: tuple[Any, ...], **kw: Any) -> Any:
        """``cls(**kw)``, a ConfigError located at the key it names."""
        try:
            return cls(**kw)
        except ConfigError as exc:
            raise self.error((*key, exc.field or ""), exc.message) from None


_KIND_WORDS = {"str": "string", "num": "number", "int": "integer"}


def load_station(path: str | PathLike[str]) -> m.Station:
    """Read a station file (module docstring). Raises :class:`~weldplan.errors.InputError`."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such station file", path=path)
    text = path.read_text(encoding="utf-8")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        at = re.search(r"at line (\d+)", str(exc))
        raise InputError(
            f"not valid TOML: {exc}", path=path, line=int(at.group(1)) if at else None
        ) from None
    r = _Reader(path, text)
    r.table(data, (), _TOP)
    r.typed(data, (), {"name": "str", "clearance": "num", "floor_z": "num", "seed": "int"})
    r.typed(data, (), {"jobs": "int"})
    if "part" not in data:
        raise r.error(("part",), "a station needs a [part] table (mesh and welds)")
    robots = data.get("robot", [])
    if not isinstance(robots, list):
        raise r.error(("robot",), "robots are an array of tables: write [[robot]]")
    pose = _part_pose(r, data["part"], data.get("floor_z"))
    specs = tuple(_robot(r, d, i) for i, d in enumerate(robots))
    _apart(r, specs)
    return r.build(
        m.Station, (),
        part=_part(r, data["part"]),
        part_pose=pose,
        robots=specs,
        cell=_settings(r, data.get("cell", {}), ("cell",), m.CellSettings),
        route=_settings(r, data.get("route", {}), ("route",), m.RouteSettings),
        tool=_settings(r, data.get("tool_settings", {}), ("tool_settings",), m.ToolSettings),
        outputs=_settings(r, data.get("output", {}), ("output",), m.OutputSpec),
        source=path,
        **{k: data[k] for k in ("name", "clearance", "floor_z", "seed", "jobs") if k in data},
    )  # fmt: skip


def key_line(path: str | PathLike[str] | None, key: tuple[Any, ...]) -> int | None:
    """The line of ``key`` (e.g. ``("robot", 1, "home")``) in the station file ``path``, for
    an error found after loading (``None``: no file, or the key is not in it)."""
    if path is None or not Path(path).is_file():
        return None
    return _Lines(Path(path).read_text(encoding="utf-8")).line(key)


#: mm: two given bases closer than this on the floor (x, y) are the same place: two robots
#: cannot stand there (a KR 150's foot is about 1 m across)
MIN_BASE_SPACING = 500.0


def _apart(r: _Reader, specs: tuple[m.RobotSpec, ...]) -> None:
    """Refuse two robots whose given bases are closer than :data:`MIN_BASE_SPACING` in x, y."""
    for j, b in enumerate(specs):
        for i, a in enumerate(specs[:j]):
            if a.base is None or b.base is None:
                continue
            d = float(((a.base[0] - b.base[0]) ** 2 + (a.base[1] - b.base[1]) ** 2) ** 0.5)
            if d < MIN_BASE_SPACING:
                raise r.error(
                    ("robot", j, "base"),
                    f"robot {j + 1} stands {d:.1f} mm from robot {i + 1} (bases closer than "
                    f"{MIN_BASE_SPACING:g} mm in x, y are the same place)",
                )


def _part_pose(r: _Reader, d: Any, floor_z: Any) -> Any:
    """The part's pose in the cell (:class:`~weldplan.cellframe.PartPose`) from ``[part]``'s
    ``up`` or ``pose`` (x, y, z mm, rx, ry, rz deg) and ``fixture_z``; None without either."""
    from weldplan.cellframe import PartPose

    if not isinstance(d, dict) or ("up" not in d and "pose" not in d):
        if isinstance(d, dict) and "fixture_z" in d:
            raise r.error(("part", "fixture_z"), "needs up or pose in [part]")
        return None
    if "up" in d and "pose" in d:
        raise r.error(("part", "pose"), "give up or pose, not both")
    r.typed(d, ("part",), {"up": "str", "fixture_z": "num"})
    floor = 0.0 if not isinstance(floor_z, (int, float)) else float(floor_z)
    fixture = d.get("fixture_z")
    key = ("part", "up" if "up" in d else "pose")
    try:
        if "up" in d:
            return PartPose.from_up(d["up"], fixture_z=fixture or 0.0, floor_z=floor)
        return PartPose.from_xyzrpy(d["pose"], fixture_z=fixture, floor_z=floor)
    except InputError as exc:
        raise r.error(key, exc.message) from None


def _part(r: _Reader, d: Any) -> m.PartSpec:
    key = ("part",)
    r.table(d, key, _PART)
    for k in ("mesh", "welds"):
        if k not in d:
            raise r.error((*key, k), f"[part] needs {k}")
    r.typed(d, key, {"units": "str", "scale": "num", "length": "num"})
    kw = {k: d[k] for k in ("units", "scale", "length") if k in d}
    return r.build(
        m.PartSpec, key, mesh=r.file(d, key, "mesh"), welds=r.file(d, key, "welds"), **kw
    )


def _settings(r: _Reader, d: Any, key: tuple[Any, ...], cls: type) -> Any:
    """A settings table: every key a field of ``cls``, each value checked by ``cls``."""
    r.table(d, key, {f.name for f in fields(cls)})
    for k, v in d.items():
        if isinstance(v, (dict, list)):
            raise r.error((*key, k), f"must be a single value, got {v!r}")
    return r.build(cls, key, **d)


def _robot(r: _Reader, d: Any, i: int) -> m.RobotSpec:
    key = ("robot", i)
    r.table(d, key, _ROBOT)
    if "tool" not in d:
        raise r.error(key, "a robot needs a [robot.tool] table")
    settings = {k: d[k] for k in _ROBOT_SETTINGS if k in d and k != "home"}
    if "home" in d:  # a list: not a single value as the other settings
        home = d["home"]
        if not isinstance(home, list) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in home
        ):
            raise r.error((*key, "home"), f"must be a list of degrees, one per axis, got {home!r}")
        settings["home"] = tuple(float(v) for v in home)
    base = d.get("base")
    if base is not None and not (isinstance(base, list) and len(base) == 4):
        raise r.error((*key, "base"), f"must be [x, y, z, yaw] (mm, degrees), got {base!r}")
    search = r.table(d.get("search", {}), (*key, "search"), _SEARCH)
    return r.build(
        m.RobotSpec, key,
        tool=_tool(r, d["tool"], (*key, "tool")),
        urdf=r.file(d, key, "urdf"),
        opw=r.file(d, key, "opw"),
        base=None if base is None else tuple(base),
        search=search,
        settings=_settings(r, settings, key, m.RobotSettings)
        if settings else m.RobotSettings(),
    )  # fmt: skip


def _tool(r: _Reader, d: Any, key: tuple[Any, ...]) -> m.ToolSpec:
    r.table(d, key, _TOOL)
    r.typed(d, key, {"builtin": "str", "tcp": "str", "units": "str", "tip_cone": "num"})
    r.typed(d, key, {"mass": "num", **{k: "num" for k in m.ARC_TORCH_PARAMS}})
    params = {k: d[k] for k in m.ARC_TORCH_PARAMS if k in d}
    return r.build(
        m.ToolSpec, key,
        file=r.file(d, key, "file"), builtin=d.get("builtin"), params=params, tcp=d.get("tcp"),
        units=d.get("units"), mesh=r.file(d, key, "mesh"), tip_cone=d.get("tip_cone"),
        mass=d.get("mass"),
    )  # fmt: skip
