"""The station: what a user plans (part, welds, robots with their tools and bases, settings).

A :class:`Station` is declarative and cheap: paths and numbers, every field checked when it is
made (``__post_init__``), nothing loaded. :func:`weldplan.station.load.load_station` reads one
from a TOML file; ``weldplan plan MESH JOINTS ...`` builds the same object from its options
(:mod:`weldplan.commands._station_args`); :func:`weldplan.station.pipeline.plan` runs it.

The settings of each stage are one frozen object (:class:`CellSettings`, :class:`RouteSettings`,
:class:`ToolSettings`, :class:`RobotSettings`, in :mod:`weldplan.station.settings`), as
../shared/DESIGN.md asks ("a stage takes its inputs and one frozen, validated settings object").
A station holds a *list* of robots, each with its tool and its base (given or searched):
:func:`weldplan.plan` plans one through :func:`~weldplan.station.pipeline.plan`, several through
:func:`weldplan.multi.station.plan_station`.

Frames and units: millimetres and degrees; the part frame is where the mesh and the welds are
given. ``part_pose`` is the part's pose in the cell (:class:`weldplan.cellframe.PartPose`; ``None``:
the part frame is the planning frame): the cell stage moves the mesh and the welds into the cell
frame, a robot stands on the cell's floor (``floor_z``, default the pose's, 0) and is checked
against it, and the programs' work object carries the pose.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from weldplan.errors import ConfigError
from weldplan.station.fields import (  # noqa: F401 - model's names since the station existed
    _choice,
    _flag,
    _normalise,
    _number,
    _optional,
    _path,
    setting,
)
from weldplan.station.settings import (  # noqa: F401 - re-exported: m.CellSettings, ...
    DEFAULT_WELD_TIME,
    ROBOT_COSTS,
    ROBOT_MOVES,
    TOOL_ORDERS,
    CellSettings,
    RobotSettings,
    RouteSettings,
    ToolSettings,
)

#: the built-in tools a station may name instead of a file (:func:`weldplan.tool.arc_torch`)
BUILTIN_TOOLS = ("arc_torch",)
#: keyword parameters of the built-in arc torch (mm, degrees; :func:`weldplan.tool.arc_torch`)
ARC_TORCH_PARAMS = (
    "neck_length",
    "diameter",
    "bend_angle",
    "stickout",
    "nozzle_length",
    "body_length",
    "body_diameter",
)


@dataclass(frozen=True)
class PartSpec:
    """The part and its welds.

    Attributes
    ----------
    mesh, welds
        The part mesh (STL, OBJ, PLY, OFF, GLB/GLTF) and the welds CSV (``id, x, y, z[, dx, dy,
        dz]``); both ``None``: the embedded demo cell (:func:`weldplan.weld.cell.demo_cell`).
    units
        ``"mm"`` or ``"m"``: of the mesh and welds files.
    scale, length
        An extra scale factor of the mesh, or the length (mm) its longest side is scaled to.
    """

    mesh: Path | None = None
    welds: Path | None = None
    units: str = "mm"
    scale: float | None = None
    length: float | None = None

    def __post_init__(self) -> None:
        if (self.mesh is None) != (self.welds is None):
            raise ConfigError("part: give both mesh and welds (or neither: the demo)", field="mesh")
        for k in ("mesh", "welds"):
            _path(self, k)
        _choice("units", self.units, ("mm", "m"))
        _optional("scale", self.scale, 0.0, lo_open=True)
        _optional("length", self.length, 0.0, lo_open=True)

    @property
    def is_demo(self) -> bool:
        return self.mesh is None


@dataclass(frozen=True)
class ToolSpec:
    """A tool as the station names it: a file (URDF, or a mesh with ``tcp``) or a built-in.

    Attributes
    ----------
    file
        A URDF (its TCP: the last fixed joint, or ``tcp`` naming a joint or link) or a mesh.
    builtin, params
        ``"arc_torch"`` (:func:`weldplan.tool.arc_torch`) with its keyword parameters (mm,
        degrees; default the bent torch, 22 deg); mounted with its body's end on the flange and
        its body along the flange's z axis.
    tcp
        With a mesh: ``"x,y,z,rx,ry,rz"`` in the mesh frame; with a URDF: a joint or link name.
    units, mesh
        Unit of the mesh file; with a URDF, a mesh in its root-link frame instead of its own.
    tip_cone
        Degrees: the tool may touch the part only within this cone about its axis behind the TCP.
    mass
        kg: the tool's load for the programs (default: a URDF's ``<inertial>`` masses).
    """

    file: Path | None = None
    builtin: str | None = None
    params: Mapping[str, float] = field(default_factory=dict)
    tcp: str | None = None
    units: str | None = None
    mesh: Path | None = None
    tip_cone: float | None = None
    mass: float | None = None

    def __post_init__(self) -> None:
        if (self.file is None) == (self.builtin is None):
            raise ConfigError("a tool is a file or a builtin, exactly one of them", field="file")
        if self.builtin is not None:
            _choice("builtin", self.builtin, BUILTIN_TOOLS)
            for k in ("tcp", "units", "mesh"):
                if getattr(self, k) is not None:
                    raise ConfigError(f"{k} goes with a tool file, not a builtin", field=k)
            for k, v in self.params.items():
                _choice("arc_torch parameter", k, ARC_TORCH_PARAMS)
                _number(k, v, -90.0 if k == "bend_angle" else 0.0)
        elif self.params:
            raise ConfigError("parameters go with a builtin tool", field=next(iter(self.params)))
        for k in ("file", "mesh"):
            _path(self, k)
        _normalise(self, "params", dict(self.params))
        if self.units is not None:
            _choice("units", self.units, ("mm", "m"))
        _optional("tip_cone", self.tip_cone, 0.0, 90.0, lo_open=True)
        _optional("mass", self.mass, 0.0, 5000.0, lo_open=True)

    @property
    def is_urdf(self) -> bool:
        return self.file is not None and self.file.suffix.lower() == ".urdf"


@dataclass(frozen=True)
class RobotSpec:
    """One robot of the station: its arm (or none: the tool alone), its tool, its base.

    Attributes
    ----------
    tool
        The tool its flange carries (:class:`ToolSpec`).
    urdf, opw
        The arm's URDF (6 revolute joints with limits) and OPW parameters (default
        ``opw_parameters.yaml`` beside it); ``urdf`` None: no arm, the tool stage only.
    base
        ``(x, y, z, yaw)`` mm and degrees about +z, in the planning frame (the cell frame when
        the station has a ``part_pose``, else the part frame); None: searched.
    search
        Where the base is searched (:class:`weldplan.robot.placement.BaseSearch` keywords but the
        floor, which is the station's): ``step``, ``half_width``, ``heights``, ``extra_yaws``,
        ``line``. Empty: the defaults.
    settings
        The robot stage's :class:`RobotSettings`.
    """

    tool: ToolSpec
    urdf: Path | None = None
    opw: Path | None = None
    base: tuple[float, float, float, float] | None = None
    search: Mapping[str, Any] = field(default_factory=dict)
    settings: RobotSettings = field(default_factory=RobotSettings)

    def __post_init__(self) -> None:
        for k in ("urdf", "opw"):
            _path(self, k)
        if self.urdf is None and (self.opw is not None or self.base is not None or self.search):
            raise ConfigError("opw, base and search need a robot urdf", field="urdf")
        if self.base is not None:
            b = tuple(self.base)
            if len(b) != 4:
                raise ConfigError(f"base must be [x, y, z, yaw], got {b!r}", field="base")
            _normalise(self, "base", tuple(_number("base", v, -1e7, 1e7) for v in b))
        if self.search:
            if self.base is not None:
                raise ConfigError("give a base or a search region, not both", field="search")
            self.base_search(None)  # checked once
        _normalise(self, "search", dict(self.search))

    def base_search(self, floor_z: float | None) -> Any:
        """The :class:`~weldplan.robot.placement.BaseSearch` on the station's floor."""
        from weldplan.robot.placement.reach import BaseSearch

        if "floor_z" in self.search:
            raise ConfigError(
                "the floor is the station's (floor_z), not the search's", field="floor_z"
            )
        kw = {k: tuple(map(tuple, v)) if k == "line" else v for k, v in self.search.items()}
        for k in ("heights", "extra_yaws"):
            if k in kw:
                kw[k] = tuple(kw[k])
        try:
            return BaseSearch(floor_z=floor_z, **kw)
        except TypeError as exc:
            raise ConfigError(f"search: {exc}", field="search") from None
        except ValueError as exc:
            raise ConfigError(f"search: {exc}", field="search") from None


@dataclass(frozen=True)
class OutputSpec:
    """Files a run writes (paths as given: relative to the current directory). ``post``:
    ``"rapid"`` or ``"krl"``. The library's :func:`~weldplan.station.pipeline.plan` writes
    nothing; :func:`weldplan.station.outputs.write_plan` and the CLI use these."""

    csv: Path | None = None
    json: Path | None = None
    html: Path | None = None
    post: str | None = None
    post_file: Path | None = None
    trajectory: Path | None = None
    tool_csv: Path | None = None
    robot_html: Path | None = None
    png: Path | None = None

    def __post_init__(self) -> None:
        for f in fields(self):
            if f.name != "post":
                _path(self, f.name)
        if self.post is not None:
            _choice("post", self.post, ("rapid", "krl"))


@dataclass(frozen=True)
class Station:
    """A station: the part placed in the cell, its welds, its robots, every stage's settings.

    Attributes
    ----------
    part
        :class:`PartSpec`.
    robots
        The robots, each with its tool and base (:class:`RobotSpec`); empty: the point-tip
        route only.
    clearance
        mm: the torch tip's radius, the route's clearance from the part.
    part_pose
        The part's pose in the cell; None is the identity (module docstring).
    floor_z
        mm: the floor's height in the planning frame (None: not known, not checked; the base
        search then stands the robot at the part's lowest point).
    cell, route, tool
        The settings of the cell, the point-tip route and the tool stage.
    jobs
        Worker processes planning local paths (1: in this process).
    seed
        The seed a run uses when :func:`~weldplan.station.pipeline.plan` is given no ``rng``.
    name
        The program's name (None: ``weldplan_route``; the CLI uses the output file's stem).
    outputs
        :class:`OutputSpec`: what the CLI writes.
    source
        The station file this came from, if any.
    """

    part: PartSpec = field(default_factory=PartSpec)
    robots: tuple[RobotSpec, ...] = ()
    clearance: float = setting(
        5.0, "--clearance", "the torch tip's radius: the point-tip route's clearance from the "
        "part, mm",
        metavar="MM",
    )  # fmt: skip
    part_pose: Any = None
    floor_z: float | None = None
    cell: CellSettings = field(default_factory=CellSettings)
    route: RouteSettings = field(default_factory=RouteSettings)
    tool: ToolSettings = field(default_factory=ToolSettings)
    jobs: int = 1
    seed: int = 0
    name: str | None = None
    outputs: OutputSpec = field(default_factory=OutputSpec)
    source: Path | None = None

    def __post_init__(self) -> None:
        _normalise(self, "robots", tuple(self.robots))
        _number("clearance", self.clearance, 0.0, lo_open=True)
        _optional("floor_z", self.floor_z, -1e6, 1e6)
        if not (isinstance(self.jobs, int) and not isinstance(self.jobs, bool) and self.jobs >= 1):
            raise ConfigError(f"jobs must be >= 1, got {self.jobs!r}", field="jobs")
        from weldplan.weld.validate import seed

        seed(self.seed)
        self.plan_config()  # the route's settings together with the cell's

    def plan_config(self) -> Any:
        """The point-tip stage's :class:`~weldplan.weld.pipeline.PlanConfig`."""
        return self.route.config(self.clearance, self.cell.pitch, self.cell.margin)

    @property
    def robot(self) -> RobotSpec | None:
        """The one robot (None without any); several: a ConfigError (a station of several
        robots is planned robot by robot: :attr:`robots`, :mod:`weldplan.multi.station`)."""
        if len(self.robots) > 1:
            raise ConfigError(
                f"{len(self.robots)} robots: this step plans one robot; a station of several "
                "is planned by weldplan.plan (weldplan plan STATION.toml)",
                field="robot",
            )
        return self.robots[0] if self.robots else None
